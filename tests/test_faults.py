"""Faults, hostile input and interruptions (issue 16): each test performs the attack.

What these tests protect, as a user meets it:

- Ctrl-C and SIGTERM, at any moment, end a run with 130 (143) and the previous result intact, or
  (when they land after the new result is published) leave the new result complete; never a
  result of mixed files, never an ignored signal, never a leftover temporary file;
- a full disk (a small tmpfs, a file-size limit, an injected ENOSPC) is one line, exit 2, nothing
  left behind;
- a sweep chunk that is truncated, altered, replaced by another file or by a folder is computed
  again, and said so;
- a dask scheduler address where something else listens fails in one bounded attempt, in one line;
- the files of a result are published together and exclusively: two runs started at once never
  both write, a stale companion is removed, a rerun finishes what an interrupted one left;
- temporary files of killed runs are removed by the next run of that output;
- absurd work is announced before it starts, a step too coarse for the block is warned about;
- no input within the validated ranges gives a non-finite number in a summary.

The hostile inputs that end in one line (YAML bombs, absurd values, bad options) are in the table of
`test_bad_input.py`.
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import threading
import time
import warnings
from http.server import BaseHTTPRequestHandler, HTTPServer
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import (
    QUICK,
    REPO,
    SHIPPED,
    _default_sigint,
    case_text,
    cli_subprocess,
    horizontal_only,
    invoke,
    listing,
    sha256,
)
from conftest import one_line_error as one_error_line
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rockslide import interrupts
from rockslide.analyses import sweep as sw
from rockslide.api import runs as api_runs
from rockslide.case import case_with, load_case
from rockslide.core import batch
from rockslide.engine import chunks
from rockslide.engine import execute as ex
from rockslide.engine import prepare as runner
from rockslide.io import files, results

posix = pytest.mark.skipif(os.name != "posix", reason="POSIX signals, processes and file systems")


def temporaries(folder: Path) -> list[str]:
    return [p for p in listing(folder) if p.endswith(".tmp")]




# --------------------------------------------------------------------------------------------------
# 16.1, 16.7 (12.8): signals at random moments
# --------------------------------------------------------------------------------------------------

# The attack, smaller: a streamed write of half a million history rows (20 s of record and
# 30 s of tail at 0.1 ms, every step kept), replacing a previous result with --overwrite.
STREAMING = {"name": "stream", "solver.dt": "0.1 ms", "ground.tail": "30 s", "output.interval": None}


def _run_streaming(ws: Path, signum=None, delay=0.0):
    """Run the streaming case with --overwrite; ``signum`` goes ``delay`` seconds after its
    temporary result file appears (the run is computing by then). Returns (code, stderr, seconds
    from the temporary file to the end)."""
    proc = cli_subprocess(["run", "case.yaml", "--overwrite"], ws,
                          preexec_fn=_default_sigint)
    try:
        deadline = time.monotonic() + 300
        while not list((ws / "out").glob(".stream.h5.*.tmp")):
            if proc.poll() is not None:
                break                       # finished before the poll saw its temporary file
            assert time.monotonic() < deadline, "no temporary file appeared"
            time.sleep(0.002)
        seen = time.monotonic()
        if signum is not None and proc.poll() is None:
            time.sleep(delay)
            proc.send_signal(signum)
        _, stderr = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return proc.returncode, stderr, time.monotonic() - seen


@posix
@pytest.mark.slow
def test_signals_at_random_moments_keep_the_previous_result_or_publish_the_new_one(ws):
    """Signals (SIGINT, SIGTERM, SIGINT) at random moments of a run that streams half a million
    rows, and one sent the moment its temporary file appears (the run then has all its rows still
    to write: it is surely computing): each run ends with 130/143 and the previous HDF5 and PNG
    untouched, or (a signal after the publication) with 0 and a new, complete pair; never an ignored
    signal, a mixed pair or a temporary file. Whatever the moment, the outcome is one of the two:
    the test asserts that, not when the signal lands (a loaded machine moves the moments), and the
    immediate signal makes sure the first outcome is exercised. The random moments are seeded."""
    (ws / "case.yaml").write_text(case_text(STREAMING))
    code, stderr, duration = _run_streaming(ws)
    assert code == 0, stderr
    out = ws / "out"
    before = (sha256(out / "stream.h5"), sha256(out / "stream.png"))
    stored = results.read_result(out / "stream.h5")
    assert stored.result.history["time"].size == 500_001
    rng = random.Random(16)
    moments = [(signal.SIGINT, 0.0)] + [((signal.SIGINT, signal.SIGTERM)[k % 2], rng.uniform(0.0, duration))
                                         for k in range(1, 4)]
    for trial, (signum, delay) in enumerate(moments):
        code, stderr, _ = _run_streaming(ws, signum, delay)
        assert "Exception ignored" not in stderr and "Traceback" not in stderr, stderr
        assert temporaries(ws) == []
        now = (sha256(out / "stream.h5"), sha256(out / "stream.png"))
        if code == 0:                       # the signal came after the new pair was published
            assert trial > 0, "a signal sent as the run starts writing must stop it"
            again = results.read_result(out / "stream.h5")
            assert again.result.history["time"].size == 500_001
            assert again.result.summary.end_time == pytest.approx(50.0)
            # the figure is drawn from the result it sits beside (same pixels: PNG bytes are reproducible)
            assert (out / "stream.png").stat().st_mtime_ns >= (out / "stream.h5").stat().st_mtime_ns - 10**9
            before = now
        else:
            word = "interrupted" if signum == signal.SIGINT else "terminated"
            assert code == 128 + signum, stderr
            assert stderr.splitlines()[-1] == f"rockslide: {word} (no partial result was written)"
            assert now == before


def test_the_signal_handler_only_records_and_check_raises(monkeypatch):
    """In-process: SIGTERM sent to this process sets the flag; `check` raises Interrupted with exit
    code 143 (the handler itself raises nothing, wherever it runs)."""
    with interrupts.handling_signals():
        interrupts.check()
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(1000):               # the handler runs between two bytecodes
            if interrupts.requested():
                break
        assert interrupts.requested() == signal.SIGTERM
        with pytest.raises(interrupts.Interrupted) as info:
            interrupts.check()
        assert info.value.exit_code == 143 and info.value.word == "terminated"
        assert isinstance(info.value, KeyboardInterrupt)    # clean-ups of `except BaseException` run
    assert interrupts.requested() is None


def test_a_chunk_group_computed_when_the_signal_comes_is_kept(ws, monkeypatch):
    """SIGINT arrives while a group of chunks computes: the group is still stored (finished work is
    kept), then the sweep stops before the next group."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    plan = sw.plan_sweep(load_case(ws / "case.yaml"), [sw.parse_axis("mu", "0.3:0.6:0.1")], records_dir=ws,
                         chunk_size=1)
    store = chunks.ChunkStore.beside(ws / "out" / "example.sweep.h5", plan.key)
    compute = ex.local_kernel()       # what a thread computes with (`batch.compute` or the build's code)

    signalled = []

    def interrupted_meanwhile(*args, **kwargs):
        if not signalled:       # one signal, during the first chunk, handled before that chunk ends
            signalled.append(os.kill(os.getpid(), signal.SIGINT))
            deadline = time.monotonic() + 30.0
            while interrupts.requested() is None and time.monotonic() < deadline:
                time.sleep(0.001)
        return compute(*args, **kwargs)

    monkeypatch.setattr(ex, "local_kernel", lambda: interrupted_meanwhile)
    # a background job (a CI script started with &) inherits SIGINT ignored, which handling_signals respects
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with interrupts.handling_signals(), pytest.raises(interrupts.Interrupted):
            ex.compute(plan, store, range(plan.n_chunks), workers=1)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert 1 <= store.count() < plan.n_chunks
    assert chunks.missing_chunks(plan, store) == list(range(store.count(), plan.n_chunks))


