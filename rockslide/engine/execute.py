"""Computing a plan: threads, an NVIDIA GPU or a dask.distributed cluster; progress and Ctrl-C.

`compute` computes given chunks of a `plan.Plan` and stores each as it is done (`chunks.ChunkStore`
or `chunks.MemoryStore`); `execute` is the whole orchestration every analysis uses: what a store
already holds is reused, the free space is checked, the kernel compiled (and said so), a progress
callback called, and the final states of every case returned.

- **Where.** Locally on a pool of threads, one chunk per task (the build's machine code case by
  case, which releases the GIL, without loading numba; numba's batch driver where the build has
  none: `local_kernel`; a thread takes the next chunk as soon as it is done), or on a
  dask.distributed cluster: one task per chunk (`batch.compute`) returning plain numpy arrays.
  All give identical results. Or on
  an NVIDIA GPU (``device="gpu"``, the optional extra ``rockslide[gpu]``: `core.gpu`, the same
  kernel compiled for the device), many chunks per launch (`DEVICE_CASES_PER_LAUNCH`); the device
  may round the last bits differently (fused multiply-adds).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .. import interrupts
from ..core import layout as L
from ..core import local_threads
from ..errors import CaseError, exception_text
from .chunks import ChunkStore, MemoryStore, collect, missing_chunks
from .cluster import (  # noqa: F401  (the cluster's names, used here and re-exported: `execute.find_scheduler`...)
    MAX_WAIT_WORKERS,
    STALL_FACTOR,
    STALL_SECONDS,
    TLS_OPTIONS,
    Scheduler,
    check_workers_match,
    cold_workers_note,
    compute_chunk,
    compute_dask,
    find_scheduler,
    local_identity,
    worker_identity,
)
from .plan import Plan, bytes_needed
from .prepare import STEPS_PER_SECOND


def compute(plan: Plan, store: ChunkStore, chunks: Sequence[int], *, workers: int | None = None,
            scheduler: str | Scheduler | None = None, progress: Callable[[int], None] | None = None,
            device: str = "cpu", wait_workers: float | None = None,
            report: Callable[[str], None] | None = None, out: np.ndarray | None = None) -> bool:
    """Compute ``chunks`` of ``plan`` and store each as soon as it is done.

    Parameters
    ----------
    plan : Plan
    store : ChunkStore
        Where finished chunks go.
    chunks : sequence of int
        The chunks to compute (the missing ones).
    workers : int, optional
        Threads for the local run (default: all cores).
    scheduler : str or Scheduler, optional
        A dask.distributed scheduler (its address, or `find_scheduler`'s `Scheduler`): the chunks
        are computed there, one task each.
    progress : callable, optional
        Called with the number of cases of each finished chunk.
    device : {"cpu", "gpu"}
        Where a local run computes (`DEVICES`): the CPU's cores, or an NVIDIA GPU (`core.gpu`).
    wait_workers : float, optional
        [s] How long ``scheduler`` may have no worker before the first joins (default
        `WAIT_FOR_WORKERS`).
    report : callable, optional
        Called with a note for the user (that it waits for a worker).
    out : float64[n, N_STATE], optional
        The final states of every case of the plan: a local run (CPU or GPU) also puts the states
        it computes there, so that they need not be read back from ``store``.

    Returns
    -------
    bool
        Whether ``out`` holds the states of ``chunks`` (a local run given ``out``).

    Raises
    ------
    CaseError
        ``workers`` out of range, the scheduler cannot be reached, has no worker in time, its
        workers run another rockslide (`check_workers_match`), it or all its workers are lost, or a
        task fails there (the chunks finished before are stored), or no GPU can be used
        (`check_device`).
    interrupts.Interrupted
        After Ctrl-C or SIGTERM, checked between chunk groups; the chunks finished before it are
        stored.
    """
    check_device(device)
    if scheduler:
        stall = max(STALL_SECONDS, STALL_FACTOR * work_estimate(plan, plan.chunk_size, workers=1))
        compute_dask(plan, store, chunks, scheduler, progress, wait_workers,
                     report if report is not None else (lambda text: None), stall)
    elif device == "gpu":
        _compute_device(plan, store, chunks, progress, out)
    else:
        _compute_local(plan, store, chunks, workers, progress, out)
    return not scheduler and out is not None


#: Where a local sweep computes (``--device``): ``auto`` is the GPU when one is usable and the study
#: is big enough to pay (`choose_device`), else the CPU.
DEVICES = ("cpu", "gpu", "auto")
#: ``--device auto`` takes the GPU from this many cases on. Measured on one H100 against its 16 CPU
#: cores (README, 'GPU'): 0.81x at 4096 rocking-heavy cases, 10.4x at 40000, 0.14x on a 270-run
#: fragility grid; the GPU overtakes 16 cores near 5000 rocking cases, and 10^4 leaves a margin
#: for studies where many cases rest (cheap on the CPU as well).
AUTO_GPU_CASES = 10_000


#: Cases per launch of the GPU kernel. A launch ends with its slowest warps while the rest of the
#: device idles, and the kernel's 255 registers a thread leave room for some 34000 resident threads
#: on an H200 (132 multiprocessors): launches of several such waves waste less of their tail.
#: Measured on lent H200s (2026-11-29, 10^6 rocking cases at ``dt: auto``, host and device
#: overlapped; results/bench_gpu.md): 2^16 cases a launch 7.3 s, 2^17 5.5 s, 2^18 4.8-5.3 s, 2^19
#: 5.1 s, one launch of 2^20 5.4 s (its inputs made before, its chunks stored after the device's
#: work). Few enough for the progress bar and Ctrl-C to come every launch (about a second there).
DEVICE_CASES_PER_LAUNCH = 1 << 18


def check_device(device: str) -> None:
    """Refuse a ``--device`` that is not one of `DEVICES`, or ``gpu`` where no GPU run can be made
    (numba-cuda not installed, no CUDA GPU or driver), with one line saying why."""
    if device not in DEVICES:
        raise CaseError(f"must be one of {', '.join(DEVICES)}, got {device!r}", source="device")
    if device == "gpu":
        from ..core import gpu
        try:
            gpu.require_device()
        except gpu.DeviceUnavailable as exc:
            raise CaseError(str(exc), source="device") from None


def choose_device(device: str, n_cases: int) -> tuple[str, str]:
    """Where ``--device`` (`DEVICES`) computes ``n_cases`` cases, and why (for ``auto``; "" else).

    ``auto`` is the GPU when numba-cuda finds one (numba's CUDA simulator is not one) and the study
    has at least :data:`AUTO_GPU_CASES` cases; else the CPU's cores.
    """
    if device != "auto":
        return device, ""
    from ..core import gpu
    try:
        gpu.require_device()
    except gpu.DeviceUnavailable as exc:
        return "cpu", f"no usable GPU: {exc}"
    if gpu.cuda_simulator():
        return "cpu", "numba's CUDA simulator is on, not a GPU"
    if n_cases < AUTO_GPU_CASES:
        return "cpu", f"{n_cases} cases; the GPU pays from about {AUTO_GPU_CASES}"
    return "gpu", f"{n_cases} cases, enough to fill it"


def _compute_device(plan, store, chunks, progress, out=None):
    """The chunks on the GPU (`core.gpu`), as many per launch as fit in `DEVICE_CASES_PER_LAUNCH`
    cases (at least one; the device sorts a launch's cases by work); each chunk of a launch is
    stored, and put in ``out`` if given, when the launch is done.

    The host works while the device computes: the next launch is prepared (`gpu.prepare`: its order
    by work, its inputs) before the running one is waited for, and the finished launch's chunks are
    stored after the next one has started, so that the device waits only for the copies between two
    launches. Ctrl-C lets the launch in flight finish and be stored."""
    from ..core import gpu

    running = None      # (chunks, their case indices, the launch on the device)
    for group in _launch_groups(plan, chunks):
        if interrupts.requested() is not None:
            break
        parts = [plan.chunk_indices(c) for c in group]
        prepared = gpu.prepare(*_chunk_inputs(plan, np.concatenate(parts)))
        finished = None if running is None else (*running[:2], running[2].result())
        running = (group, parts, gpu.Launch(*prepared))
        if finished is not None:
            _store_launch(store, progress, out, *finished)
    if running is not None:
        _store_launch(store, progress, out, *running[:2], running[2].result())
    interrupts.check()


def _launch_groups(plan, chunks):
    """``chunks`` in consecutive groups of at most `DEVICE_CASES_PER_LAUNCH` cases (at least one
    chunk each): the launches of `_compute_device`."""
    group: list[int] = []
    cases = 0
    for chunk in chunks:
        size = plan.chunk_indices(chunk).size
        if group and cases + size > DEVICE_CASES_PER_LAUNCH:
            yield group
            group, cases = [], 0
        group.append(chunk)
        cases += size
    if group:
        yield group


def _store_launch(store, progress, out, group, parts, final):
    """A finished launch's chunks stored (and put in ``out`` if given), then counted in ``progress``."""
    for c, indices, part in zip(group, parts, np.split(final, np.cumsum([p.size for p in parts])[:-1]),
                                strict=True):
        store.save(c, indices, part)
        if out is not None:
            out[indices] = part
    if progress is not None:
        progress(sum(p.size for p in parts))


def device_chunks(plan: Plan) -> Plan:
    """``plan`` chunked for the GPU: chunks of up to a launch each (`DEVICE_CASES_PER_LAUNCH`
    cases, as evenly as the cases divide), or the plan's own if larger. A chunk is a file of the
    store, and the CPU's chunks of 256 cases made the host write 3911 files for 10^6 cases (3.6 s
    of its 13 s beside the device). The plan's key stays: the device's store is keyed apart
    (`chunks.ChunkStore.for_device`) and this chunking follows from the plan."""
    launches = max(1, -(-plan.n_cases // DEVICE_CASES_PER_LAUNCH))
    size = max(plan.chunk_size, -(-plan.n_cases // launches))
    return plan if size == plan.chunk_size else replace(plan, chunk_size=size)


def check_workers(workers: int | None) -> None:
    """Refuse a ``--workers`` outside ``1 ... 4 x the cores`` (before any planning)."""
    if workers is None:
        return
    limit = 4 * local_threads()
    if isinstance(workers, bool) or not 1 <= int(workers) <= limit:
        raise CaseError(f"must be within 1 ... {limit} (4 threads per core here), got {workers!r}",
                        source="workers")


def _compute_local(plan, store, chunks, workers, progress, out=None):
    """The chunks on a pool of threads running the compiled kernel (`local_kernel`, which releases
    the GIL), one chunk at a time: each thread takes the next chunk as soon as it is done, so cases
    that rock for a minute and cases at rest even out and every core is busy to the end. Each chunk
    is stored as soon as it is done; Ctrl-C is checked while waiting, and the chunks being computed
    are finished and kept. A failure in a thread is raised here once the others have finished their
    chunks.

    The pool is plain threads and a queue: `concurrent.futures` imports `logging`, 30-40 ms of a
    study's start on a 2-core machine (issue 41, item 4)."""
    import queue
    import threading

    check_workers(workers)
    threads = min(int(workers) if workers is not None else local_threads(), len(chunks))
    run = local_kernel()
    todo = iter(chunks)
    taking = threading.Lock()
    stop = threading.Event()
    finished = queue.SimpleQueue()   # a chunk's number of cases, a thread's exception, or None as it ends

    def work() -> None:
        try:
            while not stop.is_set() and interrupts.requested() is None:   # stopping: no new chunk
                with taking:
                    chunk = next(todo, None)
                if chunk is None:
                    break
                indices = plan.chunk_indices(chunk)
                states = run(*_chunk_inputs(plan, indices))
                store.save(chunk, indices, states)
                if out is not None:     # the chunks' cases are disjoint: the threads write apart
                    out[indices] = states
                finished.put(indices.size)
        except BaseException as exc:
            finished.put(exc)
        finally:
            finished.put(None)

    pool = [threading.Thread(target=work, name=f"rockslide-sweep-{i}") for i in range(threads)]
    for thread in pool:
        thread.start()
    try:
        running = len(pool)
        while running:
            interrupts.check()
            try:
                done = finished.get(timeout=0.2)
            except queue.Empty:
                continue
            if done is None:
                running -= 1
            elif isinstance(done, BaseException):
                raise done
            elif progress is not None:
                progress(done)
    finally:
        stop.set()
        for thread in pool:
            thread.join()
    interrupts.check()


def local_kernel() -> Callable:
    """What computes a chunk on each local thread (`batch.compute`'s arguments and result).

    Where the build's machine code is there (`native.is_ahead_of_time`), that code case by case
    (`simulate.compute_batch`; it releases the GIL while a case runs, so the threads compute side
    by side): numba is neither imported nor loaded, which was most of what a study cost beyond its
    compute (issue 41, item 4). Else numba's batch driver (`batch.compute`), which releases the
    GIL as well. The states are the same to the last bit. The build's code is for a generic CPU of
    its architecture: on the 2-core development machine it ran the Kobe grid 4 % slower than
    numba's driver compiled for this CPU (median of 5 alternations, -4 to +8 %), which a study
    repays by not loading numba (1.2-1.4 s) unless it computes for more than half a minute; the
    upper estimate of a study's time (`work_estimate`) is too coarse to choose by (253 s for the
    Kobe grid's 1.4 s)."""
    from ..core import native

    if native.is_ahead_of_time():
        from ..core.simulate import compute_batch
        return compute_batch
    from ..core import batch
    return batch.compute


def _chunk_inputs(plan: Plan, indices: np.ndarray):
    """`batch.compute`'s arguments for the cases ``indices`` (an index array, or a slice)."""
    return (plan.case_params(indices), plan.case_states(indices), plan.base, plan.first[indices],
            plan.count[indices], plan.factor_h[indices], plan.factor_v[indices])


def work_estimate(plan: Plan, n_cases: int, *, workers: int | None = None) -> float:
    """An upper estimate [s] of the time ``n_cases`` cases of ``plan`` take on this machine's
    threads (every case moving until the end; cases at rest go about 3000 times faster)."""
    threads = workers or local_threads()
    return n_cases * plan.steps_per_case / (STEPS_PER_SECOND * threads)


@dataclass
class Execution:
    """What `execute` did.

    Attributes
    ----------
    states : float64[n, N_STATE]
        The final kernel state of every case of the plan, in its flat order.
    computed : int
        Cases computed now (the others were in the store).
    seconds : float
        [s] Wall time spent computing them.
    store : ChunkStore or MemoryStore
        Where the chunks are (the caller removes an on-disk store once its result is written).
    chunks : int
        The plan's chunks as computed (the GPU's are larger: `device_chunks`).
    """

    states: np.ndarray
    computed: int
    seconds: float
    store: object
    chunks: int


def check_where(*, workers: int | None = None, scheduler=None, device: str = "cpu",
                wait_workers: float | None = None, tls: dict | None = None) -> Scheduler | None:
    """Refuse ``workers``, ``scheduler`` and ``device`` that do not go together, ``workers`` out of
    range, and ``device="gpu"`` where no GPU can be used, before any planning (one line each,
    naming the command-line option); then find the scheduler (`find_scheduler`: its address
    parsed, its TLS files read, the scheduler asked who it is), so that a mistyped or unreachable
    one is said before a long planning.

    ``scheduler``: an address, a `distributed.Client` or a cluster object (`find_scheduler`);
    ``tls``: the TLS files of `TLS_OPTIONS` given on the command line. Returns the `Scheduler`
    (whose ``str`` is its address), or None without one."""
    if isinstance(scheduler, str) and not scheduler:
        scheduler = None
    if workers is not None and scheduler is not None:
        raise CaseError("sets the local threads; with a scheduler the cluster's workers compute",
                        source="workers")
    if device == "gpu" and scheduler is not None:
        raise CaseError("with a scheduler the cluster's workers compute, on their CPUs", source="device")
    if wait_workers is not None and not 0.0 <= float(wait_workers) <= MAX_WAIT_WORKERS:
        raise CaseError(f"must be within 0 ... {MAX_WAIT_WORKERS:g} s, got {wait_workers!r}", source="wait_workers")
    if wait_workers is not None and scheduler is None:
        raise CaseError("is the wait for a dask cluster's first worker: give a scheduler with it",
                        source="wait_workers")
    given = [field for field, _, _ in TLS_OPTIONS if (tls or {}).get(field) is not None]
    if given and scheduler is None:
        raise CaseError("is for a TLS dask scheduler: give it with a scheduler tls://HOST:PORT", source=given[0])
    if device == "gpu" and workers is not None:
        raise CaseError("sets the CPU threads; on the device gpu the GPU computes", source="workers")
    check_workers(workers)
    check_device(device)
    return find_scheduler(scheduler, tls) if scheduler is not None else None


def execute(plan: Plan, store=None, *, workers: int | None = None, scheduler: str | None = None,
            device: str = "cpu", progress: Callable[[int], None] | None = None,
            report: Callable[[str], None] | None = None, what: str = "study", label: str = "",
            description: str = "", unit: str = "case", free_space_at: Path | None = None,
            shard: tuple[int, int] | None = None, wait_workers: float | None = None) -> Execution:
    """Compute what ``store`` does not hold yet of ``plan``, and return every case's final state.

    The one orchestration of every analysis: the chunks ``store`` holds are reused (a damaged one is
    computed again), the free space for the rest is checked, the kernel is compiled if it must be
    (said through ``report``), and ``progress`` is told of each finished chunk.

    Parameters
    ----------
    plan : Plan
    store : ChunkStore or MemoryStore, optional
        Where finished chunks go (default: a `MemoryStore`, nothing written to disk).
    workers, scheduler, device
        Where to compute (`compute`).
    progress : callable, optional
        Called with the number of cases of each finished chunk (and once with those reused).
    report : callable, optional
        Called with each note for the user (what is reused, a first compile, a long study).
    what, label, description, unit : str
        How the notes name the study (``"sweep"``, the case's name, ``"41 mu x 37 pga = 1517
        cases"``, ``"case"``).
    free_space_at : Path, optional
        The folder whose disk must hold the chunks and the result.
    shard : (int, int), optional
        ``(i, n)``: compute only the missing chunks whose number is ``i - 1`` modulo ``n`` (one of
        ``n`` processes sharing ``store``'s folder, e.g. a SLURM job array; `parse_shard`) and
        return no states: a run without ``shard`` collects them.
    wait_workers : float, optional
        [s] How long ``scheduler`` may wait for its first worker (`compute`).

    Returns
    -------
    Execution
        Its ``states`` are None with ``shard``.

    Raises
    ------
    CaseError
        As `compute`.
    OutputError
        Too little free space; a chunk vanished from the store meanwhile.
    interrupts.Interrupted
        Ctrl-C or SIGTERM: the chunks finished before are in ``store``; raised during the compute,
        it has ``store`` (the store they are in) and ``chunks`` (the plan's, as computed).
    """
    say = report if report is not None else (lambda text: None)
    store = MemoryStore(plan.key) if store is None else store.for_plan(plan.key)
    device, why = ("cpu", "") if scheduler else choose_device(device, plan.n_cases)
    store = store.for_device(device)
    if device == "gpu":
        plan = device_chunks(plan)
    if hasattr(store, "refuse_links"):
        store.refuse_links()
    store.remove_stale_temporaries()
    for other in store.others():
        say(f"  note: {other} holds chunks of another {what} definition or device (not used; delete it to free the "
            "space)")
    final = None if shard is not None else np.empty((plan.n_cases, L.N_STATE))
    missing = missing_chunks(plan, store, final)          # each stored chunk read once
    for chunk, reason in sorted(store.damaged.items()):
        say(f"  note: {store.path(chunk)} cannot be used ({reason}); computing it again")
    reused = plan.n_chunks - len(missing)
    reused_cases = plan.n_cases - sum(plan.chunk_indices(c).size for c in missing)
    all_missing = missing
    if shard is not None:
        missing = [c for c in missing if c % shard[1] == shard[0] - 1]
    computed = sum(plan.chunk_indices(c).size for c in missing)
    where = (f"on the dask scheduler {scheduler}" if scheduler else
             "on this machine's GPU" if device == "gpu" else "on this machine")
    where += f" (--device auto: {why})" if why else ""
    if description:
        say(f"{what} {label}: {description} in {plan.n_chunks} chunk{'s' if plan.n_chunks != 1 else ''}, {where}")
    if reused:
        say(f"  reused {reused} of {plan.n_chunks} chunks ({reused_cases} {unit}s) from {store.folder}")
    if shard is not None:
        say(f"  shard {shard[0]}/{shard[1]}: {len(missing)} of the {len(all_missing)} chunks still missing (those "
            f"numbered {shard[0] - 1} modulo {shard[1]}); the same command without --shard collects them all")
    if work_estimate(plan, computed, workers=workers) > 60:
        say(f"  up to {plan.steps_per_case:.3g} integration steps per {unit} (far fewer for {unit}s at rest "
            "or overturned): the progress bar shows the time left")
    if free_space_at is not None:
        from ..io import files
        files.require_free_space(Path(free_space_at), bytes_needed(plan, len(missing)), f"the {what}")
    if not scheduler and missing and not on_machine_code(device):
        warm_up(device, say)
    if progress is not None and plan.n_cases > computed:
        progress(plan.n_cases - computed)
    started = time.perf_counter()
    try:
        held = compute(plan, store, missing, workers=workers, scheduler=scheduler, progress=progress,
                       device=device, wait_workers=wait_workers, report=say, out=final)
    except interrupts.Interrupted as exc:
        exc.store, exc.chunks = store, plan.n_chunks          # what is kept, for the message
        raise
    seconds = time.perf_counter() - started
    if shard is None and not held:                 # the chunks computed elsewhere: read them once
        collect(plan, store, missing, final)
    return Execution(final, computed, seconds, store, plan.n_chunks)


def parse_shard(text: str | None) -> tuple[int, int] | None:
    """``(i, n)`` from ``--shard I/N`` (1 <= i <= n), None for None; else one CaseError."""
    if text is None:
        return None
    parts = str(text).strip().split("/")
    try:
        index, count = (int(p) for p in parts) if len(parts) == 2 else (None, None)
    except ValueError:
        index = count = None
    if index is None or not 1 <= index <= count <= 1_000_000:
        raise CaseError(f"expected I/N with 1 <= I <= N (this process's share of N, e.g. 3/16), got {text!r}",
                        source="shard")
    return index, count


def on_machine_code(device: str) -> bool:
    """Whether a local run on ``device`` computes with the build's machine code (`local_kernel`):
    nothing to compile or load before it (`warm_up`)."""
    from ..core import simulate

    return device == "cpu" and local_kernel() is simulate.compute_batch


def warm_up(device: str, say: Callable[[str], None]) -> None:
    """Compile the batch kernel (or the device kernel) before the clock starts, saying so when it
    takes a while: a first compile on a new CPU, a new numba or an edited kernel."""
    if device == "gpu":
        from ..core import gpu
        note = first_compile_note(gpu.device_kernel(), "the device kernel", "about a minute")
        if note:
            say(note)
        compiling = time.perf_counter()
        gpu.warm_up()
        if note:
            say(f"  compiled the device kernel in {time.perf_counter() - compiling:.0f} s")
        return
    from ..core import batch

    note = first_compile_note(batch.run_batch, "the batch kernel")
    if note:
        say(note)
    try:
        batch.warm_up()
    except Exception as exc:  # noqa: BLE001 - whatever numba raises on a cache file it cannot load
        from ..core import compiled
        if not compiled.discard(batch.run_batch):
            raise
        say(f"rockslide: note: numba's cache of the core could not be read ({exception_text(exc)}); removed it, "
            "compiling again (about a minute on 2 cores)")
        batch.warm_up()


def first_compile_note(dispatcher, what: str = "the numerical kernel",
                       takes: str = "about a minute on 2 cores") -> str | None:
    """What to say before a compile: when ``dispatcher``'s machine code is not in numba's cache yet
    (`compiled.is_warm`: the package build puts it there, so this is a new CPU, a new numba or an
    edited kernel), or when no cache folder can be written at all; None when it is cached."""
    from ..core import compiled

    if compiled.CACHE_IS_TEMPORARY:
        return (f"rockslide: compiling {what} in memory, for this process only (about a minute): neither the "
                "installation nor the user's cache folder can be written; set NUMBA_CACHE_DIR to a writable "
                "folder to keep it")
    if not compiled.is_warm(dispatcher):
        folder = compiled.cache_folder(dispatcher)
        where = f"; cached in {folder}" if folder is not None else ""
        return f"rockslide: compiling {what} for this machine (once, {takes}{where})"
    return None
