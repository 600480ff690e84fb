"""Many cases at once on an NVIDIA GPU: the compiled state machine (`kernel.run`) on the device.

Pure numerical core: numpy, numba and numba-cuda only, no I/O. numba-cuda compiles the ``@njit``
functions of `kernel` and `physics` for the device when a CUDA kernel calls them, so the device
runs the very source the CPU runs: `run_cases` is one thread per case calling `kernel.run`, as
`batch.run_batch` is one loop iteration per case. There is no second copy of the state machine or
of any equation. The results are those of `batch.compute` up to the last bits: the device compiler
contracts ``a * b + c`` into fused multiply-adds, which round once instead of twice (in numba's
CUDA simulator, ``NUMBA_ENABLE_CUDASIM=1``, the arithmetic is the CPU's and the results are
identical).

Throughput. A warp of 32 threads runs until its slowest case is done, so the cases of a launch are
ordered by a cheap estimate of their work (`launch_order`) before they go to the device and the
results are put back in the original order: cases at rest through their record (a few interval
scans) end up beside each other, and so do long rocking cases. Each thread copies its state vector
into its own local memory, which the hardware interleaves across the threads of a warp (the rows of
``states`` would give each thread a stride of ``N_STATE`` doubles); the records stay in global
memory, read by every case and so held in the L2 cache (50 MB on an H100) for all but very large
suites. `warp_efficiency` says, from the final states, how much of what the warps issued was
useful.

numba-cuda is an optional extra (``pip install 'rockslide[gpu]'``) and is imported only by
`cuda_module`, when a device run is asked for; the CPU path never imports it.
"""

from __future__ import annotations

import importlib.util
import math
import warnings

import numpy as np

from . import batch
from . import kernel as K

__all__ = ["DeviceUnavailable", "cuda_module", "require_device", "device_kernel", "compute", "warm_up",
           "prepare", "Launch", "launch_order", "warp_efficiency", "THREADS_PER_BLOCK", "WARP_SIZE"]

#: Threads per block: the state machine needs many registers per thread, so small blocks keep
#: several blocks resident per multiprocessor (the cases are already ordered by work).
THREADS_PER_BLOCK = 128
WARP_SIZE = 32
#: The length of a case's state vector, as a global of this module: the device kernel's local array
#: needs its shape as a compile-time constant, and numba-cuda freezes a global int of the kernel's
#: own module as one, but types an attribute of another module (``K.N_STATE``) as a plain int64,
#: which ``cuda.local.array`` rejects on a real GPU (numba's CUDA simulator accepts either).
N_STATE = K.N_STATE


class DeviceUnavailable(RuntimeError):
    """No device run is possible here: numba-cuda is not installed, or it finds no CUDA GPU."""


cuda = None      # numba.cuda, set by `device_kernel` before `run_cases` is compiled (a global of it)
_kernel = None   # the CUDA kernel, built on first use (`device_kernel`)


def cuda_module():
    """``numba.cuda`` from numba-cuda, imported on first use.

    Raises
    ------
    DeviceUnavailable
        numba-cuda is not installed (numba's own deprecated ``numba.cuda`` cannot call ``@njit``
        functions from a kernel, so it is not used).
    """
    if importlib.util.find_spec("numba_cuda") is None:
        raise DeviceUnavailable("needs numba-cuda, the optional extra: pip install 'rockslide[gpu]'")
    if not hasattr(np, "row_stack"):
        # numba-cuda (0.30) registers an overload of np.row_stack, which numpy 2.5 removed: an
        # alias of np.vstack (what it was) lets numba-cuda load.
        np.row_stack = np.vstack
    from numba import cuda
    return cuda


def cuda_simulator() -> bool:
    """Whether numba's CUDA simulator stands in for a GPU (``NUMBA_ENABLE_CUDASIM=1``)."""
    from numba.core import config
    return bool(config.ENABLE_CUDASIM)


def require_device():
    """``numba.cuda`` when a CUDA GPU can run the kernel (or numba's CUDA simulator is on).

    Raises
    ------
    DeviceUnavailable
        With one line saying why: no numba-cuda, or no usable GPU or driver.
    """
    module = cuda_module()
    if not module.is_available():
        reason = " ".join(str(module.cuda_error() or "").split())
        raise DeviceUnavailable("no CUDA GPU found" + (f" ({reason})" if reason else ""))
    return module


