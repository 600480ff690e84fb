"""`rockslide sweep`: axes, the grid against single runs, the result file, resuming, dask, Ctrl-C.

Offline: every sweep runs the shipped example case (`configs/example.yaml`) on the synthetic records
in `records/`, on small grids.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import invoke, one_line_error, sweep_args, variables_equal

from rockslide.analyses import sweep as sw
from rockslide.case import case_to_dict, case_with, load_case
from rockslide.core import batch
from rockslide.core import kernel as K
from rockslide.engine import chunks
from rockslide.engine import execute as ex
from rockslide.engine import plan as engine_plan
from rockslide.engine import prepare as runner
from rockslide.errors import CaseError
from rockslide.io import results
from rockslide.plots import SWEEP_CATEGORIES, sweep_category, sweep_figure
from rockslide.units import parse_quantity

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "example.yaml"
EXAMPLE_TEXT = EXAMPLE.read_text().replace("../records/", "")   # copies find the records via --records-dir
RECORDS = REPO / "records"
SUMMARY_FIELDS = ("overturned", "overturn_time", "direction", "max_rotation", "max_slip",
                  "residual_slip", "impacts", "alpha", "max_rotation_ratio")


@pytest.fixture(scope="module", autouse=True)
def compiled():
    """Compile (or load) both batch drivers once, before any subprocess needs them."""
    batch.warm_up()


# --------------------------------------------------------------------------------------------------
# Axes
# --------------------------------------------------------------------------------------------------


def test_range_is_decimal_and_includes_the_stop():
    axis = sw.parse_axis("mu", "0.30:0.70:0.01")
    assert len(axis) == 41
    assert axis.values[7] == 0.37 and axis.values[0] == 0.3 and axis.values[-1] == 0.7
    assert axis.values == tuple(float(f"{0.30 + i / 100:.2f}") for i in range(41))
    assert sw.parse_axis("mu", "0:1:0.3").values == (0.0, 0.3, 0.6, 0.9)       # stop off the grid
    # the stop is on the grid within 1e-9 of a step: included, exactly
    assert sw.parse_axis("mu", "0:1:0.3333333333").values[-1] == 1.0
    assert len(sw.parse_axis("mu", "0:1:0.3333333333")) == 4
    assert sw.parse_axis("mu", "0.5:0.5:0.1").values == (0.5,)
    assert sw.parse_axis("mu", "5e-1:6e-1:5e-2").values == (0.5, 0.55, 0.6)


def test_units_as_in_case_files():
    axis = sw.parse_axis("pga", "100gal:1000gal:25gal")
    assert len(axis) == 37
    assert axis.values == tuple(parse_quantity(f"{g} gal", "acceleration") for g in range(100, 1001, 25))
    assert axis.texts[1] == "125gal"
    assert sw.parse_axis("pga", "0.5 g, 800 gal, 700gal").values == (0.5 * 9.80665, 8.0, 7.0)
    assert sw.parse_axis("pga", "5m/s^2, 8m/s^2").values == (5.0, 8.0)
    assert sw.parse_axis("pga", "1 m/s^2 : 3 m/s^2 : 1 m/s^2").values == (1.0, 2.0, 3.0)
    assert sw.parse_axis("gravity", "9.8 m/s^2, 1g").values == (9.8, 9.80665)
    assert sw.parse_axis("restitution", "0.7, 0.8").values == (0.7, 0.8)


@pytest.mark.parametrize("option, spec, expected", [
    ("mu", "0.3:0.5", "start:stop:step"),
    ("mu", "0.5:0.3:0.1", "stop is below the start"),
    ("mu", "0.3:0.5:0", "step must be positive"),
    ("mu", "0.3:0.5:-0.1", "step must be positive"),
    ("mu", "abc", "cannot read 'abc'"),
    ("mu", "0.3,,0.5", "cannot read ''"),
    ("mu", "", "empty"),
    ("mu", "0.5 gal", "unit"),
    ("mu", "0.5,0.5", "repeats"),
    ("pga", "100gal:1000:25gal", "one unit"),
    ("pga", "3, 500gal", "give a unit on every value, got"),
    ("pga", "5, 8", "5 has no unit (an acceleration needs one): '5 g' is 49.03 m/s^2"),
    ("pga", "100:1000:25", "100 has no unit"),
    ("gravity", "9.8", "'9.8 m/s^2' is 0.9993 g"),
    ("pga", "100 furlong", "unknown acceleration unit"),
    ("mu", "0:1000:0.0001", "at most"),
])
def test_bad_axis_specs_are_one_line_errors_naming_the_option(option, spec, expected, tmp_path):
    with pytest.raises(CaseError) as info:
        sw.parse_axis(option, spec)
    assert option in str(info.value) and expected in str(info.value) and "--" not in str(info.value)
    flag = "--" + option.replace("_", "-")
    one_line_error(invoke(*sweep_args(tmp_path, flag, spec)), flag, expected)
    assert not tmp_path.exists() or not any(tmp_path.iterdir())


@pytest.mark.parametrize("axes, parts", [
    (["--mu", "-0.1,0.5"], ["--mu", "contact.mu_static", "mu -0.1"]),
    (["--restitution", "0.8,1.2"], ["--restitution", "contact.restitution", "1.2"]),
    (["--height-to-width", "0,2"], ["--height-to-width", "block.width"]),
    (["--slenderness", "0.25"], ["--slenderness", "was width / height", "--height-to-width 4"]),
    (["--gravity", "-9.8m/s^2"], ["--gravity", "gravity"]),
    ([], ["give at least one axis"]),
    (["--mu", "0.5", "--mu-kinetic-ratio", "1.5"], ["--mu-kinetic-ratio", "[0, 1]"]),
    (["--pga", "7m/s^2", "--mu-kinetic-ratio", "0.9"], ["--mu-kinetic-ratio", "mu"]),
    (["--mu", "0.5", "--workers", "0"], ["--workers"]),
    (["--mu", "0.5", "--workers", "1", "--scheduler", "tcp://127.0.0.1:1"], ["--workers", "scheduler"]),
    (["--mu", "0.5", "--chunk-size", "0"], ["--chunk-size"]),
])
def test_bad_points_and_options_are_one_line_errors(axes, parts, tmp_path):
    one_line_error(invoke(*sweep_args(tmp_path, *axes)), *parts)
    assert not (tmp_path / "example.sweep.h5").exists()


def test_vertical_factor_with_pga_vertical_names_the_option(tmp_path):
    case = tmp_path / "v.yaml"
    case.write_text(EXAMPLE_TEXT.replace("vertical_factor: 1.0", "pga_vertical: 300 gal"))
    result = invoke("sweep", case, "--vertical-factor", "0.5,1", "--records-dir", RECORDS,
                    "--out-dir", tmp_path, "--no-progress")
    one_line_error(result, "--vertical-factor", "exclusive")


def _points_validated_in_full(case, axes, ratio):
    """Every point through `case_with` with all its changes (what `sw._points` shortens)."""
    import itertools
    for combo in itertools.product(*(range(len(a)) for a in axes)):
        changes = {}
        for axis, j in zip(axes, combo, strict=True):
            changes.update(sw.axis_changes(axis.name, axis.values[j], case, ratio))
        try:
            point = case_with(case, changes)
            runner.check_parameters(point)
        except CaseError as exc:
            yield combo, exc
            return
        yield combo, point


@pytest.mark.parametrize("specs, bad_field", [
    ([("mu", "0.3,0.52,0.7"), ("restitution", "0,0.8,1"), ("pga", "300gal,700gal"),
      ("vertical_factor", "0,0.5"), ("height_to_width", "2,4"), ("gravity", "9.8m/s^2,1.62m/s^2")], None),
    ([("restitution", "0.5,1"), ("mu", "0.4,-0.1")], "contact.mu_static"),   # the second point
    ([("pga", "500gal"), ("height_to_width", "2,1e12")], "block.width"),      # below the length range
])
def test_points_validated_per_section_equal_points_validated_in_full(example, specs, bad_field):
    """`_points` validates each section's changes once: the points, and the first bad point with
    its field, are those of validating every point in full."""
    axes = [sw.parse_axis(name, spec) for name, spec in specs]
    ratio = sw.kinetic_ratio(example, None)
    expected = list(_points_validated_in_full(example, axes, ratio))
    got = []
    try:
        for _, combo, point in sw._points(example, axes, ratio):
            got.append((combo, point))
    except CaseError as exc:
        got.append((None, exc))
    assert len(got) == len(expected)
    assert (expected[-1][1].field if isinstance(expected[-1][1], CaseError) else None) == bad_field
    for (combo, point), (combo_full, full) in zip(got, expected, strict=True):
        if isinstance(full, CaseError):
            assert isinstance(point, CaseError) and point.field == full.field
            assert sw._point_text(axes, combo_full) in str(point)
        else:
            assert combo == combo_full and case_to_dict(point) == case_to_dict(full)


def test_mu_kinetic_follows_the_case_ratio(example):
    assert sw.kinetic_ratio(example, None) == 0.95
    odd = case_with(example, {"contact.mu_static": 0.55, "contact.mu_kinetic": 0.5225})
    assert 0.5225 / 0.55 != 0.95 and sw.kinetic_ratio(odd, None) == 0.95   # rounded to 12 digits
    plan = sw.plan_sweep(example, [sw.parse_axis("mu", "0.4,0.6")], records_dir=RECORDS)
    assert plan.case_column(K.P_MU).tolist() == [0.4, 0.6]
    assert plan.case_column(K.P_NU).tolist() == [0.95 * 0.4, 0.95 * 0.6]
    plan = sw.plan_sweep(example, [sw.parse_axis("mu", "0.4,0.6")], records_dir=RECORDS,
                         mu_kinetic_ratio=1.0)
    assert plan.case_column(K.P_NU).tolist() == [0.4, 0.6]


def test_pga_replaces_a_factor_and_keeps_a_given_vertical_peak(tmp_path):
    with_factor = tmp_path / "f.yaml"
    with_factor.write_text(EXAMPLE_TEXT.replace("pga_horizontal: 700 gal", "factor: 1.5"))
    plan = sw.plan_sweep(load_case(with_factor), [sw.parse_axis("pga", "500gal,700gal")],
                         records_dir=RECORDS)
    ratio = plan.factor_v / plan.factor_h                    # the record's V/H ratio kept
    assert plan.factor_h[1] / plan.factor_h[0] == pytest.approx(7 / 5) and ratio[0] == ratio[1]
    with_vertical = tmp_path / "v.yaml"
    with_vertical.write_text(EXAMPLE_TEXT.replace("vertical_factor: 1.0", "pga_vertical: 300 gal"))
    plan = sw.plan_sweep(load_case(with_vertical), [sw.parse_axis("pga", "500gal,700gal")],
                         records_dir=RECORDS)
    assert plan.factor_v[0] == plan.factor_v[1] and plan.factor_h[0] < plan.factor_h[1]


# --------------------------------------------------------------------------------------------------
# The grid equals single runs
# --------------------------------------------------------------------------------------------------


def point_case(example, plan, index):
    """The case file of one grid point, as a user would write it for `rockslide run`."""
    combo = np.unravel_index(index, plan.shape)
    changes = {}
    for axis, i in zip(plan.axes, combo, strict=True):
        changes.update(sw.axis_changes(axis.name, axis.values[i], example, plan.mu_kinetic_ratio))
    return case_with(example, changes)


def assert_point_equals_run(plan, variables, index, summary):
    combo = np.unravel_index(index, plan.shape)
    for name in SUMMARY_FIELDS:
        value = variables[name][0][combo]
        expected = getattr(summary, name)
        if expected is None:
            expected = math.nan if name == "overturn_time" else 0
        if isinstance(expected, float) and math.isnan(expected):
            assert math.isnan(value), name
        else:
            assert value == pytest.approx(float(expected), rel=1e-12, abs=0.0), name
    assert K.STATUS_NAMES[variables["status"][0][combo]] == summary.status


@pytest.fixture(scope="module")
def mixed(example):
    """A 4-D grid over friction, intensity, restitution and height / width, computed."""
    axes = [sw.parse_axis("mu", "0.45,0.6"), sw.parse_axis("pga", "500gal,750gal,900gal"),
            sw.parse_axis("restitution", "0.7,0.9"), sw.parse_axis("height_to_width", "2,2.2")]
    plan = sw.plan_sweep(example, axes, records_dir=RECORDS, chunk_size=5)
    states = batch.compute(plan.case_params(), plan.case_states(), plan.base, 0, plan.base.shape[1], plan.factor_h,
                           plan.factor_v)
    return plan, sw.sweep_variables(plan, states)


def test_grid_points_equal_single_runs(example, mixed):
    plan, variables = mixed
    cats = sw.categories(variables)
    # several points, and one of each category that occurs
    picks = {0, plan.n_cases - 1, 7, 13}
    picks |= {int(np.flatnonzero(cats.ravel() == c)[0]) for c in np.unique(cats)}
    assert {1, 4} <= set(np.unique(cats))            # slip and overturned occur
    for index in sorted(picks):
        _, result = runner.run_case(point_case(example, plan, index), RECORDS, history=False)
        assert_point_equals_run(plan, variables, index, result.summary)


def test_the_chunks_key_names_the_format_of_the_file():
    assert (engine_plan.FORMAT, engine_plan.FORMAT_VERSION) == (results.SWEEP_FORMAT, results.SWEEP_FORMAT_VERSION)


def test_the_free_space_asked_for_counts_every_variable(mixed):
    """`sweep.bytes_needed` asks for `RESULT_BYTES_PER_CASE` per case of the result file: the bytes
    of the variables `sweep_variables` writes (it once counted 81 of 98)."""
    plan, variables = mixed
    assert sum(values.itemsize for values, _ in variables.values()) == engine_plan.RESULT_BYTES_PER_CASE


@pytest.mark.parametrize("axes", [["--vertical-factor", "0,0.6"], ["--gravity", "9.7m/s^2,9.80665m/s^2"]])
def test_vertical_factor_and_gravity_points_equal_rockslide_run(example, axes, tmp_path):
    """Through the command line both ways: `rockslide sweep` and `rockslide run` on a case file
    written with the point's values."""
    result = invoke(*sweep_args(tmp_path, "--mu", "0.52", "--pga", "800gal", *axes, extra=["--no-plot"]))
    assert result.exit_code == 0, result.output
    stored = results.read_sweep(tmp_path / "example.sweep.h5")
    variables = stored.variables
    plan = sw.plan_sweep(example, [sw.parse_axis("mu", "0.52"), sw.parse_axis("pga", "800gal"),
                                   sw.parse_axis(axes[0][2:].replace("-", "_"), axes[1])],
                         records_dir=RECORDS)
    for index in range(plan.n_cases):
        point = point_case(example, plan, index)
        folder = tmp_path / f"p{index}"
        folder.mkdir()
        data = case_to_dict(point, case_file=True)
        data["name"] = f"p{index}"
        (folder / "p.yaml").write_text(yaml.safe_dump(data))
        run = invoke("run", folder / "p.yaml", "--records-dir", RECORDS, "--out-dir", folder, "--no-plot")
        assert run.exit_code == 0, run.output
        summary = results.read_result(folder / f"p{index}.h5").result.summary
        assert_point_equals_run(plan, variables, index, summary)