@posix
def test_a_second_signal_stops_at_once(tmp_path):
    """A process stuck where no check comes (a first compilation): the second Ctrl-C ends it by the
    signal itself (exit -SIGINT), not an exception raised from the handler."""
    script = ("import os, signal, time\n"
              "from rockslide import interrupts\n"
              "with interrupts.handling_signals():\n"
              "    os.kill(os.getpid(), signal.SIGINT)\n"
              "    time.sleep(0.05)\n"
              "    os.kill(os.getpid(), signal.SIGINT)\n"
              "    time.sleep(5)\n"
              "print('survived')\n")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=60,
                          preexec_fn=_default_sigint)
    assert proc.returncode == -signal.SIGINT and "survived" not in proc.stdout, proc


# --------------------------------------------------------------------------------------------------
# 16.2: a full disk
# --------------------------------------------------------------------------------------------------


class _FillingDisk:
    """A file whose disk is full after ``budget`` bytes: writes beyond raise ENOSPC, as the OS does."""

    def __init__(self, raw, budget: int):
        self._raw, self._left = raw, budget

    def write(self, data):
        if memoryview(data).nbytes > self._left:
            raise OSError(errno.ENOSPC, "No space left on device")
        self._left -= memoryview(data).nbytes
        return self._raw.write(data)

    def __getattr__(self, name):
        return getattr(self._raw, name)


def fill_disk_after(monkeypatch, budget: int) -> None:
    """Every HDF5 file rockslide writes from now on fills its disk after ``budget`` bytes."""
    original = results._RawFile.__init__

    def init(self, path):
        original(self, path)
        self._file = _FillingDisk(self._file, budget)

    monkeypatch.setattr(results._RawFile, "__init__", init)


@pytest.mark.parametrize("streamed", [True, False, "ensemble"])
def test_injected_enospc_while_writing_a_run_is_one_line_and_leaves_nothing(ws, monkeypatch, streamed):
    """The disk fills after 20 kB of the result file, while the history streams into it or, held in
    memory (`api.runs.HELD_HISTORY_ROWS`), is written after the compute, or is written on a thread
    of its own while the run's ensemble computes (`api._shared.Meanwhile`): one line naming the
    file and the reason, exit 2, nothing in the output folder (libhdf5 crashed at exit on such a
    file before); and the process goes on writing HDF5 files normally afterwards."""
    (ws / "case.yaml").write_text(case_text({"solver.dt": "1 ms"}))
    if streamed is True:
        monkeypatch.setattr(api_runs, "HELD_HISTORY_ROWS", 0)
    ensemble = ["--ensemble", "4"] if streamed == "ensemble" else []
    with monkeypatch.context() as patch:
        fill_disk_after(patch, 20_000)
        result = invoke("run", "case.yaml", *ensemble)
    one_error_line(result, "out/example.h5: cannot write the file (No space left on device)",
                   "free some space")
    assert listing(ws / "out") == []
    assert invoke("run", "case.yaml").exit_code == 0
    assert results.read_result(ws / "out" / "example.h5").name == "example"


def test_a_held_history_writes_the_file_a_streamed_one_writes(ws, monkeypatch):
    """A run's history held in memory and written after the compute (`api.runs.HELD_HISTORY_ROWS`)
    gives the file the streamed history gives: the same history, events, summary and attributes
    (but the time it was written)."""
    (ws / "case.yaml").write_text(case_text({"solver.dt": "1 ms"}))
    assert invoke("run", "case.yaml", "--no-plot", "--out-dir", "held").exit_code == 0
    monkeypatch.setattr(api_runs, "HELD_HISTORY_ROWS", 0)
    assert invoke("run", "case.yaml", "--no-plot", "--out-dir", "streamed").exit_code == 0
    held, streamed = (results.read_result(ws / folder / "example.h5") for folder in ("held", "streamed"))
    assert held.result.history["time"].size == 22_001
    for name, column in streamed.result.history.items():
        assert np.array_equal(held.result.history[name], column) and held.result.history[name].dtype == column.dtype
    assert np.array_equal(held.result.events, streamed.result.events)
    assert held.result.summary == streamed.result.summary
    assert {k: str(v) for k, v in held.attrs.items() if k != "created"} == \
        {k: str(v) for k, v in streamed.attrs.items() if k != "created"}


def test_an_ensemble_writes_the_history_while_it_computes_and_the_same_file(ws, monkeypatch):
    """With an ensemble on the build's machine code, the run's history is written on a thread of
    its own while the neighbours compute (`api._shared.Meanwhile`): the file is the one written
    after the compute (no second thread: `output_modules` says none), every dataset and attribute
    (but the time it was written)."""
    (ws / "case.yaml").write_text(case_text({"solver.dt": "1 ms"}))
    threads = []
    write_history = results.ResultWriter.write_history

    def noting_the_thread(self, history):
        threads.append(threading.current_thread().name)
        return write_history(self, history)

    monkeypatch.setattr(results.ResultWriter, "write_history", noting_the_thread)
    assert invoke("run", "case.yaml", "--ensemble", "6", "--no-plot", "--out-dir", "meanwhile").exit_code == 0
    early = ["rockslide-meanwhile"] if ex.on_machine_code("cpu") else []     # numba's JIT: after the compute
    assert threads == early
    monkeypatch.setattr(api_runs, "output_modules", lambda *args, **kwargs: [])
    assert invoke("run", "case.yaml", "--ensemble", "6", "--no-plot", "--out-dir", "after").exit_code == 0
    assert threads == early
    meanwhile, after = (results.read_result(ws / folder / "example.h5") for folder in ("meanwhile", "after"))
    for name, column in after.result.history.items():
        early = meanwhile.result.history[name]
        assert np.array_equal(early, column) and early.dtype == column.dtype, name
    assert np.array_equal(meanwhile.result.events, after.result.events)
    assert meanwhile.result.summary == after.result.summary
    assert {k: str(v) for k, v in meanwhile.attrs.items() if k not in ("created", "command_line")} == \
        {k: str(v) for k, v in after.attrs.items() if k not in ("created", "command_line")}
    with h5py.File(ws / "meanwhile" / "example.h5") as a, h5py.File(ws / "after" / "example.h5") as b:
        assert sorted(a["ensemble"]) == sorted(b["ensemble"])
        for name in a["ensemble"]:
            assert np.array_equal(a["ensemble"][name][()], b["ensemble"][name][()], equal_nan=True), name


@pytest.mark.parametrize("fails", ["interrupted", "writer fails too"])
def test_an_ensemble_stopped_while_its_history_is_written_leaves_nothing(ws, monkeypatch, fails):
    """Ctrl-C while the neighbours compute, once the history's file was made on its own thread
    (or while that thread failed as well: the interruption is what is said): exit 130, the
    interruption's line, nothing in the output folder, no temporary file, no HDF5 file left open."""
    if not ex.on_machine_code("cpu"):
        pytest.skip("the history is written meanwhile only on the build's machine code, which this installation lacks")
    (ws / "case.yaml").write_text(case_text({"solver.dt": "1 ms"}))
    files_open = h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_FILE)
    written = threading.Event()
    write_history = results.ResultWriter.write_history

    def write_then_tell(self, history):
        try:
            if fails == "writer fails too":
                raise OSError(errno.EIO, "Input/output error")
            return write_history(self, history)
        finally:
            written.set()

    def interrupted_neighbourhood(*args, **kwargs):
        assert written.wait(60)          # the writer has its file (or failed): then the signal comes
        raise interrupts.Interrupted(signal.SIGINT)

    monkeypatch.setattr(results.ResultWriter, "write_history", write_then_tell)
    monkeypatch.setattr(api_runs, "_neighbourhood", interrupted_neighbourhood)
    result = invoke("run", "case.yaml", "--ensemble", "6")
    assert result.exit_code == 130, result.output
    assert result.output.splitlines()[-1] == "rockslide: interrupted (no partial result was written)"
    assert listing(ws / "out") == [] and temporaries(ws / "out") == []
    assert h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_FILE) == files_open


