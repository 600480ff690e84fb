"""Many cases at once: the compiled state machine (`kernel.run`) over a batch of cases.

Pure numerical core: numpy and numba only, no I/O. A sweep (``rockslide sweep``) builds one
parameter vector (``kernel.P_*``) and one initial state vector (``kernel.S_*``) per case, and the
ground motion of its records once, unscaled and concatenated (each case names its record by its
first interval and interval count); each case scales its own copy of its record by its factors
(``ah = kh * base_h``, ``av = kv * base_v``: the product `records.combine` forms, element by
element), so that a case of a batch is computed with exactly the arithmetic of a single run
(`simulate.simulate`): same kernel, same inputs, bit-identical results.

No history and no event log are kept (``every = 0`` and an event array of shape ``(0, 6)``); the
kernel still counts events and keeps every summary quantity in the state vector, which is what
the drivers give back. A case ends at overturning or when it leaves the model, and the kernel does
no work while a block rests.

Two drivers share one case routine:

- `run_parallel`: ``prange`` over the cases on numba's threads (``numba.set_num_threads`` sets how
  many). Costs vary a lot between cases (a block at rest costs nothing), so call it under
  ``numba.parallel_chunksize(1)`` to hand the cases out one at a time (dynamic scheduling).
- `run_serial`: the same loop on the calling thread with the GIL released, for callers that bring
  their own parallelism (the threads of a dask worker).

`compute` wraps both for plain numpy callers (the sweep, and the tasks it sends to a dask cluster).

Compiled code is cached on disk. numba keys a cached function on its own source file, not on the
files of the functions it calls, so a batch driver cached before an edit of ``kernel.py`` or
``physics.py`` would go on running the old kernel. `SOURCE_STAMP`, a hash of the compiled code of
those modules (bytecode and constants of their functions, module-level numbers), is therefore
compiled into the drivers as a closure constant, which numba's cache index includes: an edited
kernel compiles new drivers (once, a few seconds) instead of reusing stale ones.
"""

from __future__ import annotations

import hashlib
import marshal

import numba
import numpy as np
from numba import njit, prange

from . import kernel as K
from . import physics

__all__ = ["compute", "warm_up", "run_parallel", "run_serial", "run_case", "SOURCE_STAMP"]


def _source_stamp(modules=(K, physics)) -> int:
    """A 60-bit hash of what the drivers compile in: the bytecode and constants of every function
    of ``modules`` (numba's or plain) and their module-level numbers, strings and tuples."""
    digest = hashlib.sha256()
    for module in modules:
        for name, obj in sorted(vars(module).items()):
            code = getattr(getattr(obj, "py_func", obj), "__code__", None)
            if code is not None and getattr(obj, "__module__", None) == module.__name__:
                digest.update(name.encode() + marshal.dumps(code))
            elif isinstance(obj, (bool, int, float, str, tuple)) and not name.startswith("__"):
                digest.update(f"{name}={obj!r}".encode())
    return int(digest.hexdigest()[:15], 16)


#: Hash of ``kernel.py`` and ``physics.py`` compiled into the drivers (see the module notes).
SOURCE_STAMP = _source_stamp()


@njit
def run_case(p, st, base, first, count, kh, kv):
    """Run one case to its end, in place.

    Parameters
    ----------
    p : float64[N_PARAMS]
        The case's parameters (``kernel.P_*``).
    st : float64[N_STATE]
        Its initial state (``kernel.S_*``), replaced by the final state.
    base : float64[4, M]
        Unscaled ground motion of one or more records, interval by interval (``kernel.GROUND_ROWS``),
        tails of zeros included.
    first, count : int
        The case's record: intervals ``first ... first + count - 1`` of ``base``.
    kh, kv : float
        The case's horizontal and vertical scale factors.
    """
    ground = np.empty((4, count))
    for j in range(count):
        ground[0, j] = kh * base[0, first + j]
        ground[1, j] = kh * base[1, first + j]
        ground[2, j] = kv * base[2, first + j]
        ground[3, j] = kv * base[3, first + j]
    history = np.empty((len(K.HISTORY_COLUMNS), 0))
    events = np.empty((0, len(K.EVENT_COLUMNS)))
    every = history.shape[1]      # 0, not a literal: the kernel's cached signature is reused
    # contiguous copies: the kernel gets the array types `simulate` gives it
    p_case = p.copy()
    st_case = st.copy()
    K.run(p_case, ground, st_case, history, every, every, events, count)
    st[:] = st_case