def test_a_pool_of_threads_gives_the_batch_result(mixed, tmp_path):
    """The sweep's threads (each taking the next chunk when it is done) give the final states of
    one batch call, bit for bit, whatever order the chunks finish in."""
    plan, _ = mixed
    direct = batch.compute(plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
                           plan.factor_v)
    store = chunks.ChunkStore(tmp_path / "chunks", plan.key)
    ex.compute(plan, store, range(plan.n_chunks), workers=3)
    assert np.array_equal(chunks.collect(plan, store), direct, equal_nan=True)


def test_a_failure_in_one_thread_is_raised_once_the_others_are_done(mixed):
    """A chunk that fails on one of the threads (here its store cannot save it) is raised where the
    sweep waits, after the other threads have stopped; the chunks finished are kept, and no thread
    of the pool is left running."""
    import threading

    plan, _ = mixed

    class FailingStore(chunks.MemoryStore):
        def save(self, chunk, indices, states):
            if chunk == 2:
                raise OSError("disk full")
            super().save(chunk, indices, states)

    store = FailingStore(plan.key)
    before = threading.active_count()
    with pytest.raises(OSError, match="disk full"):
        ex.compute(plan, store, range(plan.n_chunks), workers=3)
    assert threading.active_count() == before
    # chunks 0 and 1 are taken before chunk 2 and finished whatever happens after; chunk 2 never is
    assert plan.n_chunks == 5 and 2 <= store.count() <= 4 and 2 not in store._chunks
    assert not any(t.name.startswith("rockslide-sweep") for t in threading.enumerate())