def run_cases(params, states, base, bounds, count, history, events):
    """The device kernel (one thread per case): `kernel.run` of case ``i`` to its end, in place.

    The arguments are those of `batch.run_batch`, plus the zero-size ``history`` and ``events``
    arrays (no allocation on the device), which keep no history and no event log.
    """
    i = cuda.grid(1)
    if i >= params.shape[0]:
        return
    st = cuda.local.array(N_STATE, np.float64)
    for j in range(N_STATE):
        st[j] = states[i, j]
    every = history.shape[1]      # 0, as in `batch.run_batch`
    run_case(params[i], base, bounds, st, history, every, every, events, count[i])
    for j in range(N_STATE):
        states[i, j] = st[j]


def simulated_run(p, ground, bounds, st, history, every, offset, events, k_end):
    """`kernel.run` as `run_cases` calls it in numba's CUDA simulator, which runs the kernel in
    Python and hands it array wrappers that compiled CPU code cannot take: the read-only arguments
    are copied to numpy arrays (``st``, the thread's local array, already is one)."""
    def plain(a):
        return a.copy_to_host() if hasattr(a, "copy_to_host") else a
    return K.run(plain(p), plain(ground), plain(bounds), st, plain(history), every, offset, plain(events), k_end)


run_case = K.run   # what `run_cases` calls: `kernel.run` itself, compiled for the device


def device_kernel():
    """`run_cases` compiled for the device (once per process; numba-cuda caches the machine code
    beside the sources, and `compiled.freshen` drops it when the core's sources change)."""
    global _kernel, cuda, run_case
    if _kernel is None:
        cuda = require_device()
        if cuda_simulator():
            run_case = simulated_run
        _kernel = cuda.jit(cache=True)(run_cases)
    return _kernel


