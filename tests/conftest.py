"""Shared fixtures: where the real (third-party) records are, and how tests that need one skip.

The real accelerograms of the paper are never copied into the project. Tests look for them in
``$ROCKSLIDE_RECORDS`` if set, else in ``../shared/records`` beside the repository (where CI and the
developers' machines have them). A test that needs one and cannot find it is skipped with a message
naming the file.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from rocking_reference import time_to_angle_under_constant_push

REPO = Path(__file__).resolve().parents[1]

# Hypothesis draws the same examples on every run (a suite that passes or fails by the luck of the
# draw is no check, on CI or on a new user's machine); ROCKSLIDE_EXPLORE=1 draws new ones, which finds
# bugs on a developer's machine, and each bug found that way stays as an @example of its test.
if not os.environ.get("ROCKSLIDE_EXPLORE"):
    from hypothesis import settings as _hypothesis_settings

    _hypothesis_settings.register_profile("repeatable", derandomize=True, print_blob=True)
    _hypothesis_settings.load_profile("repeatable")
#: The synthetic records shipped in records/ (made by records/make_example_records.py).
SHIPPED = ("synthetic_kt_h.at2", "synthetic_kt_v.at2")


def real_records_dir() -> Path | None:
    env = os.environ.get("ROCKSLIDE_RECORDS")
    candidates = [Path(env)] if env else []
    candidates.append(REPO.parent / "shared" / "records")
    for folder in candidates:
        if folder.is_dir():
            return folder
    return None


def real_record(name: str) -> Path:
    """Path of a real record, or skip the calling test with a message naming the file."""
    folder = real_records_dir()
    if folder is None or not (folder / name).is_file():
        pytest.skip(f"needs the real record {name}: not found in $ROCKSLIDE_RECORDS or ../shared/records "
                    "(see docs/guide/records.md, 'The paper's records')")
    return folder / name


@pytest.fixture
def records_dir_real() -> Path:
    folder = real_records_dir()
    if folder is None:
        pytest.skip("needs the paper's records: set ROCKSLIDE_RECORDS or place them in ../shared/records")
    return folder


@pytest.fixture(scope="module")
def example():
    """The shipped example case (configs/example.yaml), loaded."""
    from rockslide.case import load_case
    return load_case(REPO / "configs" / "example.yaml")


def invoke(*args, **kwargs):
    """``rockslide ARGS`` in this process (click's runner); each argument as a string: the one way
    the tests call the command line in process."""
    from click.testing import CliRunner

    from rockslide.cli import main
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


def one_line_error(result, *parts):
    """Exit code 2 and one line on stderr naming each of ``parts``."""
    lines = result.stderr.splitlines()
    assert result.exit_code == 2, (result.exit_code, result.output, result.exception)
    assert len(lines) == 1 and lines[0].startswith("rockslide: error: "), result.stderr
    for part in parts:
        assert part in lines[0], f"{part!r} not in {lines[0]!r}"
    return lines[0]


@pytest.fixture
def ws(tmp_path, monkeypatch):
    """A working folder with copies of the shipped synthetic records, made the current folder (and
    no $ROCKSLIDE_RECORDS: everything offline)."""
    for name in SHIPPED:
        shutil.copy(REPO / "records" / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ROCKSLIDE_RECORDS", raising=False)
    return tmp_path


@pytest.fixture
def dask_scheduler():
    """A dask scheduler in its own process on loopback: ``.address``, ``.process`` (to kill it) and
    ``.start_worker(preload=None)`` (a worker process of one thread; ``preload``: a Python file the
    worker runs at its start). Every process is killed at the end."""
    pytest.importorskip("distributed")
    with dask_processes() as cluster:
        yield cluster


@contextlib.contextmanager
def dask_processes(scheduler_options=(), worker_options=()):
    """`dask_scheduler`'s processes, the scheduler started with ``scheduler_options`` and each
    worker with ``worker_options`` (dask's command-line options: TLS files...)."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                             "--port", "0", "--no-dashboard", *map(str, scheduler_options)], env=env,
                            stderr=subprocess.PIPE, text=True)
    workers = []
    try:
        address = None
        for line in proc.stderr:                # synchronise on the scheduler saying where it listens
            if "Scheduler at:" in line:
                address = line.split("Scheduler at:")[1].strip()
                break
        assert address, "the scheduler did not start"
        threading.Thread(target=proc.stderr.read, daemon=True).start()

        def start_worker(preload: Path | None = None):
            extra = ["--preload", str(preload)] if preload else []
            worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads",
                                       "1", "--no-dashboard", *map(str, worker_options), *extra], env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            workers.append(worker)
            return worker

        yield SimpleNamespace(address=address, process=proc, start_worker=start_worker)
    finally:
        for p in (proc, *workers):
            if p.poll() is None:
                p.kill()
                p.wait()