# --------------------------------------------------------------------------------------------------
# The result file and the maps
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    """An uninterrupted CLI sweep: (folder, stdout)."""
    out = tmp_path_factory.mktemp("swept")
    result = invoke(*sweep_args(out, "--mu", "0.3:0.7:0.1", "--pga", "300gal:900gal:150gal"))
    assert result.exit_code == 0, (result.output, result.exception)
    return out, result.stdout


def test_xarray_opens_a_labelled_dataset(swept):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    out, _ = swept
    with xr.open_dataset(out / "example.sweep.h5", engine="h5netcdf") as ds:
        assert list(ds.sizes) == ["mu", "pga"] and dict(ds.sizes) == {"mu": 5, "pga": 5}
        assert ds["mu"].values.tolist() == [0.3, 0.4, 0.5, 0.6, 0.7]
        assert ds["pga"].values.tolist() == [3.0, 4.5, 6.0, 7.5, 9.0]
        assert ds["pga"].attrs["units"] == "m/s^2" and ds["mu"].attrs["units"] == "1"
        assert ds["pga"].attrs["long_name"] == "peak horizontal ground acceleration"
        for name, units in (("overturned", "1"), ("overturn_time", "s"), ("direction", "1"),
                            ("max_rotation", "rad"), ("max_slip", "m"), ("residual_slip", "m"),
                            ("impacts", "1"), ("status", "1"), ("modes", "1"), ("alpha", "rad"),
                            ("max_rotation_ratio", "1")):
            assert ds[name].dims == ("mu", "pga"), name
            assert ds[name].attrs["units"] == units and ds[name].attrs["long_name"], name
        assert ds["overturned"].dtype == np.int8 and ds["direction"].dtype == np.int8
        assert ds["impacts"].dtype == np.int32 and ds["modes"].dtype == np.int8
        assert ds["status"].attrs["flag_meanings"] == "ok flight painleve chatter"
        assert ds["status"].attrs["flag_values"].tolist() == [0, 1, 2, 3]
        assert ds["modes"].attrs["flag_masks"].tolist() == [1, 2, 4]
        over = ds["overturned"].values.astype(bool)
        assert over.any() and not over.all()
        assert np.isnan(ds["overturn_time"].values[~over]).all()
        assert (ds["overturn_time"].values[over] > 0).all()
        assert set(np.unique(ds["direction"].values[over])) <= {-1, 1}
        assert (ds["direction"].values[~over] == 0).all()
        assert (ds["modes"].values[over] & 2).all()           # overturning needs liftoff
        point = ds.sel(mu=0.3, pga=9.0)
        assert int(point["overturned"]) == 0 and float(point["max_slip"]) > 0
        assert "mu_static: 0.52" in ds.attrs["case_text"]
        assert ds.attrs["command_line"].startswith("rockslide sweep ")
        assert "--mu 0.3:0.7:0.1 --pga 300gal:900gal:150gal" in ds.attrs["command_line"]
        assert ds.attrs["format"] == "rockslide-sweep"


