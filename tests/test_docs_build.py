"""The documentation builds without a warning (Sphinx, myst-parser, sphinx-click; the `docs` extra,
part of `test`): a broken cross-reference, a page left out of the table of contents, a docstring
whose markup does not parse or a command's help that reads as bad reStructuredText fails here.
Where the packages are missing this fails too, by design: CI installs them with `.[test]`. The build
takes 2-9 s on 2 shared cores (autodoc imports the API), so it is not marked slow."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest
from conftest import REPO


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The HTML site, built once from docs/ into a temporary folder (never inside the repository)."""
    for module in ("sphinx", "myst_parser", "sphinx_click"):
        __import__(module)               # ImportError: install the test extra, pip install -e ".[test]"
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           "-d", str(out / ".doctrees"), str(REPO / "docs"), str(out)],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:] + done.stdout[-2000:]
    assert done.stderr.strip() == "", done.stderr[-4000:]
    return out


def text_of(page) -> str:
    """The visible text of an HTML page, whitespace collapsed."""
    html = page.read_text(encoding="utf-8")
    html = re.sub(r"<(script|style)\b.*?</\1>", " ", html, flags=re.S)
    return " ".join(re.sub(r"<[^>]+>", " ", html).replace("&#8217;", "'").replace("&quot;", '"').split())


def squeeze(text: str) -> str:
    """Letters and digits only: markup (code spans, links, line breaks) put aside."""
    return re.sub(r"[^a-z0-9]", "", text.lower())


def test_the_site_builds_without_warnings_and_holds_every_page(site):
    pages = {p.relative_to(REPO / "docs").with_suffix(".html")
             for p in (REPO / "docs").rglob("*.md") if "_build" not in p.parts}
    missing = sorted(str(p) for p in pages if not (site / p).is_file())
    assert missing == []
    # the toctree names every page, glob included: a page added under docs/ is in the navigation
    index = (site / "index.html").read_text(encoding="utf-8")
    unlisted = sorted(str(p) for p in pages if str(p) != "index.html" and f'href="{p.as_posix()}"' not in index)
    assert unlisted == []


def test_the_api_reference_is_made_of_the_docstrings(site):
    import rockslide.api as api

    html = (site / "api.html").read_text(encoding="utf-8")
    letters = squeeze(text_of(site / "api.html"))
    for name in api.__all__:
        assert f'id="rockslide.api.{name}"' in html, name
        summary = getattr(api, name).__doc__.strip().split("\n\n")[0]    # the docstring's first paragraph
        assert squeeze(summary) in letters, (name, summary)


def test_the_command_reference_is_made_of_the_help(site):
    from rockslide.cli import main

    text = text_of(site / "guide" / "commands.html")
    for name, command in main.commands.items():
        assert f"rockslide {name}" in text, name
        for option in command.params:
            for flag in option.opts:
                if flag.startswith("--"):
                    assert flag in text, (name, flag)       # two hyphens, not a typographic dash