def launch_order(params, base, first, count, kh):
    """The order in which to hand the cases to the device: by estimated work, largest first.

    A case whose scaled record never reaches the REST thresholds (``|ah| < min(mu, tan alpha) g``)
    does almost no work; any other may move for its whole record, ``count * n_sub`` steps. Cases
    are sorted by that estimate, then by their intensity relative to the threshold, so that the
    32 cases of a warp are alike. The order is a stable sort (ties keep their order).

    Returns
    -------
    numpy.ndarray
        int64[n]: case indices, most work first.
    """
    first = np.broadcast_to(np.asarray(first, dtype=np.int64), params.shape[:1])
    count = np.broadcast_to(np.asarray(count, dtype=np.int64), params.shape[:1])
    # the distinct records (first, count) as one integer each (both are at most the base's length):
    # numpy's unique of a 1-D int64 is a plain sort, where unique(axis=1) sorts a structured type,
    # 0.1 s per launch of 65536 cases
    span = base.shape[1] + 1
    records, which = np.unique(first * span + count, return_inverse=True)
    peak = np.array([np.abs(base[:2, f:f + c]).max(initial=0.0)
                     for f, c in zip(records // span, records % span, strict=True)])[which.ravel()]
    tan_alpha = np.where(params[:, K.P_ASYM] != 0.0, np.minimum(params[:, K.P_TAN_ALPHA], params[:, K.P_TAN_ALPHA2]),
                         params[:, K.P_TAN_ALPHA])        # the weaker pivot of an asymmetric body
    threshold = np.minimum(params[:, K.P_MU], tan_alpha) * params[:, K.P_G]
    intensity = np.abs(np.broadcast_to(kh, params.shape[:1])) * peak / threshold
    steps = np.where(intensity >= 1.0, count * params[:, K.P_N_SUB], count / K.REST_BLOCK)
    return np.lexsort((-intensity, -steps)).astype(np.int64)


def _ignore_performance_warnings():
    """Ignore numba's performance warnings (in a ``warnings.catch_warnings()`` block).

    They are advice to whoever writes a kernel (e.g. 'Grid size 1 will likely result in GPU
    under-utilization'); rockslide already chose the launch geometry, and the user can do nothing
    about them. numba-cuda has a class of its own, not a subclass of numba's: both are ignored.
    """
    from numba.core.errors import NumbaPerformanceWarning
    warnings.simplefilter("ignore", NumbaPerformanceWarning)
    try:
        from numba.cuda.core.errors import NumbaPerformanceWarning as CudaPerformanceWarning
    except ImportError:   # a numba-cuda that uses numba's class
        return
    warnings.simplefilter("ignore", CudaPerformanceWarning)


def compute(params, states, base, first, count, kh, kv):
    """Run a batch of cases on the GPU and return their final states (the inputs are not changed).

    Same parameters and result as `batch.compute`, which this is the device version of: the batch
    is made ready (`prepare`), launched (`Launch`) and waited for.

    Raises
    ------
    DeviceUnavailable
        numba-cuda is not installed or finds no GPU.
    """
    return Launch(*prepare(params, states, base, first, count, kh, kv)).result()


def prepare(params, states, base, first, count, kh, kv):
    """A batch made ready for the device on the host alone (no device call): `Launch`'s arguments.

    The parameters are `batch.compute`'s. The cases go in `launch_order`, gathered once into the
    kernel's inputs (`batch.kernel_inputs`). Each array goes to the device as it is
    (``cuda.to_device``), so these arrays fix the types the kernel is compiled for. A caller with
    several batches prepares the next one while the device computes the last (`engine.execute`),
    so that the host's share is not added to the device's.

    Returns
    -------
    tuple
        ``(order, (params, states, base, bounds, count, history, events))``: the case order, and
        `run_cases`' arguments as host arrays in that order.
    """
    params = np.asarray(params, dtype=np.float64)
    n = params.shape[0]
    first, count, kh, kv = (np.broadcast_to(np.asarray(a), (n,)) for a in (first, count, kh, kv))
    order = launch_order(params, np.asarray(base, dtype=np.float64), first, count, kh)
    params, states, base, count = batch.kernel_inputs(params[order], np.asarray(states, dtype=np.float64)[order],
                                                      base, first[order], count[order], kh[order], kv[order],
                                                      copy=False)
    return order, (params, states, base, K.rest_bounds(base), count, np.empty((len(K.HISTORY_COLUMNS), 0)),
                   np.empty((0, len(K.EVENT_COLUMNS))))


class Launch:
    """A prepared batch (`prepare`) sent to the device and launched: the kernel runs while the host
    goes on, until `result` waits for it.

    The launch holds its device arrays until `result` has copied the states back. numba-cuda frees
    a dropped device array later, with others, and CUDA's free waits for the device: arguments
    dropped as the kernel starts would, every few launches, stop the host until the kernel ends,
    and the host's work meant to run beside it (`engine.execute`) would run after it.

    Raises
    ------
    DeviceUnavailable
        numba-cuda is not installed or finds no GPU.
    """

    def __init__(self, order, host):
        self._order, self._device, self._out = order, None, None
        if not len(order):
            return
        kernel = device_kernel()
        with warnings.catch_warnings():
            _ignore_performance_warnings()
            self._device = [cuda.to_device(a) for a in host]
            kernel[math.ceil(len(order) / THREADS_PER_BLOCK), THREADS_PER_BLOCK](*self._device)

    def result(self):
        """The batch's final states in its own order (float64[n, N_STATE]), once the device is done;
        its device arrays are let go then."""
        if self._out is None:
            self._out = np.empty((len(self._order), K.N_STATE))
            if self._device is not None:
                with warnings.catch_warnings():
                    _ignore_performance_warnings()
                    self._out[self._order] = self._device[1].copy_to_host()
                self._device = None
        return self._out


def warp_efficiency(states, params, order):
    """Useful integration steps over the steps the warps issued, for cases launched in ``order``.

    A case's useful steps are its time in the moving states over its step (REST costs no steps).
    A warp issues, at best, its slowest case's steps for each of its 32 lanes; the ratio of the
    two sums (1: the warps' cases were alike) measures what the ordering (`launch_order`) bought.
    Divergence within a warp (cases in different states at one time) costs more still, so this is
    an upper bound of the true efficiency.

    Returns
    -------
    tuple of float
        ``(useful steps, issued steps)``.
    """
    moving = states[:, K.S_T_SLIP] + states[:, K.S_T_ROCK] + states[:, K.S_T_ROCKSLIP]
    steps = (moving / params[:, K.P_STEP])[np.asarray(order)]
    padded = np.zeros(math.ceil(steps.size / WARP_SIZE) * WARP_SIZE)
    padded[:steps.size] = steps
    issued = padded.reshape(-1, WARP_SIZE).max(axis=1).sum() * WARP_SIZE
    return float(steps.sum()), float(issued)


def warm_up():
    """Compile the device kernel, or load it from the cache, on `batch.warm_up_case`."""
    compute(*batch.warm_up_case())
