"""What keeps the project understandable: the import layers hold, every command has help with an
example, and the README documents every case key and every command."""

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
def test_readme_lists_every_command(command):
    assert f"rockslide {command}" in README


@pytest.mark.parametrize("key", [path for path, spec in iter_case_keys() if spec.get("type") != "mapping"
                                 and not path.startswith("ground.vertical.")
                                 and not (path.startswith(("ground.horizontal_1.", "ground.horizontal_2."))
                                          and not path.endswith(".azimuth"))])
def test_readme_documents_every_case_key(key):
    assert f"`{key}`" in README


def test_readme_set_up_is_two_commands_that_ci_runs():
    ci = (REPO / ".ci" / "run").read_text()
    for command in ('python -m pip install -e ".[test]"', "python -m pytest"):
        assert command in ci
    assert 'pip install -e ".[test]"' in README and "python -m pytest" in README