def test_a_run_into_a_folder_that_takes_no_file_is_refused_before_it_computes(ws, monkeypatch):
    """The file of a held history is written after the compute, so its folder is tried first
    (`files.check_writable`): a folder that refuses a new file (here the system's refusal injected,
    as root writes any folder) is one line naming it, exit 2, before anything is computed."""
    computed = []
    monkeypatch.setattr(runner, "simulate_prepared", lambda *args, **kwargs: computed.append(1))
    real_open_new = files.open_new

    def open_new(path, *args, **kwargs):
        if Path(path).parent.name == "locked":
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real_open_new(path, *args, **kwargs)

    monkeypatch.setattr(files, "open_new", open_new)
    (ws / "case.yaml").write_text(case_text(QUICK))
    result = invoke("run", "case.yaml", "--no-plot", "--out-dir", "locked")
    one_error_line(result, "locked: cannot write in this folder (Permission denied)")
    assert computed == [] and listing(ws / "locked") == []


def test_injected_enospc_in_the_sweep_file_keeps_the_chunks(ws, monkeypatch):
    fill_disk_after(monkeypatch, 2_000)
    (ws / "case.yaml").write_text(case_text(QUICK))
    result = invoke("sweep", "case.yaml", "--mu", "0.4,0.5", "--no-progress")
    assert result.exit_code == 2 and "Traceback" not in result.stderr
    assert result.stderr.splitlines() == [
        "rockslide: error: out/example.sweep.h5: cannot write the file (No space left on device); nothing "
        "was written; free some space or choose another output folder"]
    left = listing(ws / "out")
    assert temporaries(ws) == [] and "example.sweep.h5" not in left
    assert [p for p in left if p.startswith(".example.sweep.chunks/")]      # a rerun resumes


def test_a_sweep_that_cannot_fit_is_refused_before_it_computes(ws, monkeypatch):
    """A sweep's size is known in advance (its chunks and its file): with too little free space it
    is refused at once, in one line, without a chunk computed; a run only warns (its history
    compresses by a factor that is not known in advance)."""
    monkeypatch.setattr(files, "free_space", lambda folder: 10_000)
    (ws / "case.yaml").write_text(case_text(QUICK))
    result = invoke("sweep", "case.yaml", "--mu", "0.4,0.5", "--no-progress")
    one_error_line(result, "out: 0.01 MB free; the sweep needs about", "choose another output folder")
    assert listing(ws / "out") == []
    result = invoke("run", "case.yaml", "--no-plot")
    assert result.exit_code == 0, result.output
    assert result.stderr.startswith("rockslide: warning: out: 0.01 MB free, and the result may need up to")


def _file_size_limit(limit: int):
    def apply():
        import resource
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return apply


@posix
@pytest.mark.parametrize("command", [["run", "case.yaml"],
                                     ["sweep", "case.yaml", "--mu", "0.4,0.5", "--no-progress"]],
                         ids=["run", "sweep"])
