"""Beyond one machine: shards of a study computed by separate processes and collected, a dask
scheduler whose workers arrive late, workers that run another rockslide, and a cluster that loses
every worker midway.

Synchronisation is on what the processes print and on chunk files appearing, never on sleeps: a
loaded machine only makes these tests slower.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import CLUSTER_AXES as AXES
from conftest import CLUSTER_CHUNKS as CHUNKS
from conftest import REPO, invoke, one_line_error, sweep_args, variables_equal

from rockslide.engine.execute import check_workers_match, local_identity, parse_shard
from rockslide.errors import CaseError

posix = pytest.mark.skipif(os.name != "posix", reason="POSIX processes and signals")

EXAMPLE = REPO / "configs" / "example.yaml"
RECORDS = REPO / "records"


# --------------------------------------------------------------------------------------------------
# shards: N processes, then one that collects
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("text", ["0/3", "4/3", "3", "a/b", "1/0", "-1/2", "1/2/3", ""])
def test_a_bad_shard_is_one_line(tmp_path, text):
    result = invoke(*sweep_args(tmp_path, *AXES, extra=["--shard", text]))
    one_line_error(result, "--shard", "I/N")


def test_parse_shard():
    assert parse_shard("3/16") == (3, 16) and parse_shard(" 1/1 ") == (1, 1) and parse_shard(None) is None


@posix
@pytest.mark.slow
def test_shards_in_separate_processes_then_collected_equal_one_sweep(tmp_path):
    """Shards 1/3, 2/3, 3/3 as three processes into one folder, then the same command without
    --shard: it computes nothing and publishes a result equal bit for bit to a one-process sweep."""
    one = tmp_path / "one"
    assert invoke(*sweep_args(one, *AXES, extra=["--no-plot", *CHUNKS])).exit_code == 0
    shared = tmp_path / "shared"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    procs = [subprocess.Popen([sys.executable, "-m", "rockslide",
                               *map(str, sweep_args(shared, *AXES, extra=["--no-plot", *CHUNKS, "--workers", "1",
                                                                          "--shard", f"{i}/3"]))],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i in (1, 2, 3)]
    outputs = [p.communicate(timeout=600) for p in procs]
    for p, (out, err) in zip(procs, outputs, strict=True):
        assert p.returncode == 0, (out, err)
        assert "shard" in out and "without --shard collects" in out
    assert not (shared / "example.sweep.h5").exists()            # shards publish nothing
    # chunks of 5, 5, 5, 5 and 4 cases: shard 1 takes chunks 0 and 3, shard 2 chunks 1 and 4, shard 3 chunk 2
    assert "computed 10 cases" in outputs[0][0] and "computed 9 cases" in outputs[1][0], outputs
    assert "computed 5 cases" in outputs[2][0]
    result = invoke(*sweep_args(shared, *AXES, extra=["--no-plot", *CHUNKS]))
    assert result.exit_code == 0, result.output
    assert "reused 5 of 5 chunks" in result.stdout
    variables_equal(one / "example.sweep.h5", shared / "example.sweep.h5")


# --------------------------------------------------------------------------------------------------
# the workers' rockslide, checked before any task
# --------------------------------------------------------------------------------------------------


def test_workers_that_match_pass():
    mine = local_identity()
    check_workers_match({"tcp://a:1": dict(mine), "tcp://b:2": dict(mine)}, mine, "tcp://s:8786")


def test_workers_that_must_compile_are_said_once():
    """A worker whose numba cache holds no batch kernel (`worker_identity`'s ``warm``) compiles it
    in its first task, a minute or two: said once, naming the workers; nothing when all are warm."""
    from rockslide.engine.execute import cold_workers_note, worker_identity

    mine = local_identity()
    assert worker_identity(mine)["warm"] is True      # this process loaded the compiled core (the fixtures)
    assert "warm" not in worker_identity({**mine, "core": "0" * 64})     # another core's cache is not touched
    warm, cold = {**mine, "warm": True}, {**mine, "warm": False}
    assert cold_workers_note({"tcp://a:1": warm, "tcp://b:2": warm}) is None
    note = cold_workers_note({f"tcp://w:{k}": cold for k in range(5)} | {"tcp://a:1": warm})
    assert note.startswith("rockslide: note: 5 of 6 dask workers (tcp://w:0, tcp://w:1, tcp://w:2 and 2 more) compile")
    assert "tcp://a:1" not in note and "\n" not in note


@pytest.mark.parametrize("field, words", [
    ("rockslide", ["runs rockslide 9.9.9", "this client"]),
    ("core", ["compiled core", "this client"]),
    ("numba", ["runs numba 9.9.9", "this client"]),
])
def test_a_worker_with_another_rockslide_is_refused(field, words):
    mine = local_identity()
    other = {**mine, field: "9.9.9" if field != "core" else "0" * 64}
    with pytest.raises(CaseError) as caught:
        check_workers_match({"tcp://a:1": dict(mine), "tcp://b:2": other}, mine, "tcp://s:8786")
    text = str(caught.value)
    assert "tcp://b:2" in text and "tcp://a:1" not in text and "\n" not in text
    for word in words:
        assert word in text


def test_a_worker_without_rockslide_is_named():
    mine = local_identity()
    with pytest.raises(CaseError) as caught:
        check_workers_match({"tcp://b:2": {"error": "ModuleNotFoundError: No module named 'rockslide'"}},
                            mine, "tcp://s:8786")
    assert "tcp://b:2 cannot import rockslide" in str(caught.value)
    assert f"install rockslide=={mine['rockslide']}" in str(caught.value)


# --------------------------------------------------------------------------------------------------
# real schedulers and workers, in processes of their own
# --------------------------------------------------------------------------------------------------


@pytest.fixture
def scheduler(dask_scheduler):
    """``(address, start_worker)`` of `conftest.dask_scheduler`."""
    return dask_scheduler.address, dask_scheduler.start_worker


def _sweep_process(out: Path, address: str, *extra):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.Popen([sys.executable, "-m", "rockslide",
                             *map(str, sweep_args(out, *AXES, extra=["--no-plot", *CHUNKS, "--scheduler", address,
                                                                     *extra]))],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@posix
@pytest.mark.slow
def test_workers_that_arrive_late_are_waited_for(scheduler, tmp_path):
    """The scheduler starts with no worker (SLURM, Kubernetes): the sweep says it waits, a worker
    joins, the sweep completes with the local result."""
    address, start_worker = scheduler
    proc = _sweep_process(tmp_path / "remote", address, "--wait-workers", "600")
    for line in proc.stdout:                     # synchronise on the sweep saying it waits
        if "waiting for a first dask worker" in line:
            break
    else:
        pytest.fail(f"the sweep did not wait: {proc.communicate()}")
    start_worker()
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, (out, err)
    local = tmp_path / "local"
    assert invoke(*sweep_args(local, *AXES, extra=["--no-plot", *CHUNKS])).exit_code == 0
    variables_equal(local / "example.sweep.h5", tmp_path / "remote" / "example.sweep.h5")


@posix
@pytest.mark.slow
def test_no_worker_in_time_is_one_line(scheduler, tmp_path):
    address, _ = scheduler
    proc = _sweep_process(tmp_path, address, "--wait-workers", "1")
    out, err = proc.communicate(timeout=300)
    lines = err.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, (out, err)
    assert "no dask worker joined the scheduler" in lines[0] and "--wait-workers" in lines[0]


def test_wait_workers_needs_a_scheduler(tmp_path):
    one_line_error(invoke(*sweep_args(tmp_path, *AXES, extra=["--wait-workers", "5"])), "--wait-workers",
                   "scheduler")


@posix
@pytest.mark.slow
@pytest.mark.parametrize("patch, words", [
    ("import rockslide.core.compiled as c\nc.source_stamp = lambda: '0' * 64\n", ["compiled core", "would differ"]),
    ("import rockslide._version as v\nv.__version__ = '0.0.0+changed'\n", ["rockslide 0.0.0+changed", "would differ"]),
    ("import sys\nsys.modules['rockslide'] = None\n", ["cannot import rockslide", "install rockslide=="]),
])
def test_a_worker_from_a_changed_copy_is_refused_before_any_task(scheduler, tmp_path, patch, words):
    """A worker whose rockslide differs (its core's source stamp or version patched at its start,
    as a changed copy would be) or is missing: one line naming it, exit 2, no chunk computed."""
    address, start_worker = scheduler
    preload = tmp_path / "changed_copy.py"
    preload.write_text(patch)
    start_worker(preload)
    proc = _sweep_process(tmp_path / "out", address, "--wait-workers", "600")
    out, err = proc.communicate(timeout=600)
    lines = err.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, (out, err)
    assert lines[0].startswith("rockslide: error: --scheduler: the dask worker tcp://127.0.0.1:")
    for word in words:
        assert word in lines[0]
    assert not list(tmp_path.glob("out/.example.sweep.chunks/*/chunk-*.npz"))


@posix
@pytest.mark.slow
def test_the_last_worker_killed_is_one_line_and_the_resume_is_identical(scheduler, tmp_path):
    """The only worker is killed once a chunk is stored: one line saying the workers are gone (not
    the scheduler), exit 2, the chunks kept; a new worker and the same command finish the sweep
    with the local result."""
    address, start_worker = scheduler
    # the worker computes one chunk, then hangs (dask may load a preload file twice: patch once)
    stuck = tmp_path / "stuck_after_one_chunk.py"
    stuck.write_text("import threading\nimport rockslide.core.batch as b\n"
                     "_compute = b.__dict__.setdefault('_unpatched_compute', b.compute)\n_done = []\n"
                     "def compute(*args):\n    if _done:\n        threading.Event().wait()\n"
                     "    _done.append(1)\n    return _compute(*args)\nb.compute = compute\n")
    worker = start_worker(stuck)
    out = tmp_path / "remote"
    proc = _sweep_process(out, address, "--wait-workers", "600")
    deadline = time.monotonic() + 600
    while not list(out.glob(".example.sweep.chunks/*/chunk-*.npz")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no chunk was stored"
        time.sleep(0.02)
    worker.kill()
    worker.wait()
    stdout, stderr = proc.communicate(timeout=300)
    lines = stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, (stdout, stderr)
    assert "every worker of the dask scheduler" in lines[0] and "chunks are kept" in lines[0]
    start_worker()
    proc = _sweep_process(out, address, "--wait-workers", "600")
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, (stdout, stderr)
    assert "reused" in stdout
    local = tmp_path / "local"
    assert invoke(*sweep_args(local, *AXES, extra=["--no-plot", *CHUNKS])).exit_code == 0
    variables_equal(local / "example.sweep.h5", out / "example.sweep.h5")


def test_records_path_is_the_shipped_one():
    assert Path(RECORDS).is_dir() and Path(EXAMPLE).is_file()


# --------------------------------------------------------------------------------------------------
# the compiled core where numba is told to cache elsewhere (containers, HPC modules, read-only installs)
# --------------------------------------------------------------------------------------------------


@posix
def test_a_numba_cache_dir_elsewhere_reads_the_shipped_core(tmp_path):
    """With NUMBA_CACHE_DIR set to an empty folder (as containers and HPC modules do), a first sweep
    compiles nothing: the shipped compiled core is copied there and loads (a compile would say
    'compiling the batch kernel' and take a minute)."""
    from rockslide.core import batch, compiled

    if compiled.cache_folder(batch.run_batch) != compiled.shipped_folder():
        pytest.skip("numba caches outside the package here (NUMBA_CACHE_DIR is set): nothing shipped to copy")
    batch.warm_up()                          # the package's own cache holds the batch kernel
    assert compiled.is_warm(batch.run_batch)
    env = {**os.environ, "PYTHONPATH": str(REPO), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    probe = subprocess.run([sys.executable, "-c", "from rockslide.core import batch, compiled; "
                            "print(compiled.is_warm(batch.run_batch), compiled.cache_folder(batch.run_batch))"],
                           env=env, capture_output=True, text=True, timeout=300)
    warm, folder = probe.stdout.split()
    assert warm == "True" and Path(folder).is_relative_to(tmp_path / "numba"), probe
    done = subprocess.run([sys.executable, "-m", "rockslide",
                           *map(str, sweep_args(tmp_path / "out", *AXES, extra=["--no-plot", *CHUNKS]))],
                          env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "compiling" not in done.stdout + done.stderr


def test_a_worker_that_joins_later_with_another_rockslide_refuses_its_tasks():
    """Workers are checked before any task (`check_workers_match`); one that joins later (SLURM
    jobs start when they start) checks each task against the client's identity sent with it."""
    from rockslide.engine import execute

    mine = local_identity()
    inputs = [np.zeros((0, 1)), np.zeros((0, 1)), np.zeros((4, 1)), np.zeros(0, np.int64), np.zeros(0, np.int64),
              np.zeros(0), np.zeros(0)]
    with pytest.raises(RuntimeError, match="this worker runs rockslide .* the client 9.9.9 .* would differ"):
        execute.compute_chunk(inputs, 0, 1, {**mine, "rockslide": "9.9.9"})
