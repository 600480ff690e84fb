"""One conductor per study (issue 38): the command line is a thin client of the Python API, a store
knows its plan, the library speaks of its arguments, records are read once."""

from __future__ import annotations

import inspect
import statistics
import sys

import numpy as np
import pytest
from conftest import REPO, invoke, one_line_error

import rockslide
from rockslide.engine.chunks import ChunkStore, MemoryStore
from rockslide.errors import CaseError, RockslideError


def test_the_command_line_may_not_import_the_inner_layers():
    """A forbidden contract in pyproject.toml keeps `rockslide.cli` off `core`, `engine` and
    `analyses` (checked by `test_docs_and_architecture.test_import_contracts_hold`); here: it is
    there, and no module of the command line names them, at any level of the code."""
    text = " ".join((REPO / "pyproject.toml").read_text().split())
    assert ('source_modules = ["rockslide.cli"] forbidden_modules = ["rockslide.core", "rockslide.engine", '
            '"rockslide.analyses"]') in text
    for path in (REPO / "rockslide" / "cli").glob("*.py"):
        text = path.read_text()
        for inner in ("core", "engine", "analyses"):
            assert f"from ..{inner}" not in text and f"rockslide.{inner}" not in text, (path.name, inner)


def test_commands_are_short():
    """Each command parses, calls the API and prints: a median of at most 30 lines, none over 60
    (the function with its docstring, blank lines not counted)."""
    from rockslide.cli import main

    lengths = {}
    for name, command in main.commands.items():
        source = inspect.getsource(command.callback).splitlines()
        start = next(i for i, line in enumerate(source) if line.startswith("def "))
        lengths[name] = sum(1 for line in source[start:] if line.strip())
    assert statistics.median(lengths.values()) <= 30, lengths
    assert max(lengths.values()) <= 60, lengths


def test_a_store_made_for_one_grid_refuses_another(tmp_path, example):
    """`rockslide.sweep(..., store=ChunkStore(folder, key))` with the key of an earlier grid used to
    return that grid's numbers for a new one: it is now one line naming the store."""
    first = rockslide.sweep(example, mu="0.3,0.5", pga="300gal", store=ChunkStore(tmp_path / "chunks"))
    keyed = ChunkStore(tmp_path / "chunks", first.attrs["sweep_key"])
    with pytest.raises(CaseError, match="another study") as caught:
        rockslide.sweep(example, mu="0.4,0.6", pga="300gal", store=keyed)
    assert caught.value.source == "store"
    memory = MemoryStore()
    rockslide.sweep(example, mu="0.3,0.5", pga="300gal", store=memory)
    with pytest.raises(CaseError, match="another study"):
        rockslide.sweep(example, mu="0.4,0.6", pga="300gal", store=memory)


def test_a_store_without_a_key_takes_each_grid_its_own(tmp_path, example):
    """The same keyless store for two grids: each gets its own numbers (those of a sweep in memory)."""
    store = ChunkStore(tmp_path / "chunks")
    rockslide.sweep(example, mu="0.3,0.5", pga="700gal", store=store)
    again = rockslide.sweep(example, mu="0.52,0.6", pga="700gal", store=store)
    fresh = rockslide.sweep(example, mu="0.52,0.6", pga="700gal")
    np.testing.assert_array_equal(again.max_rotation.values, fresh.max_rotation.values)


@pytest.mark.parametrize("call", [
    lambda case: rockslide.sweep(case, mu="abc"),
    lambda case: rockslide.ensemble(case, -5),
    lambda case: rockslide.risk(median="0.5 g", beta=-1, hazard={"site": ([1.0, 2.0], [1e-2, 1e-3])}),
    lambda case: rockslide.sweep(case, mu="0.3", workers=2, scheduler="tcp://127.0.0.1:1"),
], ids=["sweep mu", "ensemble n", "risk beta", "workers and scheduler"])
def test_library_errors_name_arguments_not_flags(example, call):
    with pytest.raises(RockslideError) as caught:
        call(example)
    assert "--" not in str(caught.value), str(caught.value)


def test_the_command_line_names_its_flags(ws):
    """The same errors from the command line name the options."""
    (ws / "case.yaml").write_text((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))
    one_line_error(invoke("sweep", "case.yaml", "--mu", "abc"), "--mu", "cannot read 'abc'")
    one_line_error(invoke("run", "case.yaml", "--ensemble", "-5"), "--ensemble")
    one_line_error(invoke("risk", "--median", "0.5g", "--beta", "-1", "--hazard", "h.csv"), "--beta")


_OPENED: list[str] = []
_RECORDING: list[bool] = [False]


def _audit(event, args):
    if _RECORDING[0] and event == "open" and isinstance(args[0], str):
        _OPENED.append(args[0])


def test_a_run_with_its_ensemble_reads_each_record_as_often_as_the_run(ws):
    """``run --ensemble`` used to read every record file twice (the run, then the ensemble's plan):
    counted with Python's audit events for ``open``."""
    (ws / "case.yaml").write_text((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))
    sys.addaudithook(_audit)
    counts = []
    for extra in ([], ["--ensemble", "20"]):
        _OPENED.clear()
        _RECORDING[0] = True
        try:
            result = invoke("run", "case.yaml", "--no-plot", "--overwrite", *extra)
        finally:
            _RECORDING[0] = False
        assert result.exit_code == 0, result.output
        counts.append({name: sum(p.endswith(name) for p in _OPENED)
                       for name in ("synthetic_kt_h.at2", "synthetic_kt_v.at2")})
    assert counts[0] == counts[1], counts
    assert all(n >= 1 for n in counts[0].values()), counts


def test_run_at_another_pga_is_the_case_at_that_pga(ws):
    """``rockslide run CASE --pga 0.6g`` equals the case file with ``pga_horizontal: 0.6 g``, bit for
    bit (issue 42.3)."""
    text = (REPO / "configs" / "example.yaml").read_text().replace("../records/", "")
    (ws / "case.yaml").write_text(text)
    (ws / "edited.yaml").write_text(text.replace("pga_horizontal: 700 gal", "pga_horizontal: 0.6 g"))
    assert invoke("run", "case.yaml", "--pga", "0.6g", "--no-plot", "--out-dir", "a").exit_code == 0
    assert invoke("run", "edited.yaml", "--no-plot", "--out-dir", "b").exit_code == 0
    a, b = rockslide.read_result("a/example.h5"), rockslide.read_result("b/example.h5")
    for column in a.history:
        np.testing.assert_array_equal(a.history[column], b.history[column])
    assert a.summary == b.summary
    assert a.ground == b.ground