def _drivers(stamp):
    """The two drivers, with ``stamp`` compiled in (their cache key changes with it)."""

    @njit(parallel=True, cache=True)
    def run_parallel(params, states, base, first, count, kh, kv):
        if stamp == 0:            # folded away; it makes ``stamp`` part of the cache key
            return
        for i in prange(params.shape[0]):
            run_case(params[i], states[i], base, first[i], count[i], kh[i], kv[i])

    @njit(nogil=True, cache=True)
    def run_serial(params, states, base, first, count, kh, kv):
        if stamp == 0:
            return
        for i in range(params.shape[0]):
            run_case(params[i], states[i], base, first[i], count[i], kh[i], kv[i])

    return run_parallel, run_serial


run_parallel, run_serial = _drivers(SOURCE_STAMP)
run_parallel.__doc__ = """Run every case of a batch, in parallel over the cases (numba threads).

Parameters
----------
params : float64[n, N_PARAMS]
    One parameter vector per case (``kernel.P_*``).
states : float64[n, N_STATE]
    Initial states (``kernel.S_*``), replaced by the final states (the results are read from them).
base : float64[4, M]
    Unscaled ground motion of the records the cases use, concatenated (`simulate.ground_array` of
    each, tails included).
first, count : int64[n]
    Each case's record: intervals ``first[i] ... first[i] + count[i] - 1`` of ``base``.
kh, kv : float64[n]
    Horizontal and vertical scale factors of each case.
"""
run_serial.__doc__ = """`run_parallel` on the calling thread only, with the GIL released; same arguments."""


def compute(params, states, base, first, count, kh, kv, *, parallel=True):
    """Run a batch of cases and return their final states (the inputs are not changed).

    Parameters
    ----------
    params : array_like, float64[n, N_PARAMS]
    states : array_like, float64[n, N_STATE]
        Initial states.
    base : array_like, float64[4, M]
    first, count : array_like, int64[n]
    kh, kv : array_like, float64[n]
        As for `run_parallel`.
    parallel : bool
        `run_parallel` on numba's threads, cases handed out one at a time; or `run_serial`.

    Returns
    -------
    numpy.ndarray
        float64[n, N_STATE]: the final states.
    """
    params = np.ascontiguousarray(params, dtype=np.float64)
    out = np.array(states, dtype=np.float64, order="C", copy=True)
    n = params.shape[0]
    args = (params, out, np.ascontiguousarray(base, dtype=np.float64),
            np.ascontiguousarray(np.broadcast_to(first, n), dtype=np.int64),
            np.ascontiguousarray(np.broadcast_to(count, n), dtype=np.int64),
            np.ascontiguousarray(kh, dtype=np.float64), np.ascontiguousarray(kv, dtype=np.float64))
    if n == 0:
        return out
    if parallel:
        with numba.parallel_chunksize(1):
            run_parallel(*args)
    else:
        run_serial(*args)
    return out


def warm_up(parallel=True):
    """Compile a driver, or load it from numba's cache, on a trivial case (a block at rest on
    still ground), so that the first real batch is not charged with it."""
    p = np.zeros((1, K.N_PARAMS))
    p[0, K.P_R], p[0, K.P_ALPHA], p[0, K.P_TAN_ALPHA] = 0.1, 0.5, np.tan(0.5)
    p[0, K.P_G], p[0, K.P_MU], p[0, K.P_NU], p[0, K.P_E] = 9.80665, 0.5, 0.5, 0.8
    p[0, K.P_H], p[0, K.P_DT_REC], p[0, K.P_N_SUB], p[0, K.P_LOCATED] = 0.01, 0.01, 1.0, 1.0
    states = K.new_state()[None, :]
    compute(p, states, np.zeros((4, 1)), 0, 1, np.ones(1), np.ones(1), parallel=parallel)
