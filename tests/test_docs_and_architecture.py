"""What keeps the project understandable: the import layers hold, every command has help with an
example, the documentation (docs/) documents every case key and every command, and the README's
first session runs as written."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import REPO

from rockslide.case import iter_case_keys
from rockslide.cli import main

README = (REPO / "README.md").read_text()
#: import-linter's command, beside this Python's (a virtual environment used without activating it) or on PATH
LINT_IMPORTS = shutil.which("lint-imports", path=str(Path(sys.executable).parent)) or shutil.which("lint-imports")


@pytest.mark.skipif(LINT_IMPORTS is None, reason="import-linter is not installed")
def test_import_contracts_hold():
    """The numerical core imports no outer layer and no I/O library; layers go one way
    (pyproject.toml, [tool.importlinter])."""
    done = subprocess.run([LINT_IMPORTS, "--no-cache"], cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-2000:]


def test_no_package_of_rockslide_imports_itself_in_a_circle():
    """Within each package (the core, the engine, the analyses, the files, the command line), no
    module imports another that imports it back, directly or not, at any level of the code
    (function-level imports count: they are dependencies too)."""
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("rockslide")
    circles = []
    for package in ("rockslide.core", "rockslide.engine", "rockslide.analyses", "rockslide.io", "rockslide.cli"):
        modules = sorted(m for m in graph.modules if m.startswith(package + "."))
        for a in modules:
            for b in graph.find_modules_directly_imported_by(a):
                if b in modules and graph.find_shortest_chain(importer=b, imported=a):
                    circles.append((a, b))
    assert circles == []


def test_the_core_imports_without_io_libraries():
    """At run time too (numba itself loads yaml for its configuration: the baseline)."""
    code = ("import sys; import numba, numpy, scipy.integrate, scipy.optimize; "
            "before = set(sys.modules); "
            "import rockslide.core.simulate, rockslide.core.reference, rockslide.core.criteria, rockslide.core.batch; "
            "new = set(sys.modules) - before; "
            "bad = [m for m in ('yaml', 'h5py', 'obspy', 'matplotlib', 'click', 'dask') if m in new]; "
            "print(','.join(bad))")
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=True)
    assert done.stdout.strip() == ""


@pytest.mark.parametrize("command", sorted(main.commands))
def test_every_command_has_help_with_an_example(command):
    result = CliRunner().invoke(main, [command, "--help"])
    assert result.exit_code == 0
    assert "Example:" in result.output and f"rockslide {command}" in result.output


@pytest.mark.parametrize("command", sorted(main.commands))
def test_the_guide_lists_every_command(command):
    assert f"rockslide {command}" in (REPO / "docs" / "guide" / "commands.md").read_text()


@pytest.mark.parametrize("key", [path for path, spec in iter_case_keys() if spec.get("type") != "mapping"
                                 and not path.startswith("ground.vertical.")
                                 and not (path.startswith(("ground.horizontal_1.", "ground.horizontal_2."))
                                          and not path.endswith(".azimuth"))])
def test_the_guide_documents_every_case_key(key):
    assert f"`{key}`" in (REPO / "docs" / "guide" / "case-file.md").read_text()


def test_readme_set_up_is_two_commands_that_ci_runs():
    ci = (REPO / ".ci" / "run").read_text()
    for command in ('python -m pip install -e ".[test]"', "python -m pytest"):
        assert command in ci
    for command in ('python -m pip install -e ".[test]"', "python -m pytest", "rockslide run configs/example.yaml"):
        assert command in README, command


def test_the_python_the_docs_ask_for_is_the_packages():
    """The README and the getting-started page name the Python the package requires (they said
    3.10 while pyproject.toml required 3.11, for the possessive quantifiers of its parsers)."""
    required = re.search(r'requires-python = ">=(\d+\.\d+)"', (REPO / "pyproject.toml").read_text()).group(1)
    for page in (README, (REPO / "docs" / "guide" / "getting-started.md").read_text()):
        assert re.findall(r"Python (\d+\.\d+) or later", page) == [required]


def first_session() -> tuple[str, list[tuple[str, str]]]:
    """The README's section 'A first session' and its fenced blocks, in order, as (language, text)."""
    section = README.split("\n## A first session\n", 1)[1].split("\n## ", 1)[0]
    return section, re.findall(r"^```(\w*)\n(.*?)^```", section, flags=re.S | re.M)


def without_timings(text: str) -> list[str]:
    """Printed lines with the times a run took put aside (``in 0.51 s``, ``in 0.1 s (1037 runs/s)``)."""
    return [re.sub(r" in [0-9.]+ s( \([0-9.]+ \w+/s\))?", " in T s", line) for line in text.strip().splitlines()]


@pytest.mark.slow
def test_the_readmes_first_session_runs_as_written(tmp_path):
    """Every command of the README's 'A first session', in order, from a folder laid out as the
    repository's root (configs/ and records/ copied), exits 0; a printout the README quotes after a
    command is what the command prints (the time it took aside); the files the section names are
    written; and its Python runs. Without ROCKSLIDE_RECORDS, as a new user has it."""
    section, blocks = first_session()
    assert [language for language, _ in blocks].count("sh") >= 4 and ("python", blocks[-1][1]) in blocks
    for folder in ("configs", "records"):
        shutil.copytree(REPO / folder, tmp_path / folder)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    env.pop("ROCKSLIDE_RECORDS", None)
    printed = None
    compared = 0
    for language, text in blocks:
        if language == "sh":
            for line in filter(None, (line.strip() for line in text.splitlines())):
                # a line of the section's shell blocks that this test would not run has no place there
                assert line.startswith("rockslide "), line
                done = subprocess.run([sys.executable, "-m", "rockslide", *shlex.split(line)[1:]], cwd=tmp_path,
                                      env=env, capture_output=True, text=True, timeout=600)
                assert done.returncode == 0, (line, done.stderr[-3000:])
                printed = done.stdout
        elif language == "python":
            done = subprocess.run([sys.executable, "-c", text], cwd=tmp_path, env=env, capture_output=True,
                                  text=True, timeout=600)
            assert done.returncode == 0, done.stderr[-3000:]
        elif printed is not None:          # a printout quoted right after its command
            assert without_timings(printed) == without_timings(text)
            compared += 1
        printed = None if language != "sh" else printed
    assert compared >= 2
    named = set(re.findall(r"`(out/[\w./-]+\.(?:h5|png|pdf))`", section))
    assert {"out/example.h5", "out/example.png", "out/example.sweep.h5"} <= named
    assert sorted(name for name in named if not (tmp_path / name).is_file()) == []