#: Test modules that are slow as a whole (`make test-fast` leaves them out; `make test` runs them):
#: each test starts processes (dask schedulers and workers, `python -m rockslide` killed by
#: signals) or builds the documentation site, 5 to 90 s a test on 2 cores.
SLOW_MODULES = {
    "test_cluster.py": "dask clusters of worker processes",
    "test_cluster_access.py": "dask clusters over TLS, with certificates made for the test",
    "test_faults.py": "signals, killed processes, full disks and locks, in subprocesses",
    "test_docs_build.py": "the Sphinx site built from docs/",
}


#: Single tests (node ids without their parameters, or with one) that `make test-fast` leaves out:
#: each takes 10 to 35 s on a loaded 2-core machine (`--durations` of 2026-11-28) and checks what
#: the inner loop of a change to the physics or the files does not need every time.
SLOW_TESTS = {
    "test_gpu.py": "the GPU path on numba's CUDA simulator (a sweep, a fragility, a subprocess)",
    "test_docs_python.py::test_the_python_page_runs": "every example of docs/python.md",
    "test_engine.py::test_the_device_gets_many_chunks_per_launch": "the CUDA simulator again",
    "test_hard_cases.py::test_stick_slip_is_consistent_across_steps_modes_and_the_reference[slow]":
        "the reference integrator on the long case (the [fast] case stays)",
    "test_cli.py::test_criteria_takes_the_block_of_a_case_file": "four criteria maps drawn",
    "test_case.py::test_random_mutations": "hypothesis: mutated case files",
    "test_case.py::test_random_case_with": "hypothesis: random case files",
    "test_bad_input.py::test_random_record_bytes_through_info_give_a_summary_or_a_clean_error": "hypothesis",
    "test_bad_input.py::test_random_case_files_give_a_result_or_a_clean_error": "hypothesis",
}

# Tests of 1 to 18 s each (`--durations=0` of `make test-fast` on 2026-11-28, 2 loaded cores) that
# the inner loop leaves out in groups, each group keeping a quicker test of the same feature in
# `make test-fast` (named after the group).
SLOW_TESTS.update(dict.fromkeys([
    "test_paper.py::test_every_verdict_and_description_matches_with_the_papers_gravity",
    "test_paper.py::test_with_standard_gravity_only_gravity_sensitive_rows_differ",
    "test_paper.py::test_the_papers_remarks_hold",
    "test_paper.py::test_interaction_times_on_the_papers_time_axis",
    "test_paper.py::test_outputs_are_written",
    "test_paper.py::test_the_committed_table_is_what_make_table1_writes_now",
    "test_paper.py::test_the_kobe_vertical_peaks_of_table_1_follow_from_the_recorded_ratio",
    "test_hard_cases.py::test_table1_verdicts_hold_at_half_the_step",
], "Table 1 at the case files' 0.1 ms step, twice (test_paper keeps the 15 rows at the auto step)"))
SLOW_TESTS.update(dict.fromkeys([
    "test_asymmetric.py::test_kernel_and_reference_solver_agree_on_an_asymmetric_body_with_vertical_motion",
    "test_asymmetric.py::test_rocking_accelerations_and_contact_forces_at_the_contracts_states",
    "test_hard_cases.py::test_slender_block_agrees_with_the_reference",
    "test_hard_cases.py::test_outcome_near_a_painleve_point_does_not_depend_on_the_step",
    "test_pulse_closed_forms.py::test_half_sine_minimum_amplitude_tends_to_housners_as_alpha_vanishes",
    "test_two_components.py::test_rotd50_and_rotd100_by_brute_force",
    "test_two_components.py::test_the_bootstrap_over_orientations_resamples_records_not_orientations",
    "test_fragility.py::test_bootstrap_intervals_cover_the_true_median_and_beta",
    "test_large_grids.py::test_a_grid_beyond_a_million_points_is_planned_in_distinct_rows",
    "test_hard_cases.py::test_reference_does_not_skip_a_failed_integration",
    "test_hostile_files.py::test_time_options_at_the_edge_of_float_are_a_line_or_the_whole_record",
    "test_reference.py::test_kernel_and_reference_agree_event_by_event[low friction, slip only]",
], "long simulations and resamplings (test_reference, test_exact, test_equations and the other cases of "
   "the same modules stay)"))
