"""Sphinx configuration of rockslide's documentation (``sphinx-build -W -b html docs OUT``).

The pages are Markdown (myst-parser); the Python API comes from the docstrings (autodoc with
napoleon, numpydoc style) and the command-line reference from click itself (sphinx-click), so
neither can drift from the code. Build it outside the repository, or under ``docs/_build``, which
git ignores.
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))          # the checkout's rockslide, installed or not

from rockslide import __version__  # noqa: E402

project = "rockslide"
author = "the rockslide developers"
copyright = "the rockslide developers, MIT licence"
release = version = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_click",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]

# Markdown: heading anchors so that [Units](#units) and [case file](case-file.md#scaling) resolve;
# $...$ and $$...$$ as mathematics (docs/model.md)
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
# code blocks written ``` without a language are shown as plain text, not highlighted as Python
highlight_language = "text"

# the API: numpydoc docstrings through napoleon, members in the order they are written
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"   # types beside what the docstring documents
autodoc_preserve_defaults = True
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# `name` in a docstring (numpydoc's habit) links to that object where Sphinx knows it, else shows as code
default_role = "py:obj"

html_theme = "alabaster"
html_title = f"rockslide {release}"
html_static_path: list[str] = []


# The commands' help is plain text written for a terminal ("Largest |A_h|", "'records/*.csv'"), which
# reStructuredText would read as markup: escape it where sphinx-click passes it on as text, leaving
# its own directives, fields and line blocks ("| " before the lines of an example) alone.
_MARKUP = re.compile(r"([*|`\\])|(?<=\w)_(?=\W|$)")


def _plain(text: str) -> str:
    return _MARKUP.sub(lambda m: "\\" + m.group(0), text)


def _escape_help(app, ctx, lines: list[str]) -> None:
    for i, line in enumerate(lines):
        body = line.lstrip()
        indent = line[:len(line) - len(body)]
        if not body or body.startswith((".. ", ":")):
            continue
        if body.startswith("| "):
            lines[i] = indent + "| " + _plain(body[2:])
        else:
            lines[i] = indent + _plain(body)


def setup(app):
    for event in ("description", "options", "arguments", "epilog"):
        app.connect(f"sphinx-click-process-{event}", _escape_help)
smartquotes = False     # "--height" stays two hyphens, quotes stay as typed

