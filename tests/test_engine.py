"""One engine behind every analysis: the same case gives the same error, warning or outcome from
``rockslide run``, ``rockslide sweep`` (a one-point grid at the case's own value) and ``rockslide
fragility`` (a suite of the case's own records, scaled to the case's own PGA), because the three
go through one set of checks (`engine.prepare`); and the Python API's results equal the command
line's files bit for bit.

The case is the shipped example with one key changed; its records are copied beside it. A sweep
over ``--mu`` at the case's own mu and a fragility analysis at the case's own PGA compute exactly
the case, so an error or warning that one of them gives and another does not is a check that one
planner makes and another does not (the defect this file guards against).
"""

from __future__ import annotations

import copy
import math
import shutil

import numpy as np
import pytest
import yaml
from conftest import REPO, SHIPPED, cpu_as_device, invoke

import rockslide
from rockslide.io import results

EXAMPLE = yaml.safe_load((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))
MU = EXAMPLE["contact"]["mu_static"]
PGA = EXAMPLE["ground"]["scale"]["pga_horizontal"]          # e.g. "800 gal"
SUITE = {"records": [{"name": "own", "horizontal": SHIPPED[0], "vertical": SHIPPED[1]}]}
# a short run: the checks, not the physics, are what is compared
QUICK = {"ground.tail": "0 s"}


def write_case(folder, changes: dict) -> None:
    data = copy.deepcopy(EXAMPLE)
    for dotted, value in {**QUICK, **changes}.items():
        *parents, leaf = dotted.split(".")
        node = data
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = value
    (folder / "case.yaml").write_text(yaml.safe_dump(data))
    (folder / "suite.yaml").write_text(yaml.safe_dump(SUITE))
    for name in SHIPPED:
        if not (folder / name).exists():
            shutil.copy(REPO / "records" / name, folder / name)


def three_ways(folder, level: str = PGA.replace(" ", "")):
    """``run``, ``sweep`` and ``fragility`` of ``folder/case.yaml``, each into its own folder (the
    fragility analysis at ``level``, by default the case's own PGA)."""
    common = ["--no-plot", "--records-dir", folder]
    return {
        "run": invoke("run", folder / "case.yaml", "--out-dir", folder / "run", *common),
        "sweep": invoke("sweep", folder / "case.yaml", "--mu", str(MU), "--out-dir", folder / "sweep",
                        "--no-progress", *common),
        "fragility": invoke("fragility", folder / "case.yaml", "--suite", folder / "suite.yaml", "--levels", level,
                            "--bootstrap", "0", "--out-dir", folder / "fragility", "--no-progress", *common),
    }


def error_line(result) -> str:
    lines = result.stderr.splitlines()
    assert result.exit_code == 2, (result.exit_code, result.output)
    assert len(lines) == 1 and lines[0].startswith("rockslide: error: "), result.stderr
    return lines[0]


