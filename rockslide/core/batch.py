"""Many cases at once: the compiled state machine (`kernel.run`) over a batch of cases.

Pure numerical core: numpy and numba only, no I/O. A sweep (``rockslide sweep``) or a fragility
analysis builds one parameter vector (``kernel.P_*``) and one initial state vector (``kernel.S_*``)
per case, and the ground motion of its records once, unscaled and concatenated; each case names its
record (its first interval and interval count) and its scale factors, and the kernel reads and
scales the shared record as it goes (``ah = kh * base_h``, ``av = kv * base_v``: the product
`records.combine` forms, element by element), so that a case of a batch is computed with exactly
the arithmetic of a single run (`simulate.simulate`): same kernel, same inputs, bit-identical
results, and no copy of the record per case.

No history and no event log are kept (``every = 0`` and an event array of shape ``(0, 8)``); the
kernel still counts events and keeps every summary quantity in the state vector, which is what the
driver gives back. A case ends at overturning or when it leaves the model, and the kernel does no
work while a block rests (whole blocks of the record at rest are skipped, `kernel.rest_bounds`).

`run_batch` runs on the calling thread with the GIL released, so that callers bring their own
parallelism: the sweep hands chunks of cases to a pool of threads (each free to take the next chunk
as soon as it is done), a dask worker runs its tasks on its own threads. `compute` wraps it for
plain numpy callers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import kernel as K
from .simulate import kernel_inputs  # noqa: F401  (plain numpy, shared with `simulate.compute_batch`; re-exported)

__all__ = ["compute", "kernel_inputs", "warm_up", "warm_up_case", "run_batch"]


@njit(nogil=True, cache=True)
def run_batch(params, states, base, bounds, count):
    """Run every case of a batch to its end, in place, on the calling thread (GIL released).

    Parameters
    ----------
    params : float64[n, N_PARAMS]
        One parameter vector per case (``kernel.P_*``), its record given by ``P_FIRST``, ``P_KH``
        and ``P_KV``.
    states : float64[n, N_STATE]
        Initial states (``kernel.S_*``), replaced by the final states (the results are read from them).
    base : float64[4, M]
        Unscaled ground motion of the records the cases use, concatenated (`simulate.ground_array`
        of each, tails included).
    bounds : float64[3, n_blocks]
        `kernel.rest_bounds` of ``base``.
    count : int64[n]
        Each case's number of record intervals.
    """
    history = np.empty((len(K.HISTORY_COLUMNS), 0))
    events = np.empty((0, len(K.EVENT_COLUMNS)))
    every = history.shape[1]      # 0, not a literal: the kernel's cached signature is reused
    for i in range(params.shape[0]):
        K.run(params[i], base, bounds, states[i], history, every, every, events, count[i])


def compute(params, states, base, first, count, kh, kv):
    """Run a batch of cases and return their final states (the inputs are not changed).

    Parameters
    ----------
    params : array_like, float64[n, N_PARAMS]
        The cases' parameters (`simulate.parameters`); their record columns are set here.
    states : array_like, float64[n, N_STATE]
        Initial states.
    base : array_like, float64[4, M]
        The records, unscaled and concatenated.
    first, count : array_like, int64[n]
        Each case's record: intervals ``first[i] ... first[i] + count[i] - 1`` of ``base``.
    kh, kv : array_like, float64[n]
        Horizontal and vertical scale factors of each case.

    Returns
    -------
    numpy.ndarray
        float64[n, N_STATE]: the final states.
    """
    params, out, base, count = kernel_inputs(params, states, base, first, count, kh, kv)
    if params.shape[0]:
        run_batch(params, out, base, K.rest_bounds(base), count)
    return out


def warm_up_case():
    """`compute`'s arguments for a trivial case (a block at rest on still ground), which compiles a
    driver, or loads it from numba's cache, at almost no cost."""
    p = np.zeros((1, K.N_PARAMS))
    p[0, K.P_R], p[0, K.P_ALPHA], p[0, K.P_TAN_ALPHA] = 0.1, 0.5, np.tan(0.5)
    p[0, K.P_R2], p[0, K.P_ALPHA2], p[0, K.P_TAN_ALPHA2] = 0.1, 0.5, np.tan(0.5)
    p[0, K.P_KR1] = p[0, K.P_KR2] = 7.5
    p[0, K.P_Q1] = p[0, K.P_Q2] = 4.0 / 3.0
    p[0, K.P_M1] = p[0, K.P_M2] = 2.0 / 300.0
    p[0, K.P_P2_1] = p[0, K.P_P2_2] = 0.75 * 9.80665 / 0.1
    p[0, K.P_G], p[0, K.P_MU], p[0, K.P_NU], p[0, K.P_E] = 9.80665, 0.5, 0.5, 0.8
    p[0, K.P_STEP], p[0, K.P_DT_REC], p[0, K.P_N_SUB], p[0, K.P_LOCATED] = 0.01, 0.01, 1.0, 1.0
    states = K.new_state()[None, :]
    return p, states, np.zeros((4, 1)), 0, 1, np.ones(1), np.ones(1)


def warm_up():
    """Compile the driver, or load it from numba's cache, on `warm_up_case`, so that the first real
    batch is not charged with it."""
    compute(*warm_up_case())