def test_png_maps_are_written_and_the_chunks_removed(swept):
    out, stdout = swept
    png = out / "example.sweep.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "5 mu x 5 pga = 25 cases" in stdout and "reused" not in stdout
    assert sorted(p.name for p in out.iterdir()) == ["example.sweep.h5", "example.sweep.png"]


def test_sweep_figures_for_one_two_and_more_axes():
    rng = np.random.default_rng(3)
    for shape in [(5,), (4, 3), (3, 4, 6), (2, 3, 2, 2)]:
        cat = rng.integers(0, len(SWEEP_CATEGORIES), size=shape)
        rot = np.where(cat == 0, 0.0, rng.random(shape))
        axes = [(f"axis {i}", np.arange(n, dtype=float)[::-1]) for i, n in enumerate(shape)]
        fig = sweep_figure(axes, cat, rot, rng.normal(size=shape) * 1e-3, title="t")
        rows = 1 if len(shape) <= 2 else min(shape[2], 4)
        maps = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
        assert len(maps) == (3 if len(shape) == 1 else 3 * rows)
        if len(shape) == 4:
            assert "first value" in fig._suptitle.get_text()


def test_sweep_category_precedence():
    overturned = np.array([0, 0, 0, 0, 1, 1, 0])
    status = np.array([0, 0, 0, 0, 0, 2, 1])
    modes = np.array([0, 1, 3, 7, 6, 6, 1])
    assert sweep_category(overturned, status, modes).tolist() == [0, 1, 2, 3, 4, 5, 5]