SLOW_TESTS.update(dict.fromkeys([
    "test_hostile_results.py::test_a_read_only_home_adds_no_line_of_matplotlib",
    "test_auto_step.py::test_bench_gpu_writes_its_file_from_what_it_measured",
    "test_bad_input.py::test_bad_environment_and_options_are_one_line",
    "test_plots.py::test_rendering_does_not_load_pyplot",
    "test_startup.py::test_without_a_writable_cache_folder_the_core_compiles_in_memory",
    "test_startup.py::test_a_run_loads_what_it_needs",
    "test_docs_and_architecture.py::test_the_core_imports_without_io_libraries",
    "test_asymmetric.py::test_simulated_device_gives_the_cpu_final_states_of_asymmetric_bodies",
    "test_results.py::test_killed_writer_never_leaves_a_half_written_result",
    "test_results.py::test_ctrl_c_during_a_write_leaves_nothing",
    "test_hostile_text.py::test_a_quantity_of_thousands_of_digits_is_refused_at_once",
    "test_hostile_text.py::test_record_headers_that_crawled_are_read_at_once",
    "test_startup.py::test_a_sweep_on_one_thread_loads_no_numba_with_the_build",
    "test_startup.py::test_a_risk_of_a_given_fragility_loads_no_numba",
    "test_startup.py::test_a_fragility_analysis_of_peaks_on_one_thread_loads_no_numba",
    "test_startup.py::test_the_figure_module_leaves_matplotlib_as_it_found_it",
], "a fresh Python process (imports, compiling, signals, time bounds): the command line is tested in "
   "process (test_cli, test_bad_input) in the fast loop"))
SLOW_TESTS.update(dict.fromkeys([
    "test_plots.py::test_other_formats",
    "test_plots.py::test_save_figure_is_atomic",
    "test_plots.py::test_save_figure_refuses_to_overwrite",
    "test_plots.py::test_titles_placed_without_a_search_are_where_matplotlib_puts_them",
    "test_plots.py::test_png_holds_the_figure_as_drawn",
    "test_figure_captions.py::test_size_column_is_a_column_wide_with_fonts_of_6_pt_at_least",
    "test_figure_captions.py::test_named_and_explicit_sizes",
    "test_startup.py::test_the_run_figure_is_the_figure_of_the_file",
    "test_no_plot_figure.py::test_the_same_sweep_again_without_plot_keeps_its_figure",
    "test_no_plot_figure.py::test_another_sweep_without_plot_removes_the_figure_it_does_not_show",
    "test_mesh.py::test_the_meshes_page_runs",
    "test_two_components.py::test_two_orientations_plotted_have_different_captions",
    "test_cli.py::test_criteria_options_take_units",
    "test_figure_captions.py::test_plot_two_fragility_files_overlays_their_curves_with_bands",
    "test_figure_captions.py::test_sweep_maps_give_each_colour_one_meaning",
    "test_figure_captions.py::test_plot_two_runs_writes_one_figure_with_the_cases_in_its_legend",
    "test_floors.py::test_a_floor_run_and_a_ground_run_overlaid_say_which_is_which",
    "test_mesh_case.py::test_a_run_of_a_body_draws_its_planes",
    "test_criteria_body.py::test_the_criteria_command_draws_a_body_on_both_sides",
    "test_no_plot_figure.py::test_the_same_fragility_for_its_json_keeps_its_figure_another_does_not",
], "figures drawn to files (test_plots keeps every kind rendered to PNG, the labels and the layout at "
   "150 dpi)"))
