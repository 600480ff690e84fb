"""Shared fixtures: where the real (third-party) records are, and how tests that need one skip.

The real accelerograms of the paper are never copied into the project. Tests look for them in
``$ROCKSLIDE_RECORDS`` if set, else in ``../shared/records`` beside the repository (where CI and the
developers' machines have them). A test that needs one and cannot find it is skipped with a message
naming the file.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import pytest

REPO = Path(__file__).resolve().parents[1]

# Hypothesis draws new examples on every run, which finds bugs on a developer's machine; CI draws the
# same ones every time (a test suite that passes or fails by the luck of the draw is no check), and
# each bug found on the way stays as an @example of its test.
if os.environ.get("CI"):
    from hypothesis import settings as _hypothesis_settings

    _hypothesis_settings.register_profile("ci", derandomize=True, print_blob=True)
    _hypothesis_settings.load_profile("ci")
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


def invoke(*args):
    """``rockslide ARGS`` in this process (click's runner); each argument as a string."""
    from click.testing import CliRunner

    from rockslide.cli import main
    return CliRunner().invoke(main, [str(a) for a in args])


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


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = item.path.name
        test = f"{name}::{item.name}"
        if name in SLOW_MODULES or name in SLOW_TESTS or test in SLOW_TESTS or \
                f"{name}::{item.originalname}" in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)