def test_existing_result_is_refused_before_computing(swept, tmp_path):
    out, _ = swept
    before = (out / "example.sweep.h5").read_bytes()
    result = invoke(*sweep_args(out, "--mu", "0.3,0.4"))
    one_line_error(result, "example.sweep.h5 exists", "--overwrite")
    assert (out / "example.sweep.h5").read_bytes() == before
    assert not any(p.name.startswith(".") for p in out.iterdir())      # no chunk folder made
    # the PNG alone is refused too; --overwrite replaces both
    (tmp_path / "example.sweep.png").write_bytes(b"x")
    one_line_error(invoke(*sweep_args(tmp_path, "--mu", "0.3,0.4")), "example.sweep.png exists")
    result = invoke(*sweep_args(tmp_path, "--mu", "0.3,0.4", extra=["--overwrite"]))
    assert result.exit_code == 0, result.output
    assert results.read_sweep(tmp_path / "example.sweep.h5").coords[0][1].tolist() == [0.3, 0.4]


def test_read_sweep_round_trip(swept):
    out, _ = swept
    stored = results.read_sweep(out / "example.sweep.h5")
    assert [c[0] for c in stored.coords] == ["mu", "pga"]
    assert stored.variables["overturned"][0].shape == (5, 5)
    assert stored.attrs["name"] == "example" and stored.attrs["axes"] == "mu pga"