# Bad cases: (changes, the part of the error every command must give: file, key, what is wrong)
BAD = {
    "block-too-small": ({"block.height": "1e-13 m", "block.width": "1e-13 m"},
                        "case.yaml: block.height: 1e-13 m is outside what rockslide computes reliably"),
    "mass-absurd": ({"block.mass": "1e25 kg"}, "case.yaml: block.mass: 1e+25 kg is outside"),
    "gravity-absurd": ({"gravity": "1e5 m/s^2"}, "case.yaml: gravity: 100000 m/s^2 is outside"),
    "rate-absurd": ({"initial.rotation_rate": "1e7 rad/s"}, "case.yaml: initial.rotation_rate: 1e+07 rad/s is"),
    "tail-absurd": ({"ground.tail": "1e12 s"}, "case.yaml: ground.tail: a tail of 1e+12 s adds"),
    "dt-absurdly-small": ({"solver.dt": 1e-300, "output.interval": None},
                          "case.yaml: solver.dt: dt = 1e-300 s gives"),
    "start-too-late": ({"ground.time_shift": "1e7 s"}, "case.yaml: ground.time_shift: the ground motion starts"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_a_bad_case_gives_the_same_error_from_every_analysis(tmp_path, name):
    changes, expected = BAD[name]
    write_case(tmp_path, changes)
    for command, result in three_ways(tmp_path).items():
        line = error_line(result)
        assert expected in line, (command, line)
        assert not any((tmp_path / command).glob("*.h5")), command


# Borderline cases: (changes, the warning every command must give)
WARNED = {
    "step-too-coarse": ({"block.height": "2 cm", "block.width": "1 cm", "solver.dt": "5 ms",
                         "output.interval": "5 ms"},
                        "case.yaml: solver.dt: the step 0.005 s is too coarse for this block"),
    "absurd-acceleration": ({"ground.scale.pga_horizontal": "15 g", "ground.scale.vertical_factor": 0},
                            "case.yaml: ground.scale: the scaled ground motion reaches"),
}


@pytest.mark.parametrize("name", list(WARNED))
def test_a_borderline_case_gives_the_same_warning_from_every_analysis(tmp_path, name):
    changes, expected = WARNED[name]
    write_case(tmp_path, changes)
    results_by_command = three_ways(tmp_path, "15g" if name == "absurd-acceleration" else PGA.replace(" ", ""))
    for command, result in results_by_command.items():
        assert result.exit_code == 0, (command, result.output)
        warned = [line for line in result.stderr.splitlines() if line.startswith("rockslide: warning: ")]
        assert len(warned) == 1 and expected in warned[0], (command, result.stderr)


def test_a_block_that_would_fly_is_a_status_everywhere_with_the_same_warning(tmp_path):
    """A vertical motion that lifts the block off the ground (g + av <= 0) is an outcome, not an
    error: each command warns alike, runs, and records the status 'flight' at the same time."""
    write_case(tmp_path, {"ground.scale.vertical_factor": 5})
    outcome = three_ways(tmp_path)
    for command, result in outcome.items():
        assert result.exit_code == 0, (command, result.output)
        warned = [line for line in result.stderr.splitlines() if line.startswith("rockslide: warning: ")]
        assert len(warned) == 1 and "g + av =" in warned[0] and "'flight'" in warned[0], (command, result.stderr)
    run = results.read_result(tmp_path / "run" / "example.h5").result.summary
    grid = results.read_dataset(tmp_path / "sweep" / "example.sweep.h5", format=results.SWEEP_FORMAT).variables
    frag = results.read_dataset(tmp_path / "fragility" / "example.fragility.h5",
                                format=results.FRAGILITY_FORMAT).variables
    assert run.status == "flight"
    for variables in (grid, frag):
        assert int(np.ravel(variables["status"][1])[0]) == 1            # STATUS_FLIGHT
        assert float(np.ravel(variables["end_time"][1])[0]) == run.end_time


def test_a_notebook_session_equals_the_command_line_bit_for_bit(tmp_path):
    """The documented API only: a case from a mapping, a run, a 2-axis sweep in memory and a
    fragility analysis; every number equals the command line's files exactly."""
    write_case(tmp_path, {})
    data = yaml.safe_load((tmp_path / "case.yaml").read_text())
    case = rockslide.load_case(data, base_dir=tmp_path)
    assert case.to_dict() == rockslide.load_case(tmp_path / "case.yaml").to_dict()

    run = rockslide.run(case, records_dir=tmp_path)
    grid = rockslide.sweep(case, mu="0.3,0.5", pga=["400gal", "800gal"], records_dir=tmp_path)
    curves = rockslide.fragility(case, tmp_path / "suite.yaml", levels="0.2g,0.6g", resamples=0,
                                 records_dir=tmp_path)

    assert invoke("run", tmp_path / "case.yaml", "--out-dir", tmp_path / "cli", "--no-plot").exit_code == 0
    assert invoke("sweep", tmp_path / "case.yaml", "--mu", "0.3,0.5", "--pga", "400gal,800gal", "--out-dir",
                  tmp_path / "cli", "--no-plot", "--no-progress").exit_code == 0
    assert invoke("fragility", tmp_path / "case.yaml", "--suite", tmp_path / "suite.yaml", "--levels", "0.2g,0.6g",
                  "--bootstrap", "0", "--out-dir", tmp_path / "cli", "--no-plot", "--no-progress").exit_code == 0

    stored = rockslide.read_result(tmp_path / "cli" / "example.h5")
    assert stored.summary == run.summary
    for column, values in run.history.items():
        assert np.array_equal(values, stored.history[column]), column
    assert np.array_equal(run.events, stored.events)
    for mine, path in ((grid, "example.sweep.h5"), (curves, "example.fragility.h5")):
        theirs = rockslide.read_result(tmp_path / "cli" / path)
        assert set(mine.data_vars) == set(theirs.data_vars)
        for name in mine.data_vars:
            a, b = mine[name].values, theirs[name].values
            assert a.dtype == b.dtype and a.shape == b.shape, name
            if a.dtype.kind == "f":
                assert np.array_equal(a, b, equal_nan=True), name
            else:
                assert (a == b).all(), name
    assert grid.overturned.dtype == np.int8 and grid.overturned.dims == ("mu", "pga")


def test_one_axis_sweeps_and_fragility_counts_keep_their_integer_types(tmp_path):
    """A sweep over one axis stores its flags as integers (``ds.modes & 2`` works), and a fragility
    file's counts are integers, as written (the file once made them float64)."""
    import xarray as xr

    write_case(tmp_path, {})
    assert invoke("sweep", tmp_path / "case.yaml", "--pga", "400gal,800gal", "--out-dir", tmp_path, "--no-plot",
                  "--no-progress").exit_code == 0
    assert invoke("fragility", tmp_path / "case.yaml", "--suite", tmp_path / "suite.yaml", "--levels", "0.2g,0.6g",
                  "--bootstrap", "0", "--out-dir", tmp_path, "--no-plot", "--no-progress").exit_code == 0
    with xr.open_dataset(tmp_path / "example.sweep.h5", engine="h5netcdf") as ds:
        for name in ("overturned", "modes", "status", "direction", "undecided"):
            assert ds[name].dtype == np.int8, name
        assert ds["impacts"].dtype == np.int32
        assert ((ds.modes & 2) >= 0).all()
    with xr.open_dataset(tmp_path / "example.fragility.h5", engine="h5netcdf") as ds:
        for name in ("n_runs", "n_outside_model", "n_exceeded", "n_censored"):
            assert ds[name].dtype.kind == "i", name


def test_a_run_file_opens_as_a_labelled_dataset(tmp_path):
    """A single run's file opens with xarray's h5netcdf engine: the event log at the root, the
    histories in their group, with their units; and `RunResult.to_xarray` holds the same values."""
    import xarray as xr

    write_case(tmp_path, {})
    assert invoke("run", tmp_path / "case.yaml", "--out-dir", tmp_path, "--no-plot").exit_code == 0
    run = rockslide.read_result(tmp_path / "example.h5")
    with xr.open_dataset(tmp_path / "example.h5", engine="h5netcdf", group="time_history") as ds:
        assert ds.rotation.attrs["units"] == "rad" and ds.time.attrs["units"] == "s"
        assert np.array_equal(ds.rotation.values, run.history["rotation"])
    with xr.open_dataset(tmp_path / "example.h5", engine="h5netcdf") as ds:
        assert ds.sizes["event"] == len(run.events)
        assert ds.attrs["verdict"] == run.summary.verdict
    labelled = run.to_xarray()
    assert np.array_equal(labelled.rotation.values, run.history["rotation"])
    assert labelled.attrs["max_rotation"] == run.summary.max_rotation
    assert math.isfinite(labelled.attrs["max_rotation_ratio"])


def test_a_fragility_without_the_cases_vertical_says_so_and_can_use_it(tmp_path):
    """A suite without vertical records, for a case with one: the console, the JSON and the file say
    that the runs are horizontal only, and ``--case-vertical`` runs the case's vertical record
    scaled with each horizontal one (Kobe-like: the example at its own PGA then equals `run`)."""
    import json

    write_case(tmp_path, {})
    (tmp_path / "suite.yaml").write_text(yaml.safe_dump({"records": [{"name": "own", "horizontal": SHIPPED[0]}]}))
    args = ["fragility", tmp_path / "case.yaml", "--suite", tmp_path / "suite.yaml", "--levels", PGA.replace(" ", ""),
            "--bootstrap", "0", "--no-plot", "--no-progress"]
    plain = invoke(*args, "--out-dir", tmp_path / "h")
    assert plain.exit_code == 0 and "the runs are horizontal only" in plain.output
    as_json = invoke(*args, "--out-dir", tmp_path / "j", "--json")
    assert json.loads(as_json.stdout)["vertical"]["source"] == "none"
    stored = results.read_dataset(tmp_path / "h" / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    assert stored.attrs["vertical_motion"] == "none" and "horizontal only" in stored.attrs["vertical_note"]

    both = invoke(*args, "--out-dir", tmp_path / "v", "--case-vertical")
    assert both.exit_code == 0 and "horizontal only" not in both.output
    stored = results.read_dataset(tmp_path / "v" / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    assert stored.attrs["vertical_motion"] == "case"
    run = rockslide.run(rockslide.load_case(tmp_path / "case.yaml"), records_dir=tmp_path, history=False)
    assert float(np.ravel(stored.variables["max_rotation"][1])[0]) == run.summary.max_rotation


def test_a_vertical_pulse_that_lifts_the_block_is_a_status_with_its_time(tmp_path):
    """A pulse case: the warning gives the time on the result's axis (``ground.time_shift``
    included), and the run and a sweep over the case's own amplitude both end in 'flight' at one
    instant."""
    data = copy.deepcopy(EXAMPLE)
    data["ground"] = {"horizontal": {"pulse": "rectangular", "amplitude": "0.5 g", "duration": "0.2 s"},
                      "vertical": {"pulse": "half-sine", "amplitude": "-1.2 g", "duration": "0.2 s"},
                      "time_shift": "5 s", "tail": "0 s"}
    data["solver"]["dt"] = "1 ms"
    data.pop("output", None)
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(data))
    run = invoke("run", tmp_path / "case.yaml", "--out-dir", tmp_path, "--no-plot")
    grid = invoke("sweep", tmp_path / "case.yaml", "--amplitude", "0.5g", "--out-dir", tmp_path, "--no-plot",
                  "--no-progress")
    for result in (run, grid):
        assert result.exit_code == 0, result.output
        assert "ground.vertical.amplitude: the scaled vertical acceleration reaches -1176.8 gal at t = 5.100 s" \
            in result.stderr
    summary = results.read_result(tmp_path / "example.h5").result.summary
    stored = results.read_dataset(tmp_path / "example.sweep.h5", format=results.SWEEP_FORMAT).variables
    assert summary.status == "flight" and 5.0 < summary.end_time < 5.1
    assert float(np.ravel(stored["end_time"][1])[0]) == summary.end_time


# ------------------------------------------------------------------------------------------------
# Where a study computes (issue 26): the device gets big launches; --device auto
# ------------------------------------------------------------------------------------------------


def test_the_device_gets_many_chunks_per_launch(monkeypatch):
    """The example's 1517-case grid in chunks of 16 (95 chunks) goes to the device in one launch,
    and each chunk is still stored on its own (resume works as on the CPU)."""
    from rockslide.analyses import sweep as sw
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    case = rockslide.load_case(REPO / "configs" / "example.yaml")
    plan = sw.plan_sweep(case, [sw.parse_axis("mu", "0.30:0.70:0.01"), sw.parse_axis("pga", "100gal:1000gal:25gal")],
                         records_dir=REPO / "records", chunk_size=16)
    launches = []
    cpu_as_device(monkeypatch, lambda inputs: launches.append(inputs[0].shape[0]),
                  per_launch=ex.DEVICE_CASES_PER_LAUNCH)
    store = chunks.MemoryStore(plan.key)
    ex.compute(plan, store, range(plan.n_chunks), device="gpu")
    assert plan.n_chunks == 95 and launches == [1517]
    assert store.count() == 95
    cpu = chunks.MemoryStore(plan.key)
    ex.compute(plan, cpu, range(plan.n_chunks), workers=1)
    assert np.array_equal(chunks.collect(plan, store), chunks.collect(plan, cpu), equal_nan=True)


def test_a_resume_never_mixes_chunks_of_the_gpu_and_the_cpu(tmp_path, monkeypatch):
    """Chunks computed on the CPU are not reused by a run on the GPU, nor the reverse: the GPU rounds
    the last bits its own way (fused multiply-adds), so its chunks live under a key of their own
    (`ChunkStore.for_device`). The GPU here is the CPU's kernel behind the device's entry points."""
    from rockslide.analyses import sweep as sw
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    case = rockslide.load_case(REPO / "configs" / "example.yaml")
    plan = sw.plan_sweep(case, [sw.parse_axis("mu", "0.3,0.5"), sw.parse_axis("pga", "300gal,900gal")],
                         records_dir=REPO / "records", chunk_size=1)
    launched = []
    cpu_as_device(monkeypatch, lambda inputs: launched.append(len(inputs[0])), per_launch=ex.DEVICE_CASES_PER_LAUNCH)
    store = chunks.ChunkStore.beside(tmp_path / "example.sweep.h5", plan.key)
    assert ex.execute(plan, store, workers=1).computed == 4
    assert ex.execute(plan, store, device="gpu").computed == 4 and launched == [4]
    assert ex.execute(plan, store, device="gpu").computed == 0 and launched == [4]       # its own, reused
    assert ex.execute(plan, store, workers=1).computed == 0
    assert store.for_device("gpu").folder != store.folder and store.for_device("cpu") is store


def test_device_auto_takes_the_gpu_only_where_it_pays(monkeypatch):
    from rockslide.core import gpu
    from rockslide.engine import execute as ex

    def missing():
        raise gpu.DeviceUnavailable("no CUDA GPU found")

    monkeypatch.setattr(gpu, "require_device", missing)
    assert ex.choose_device("auto", 10**6) == ("cpu", "no usable GPU: no CUDA GPU found")
    monkeypatch.setattr(gpu, "require_device", lambda: object())
    monkeypatch.setattr(gpu, "cuda_simulator", lambda: True)
    assert ex.choose_device("auto", 10**6)[0] == "cpu"
    monkeypatch.setattr(gpu, "cuda_simulator", lambda: False)
    assert ex.choose_device("auto", ex.AUTO_GPU_CASES) == ("gpu", f"{ex.AUTO_GPU_CASES} cases, enough to fill it")
    device, why = ex.choose_device("auto", ex.AUTO_GPU_CASES - 1)
    assert device == "cpu" and f"pays from about {ex.AUTO_GPU_CASES}" in why
    assert ex.choose_device("cpu", 10**6) == ("cpu", "") and ex.choose_device("gpu", 1) == ("gpu", "")


def test_device_auto_says_where_and_why(tmp_path):
    write_case(tmp_path, {})
    result = invoke("sweep", tmp_path / "case.yaml", "--mu", "0.3,0.5", "--device", "auto", "--out-dir", tmp_path,
                    "--no-plot", "--no-progress")
    assert result.exit_code == 0, result.output
    assert "on this machine (--device auto: " in result.output


def test_info_reads_a_results_summary_without_computing_again(tmp_path):
    """``rockslide info OUT/NAME.h5 --json`` gives the summary ``run --json`` printed (from the
    file), the human form the run's printout; a sweep and a fragility file give their counts and fits."""
    import json

    write_case(tmp_path, {})
    ran = invoke("run", tmp_path / "case.yaml", "--out-dir", tmp_path, "--no-plot", "--json")
    assert ran.exit_code == 0, ran.output
    printed = json.loads(ran.stdout)
    stored = json.loads(invoke("info", tmp_path / "example.h5", "--json").stdout)
    for key in ("verdict", "max_rotation", "max_slip", "impacts", "events", "ground", "status"):
        assert stored[key] == printed[key], key
    human = invoke("info", tmp_path / "example.h5").stdout
    assert human.splitlines()[0] == invoke("run", tmp_path / "case.yaml", "--out-dir", tmp_path / "again",
                                           "--no-plot").stdout.splitlines()[0]
    assert invoke("fragility", tmp_path / "case.yaml", "--suite", tmp_path / "suite.yaml", "--levels", "0.2g,0.6g",
                  "--bootstrap", "0", "--out-dir", tmp_path, "--no-plot", "--no-progress").exit_code == 0
    fits = json.loads(invoke("info", tmp_path / "example.fragility.h5", "--json").stdout)
    assert fits["kind"] == "fragility" and fits["n_cases"] == 2 and "overturn" in fits["fits"]


def test_csv_tables_read_back_to_the_files_values(tmp_path):
    """``--csv`` writes one row per case (sweep) or per record and level (fragility), a column per
    coordinate and result, units in the headers; every number reads back to the HDF5 file's value
    exactly, and the rows are as many as the cases."""
    import csv

    write_case(tmp_path, {})
    assert invoke("sweep", tmp_path / "case.yaml", "--mu", "0.3,0.5", "--pga", "400gal,800gal", "--csv",
                  "--out-dir", tmp_path, "--no-plot", "--no-progress").exit_code == 0
    assert invoke("fragility", tmp_path / "case.yaml", "--suite", tmp_path / "suite.yaml", "--levels", "0.2g,0.6g",
                  "--bootstrap", "0", "--csv", "--out-dir", tmp_path, "--no-plot", "--no-progress").exit_code == 0
    for name, fmt, dims in (("example.sweep", results.SWEEP_FORMAT, ("mu", "pga")),
                            ("example.fragility", results.FRAGILITY_FORMAT, ("record", "level"))):
        stored = results.read_dataset(tmp_path / f"{name}.h5", format=fmt)
        with open(tmp_path / f"{name}.csv", newline="") as handle:
            rows = list(csv.DictReader(handle))
        shape = tuple(len(values) for n, values, _ in stored.coords if n in dims)
        assert len(rows) == int(np.prod(shape))
        header = {key.split(" [")[0]: key for key in rows[0]}
        for variable in ("max_rotation", "max_slip", "overturned", "status", "end_time"):
            dims_of, values, _ = stored.variables[variable]
            assert dims_of == dims
            column = [row[header[variable]] for row in rows]
            parsed = np.array([float(v) if v else np.nan for v in column]).reshape(shape)
            assert np.array_equal(parsed, values.astype(float), equal_nan=True), (name, variable)
        assert "max_rotation [rad]" in rows[0]


def test_the_api_names_an_unknown_axis():
    case = rockslide.load_case(REPO / "configs" / "example.yaml")
    with pytest.raises(rockslide.errors.CaseError, match="unknown axis 'friction'; expected one of mu, pga"):
        rockslide.sweep(case, friction="0.3,0.5", records_dir=REPO / "records")
