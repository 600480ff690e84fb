"""``--no-plot --overwrite`` and the figure beside a study's result (issue 27): a figure must never
stand beside results it does not show, but rerunning the same study (for its --json, say) must not
delete the figure that still shows them. The rule: with --no-plot, NAME.png is kept only when the
result it was published with holds the same results as the new one (`results.same_results`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import invoke

from rockslide.core import batch
from rockslide.io import results

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "example.yaml"
SUITE = REPO / "records" / "suite-synthetic.yaml"
RECORDS = REPO / "records"


@pytest.fixture(scope="module", autouse=True)
def compiled():
    batch.warm_up()


def sweep(out, *axes, extra=()):
    result = invoke("sweep", EXAMPLE, *axes, "--records-dir", RECORDS, "--out-dir", out, "--no-progress", *extra)
    assert result.exit_code == 0, (result.output, result.exception)
    return result


def test_the_same_sweep_again_without_plot_keeps_its_figure(tmp_path):
    sweep(tmp_path, "--mu", "0.5,0.6", "--pga", "600gal")
    png = tmp_path / "example.sweep.png"
    drawn = png.read_bytes()
    sweep(tmp_path, "--mu", "0.5,0.6", "--pga", "600gal", extra=["--no-plot", "--overwrite"])
    assert png.read_bytes() == drawn


def test_another_sweep_without_plot_removes_the_figure_it_does_not_show(tmp_path):
    sweep(tmp_path, "--mu", "0.5,0.6", "--pga", "600gal")
    sweep(tmp_path, "--mu", "0.5,0.6", "--pga", "700gal", extra=["--no-plot", "--overwrite"])
    assert not (tmp_path / "example.sweep.png").exists()
    assert (tmp_path / "example.sweep.h5").exists()


def test_the_same_fragility_for_its_json_keeps_its_figure_another_does_not(tmp_path):
    def fragility(levels, *extra):
        result = invoke("fragility", EXAMPLE, "--suite", SUITE, "--levels", levels, "--bootstrap", "20",
                        "--out-dir", tmp_path, "--no-progress", *extra)
        assert result.exit_code == 0, (result.output, result.exception)
        return result

    fragility("0.6g,1.2g")
    png = tmp_path / "example.fragility.png"
    drawn = png.read_bytes()
    again = fragility("0.6g,1.2g", "--json", "--no-plot", "--overwrite")
    assert png.read_bytes() == drawn
    assert json.loads(again.stdout)["files"]["png"] is None          # this run drew nothing
    fragility("0.6g,1.4g", "--no-plot", "--overwrite")
    assert not png.exists()


def _stored(coords, variables, attrs):
    return results.StoredDataset(coords=coords, variables=variables, attrs=attrs)


def test_same_results_ignores_only_the_writing():
    coords = [("level", np.array([1.0, 2.0]), {"units": "m/s^2"})]
    variables = {"p": (("level",), np.array([0.1, np.nan]), {"units": "1"})}
    a = _stored(coords, variables, {"created": "2026-01-01", "command_line": "a", "numpy_version": "1", "key": "k"})
    b = _stored(coords, variables, {"created": "2026-02-02", "command_line": "b", "numpy_version": "2", "key": "k"})
    assert results.same_results(a, b)                                # NaN equals NaN, provenance ignored
    changed = {"p": (("level",), np.array([0.1, 0.2]), {"units": "1"})}
    assert not results.same_results(a, _stored(coords, changed, a.attrs))
    assert not results.same_results(a, _stored(coords, variables, {**a.attrs, "key": "other"}))
    moved = [("level", np.array([1.0, 3.0]), {"units": "m/s^2"})]
    assert not results.same_results(a, _stored(moved, variables, a.attrs))