# --------------------------------------------------------------------------------------------------
# Chunks: keys, resuming, interruption
# --------------------------------------------------------------------------------------------------


def test_definition_key_depends_on_what_defines_the_results(example, tmp_path):
    def key(case=example, mu="0.4,0.6", ratio=None, chunk=None):
        axes = [sw.parse_axis("mu", mu), sw.parse_axis("pga", "600gal,700gal")]
        return sw.plan_sweep(case, axes, records_dir=RECORDS, mu_kinetic_ratio=ratio,
                             chunk_size=chunk).key

    base = key()
    assert key() == base
    assert key(mu="0.4,0.61") != base
    assert key(ratio=0.9) != base
    assert key(chunk=1) != base
    changed = tmp_path / "example.yaml"
    changed.write_text(EXAMPLE_TEXT.replace("tail: 2 s", "tail: 2.5 s"))
    assert key(case=load_case(changed)) != base


def test_chunks_of_another_definition_are_not_used(example, tmp_path):
    plan = sw.plan_sweep(example, [sw.parse_axis("mu", "0.4,0.5,0.6"), sw.parse_axis("pga", "700gal")],
                         records_dir=RECORDS, chunk_size=1)
    store = chunks.ChunkStore.beside(tmp_path / "example.sweep.h5", plan.key)
    ex.compute(plan, store, [0, 1])
    assert chunks.missing_chunks(plan, store) == [2]
    # the same command resumes ...
    result = invoke(*sweep_args(tmp_path, "--mu", "0.4,0.5,0.6", "--pga", "700gal",
                                extra=["--chunk-size", "1", "--no-plot"]))
    assert result.exit_code == 0, result.output
    assert "reused 2 of 3 chunks (2 cases)" in result.stdout
    assert not (tmp_path / ".example.sweep.chunks").exists()
    # ... another definition does not
    (tmp_path / "example.sweep.h5").unlink()
    ex.compute(plan, store, [0, 1])
    result = invoke(*sweep_args(tmp_path, "--mu", "0.4,0.5,0.65", "--pga", "700gal",
                                extra=["--chunk-size", "1", "--no-plot"]))
    assert result.exit_code == 0, result.output
    assert "reused" not in result.stdout and "another sweep definition" in result.stdout
    assert store.count() == 2                    # left alone
    # a damaged chunk file counts as missing
    store.path(0).write_bytes(b"not a chunk")
    assert chunks.missing_chunks(plan, store) == [0, 2]