SLOW_TESTS.update(dict.fromkeys([
    "test_risk.py::test_command_writes_file_figure_and_json",
    "test_goodness.py::test_two_measures_on_the_command_line",
    "test_pulses.py::test_spectrum_file_and_figure",
    "test_fragility.py::test_the_shared_suite_of_real_records",
    "test_fragility.py::test_parameter_samples_are_in_the_file_the_json_and_the_figure",
    "test_precision.py::test_the_command_prints_and_draws",
    "test_ensemble.py::test_the_statue_under_kobe_is_neither_safe_nor_doomed",
], "a whole analysis from the command line with its figure (each module's other tests of the same "
   "command stay)"))
SLOW_TESTS.update(dict.fromkeys([
    "test_records.py::test_the_printed_exponent_is_the_decimal_one",
    "test_records.py::test_fields_are_split_at_commas_and_white_space",
    "test_records.py::test_random_at2_text_reads_or_refuses",
    "test_records.py::test_random_column_text_reads_or_refuses",
    "test_records.py::test_random_text_sniffed_reads_or_refuses",
    "test_records.py::test_the_quick_reading_of_numbers_reads_what_the_careful_one_reads",
    "test_records.py::test_plain_numbers_read_at_once_give_the_numbers_read_line_by_line",
    "test_case.py::test_random_text",
    "test_case.py::test_random_yamlish_text",
    "test_equations.py::test_impact_never_creates_energy_and_respects_coulomb",
    "test_hostile_results.py::test_any_attribute_value_is_read_or_one_output_error",
    "test_hostile_results.py::test_an_empty_attribute_is_read_or_one_output_error",
    "test_bad_input.py::test_random_record_text_through_run_gives_a_result_or_a_clean_error",
], "hypothesis: 100 to 500 examples (test_hostile_text's fuzzers stay)"))


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = item.path.name
        test = f"{name}::{item.name}"
        if name in SLOW_MODULES or name in SLOW_TESTS or test in SLOW_TESTS or \
                f"{name}::{item.originalname}" in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)


#: Tests whose work starts in a process of its own as soon as the session has collected (and
#: selected) them, so that it computes on a second core while the other tests run: the test -> the
#: function of its module that starts the work and returns an object with ``stop()`` (None: nothing
#: started), which the session calls at its end.
STARTED_EARLY = {"test_gpu_compile.py::test_run_cases_compiles_for_sm_90": "start_compile"}
_started_early = []


def pytest_collection_finish(session):
    for item in session.items:
        starter = STARTED_EARLY.get(f"{item.path.name}::{item.name}")
        if starter is not None and not session.config.option.collectonly:
            started = getattr(item.module, starter)()
            if started is not None:
                _started_early.append(started)


def pytest_sessionfinish(session, exitstatus):
    while _started_early:
        _started_early.pop().stop()


# --------------------------------------------------------------------------------------------------
# Shared by several test files (tests import this module, never each other)
# --------------------------------------------------------------------------------------------------

G0 = 9.80665


def critical_duration(A, alpha, R):
    """Housner (1963), exact (no small-angle approximation): a rectangular pulse ``A > g tan(alpha)``
    lifts the block at once and pushes it up monotonically; after the pulse the motion is free, so
    the block overturns without impact exactly when the energy at the pulse's end reaches the
    barrier at ``theta = alpha``:
    ``(3 / (2 R)) [A (sin(alpha) - sin(alpha - theta1)) - g (cos(alpha - theta1) - cos(alpha))]
    = (3 g / (2 R)) (1 - cos(alpha - theta1))``, whose root is
    ``sin(alpha - theta1) = sin(alpha) - (g / A) (1 - cos(alpha))``. The critical duration is the
    time to reach that ``theta1`` under the pulse (`rocking_reference`'s quadrature)."""
    theta1 = alpha - math.asin(math.sin(alpha) - G0 / A * (1.0 - math.cos(alpha)))
    return time_to_angle_under_constant_push(theta1, A / G0, alpha, 0.75 * G0 / R)