def test_file_size_limit_is_one_line_and_leaves_nothing(ws, command):
    """A child whose files may not exceed 20 kB (RLIMIT_FSIZE: writes fail with EFBIG, as on a full
    disk, without privileges): one line, exit 2, no temporary file, no result."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    runner.run_case(load_case(ws / "case.yaml"), ws, history=False)   # the kernels compiled and cached
    batch.warm_up()                                                   # (a child could not cache them)
    proc = cli_subprocess(command, ws, preexec_fn=_file_size_limit(20_000))
    _, stderr = proc.communicate(timeout=300)
    lines = stderr.splitlines()
    assert proc.returncode == 2, stderr
    assert len(lines) == 1 and lines[0].startswith("rockslide: error: ") and "File too large" in lines[0], stderr
    assert temporaries(ws) == []
    assert not [p for p in listing(ws / "out") if p.endswith((".h5", ".png"))]


def _unshare_works() -> bool:
    if os.name != "posix" or not shutil.which("unshare"):
        return False
    probe = subprocess.run(["unshare", "-Urm", "sh", "-c", "mount -t tmpfs -o size=64k none /mnt"],
                           capture_output=True, timeout=30)
    return probe.returncode == 0


@pytest.mark.skipif(not _unshare_works(), reason="needs unprivileged user and mount namespaces "
                    "(unshare -Urm) to mount a small tmpfs")
def test_small_tmpfs_as_output_folder(ws):
    """The issue's reproduction: a 200 kB tmpfs as the output folder of a run. One line, exit 2
    (not 139), and no result or temporary file afterwards (listed inside the namespace, before the
    tmpfs goes). (A sweep, whose size is known, is refused before it computes; its write failures
    are the file-size-limit and injected cases above.)"""
    command, size, reason = ["run"], "200k", "No space left on device"
    (ws / "case.yaml").write_text(case_text({"output.dir": "full"}))
    (ws / "full").mkdir()
    rockslide = " ".join([f"'{sys.executable}'", "-m", "rockslide.cli", command[0], "case.yaml", *command[1:]])
    script = (f"mount -t tmpfs -o size={size} none full && {rockslide} 2> err.txt; echo $? > rc.txt; "
              "ls -A full > left.txt")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    subprocess.run(["unshare", "-Urm", "sh", "-c", script], cwd=ws, env=env, timeout=300, check=True)
    stderr = (ws / "err.txt").read_text()
    assert (ws / "rc.txt").read_text().strip() == "2", stderr
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rockslide: error: ") and reason in lines[0], stderr
    left = (ws / "left.txt").read_text().split()
    assert not [name for name in left if name.endswith((".tmp", ".h5", ".png"))], left


# --------------------------------------------------------------------------------------------------
# 16.3: damaged chunks
# --------------------------------------------------------------------------------------------------

GRID = ("--mu", "0.4,0.5,0.6", "--pga", "600gal,800gal")


def _swept(folder: Path, *extra):
    return invoke("sweep", "case.yaml", *GRID, "--chunk-size", "1", "--no-plot", "--no-progress",
                  "--out-dir", folder, *extra)


def test_damaged_chunks_are_computed_again_and_named(ws):
    """Six chunks: one truncated, one with a byte flipped, one replaced by a .npy, one by a folder,
    one well-formed with altered states (its checksum no longer matches), one intact. The sweep
    recomputes the five, names each with its reason, and gives the result of an undisturbed sweep."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    assert _swept(ws / "reference").exit_code == 0
    case = load_case(ws / "case.yaml")
    plan = sw.plan_sweep(case, [sw.parse_axis("mu", GRID[1]), sw.parse_axis("pga", GRID[3])],
                         records_dir=ws, chunk_size=1)
    store = chunks.ChunkStore.beside(ws / "out" / "example.sweep.h5", plan.key)
    ex.compute(plan, store, range(plan.n_chunks))
    data = store.path(0).read_bytes()
    store.path(0).write_bytes(data[:len(data) // 2])
    flipped = bytearray(store.path(1).read_bytes())
    flipped[len(flipped) // 2] ^= 0x01
    store.path(1).write_bytes(bytes(flipped))
    with open(store.path(2), "wb") as handle:
        np.save(handle, np.zeros((1, 40)))
    store.path(3).unlink()
    store.path(3).mkdir()
    (store.path(3) / "inside").write_text("a folder where a chunk was")
    with np.load(store.path(4)) as chunk:
        fields = dict(chunk)
    fields["states"] = fields["states"] * 1.5
    np.savez(store.path(4), **fields)
    for attempt in ("first", "--overwrite"):
        extra = ["--overwrite"] if attempt == "--overwrite" else []
        result = _swept(ws / "out", *extra)
        assert result.exit_code == 0, result.output
        notes = [line for line in result.stdout.splitlines() if "cannot be used" in line]
        if attempt == "first":
            assert len(notes) == 5 and all(str(store.folder) in n and "computing it again" in n for n in notes)
            assert "checksum does not match" in notes[4]
            assert "reused 1 of 6 chunks" in result.stdout
        variables = results.read_sweep(ws / "out" / "example.sweep.h5").variables
        reference = results.read_sweep(ws / "reference" / "example.sweep.h5").variables
        for name, (values, _) in reference.items():
            assert np.array_equal(values, variables[name][0], equal_nan=values.dtype.kind == "f"), name
        assert not (ws / "out" / ".example.sweep.chunks").exists()
        if attempt == "first":            # damage again, then --overwrite
            ex.compute(plan, store, range(plan.n_chunks))
            store.path(5).write_bytes(b"")


# --------------------------------------------------------------------------------------------------
# 16.6: a scheduler address where something else listens
# --------------------------------------------------------------------------------------------------


class _Quiet(BaseHTTPRequestHandler):
    def log_message(self, *args):
        pass


def test_http_server_as_scheduler_is_one_bounded_attempt(ws, monkeypatch):
    """An HTTP server on 127.0.0.1 as --scheduler hung for 200 s and more: now one attempt bounded
    by SCHEDULER_TIMEOUT (1 s here), one line, exit 2."""
    pytest.importorskip("distributed")
    from rockslide.engine import cluster

    monkeypatch.setattr(cluster, "SCHEDULER_TIMEOUT", 1.0)
    server = HTTPServer(("127.0.0.1", 0), _Quiet)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        (ws / "case.yaml").write_text(case_text(QUICK))
        address = f"tcp://127.0.0.1:{server.server_port}"
        result = invoke("sweep", "case.yaml", "--mu", "0.5", "--no-progress", "--scheduler", address)
    finally:
        server.shutdown()
    one_error_line(result, "--scheduler: no dask scheduler answered at", "within 1 s")
    assert not (ws / "out" / "example.sweep.h5").exists()


@posix
@pytest.mark.slow
def test_a_scheduler_that_dies_midway_is_one_line_and_the_chunks_stay(tmp_path, dask_scheduler):
    """A scheduler and a worker in their own processes; the scheduler is killed once the first chunk
    is stored: one line saying so (no distributed tracebacks), exit 2, the chunks kept."""
    dask_scheduler.start_worker()
    (tmp_path / "case.yaml").write_text((REPO / "configs" / "example.yaml").read_text().replace("../records/", ""))
    for name in SHIPPED:
        shutil.copy(REPO / "records" / name, tmp_path / name)
    proc = cli_subprocess(["sweep", "case.yaml", "--mu", "0.60:0.90:0.02", "--pga", "450gal:930gal:20gal",
                           "--restitution", "0.95", "--chunk-size", "8", "--no-plot", "--no-progress",
                           "--scheduler", dask_scheduler.address], tmp_path)
    deadline = time.monotonic() + 300
    while not list(tmp_path.glob("out/.example.sweep.chunks/*/chunk-*.npz")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no chunk was stored"
        time.sleep(0.02)
    dask_scheduler.process.kill()
    _, stderr = proc.communicate(timeout=120)
    lines = stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, stderr
    assert lines[0].startswith("rockslide: error: --scheduler: lost the connection to the dask scheduler")
    assert "chunks are kept" in lines[0]
    assert list(tmp_path.glob("out/.example.sweep.chunks/*/chunk-*.npz"))


# --------------------------------------------------------------------------------------------------
# 16.7 (12.6), 16.8: results published together and exclusively; a rerun finishes what is missing
# --------------------------------------------------------------------------------------------------


def test_no_plot_with_overwrite_removes_the_old_figure(ws):
    (ws / "case.yaml").write_text(case_text(QUICK))
    assert invoke("run", "case.yaml").exit_code == 0
    assert (ws / "out" / "example.png").exists()
    result = invoke("run", "case.yaml", "--no-plot", "--overwrite")
    assert result.exit_code == 0, result.output
    assert listing(ws / "out") == ["example.h5"]
    # without --overwrite, a figure without its result is refused rather than left beside a new one
    (ws / "out" / "example.h5").unlink()
    (ws / "out" / "example.png").write_bytes(b"an old figure")
    one_error_line(invoke("run", "case.yaml", "--no-plot"), "out/example.png exists")


def test_a_rerun_draws_the_missing_figure_of_a_complete_result(ws):
    (ws / "case.yaml").write_text(case_text(QUICK))
    assert invoke("run", "case.yaml", "--no-plot").exit_code == 0
    h5 = ws / "out" / "example.h5"
    before = sha256(h5)
    result = invoke("run", "case.yaml")
    assert result.exit_code == 0, result.output
    assert "the missing figure of the complete" in result.stdout
    assert sha256(h5) == before and (ws / "out" / "example.png").stat().st_size > 10_000
    # complete now: refused as usual; and a changed case is not this result
    one_error_line(invoke("run", "case.yaml"), "out/example.h5 exists")
    (ws / "out" / "example.png").unlink()
    (ws / "case.yaml").write_text(case_text({**QUICK, "contact.restitution": 0.7}))
    one_error_line(invoke("run", "case.yaml"), "out/example.h5 exists")


def test_a_sweep_stopped_in_its_final_phase_is_finished_by_a_rerun(ws):
    """The state a stop in the final phase left before: a complete NAME.sweep.h5, no PNG, its chunks.
    The same command draws the figure, removes the chunks and says so; the result is unchanged."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    assert _swept(ws / "out").exit_code == 0
    h5 = ws / "out" / "example.sweep.h5"
    before = sha256(h5)
    plan = sw.plan_sweep(load_case(ws / "case.yaml"), [sw.parse_axis("mu", GRID[1]), sw.parse_axis("pga", GRID[3])],
                         records_dir=ws, chunk_size=1)
    ex.compute(plan, chunks.ChunkStore.beside(h5, plan.key), [0, 1])
    result = invoke("sweep", "case.yaml", *GRID, "--chunk-size", "1", "--no-progress")
    assert result.exit_code == 0, result.output
    assert "is this sweep's complete result; drew its missing figure" in result.stdout
    assert sha256(h5) == before and (ws / "out" / "example.sweep.png").exists()
    assert not (ws / "out" / ".example.sweep.chunks").exists()
    one_error_line(invoke("sweep", "case.yaml", *GRID, "--chunk-size", "1", "--no-progress"),
                   "example.sweep.h5 exists")


#: One side of a publication race: stage NAME.h5 and NAME.png in the folder argv[1], each holding
#: the text argv[2]; say "staged"; publish the pair when a line arrives on standard input; print
#: "won", or the name of the exception that refused it.
RACER = """
import sys
from pathlib import Path
from rockslide.io import files
folder, tag = Path(sys.argv[1]), sys.argv[2]
staging = files.Staging(overwrite=False)
for suffix in (".h5", ".png"):
    Path(staging.stage(folder / f"same{suffix}")).write_text(tag)
print("staged", flush=True)
sys.stdin.readline()
try:
    staging.publish()
    print("won")
except Exception as exc:
    staging.discard()
    print(type(exc).__name__)
"""


@posix
def test_concurrent_publications_have_one_winner_and_no_mixed_pair(tmp_path):
    """20 rounds of two processes publishing a pair of files under the same names at the same
    instant (the publication `run` and `sweep` end with): exactly one wins each round, the other is
    refused, and both files are the winner's. (Two whole runs started together rarely meet in the
    window between a check and a rename: 6 of 40 pairs did. Here both have staged their files and
    wait on their standard input, which is written to both at once.) The racers are new
    interpreters, not forks of this one: other tests leave threads behind here (dask's offload
    thread), and a fork of a process with threads may deadlock in the child."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    for round_ in range(20):
        folder = tmp_path / str(round_)
        folder.mkdir()
        racers = {tag: subprocess.Popen([sys.executable, "-c", RACER, str(folder), tag], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, text=True, env=env) for tag in "ab"}
        try:
            for racer in racers.values():
                assert racer.stdout.readline().strip() == "staged"
            for racer in racers.values():
                racer.stdin.write("go\n")
                racer.stdin.flush()
            outcomes = {tag: racer.communicate(timeout=60)[0].strip() for tag, racer in racers.items()}
        finally:
            for racer in racers.values():
                if racer.poll() is None:
                    racer.kill()
                    racer.wait()
        winners = [tag for tag, what in outcomes.items() if what == "won"]
        assert len(winners) == 1 and set(outcomes.values()) == {"won", "OutputError"}, outcomes
        assert {(folder / n).read_text() for n in ("same.h5", "same.png")} == set(winners)
        assert sorted(os.listdir(folder)) == ["same.h5", "same.png"]


# --------------------------------------------------------------------------------------------------
# 16.10: temporary files of killed runs
# --------------------------------------------------------------------------------------------------


#: A process that holds ``flock`` on the file argv[1] until its stdin closes, as the owner of a
#: temporary file does (`files.open_new`); it says "locked" once it holds it.
LOCK_HOLDER = ("import fcntl, os, sys; fd = os.open(sys.argv[1], os.O_RDONLY); fcntl.flock(fd, fcntl.LOCK_EX); "
               "print('locked', flush=True); sys.stdin.read()")


def hold_lock(path: Path) -> subprocess.Popen:
    """Start `LOCK_HOLDER` on ``path`` and return once it holds the lock (synchronised on its
    output, no sleep)."""
    holder = subprocess.Popen([sys.executable, "-c", LOCK_HOLDER, str(path)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "locked"
    return holder


def release_lock(holder: subprocess.Popen) -> None:
    holder.stdin.close()
    holder.wait(timeout=60)


@posix
def test_temporary_files_of_dead_processes_go_with_the_next_run(ws):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    out = ws / "out"
    out.mkdir()
    owned = out / f".example.h5.{dead.pid}.7.tmp"      # its owner lives elsewhere: a recycled pid
    owned.write_bytes(b"x" * 1000)
    alive = hold_lock(owned)
    try:
        stale = [out / f".example.h5.{dead.pid}.tmp", out / f".example.png.{dead.pid}.tmp"]
        kept = [owned, out / f".other.h5.{dead.pid}.tmp", out / f".example.h5.{dead.pid}.notes"]
        for path in stale + kept[1:]:
            path.write_bytes(b"x" * 1000)
        (ws / "case.yaml").write_text(case_text(QUICK))
        assert invoke("run", "case.yaml").exit_code == 0
        assert not any(p.exists() for p in stale) and all(p.exists() for p in kept)
        # and the chunk files of a killed sweep
        chunk_dir = out / ".example.sweep.chunks" / "0123456789abcdef"
        chunk_dir.mkdir(parents=True)
        (chunk_dir / f".chunk-000000.npz.{dead.pid}.140000000000.tmp").write_bytes(b"x")
        plan = sw.plan_sweep(load_case(ws / "case.yaml"), [sw.parse_axis("mu", "0.5")], records_dir=ws)
        store = chunks.ChunkStore(out / ".example.sweep.chunks", "0123456789abcdef" + plan.key[16:])
        assert [p.name for p in store.remove_stale_temporaries()] == [
            f".chunk-000000.npz.{dead.pid}.140000000000.tmp"]
    finally:
        release_lock(alive)


@posix
def test_a_temporary_of_another_pid_namespace_is_kept_while_its_owner_holds_its_lock(tmp_path):
    """Issue 28.4. A run in another container (another pid namespace) or on another host writes
    ``.x.h5.<pid>.<place>.tmp``: its pid may name a process here that is alive and unrelated, or
    none at all. The file is kept exactly as long as its owner holds the file's lock, whatever the
    pid says; once the lock is free it is removed. And a run's own temporaries are locked while it
    writes them: another process's cleaner leaves them alone."""
    foreign_place = (files.place_token() + 1) % 2**32
    unrelated_alive = os.getppid()                       # a live process that owns nothing here
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    target = tmp_path / "x.h5"
    temporaries_ = [tmp_path / f".x.h5.{unrelated_alive}.{foreign_place}.tmp",
                    tmp_path / f".x.h5.{gone.pid}.{foreign_place}.tmp"]
    for path in temporaries_:
        path.write_bytes(b"half a result")
    holders = [hold_lock(path) for path in temporaries_]
    try:
        assert files.remove_stale_temporaries([target]) == []
        assert all(path.exists() for path in temporaries_)
    finally:
        for holder in holders:
            release_lock(holder)
    assert sorted(files.remove_stale_temporaries([target])) == sorted(temporaries_)
    # this process's own temporary, open and locked: a cleaner in another process keeps it
    with files.open_new(files.temporary_path(target)) as handle:
        handle.write(b"being written")
        script = ("import sys; from pathlib import Path; from rockslide.io import files; "
                  "print(len(files.remove_stale_temporaries([Path(sys.argv[1])])))")
        other = subprocess.run([sys.executable, "-c", script, str(target)], capture_output=True, text=True,
                               env={**os.environ, "PYTHONPATH": str(REPO)}, timeout=120)
        assert other.stdout.strip() == "0", other.stderr
        assert files.temporary_path(target).exists()
    files.remove_quietly(files.temporary_path(target))
    assert not list(tmp_path.glob(".*.tmp"))


# --------------------------------------------------------------------------------------------------
# 16.11: absurd work is said before it starts
# --------------------------------------------------------------------------------------------------


@posix
def test_a_run_of_hours_says_so_before_it_starts_and_stops_on_ctrl_c(ws):
    """dt = 2e-9 s on the 20 s synthetic record with a 2 s tail: 1.1e10 steps. The estimate comes
    before any computing; Ctrl-C then stops the run at its first kernel chunk."""
    (ws / "case.yaml").write_text(case_text({"solver.dt": 2e-9, "output.interval": "10 ms"}))
    proc = cli_subprocess(["run", "case.yaml", "--no-plot"], ws,
                          preexec_fn=_default_sigint)
    try:
        line = proc.stderr.readline()
        assert line.startswith("rockslide: note: 1.1e+10 integration steps"), line
        assert "up to about" in line and " h" in line
        proc.send_signal(signal.SIGINT)
        _, rest = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, rest
    assert rest.splitlines()[-1] == "rockslide: interrupted (no partial result was written)"


def test_a_step_too_coarse_for_the_block_is_warned(ws):
    """A 1 nm block at the default 0.1 ms (p dt = 11: it was reported as 'flight', while dt <= 0.01
    ms gives overturning): a warning with the step to use."""
    (ws / "case.yaml").write_text(case_text({"block": {"height": "1e-9 m", "width": "0.5e-9 m", "mass": "1 kg"},
                                             "ground.tail": "0 s"}))
    result = invoke("run", "case.yaml", "--no-plot")
    assert result.exit_code == 0, result.output
    (line,) = result.stderr.splitlines()
    assert line.startswith("rockslide: warning: case.yaml: solver.dt: the step 0.0001 s is too coarse")
    assert "p dt = 11.5 > 0.1" in line and "use dt <= 8.7e-07 s" in line


def test_absurd_scale_is_warned_and_the_work_of_a_large_sweep_is_said(ws, monkeypatch):
    (ws / "case.yaml").write_text(horizontal_only("synthetic_kt_h.at2", **QUICK,
                                                  **{"ground.scale": {"pga_horizontal": "1000 g"}}))
    result = invoke("run", "case.yaml", "--no-plot")
    assert result.exit_code == 0, result.output
    assert "the scaled ground motion reaches 1000 g (above 10 g)" in result.stderr
    monkeypatch.setattr(ex, "STEPS_PER_SECOND", 1.0)          # as if the machine were very slow
    monkeypatch.setattr(sw, "PLAN_SECONDS_PER_POINT", 10.0)
    result = invoke("sweep", "case.yaml", "--mu", "0.4,0.5", "--no-progress", "--no-plot")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == "sweep example: checking the 2 points of the grid first (about 20 s)"
    assert "  up to 2e+04 integration steps per case (far fewer for cases at rest or overturned): the progress "\
           "bar shows the time left" in lines
    assert result.stderr.count("above 10 g") == 1                # once for the grid


def test_workers_are_checked_before_planning(ws, monkeypatch):
    def no_planning(*args, **kwargs):
        raise AssertionError("planned before checking --workers")

    monkeypatch.setattr(sw, "plan_sweep", no_planning)
    (ws / "case.yaml").write_text(case_text(QUICK))
    one_error_line(invoke("sweep", "case.yaml", "--mu", "0:1:0.001", "--pga", "1gal:1000gal:1gal", "--workers", "0"),
                   "--workers: must be within 1")


# --------------------------------------------------------------------------------------------------
# 16.12: smaller ones
# --------------------------------------------------------------------------------------------------


def test_tilde_in_output_dir_is_the_home_folder(ws, monkeypatch):
    monkeypatch.setenv("HOME", str(ws / "home"))
    (ws / "case.yaml").write_text(case_text({**QUICK, "output.dir": "~/results"}))
    result = invoke("run", "case.yaml", "--no-plot")
    assert result.exit_code == 0, result.output
    assert (ws / "home" / "results" / "example.h5").exists() and not (ws / "~").exists()


# --------------------------------------------------------------------------------------------------
# 16.9: no input within the validated ranges gives a non-finite summary
# --------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def finite_base(tmp_path_factory):
    """The example with its horizontal record only (no flight from the vertical), no tail."""
    folder = tmp_path_factory.mktemp("finite")
    for name in SHIPPED:
        shutil.copy(REPO / "records" / name, folder / name)
    (folder / "case.yaml").write_text(horizontal_only("synthetic_kt_h.at2", **{"ground.tail": "0 s"}))
    return load_case(folder / "case.yaml")


def log_uniform(low, high):
    return st.floats(math.log10(low), math.log10(high)).map(lambda e: 10.0 ** e)


@settings(deadline=None, max_examples=30, suppress_health_check=[HealthCheck.too_slow])
@given(height=log_uniform(*runner.LENGTH_RANGE), slender=log_uniform(1e-3, 1e3),
       mass=log_uniform(*runner.MASS_RANGE), gravity=log_uniform(*runner.GRAVITY_RANGE),
       pga_in_g=log_uniform(1e-6, runner.MAX_ACCELERATION_IN_G), mu=log_uniform(1e-6, 1e6),
       restitution=st.floats(0.0, 1.0), dt=st.sampled_from(["1 ms", "0.1 ms"]),
       rate=st.one_of(st.just(0.0), log_uniform(1e-6, runner.MAX_INITIAL_RATE)))
@example(height=1.0, slender=1.0, mass=1.0, gravity=0.1, pga_in_g=1e6, mu=1.0, restitution=0.0, dt="1 ms",
         rate=0.0)    # found by a random draw: scaled to the bound itself, the peak rounded above it
def test_every_summary_number_is_finite_within_the_validated_ranges(finite_base, height, slender, mass,
                                                                     gravity, pga_in_g, mu, restitution, dt,
                                                                     rate):
    """Corners and interiors of the validated box (log-uniform): sizes 1e-12 to 1e6 m, masses 1e-20
    to 1e20 kg, gravity 1e-3 to 1e3 m/s^2, ground motion up to 1e6 g, any friction, initial rates up
    to 1e6: the summary is finite (a verdict, or an outcome outside the model), never NaN."""
    width = min(max(height * slender, runner.LENGTH_RANGE[0]), runner.LENGTH_RANGE[1])
    case = case_with(finite_base, {"block.height": height, "block.width": width, "block.mass": mass,
                                   "gravity": gravity, "ground.scale.pga_horizontal": pga_in_g * gravity,
                                   "contact.mu_static": mu, "contact.mu_kinetic": mu,
                                   "contact.restitution": restitution, "solver.dt": dt,
                                   "initial.slip_rate": rate})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")              # a step too coarse, an absurd scale: not the point
        _, result = runner.run_case(case, history=False)
    s = result.summary
    numbers = [s.max_rotation, s.max_rotation_time, s.max_slip, s.residual_slip, s.end_time,
               *s.time_in_state.values(), *s.energy.values()]
    assert all(math.isfinite(x) for x in numbers), s
    assert s.status in ("ok", "flight", "painleve")


def test_the_promises_quote_the_bounds_in_force():
    """The promises (docs/guide/promises.md) state the bounds the code enforces (a change of one shows here)."""
    from rockslide import case as case_module

    def short(x: float) -> str:
        return f"{x:.0e}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")

    readme = " ".join((REPO / "docs" / "guide" / "promises.md").read_text().split())
    quoted = [f"at most {short(runner.MAX_ACCELERATION_IN_G)} g",
              f"{short(runner.LENGTH_RANGE[0])} m to {short(runner.LENGTH_RANGE[1])} m",
              f"mass {short(runner.MASS_RANGE[0])} kg to {short(runner.MASS_RANGE[1])} kg",
              f"gravity {short(runner.GRAVITY_RANGE[0])} to {short(runner.GRAVITY_RANGE[1])} m/s^2",
              f"at most {case_module.MAX_CASE_BYTES // 1024} KiB",
              f"at most {case_module.MAX_YAML_NODES:,} YAML values".replace(",", " "),
              f"at most {case_module.MAX_YAML_DEPTH} levels", f"{case_module.MAX_NAME_LENGTH} characters",
              f"above `p dt` = {runner.MAX_P_DT:g}"]
    for text in quoted:
        assert text in readme, text


def test_docs_promises_quote_the_bounds_in_force():
    """docs/guide/promises.md states the bounds of issue 28 the code enforces (a change of one shows here)."""
    from rockslide.analyses import fragility
    from rockslide.api import tools
    from rockslide.cli import run as run_command
    from rockslide.io import records

    page = " ".join((REPO / "docs" / "guide" / "promises.md").read_text().split())
    quoted = [f"1 GiB ({records.MAX_RECORD_BYTES} bytes, `records.MAX_RECORD_BYTES`)",
              f"{records.MAX_TEXT_NUMBERS:.0e} numbers (`records.MAX_TEXT_NUMBERS`)".replace("e+0", "e"),
              f"{fragility.MAX_SUITE_SAMPLES:.0e} ground samples".replace("e+0", "e"),
              f"{tools.MAX_CRITERIA_PANELS} values (one panel each)",
              f"+-{run_command.MAX_TIME_SHIFT:.0e} s".replace("e+0", "e"),
              f"1 MiB ({results.MAX_ATTRIBUTE_BYTES} bytes, `results.MAX_ATTRIBUTE_BYTES`)",
              f"{results.MAX_RESULT_ROWS:.0e} rows or values".replace("e+0", "e"),
              f"every {files.LOCK_RETRY * 1000:.0f} ms (`files.LOCK_RETRY`)"]
    for text in quoted:
        assert text in page, text


@pytest.mark.parametrize("command", ["info", "run"])
def test_a_reader_that_goes_away_ends_the_command_quietly(ws, command):
    """``rockslide info r.at2 | head -1``: when standard output's reader has gone, the command stops
    with 141 (128 + SIGPIPE), as Unix tools do, and says nothing (it used to call the closed pipe an
    internal error, exit 1); a run's result, published before its summary is printed, is complete."""
    args = (["info", REPO / "records" / SHIPPED[0]] if command == "info"
            else ["run", REPO / "configs" / "example.yaml", "--no-plot", "--out-dir", ws / "out"])
    read, write = os.pipe()
    os.close(read)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    try:
        done = subprocess.run([sys.executable, "-m", "rockslide", *map(str, args)], cwd=ws, env=env,
                              stdout=write, stderr=subprocess.PIPE, text=True, timeout=300)
    finally:
        os.close(write)
    assert (done.returncode, done.stderr) == (141, "")
    if command == "run":
        assert results.read_result(ws / "out" / "example.h5").result.summary.status == "ok"


@pytest.mark.slow
def test_a_damaged_numba_cache_is_removed_and_compiled_again(ws, tmp_path):
    """A truncated cache file of the batch kernel (a full disk, a killed compile, a flipped
    byte) made every sweep fail for good with an internal error; now the sweep says so in one note,
    removes the core's cache, compiles it again and succeeds, and the next sweep loads the new cache.
    The cache lives in a folder of the test's own (NUMBA_CACHE_DIR), so the project's stays as it is.
    The sweeps run as on an installation without the build's machine code (`native.ahead_of_time`
    None: no C compiler at install, or an edited core), where every study computes on numba's JIT."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    cache = tmp_path / "numba-cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": os.pathsep.join(
        [str(REPO), os.environ.get("PYTHONPATH", "")])}
    env.pop("ROCKSLIDE_RECORDS", None)

    def sweep():
        code = ("import sys\nfrom rockslide.core import native\nnative.ahead_of_time = lambda: None\n"
                "from rockslide.cli import main\nmain(sys.argv[1:], prog_name='rockslide')\n")
        return subprocess.run([sys.executable, "-c", code, "sweep", "case.yaml", "--mu", "0.3,0.5", "--overwrite",
                               "--no-plot", "--no-progress"], cwd=ws, env=env, capture_output=True, text=True,
                              timeout=900)

    first = sweep()
    assert first.returncode == 0, first.stderr
    damaged = sorted(cache.rglob("batch.run_batch-*.nbc"))
    assert damaged, "the batch kernel was not cached where NUMBA_CACHE_DIR says"
    for path in damaged:
        path.write_bytes(path.read_bytes()[:100])
    repaired = sweep()
    assert repaired.returncode == 0, repaired.stderr
    assert "numba's cache of the core could not be read" in repaired.stderr and "Traceback" not in repaired.stderr
    again = sweep()
    assert again.returncode == 0 and "could not be read" not in again.stderr and "compiling" not in again.stderr


# --------------------------------------------------------------------------------------------------
# Issue 28.3: no wait that a signal cannot end
# --------------------------------------------------------------------------------------------------


def stderr_line_with(proc: subprocess.Popen, text: str) -> str:
    """The first line of ``proc``'s stderr that holds ``text`` (read as it comes: the test waits
    for what the process says, not for time to pass), or the last line read if it ended first."""
    line = proc.stderr.readline()
    while line and text not in line:
        line = proc.stderr.readline()
    return line


def communicate_or_kill(proc: subprocess.Popen, timeout: float = 300) -> tuple[str, str]:
    """``proc.communicate``; a process still running after ``timeout`` s is killed (the test then
    fails on its exit code, instead of hanging)."""
    try:
        return proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


@posix
@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_a_run_waiting_for_the_folders_lock_says_so_and_stops_on_a_signal(ws, signum, code):
    """Another process holds ``flock`` on the output folder (as a rockslide publishing there does):
    the run computes, says once that it waits and for which process, and a signal ends it with
    130/143, nothing published, no temporary left (it used to wait in ``flock`` until SIGKILL). The
    test waits for the note on stderr, not for time to pass."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    out = ws / "out"
    out.mkdir()
    holder = hold_lock(out)
    try:
        proc = cli_subprocess(["run", "case.yaml"], ws, preexec_fn=_default_sigint)
        note = stderr_line_with(proc, "waiting for")
        assert "waiting for another process publishing in out" in note, note
        assert f"process {holder.pid}" in note
        proc.send_signal(signum)
        _, rest = communicate_or_kill(proc, 120)
        assert proc.returncode == code, rest
        assert listing(out) == []
    finally:
        release_lock(holder)


@posix
def test_threads_of_one_process_publish_in_turn_without_a_note(tmp_path, monkeypatch, capsys):
    """Two threads of one process publishing in one folder (a sweep's chunks) wait for each other on
    a lock of the process, silently: ``flock`` alone set them apart as two processes, and the second
    said 'waiting for another process' (11 times in a 10^6-case sweep) and slept 50 ms. The test
    holds the folder in one thread and lets the other reach its wait (signalled by the wait's own
    check for Ctrl-C), then frees it."""
    from rockslide.io import files

    waiting = threading.Event()
    checked = interrupts.check
    monkeypatch.setattr(interrupts, "check", lambda: (waiting.set(), checked())[1])
    done = []

    def second():
        with files.folder_locks([tmp_path]):
            done.append(True)

    with files.folder_locks([tmp_path]):
        thread = threading.Thread(target=second)
        thread.start()
        assert waiting.wait(60), "the second thread never waited"
        assert not done
    thread.join(60)
    assert done == [True]
    assert "waiting for" not in capsys.readouterr().err


@posix
def test_a_run_publishes_once_the_folders_lock_is_free(ws):
    (ws / "case.yaml").write_text(case_text(QUICK))
    out = ws / "out"
    out.mkdir()
    holder = hold_lock(out)
    proc = cli_subprocess(["run", "case.yaml", "--no-plot"], ws)
    try:
        assert "waiting for" in stderr_line_with(proc, "waiting for")
    finally:
        release_lock(holder)
    _, rest = communicate_or_kill(proc, 120)
    assert proc.returncode == 0, rest
    assert listing(out) == ["example.h5"]


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


@posix
@pytest.mark.parametrize("args, made, expected", [
    (["run", "case.fifo"], lambda ws: _fifo(ws / "case.fifo"), "case.fifo: is a FIFO (named pipe), not a regular "
                                                               "file; expected a case file"),
    (["run", "case.yaml"], lambda ws: (ws / "case.yaml").write_text(horizontal_only("rec.at2", **QUICK))
     and _fifo(ws / "rec.at2"), "is a FIFO (named pipe), not a regular file; expected a record file"),
    (["info", "rec.txt", "--dt", "0.01", "--units", "g"], lambda ws: _fifo(ws / "rec.txt"),
     "rec.txt: is a FIFO (named pipe), not a regular file; expected a record file"),
    (["plot", "fifo.h5"], lambda ws: _fifo(ws / "fifo.h5"),
     "fifo.h5: is a FIFO (named pipe), not a regular file; expected a result file"),
    (["info", "fifo.h5"], lambda ws: _fifo(ws / "fifo.h5"), "fifo.h5: is a FIFO (named pipe)"),
    (["run", "/dev/zero"], lambda ws: None, "/dev/zero: is a character device, not a regular file"),
], ids=["case", "record-of-a-case", "record", "plot-result", "info-result", "device-as-case"])
def test_a_fifo_or_device_given_as_input_is_refused_without_opening_it(ws, args, made, expected):
    """Reading a FIFO without a writer blocked in ``open``, deaf to SIGINT and SIGTERM; a device
    never ends. Now: one line, exit 2, at once (a subprocess with a time limit, so that a
    regression fails instead of hanging the suite)."""
    made(ws)
    proc = cli_subprocess(args, ws)
    _, stderr = communicate_or_kill(proc, 120)
    lines = stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, stderr
    assert expected in lines[0]


# --------------------------------------------------------------------------------------------------
# Issue 28.5: inputs bounded before they are read, in one line naming the bound
# --------------------------------------------------------------------------------------------------


def test_a_20_gb_sparse_record_is_refused_before_a_byte_is_read(ws):
    """The size on the file system (st_size) is checked first: a sparse 20 GB file costs nothing
    to make and was read whole."""
    from rockslide.io import records

    with open(ws / "huge.txt", "wb") as handle:
        handle.truncate(20 * 2**30)
    line = one_error_line(invoke("info", "huge.txt", "--dt", "0.01", "--units", "g"))
    bound = records.MAX_RECORD_BYTES
    assert f"huge.txt: the record file has {20 * 2**30} bytes; rockslide reads at most {bound}" in line


def test_text_that_is_not_plain_numbers_is_counted_before_it_is_parsed(ws, monkeypatch):
    """Column text (two numbers and a comma on a line) goes through the general reader, which
    keeps each number as a string: its numbers are counted on the bytes first and refused above
    the bound (lowered here to 1000: the file has 2 x 2000 numbers). Plain values of the same count
    are read by the linear reader, whatever that bound."""
    from rockslide.io import records

    monkeypatch.setattr(records, "MAX_TEXT_NUMBERS", 1000)
    (ws / "columns.csv").write_text("".join(f"{0.01 * i:.2f},{0.001 * (i % 7):.3f}\n" for i in range(2000)))
    line = one_error_line(invoke("info", "columns.csv", "--units", "g"))
    assert "about 4e+03 numbers in text with comments, commas" in line and "at most 1e+03 such numbers" in line
    (ws / "values.txt").write_text("".join(f"{0.001 * (i % 7):.3f}\n" for i in range(2000)))
    done = invoke("info", "values.txt", "--dt", "0.01", "--units", "g")
    assert done.exit_code == 0 and "samples   2000, dt = 0.01 s" in done.stdout, done.output


def test_a_suite_listing_one_record_many_times_is_bounded_before_any_run(ws, monkeypatch):
    """An 18 KB suite listing one long record 400 times ran for minutes, then failed: a record listed
    twice is now refused before any record is read, and the suite's samples together are bounded as
    its records are read (the bound lowered here to 1.5 times a record's samples: the second entry
    passes it)."""
    from rockslide.analyses import fragility
    from rockslide.io import records

    (ws / "case.yaml").write_text(case_text(QUICK))
    reads = []
    real = records.load_record
    monkeypatch.setattr(records, "load_record", lambda *a, **k: reads.append(a) or real(*a, **k))
    (ws / "suite.yaml").write_text("records:\n" + "".join(
        f"  - {{name: r{i}, horizontal: synthetic_kt_h.at2}}\n" for i in range(400)))
    line = one_error_line(invoke("fragility", "case.yaml", "--suite", "suite.yaml", "--levels", "0.5g",
                                 "--no-plot", "--records-dir", "."))
    assert "suite.yaml: records[1] (r1) is records[0] (r0) again" in line and reads == []
    samples = real(ws / "synthetic_kt_h.at2").data.size
    monkeypatch.setattr(fragility, "MAX_SUITE_SAMPLES", int(1.5 * samples))
    (ws / "suite.yaml").write_text("records:\n  - {name: h, horizontal: synthetic_kt_h.at2}\n"
                                   "  - {name: v, horizontal: synthetic_kt_v.at2}\n")
    line = one_error_line(invoke("fragility", "case.yaml", "--suite", "suite.yaml", "--levels", "0.5g",
                                 "--no-plot", "--records-dir", "."))
    assert "suite.yaml: the suite's records hold more than" in line and "reached at records[1], v, of 2" in line
    assert not (ws / "out").exists() or listing(ws / "out") == []


# --------------------------------------------------------------------------------------------------
# Issue 28.6: never a mixed set, never a false "damaged"
# --------------------------------------------------------------------------------------------------


def test_plot_publishes_nothing_when_a_run_replaced_the_result_while_it_drew(ws, monkeypatch):
    """``plot`` racing ``run --overwrite`` left the new ``.h5`` beside a figure of the old one.
    The race made deterministic: the moment ``plot`` has drawn, a run publishes a new result and
    figure. ``plot`` then publishes nothing (one line, exit 2) and the run's pair stays as it
    published it."""
    from rockslide import plots

    (ws / "case.yaml").write_text(case_text(QUICK))
    assert invoke("run", "case.yaml").exit_code == 0
    (ws / "other.yaml").write_text(case_text({**QUICK, "contact.mu_static": 0.8}))
    real_save = plots.save_figure

    def draw_then_a_run_publishes(*args, **kwargs):
        real_save(*args, **kwargs)
        monkeypatch.setattr(plots, "save_figure", real_save)
        other = cli_subprocess(["run", "other.yaml", "--overwrite"], ws)   # the same names: example.h5, .png
        _, stderr = other.communicate(timeout=300)
        assert other.returncode == 0, stderr

    monkeypatch.setattr(plots, "save_figure", draw_then_a_run_publishes)
    out = ws / "out"
    line = one_error_line(invoke("plot", out / "example.h5"), "example.h5: was replaced while its figure was drawn")
    assert "nothing was written" in line
    assert results.read_result(out / "example.h5").case["contact"]["mu_static"] == 0.8
    run_figure = sha256(out / "example.png")
    assert invoke("plot", out / "example.h5").exit_code == 0   # the figure of the new result: the run's
    assert sha256(out / "example.png") == run_figure
    assert temporaries(out) == []


@posix
@pytest.mark.parametrize("overwrite", [False, True], ids=["second-refused", "second-overwrites"])
def test_two_identical_sweeps_into_one_folder_run_one_after_the_other(ws, monkeypatch, overwrite):
    """Two identical sweeps 0.7 s apart: the second said "chunk 0 is missing or damaged" (false)
    and left chunk files. Made deterministic: the first holds the study's lock (as a running sweep
    does) while the second starts and says it waits; the first then computes and publishes (here,
    in this process, with the lock already held), and lets go. The second then refuses the result
    that now exists (or, with --overwrite, replaces it), never a false "damaged", and no chunk file
    is left."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    out = ws / "out"
    out.mkdir()
    lock = out / ".example.sweep.h5.lock"
    lock.touch()
    first = hold_lock(lock)
    try:
        second = cli_subprocess(["sweep", "case.yaml", *GRID, "--no-progress"] + (["--overwrite"] if overwrite else []),
                                ws)
        note = stderr_line_with(second, "waiting for")
        assert "waiting for another sweep writing out/example.sweep.h5" in note, note
        monkeypatch.setattr(files, "exclusive", lambda *a, **k: contextlib.nullcontext())   # the first holds it
        done = invoke("sweep", "case.yaml", *GRID, "--no-progress")
        assert done.exit_code == 0, done.output
        published = sha256(out / "example.sweep.h5")
    finally:
        lock.unlink()                          # as the first sweep does when it ends
        release_lock(first)
    stdout, stderr = communicate_or_kill(second)
    assert "missing or damaged" not in stdout + stderr
    if overwrite:
        assert second.returncode == 0, stderr
        assert results.read_sweep(out / "example.sweep.h5").attrs["sweep_key"]
    else:
        assert second.returncode == 2, stderr
        assert "example.sweep.h5 exists (use --overwrite to replace it)" in stderr
        assert sha256(out / "example.sweep.h5") == published
    assert listing(out) == ["example.sweep.h5", "example.sweep.png"]


@posix
@pytest.mark.skipif(os.name == "posix" and os.geteuid() == 0, reason="root reads and writes any folder")
@pytest.mark.parametrize("where", ["records", "output"])
def test_a_folder_without_permission_is_one_line(ws, where):
    """Permission denied on the record's folder or on the output folder: one line, exit 2."""
    locked = ws / "locked"
    locked.mkdir()
    shutil.copy(ws / "synthetic_kt_h.at2", locked / "rec.at2")
    record = "locked/rec.at2" if where == "records" else "synthetic_kt_h.at2"
    (ws / "case.yaml").write_text(horizontal_only(record, **QUICK))
    locked.chmod(0o000 if where == "records" else 0o500)
    try:
        args = ["run", "case.yaml"] + (["--out-dir", locked / "out"] if where == "output" else [])
        one_error_line(invoke(*args), "ermission denied")
    finally:
        locked.chmod(0o700)


@posix
def test_permission_denied_while_looking_for_a_record_names_the_case_field(ws, monkeypatch):
    """As root (where folders cannot be locked), the refusal of the system is injected where a
    record is looked for: one line naming the case's key, exit 2."""
    real_exists = Path.exists

    def exists(self, *args, **kwargs):
        if "locked" in str(self):
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        return real_exists(self, *args, **kwargs)

    monkeypatch.setattr(Path, "exists", exists)
    (ws / "case.yaml").write_text(horizontal_only("locked/rec.at2", **QUICK))
    one_error_line(invoke("run", "case.yaml"), "case.yaml: ground.horizontal.file: cannot look for the record file",
                   "Permission denied")