def start_sweep(out: Path, *extra) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))}
    args = [sys.executable, "-m", "rockslide.cli", *map(str, sweep_args(out, *SLOW_GRID)),
            "--workers", "1", "--chunk-size", "8", *extra]
    return subprocess.Popen(args, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))   # not inherited SIG_IGN


# 400 long-rocking cases (e = 0.95): about two seconds on one thread, in 50 chunks of 8.
SLOW_GRID = ("--mu", "0.60:0.90:0.02", "--pga", "450gal:930gal:20gal", "--restitution", "0.95")


def wait_for_chunk(proc: subprocess.Popen, out: Path, timeout: float = 600.0) -> None:
    """Wait until the first chunk file of the sweep in ``out`` exists."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if list(out.glob(".example.sweep.chunks/*/chunk-*.npz")):
            return
        if proc.poll() is not None:
            pytest.fail(f"the sweep ended before its first chunk: {proc.communicate()}")
        time.sleep(0.01)
    proc.kill()
    pytest.fail("no chunk file appeared")


@pytest.fixture(scope="module")
def slow_reference(tmp_path_factory):
    """The slow grid computed without interruption."""
    out = tmp_path_factory.mktemp("reference")
    result = invoke(*sweep_args(out, *SLOW_GRID, extra=["--chunk-size", "8", "--no-plot"]))
    assert result.exit_code == 0, result.output
    return out / "example.sweep.h5"


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL is POSIX-only")
def test_a_killed_sweep_resumes_and_gives_the_same_result(tmp_path, slow_reference):
    proc = start_sweep(tmp_path, "--no-plot")
    wait_for_chunk(proc, tmp_path)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    assert not (tmp_path / "example.sweep.h5").exists()
    kept = list(tmp_path.glob(".example.sweep.chunks/*/chunk-*.npz"))
    assert kept
    result = invoke(*sweep_args(tmp_path, *SLOW_GRID, extra=["--chunk-size", "8", "--no-plot"]))
    assert result.exit_code == 0, result.output
    reused = int(result.stdout.split("reused ")[1].split(" of ")[0])
    assert reused >= len(kept) >= 1
    variables_equal(tmp_path / "example.sweep.h5", slow_reference)
    assert not (tmp_path / ".example.sweep.chunks").exists()


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX-only")
@pytest.mark.parametrize("signum, code, word", [(signal.SIGINT, 130, "interrupted"),
                                                (signal.SIGTERM, 143, "terminated")], ids=["ctrl-c", "sigterm"])
def test_ctrl_c_keeps_the_chunks_and_writes_no_result(tmp_path, signum, code, word):
    proc = start_sweep(tmp_path, "--no-plot")
    wait_for_chunk(proc, tmp_path)
    proc.send_signal(signum)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the sweep did not stop on the signal")
    assert proc.returncode == code, (out, err)
    lines = [line for line in err.splitlines() if not line.startswith("  note: ")]    # what auto would take
    assert len(lines) == 1 and lines[0].startswith(f"rockslide: {word}: "), err
    kept = len(list(tmp_path.glob(".example.sweep.chunks/*/chunk-*.npz")))
    assert f" {kept} of " in lines[0] and "chunks are kept" in lines[0] and "resumes" in lines[0]
    assert kept >= 1
    assert not (tmp_path / "example.sweep.h5").exists()
    assert not list(tmp_path.glob("*.tmp")) and not list(tmp_path.glob(".example.sweep.chunks/*/.*.tmp"))


# --------------------------------------------------------------------------------------------------
# dask.distributed
# --------------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_dask_cluster_on_loopback_gives_the_local_result(tmp_path):
    distributed = pytest.importorskip("distributed")
    axes = ("--mu", "0.4:0.7:0.1", "--pga", "400gal:900gal:100gal")
    local = tmp_path / "local"
    result = invoke(*sweep_args(local, *axes, extra=["--no-plot", "--chunk-size", "5"]))
    assert result.exit_code == 0, result.output
    with distributed.LocalCluster(host="127.0.0.1", n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        remote = tmp_path / "remote"
        result = invoke(*sweep_args(remote, *axes, extra=["--no-plot", "--chunk-size", "5", "--scheduler",
                                                          cluster.scheduler_address]))
        assert result.exit_code == 0, (result.output, result.exception)
    assert "on the dask scheduler tcp://127.0.0.1:" in result.stdout
    variables_equal(local / "example.sweep.h5", remote / "example.sweep.h5")


def test_unreachable_scheduler_is_a_one_line_error(tmp_path):
    pytest.importorskip("distributed")
    result = invoke(*sweep_args(tmp_path, "--mu", "0.5", extra=["--scheduler", "tcp://127.0.0.1:9"]))
    one_line_error(result, "--scheduler", "cannot connect")
    assert not (tmp_path / "example.sweep.h5").exists()


def test_rockslide_plot_redraws_a_sweep_file(swept, tmp_path):
    """`rockslide plot` recognises a sweep file by its format and redraws its maps."""
    out, _ = swept
    source = out / "example.sweep.h5"
    png = tmp_path / "again.png"
    result = invoke("plot", source, "-o", png)
    assert result.exit_code == 0, result.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


@pytest.mark.parametrize("option, value", [("--window", "1:2"), ("--crop", "all"), ("--time-shift", "5 s")])
def test_options_of_result_figures_are_refused_for_a_sweep_file(swept, tmp_path, option, value):
    out, _ = swept
    one_line_error(invoke("plot", out / "example.sweep.h5", option, value, "-o", tmp_path / "x.png"),
                   f"{option}: applies to result files, not to sweep files")
    assert not (tmp_path / "x.png").exists()


def test_a_sweep_of_one_point_says_one_case_and_one_chunk(tmp_path):
    """The printout's counts agree with their nouns at one (the GPU's chunks of a launch make a
    study of a single chunk common)."""
    result = invoke(*sweep_args(tmp_path, "--mu", "0.5", "--pga", "500gal", extra=["--no-plot"]))
    assert result.exit_code == 0, result.output
    assert "= 1 case in 1 chunk, on this machine" in result.stdout
    assert "computed 1 case in " in result.stdout
