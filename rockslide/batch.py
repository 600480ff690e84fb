"""Many cases at once: the compiled state machine (`kernel.run`) over a batch of cases.

Pure numerical core: numpy and numba only, no I/O. A sweep (``rockslide sweep``) builds one
parameter vector (``kernel.P_*``) and one initial state vector (``kernel.S_*``) per case, and the
ground motion once, unscaled; each case scales its own copy of the ground motion by its factors
(``ah = kh * base_h``, ``av = kv * base_v``, the same product, element by element, as
`records.combine`), so that a case of a batch is computed with exactly the arithmetic of a single
run (`simulate.simulate`): same kernel, same inputs, bit-identical results.

No history and no event log are kept (``every = 0`` and an event array of shape ``(0, 6)``); the
kernel still counts events and keeps every summary quantity in the state vector. Each case ends
at overturning or when it leaves the model, and the kernel does no work while a block rests.

Two drivers share one case routine:

- `run_parallel`: ``prange`` over the cases on numba's threads (``numba.set_num_threads`` sets how
  many). Costs vary a lot between cases (a block at rest costs nothing), so call it under
  ``numba.parallel_chunksize(1)`` to hand the cases out one by one (dynamic scheduling).
- `run_serial`: the same loop on the calling thread, releasing the GIL, for callers that bring
  their own parallelism (a dask worker's threads).

The drivers are compiled without numba's on-disk cache on purpose: numba invalidates a cached
function when its own file changes, not when a function it calls (`kernel.run`, in another file)
does, so a cached batch driver could silently run an outdated kernel. `kernel.run` itself is cached
with its module; compiling the small drivers around it takes a few seconds once per process.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from . import kernel as K

__all__ = ["run_parallel", "run_serial", "run_case", "ground_length"]


@njit
def ground_length(n_samples):
    """Number of ground samples the kernel needs: at least two (as `simulate.simulate` pads)."""
    return max(n_samples, 2)


@njit
def run_case(p, st, base_h, base_v, kh, kv):
    """Run one case to its end, in place.

    Parameters
    ----------
    p : float64[N_PARAMS]
        The case's parameters (``kernel.P_*``).
    st : float64[N_STATE]
        Its initial state (``kernel.S_*``), replaced by the final state.
    base_h, base_v : float64[m]
        Unscaled ground accelerations [m/s^2], tail of zeros included.
    kh, kv : float
        The case's horizontal and vertical scale factors.
    """
    m = base_h.shape[0]
    n = ground_length(m)
    ah = np.zeros(n)
    av = np.zeros(n)
    for j in range(m):
        ah[j] = kh * base_h[j]
        av[j] = kv * base_v[j]
    history = np.empty((len(K.HISTORY_COLUMNS), 0))
    events = np.empty((0, len(K.EVENT_COLUMNS)))
    # contiguous copies: the kernel is called with the array types `simulate` uses, so its cached
    # compilation serves both
    p_case = p.copy()
    st_case = st.copy()
    K.run(p_case, ah, av, st_case, history, 0, 0, events, n - 1)
    st[:] = st_case


@njit(parallel=True)
def run_parallel(params, states, base_h, base_v, kh, kv):
    """Run every case of a batch, in parallel over the cases (numba threads).

    Parameters
    ----------
    params : float64[n, N_PARAMS]
        One parameter vector per case.
    states : float64[n, N_STATE]
        Initial states, replaced by the final states (read the results from them).
    base_h, base_v : float64[m]
        Unscaled ground accelerations [m/s^2] shared by the cases, tail included.
    kh, kv : float64[n]
        Horizontal and vertical scale factors of each case.
    """
    for i in prange(params.shape[0]):
        run_case(params[i], states[i], base_h, base_v, kh[i], kv[i])


@njit(nogil=True)
def run_serial(params, states, base_h, base_v, kh, kv):
    """`run_parallel` on the calling thread only (the GIL released); same arguments."""
    for i in range(params.shape[0]):
        run_case(params[i], states[i], base_h, base_v, kh[i], kv[i])