def sweep_args(out: Path, *axes, extra=()):
    """``rockslide sweep`` of the shipped example over ``axes`` into ``out`` (its records, no progress bar)."""
    return ["sweep", REPO / "configs" / "example.yaml", *axes, "--records-dir", REPO / "records", "--out-dir", out,
            "--no-progress", *extra]


def variables_equal(a: Path, b: Path) -> None:
    """Two sweep files hold the same grid and exactly the same values."""
    from rockslide.io import results

    x, y = results.read_sweep(a), results.read_sweep(b)
    assert [(n, v.tolist()) for n, v, _ in x.coords] == [(n, v.tolist()) for n, v, _ in y.coords]
    assert x.variables.keys() == y.variables.keys()
    for name, (values, attrs) in x.variables.items():
        other, other_attrs = y.variables[name]
        assert values.dtype == other.dtype, name
        assert np.array_equal(values, other, equal_nan=values.dtype.kind == "f"), name
        assert attrs == other_attrs


#: A small cluster grid (4 x 6 = 24 cases in 5 chunks), shared by the cluster tests.
CLUSTER_AXES = ("--mu", "0.4:0.7:0.1", "--pga", "400gal:900gal:100gal")
CLUSTER_CHUNKS = ("--chunk-size", "5")


# cases, files and processes of the command line (test_bad_input, test_faults)

# the shipped example names its records relative to configs/; here they are copied beside the case
EXAMPLE_TEXT = (REPO / "configs" / "example.yaml").read_text(encoding="utf-8").replace("../records/", "")
EXAMPLE = yaml.safe_load(EXAMPLE_TEXT)


DROP = object()   # a change that removes the key


def case_text(changes: dict | None = None) -> str:
    """The shipped example with dotted keys changed (value DROP removes the key), as YAML."""
    data = copy.deepcopy(EXAMPLE)
    for dotted, value in (changes or {}).items():
        *parents, leaf = dotted.split(".")
        node = data
        for part in parents:
            child = node.get(part)
            if not isinstance(child, dict):
                if value is DROP:
                    break                       # nothing to remove
                child = node[part] = {}
            node = child
        else:
            if value is DROP:
                node.pop(leaf, None)
            else:
                node[leaf] = value
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def horizontal_only(spec, **changes) -> str:
    """A case whose only record is ``spec`` (a file name or a record mapping)."""
    return case_text({"ground.horizontal": spec, "ground.vertical": DROP, **changes})


def listing(folder: Path) -> list[str]:
    """Every file below ``folder`` (hidden temporary files included), relative, sorted."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def cli_subprocess(args, cwd: Path, **kwargs):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    env.pop("ROCKSLIDE_RECORDS", None)
    return subprocess.Popen([sys.executable, "-m", "rockslide.cli", *map(str, args)], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)   # a background job may have inherited SIG_IGN


QUICK = {"solver.dt": "1 ms", "ground.tail": "0 s"}   # a valid case that runs in a fraction of a second


# hazard curves, fragility files and hostile cases (test_risk, test_hostile_*)

G = 9.80665


def openquake_csv(path, levels_g, poes, *, imt="PGA", years=50.0, kind="mean", sites=None):
    """A hazard-curve CSV as OpenQuake's ``export_hcurves_csv`` writes it (levels with 7 decimals,
    PoEs as %.6E, site coordinates with 5)."""
    sites = sites or [(0.0, 0.0)] * len(poes)
    comment = (f'#,,,,,"generated_by=\'OpenQuake engine 3.18.0\', start_date=\'2023-10-03T06:09:08\', '
               f"checksum=2107362341, kind='{kind}', investigation_time={years}, imt='{imt}'\"")
    header = "lon,lat,depth," + ",".join(f"poe-{v:.7f}" for v in levels_g)
    rows = [f"{lon:.5f},{lat:.5f},-0.10000," + ",".join(f"{p:.6E}" for p in row)
            for (lon, lat), row in zip(sites, poes, strict=True)]
    path.write_text("\n".join([comment, header, *rows]) + "\n")
    return path


def fragility_file(path, *, median=0.5 * G, beta=0.4, interval=True, im="pga", bootstrap=None, suite_text=None):
    """A fragility file with the variables `rockslide fragility` writes that `risk` reads
    (``bootstrap``: ``(medians, betas)`` of resamples, for the first state)."""
    levels = np.array([0.2, 0.4, 0.6, 0.8, 1.0]) * G
    fraction = np.array([[0.0, 0.3, 0.7, 0.9, 1.0], [0.2, 0.6, 0.9, 1.0, 1.0]])
    per_state = ("damage_state",)
    bounds = (0.8, 1.25) if interval else (math.nan, math.nan)
    exceeded = (np.random.default_rng(1).random((3, levels.size, 2)) < fraction.T).astype(np.int8)   # 3 records
    variables = {"exceeded": (("record", "level", "damage_state"), exceeded, {}),
                 "definition": (per_state, np.array(["overturn", "rotation>0.5alpha"], dtype=object), {}),
                 "fraction_exceeded": (("damage_state", "level"), fraction, {"units": "1"}),
                 "median": (per_state, np.array([median, median / 2]), {"units": "m/s^2"}),
                 "beta": (per_state, np.array([beta, beta]), {"units": "1"}),
                 "fit_note": (per_state, np.array(["", ""], dtype=object), {})}
    for name, value in (("median", median), ("beta", beta)):
        for side, factor in zip(("lower", "upper"), bounds, strict=True):
            variables[f"{name}_{side}"] = (per_state, np.array([value * factor] * 2), {})
    coords = [("record", np.array(["r1", "r2", "r3"], dtype=object), {}), ("level", levels, {"units": "m/s^2"}),
              ("damage_state", np.array(["overturn", "rotation>0.5alpha"], dtype=object), {})]
    if bootstrap is not None:
        n = len(bootstrap[0])
        coords.append(("resample", np.arange(n, dtype=np.float64), {}))
        for name, values in zip(("median", "beta"), bootstrap, strict=True):
            variables[f"bootstrap_{name}"] = (("damage_state", "resample"), np.array([values, [np.nan] * n]), {})
    attrs = {"intensity_measure": im, "confidence_level": 0.95}
    if suite_text is not None:
        attrs["suite_text"] = suite_text
    from rockslide.io import results

    results.write_dataset(path, coords, variables, format=results.FRAGILITY_FORMAT, attrs=attrs)
    return path


def _case(folder):
    data = yaml.safe_load((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))
    data["ground"]["tail"] = "0 s"
    data["solver"]["dt"] = "1 ms"
    data["output"] = {"dir": str(folder / "out"), "interval": "10 ms"}
    (folder / "case.yaml").write_text(yaml.safe_dump(data))
    for name in SHIPPED:
        shutil.copy(REPO / "records" / name, folder / name)


def cpu_as_device(monkeypatch, launched=lambda inputs: None, log=None, per_launch=5):
    """The GPU path of `execute` with the CPU's batch driver as the device (`core.gpu.prepare` and
    `core.gpu.Launch` replaced), ``per_launch`` cases a launch: each launch calls ``launched(its
    batch.compute inputs)``, and ``log`` (a list) gets ``("prepare", n)``, ``("launch", n)``,
    ``("result", n)`` and ``("store", chunk)`` in the order they happen."""
    from rockslide.core import batch, gpu
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    log = [] if log is None else log

    class Launch:
        def __init__(self, *inputs):
            launched(inputs)
            log.append(("launch", len(inputs[0])))
            self.states = batch.compute(*inputs)

        def result(self):
            log.append(("result", len(self.states)))
            return self.states

    def prepare(*inputs):
        log.append(("prepare", len(inputs[0])))
        return inputs

    save = chunks.ChunkStore.save

    def logged_save(store, chunk, *args):
        log.append(("store", chunk))
        return save(store, chunk, *args)

    monkeypatch.setattr(ex, "DEVICE_CASES_PER_LAUNCH", per_launch)
    monkeypatch.setattr(gpu, "prepare", prepare)
    monkeypatch.setattr(gpu, "Launch", Launch)
    monkeypatch.setattr(ex, "check_device", lambda device: None)
    monkeypatch.setattr(ex, "warm_up", lambda device, say: None)
    monkeypatch.setattr(chunks.ChunkStore, "save", logged_save)

