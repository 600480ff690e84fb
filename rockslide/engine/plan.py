"""The engine's plan: every case's kernel inputs, and nothing computed yet.

Every analysis (a run's neighbourhood, a sweep, a fragility analysis, a spectrum) becomes a `Plan`:
a flat list of cases, each a row of kernel parameters and an initial state (`core.simulate.parameters`,
`core.simulate.initial_state`), a pair of scale factors and a window of the concatenated unscaled
ground motion ``base``. The analysis keeps its axes (dimension ``i`` of its result is ``axes[i]``),
and the engine cuts the cases into chunks (`chunk_indices`) that it computes (`execute`) and may keep
on disk (`chunks.ChunkStore`) under the plan's `definition_key`.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._version import __version__
from ..core import layout as L
from ..core import native
from ..errors import CaseError

if TYPE_CHECKING:
    from ..case import Case


#: Most values of one sweep axis, and most cases of a fragility analysis or an ensemble.
MAX_POINTS = 1_000_000


#: Most cases of a sweep's grid; below it, the memory of the machine decides (`check_memory`).
MAX_GRID_POINTS = 100_000_000


#: [bytes] Memory a sweep's command needs per case at its peak, besides the libraries (the final
#: states, 288 bytes, the result's variables, 98, the plan, 48, and what writing the file takes): 430
#: measured by benchmarks/bench_large.py's phases and 550 by ``rockslide sweep`` of 10^6 cases
#: whole (0.72 GB at its peak on 2 threads, 0.69 GB as a dask client; 0.17 GB of libraries), rounded up.
SWEEP_BYTES_PER_CASE = 700


#: Chunk sizes: about ``n / CHUNKS_WANTED`` cases, within these bounds (the default), and larger
#: chunks beyond ``MAX_CHUNK * MAX_CHUNK_FILES`` cases, so that a chunk folder holds at most
#: ``MAX_CHUNK_FILES`` files.
CHUNKS_WANTED = 100


MIN_CHUNK, MAX_CHUNK = 4, 256


MAX_CHUNK_FILES = 40_000


#: The sweep file's format, part of a chunk's definition key: `results.SWEEP_FORMAT` and
#: `results.SWEEP_FORMAT_VERSION`, not imported from there (that would load h5py); a test keeps them equal.
FORMAT = "rockslide-sweep"


FORMAT_VERSION = 1


@dataclass
class Plan:
    """Everything needed to compute a sweep, and nothing computed yet.

    Attributes
    ----------
    case : Case
        The case file the points start from.
    axes : list of Axis
        In dimension order.
    mu_kinetic_ratio : float or None
        ``mu_kinetic / mu_static`` used with ``--mu`` (None without ``--mu``).
    params, states : float64[m, N_PARAMS], float64[m, N_STATE]
        Each point's kernel parameters and initial state, flat in C order of the grid (m = n); or,
        with ``rows``, the distinct ones (`case_params`, `case_states`).
    factor_h, factor_v : float64[n]
        Each point's horizontal and vertical scale factors (`records.combine`).
    base : float64[4, K]
        The unscaled ground motion [m/s^2] interval by interval (`simulate.ground_array`), the
        case's tail of zeros included; several records are concatenated.
    first, count : int64[n]
        Each point's record: intervals ``first ... first + count - 1`` of ``base``.
    record_end : float64[n]
        [s] time of each point's last ground sample (tail included): the end of a run that ends
        standing.
    step : float
        [s] integration step (the smallest, when the records' sampling steps differ).
    records : list of dict
        The records' file names and checksums.
    chunk_size : int
        Cases per chunk.
    key : str
        `definition_key` of the sweep.
    step_study : step.StudyStep, optional
        The pilots of ``solver.dt: auto`` (`prepare.study_step`): the step taken or what it would save.
    rows : int64[n], optional
        Each point's row of ``params`` and ``states`` (a 1000 x 1000 ``--mu`` x ``--pga`` grid has
        1000 distinct rows: 16 MB instead of 400). None: row i is point i.
    """

    case: Case
    axes: list
    mu_kinetic_ratio: float | None
    params: np.ndarray
    states: np.ndarray
    factor_h: np.ndarray
    factor_v: np.ndarray
    base: np.ndarray
    first: np.ndarray
    count: np.ndarray
    record_end: np.ndarray
    step: float
    records: list
    chunk_size: int
    key: str = ""
    rows: np.ndarray | None = None
    step_study: object = None       # step.StudyStep: the step auto took or would take, and its estimate

    @property
    def shape(self) -> tuple:
        """The grid's shape, one dimension per axis."""
        return tuple(len(a) for a in self.axes)

    @property
    def n_cases(self) -> int:
        """Number of points of the grid."""
        return int(self.first.shape[0])

    @property
    def n_chunks(self) -> int:
        """Number of chunks (the last ones may hold one case less)."""
        return -(-self.n_cases // self.chunk_size)

    def chunk_indices(self, chunk: int) -> np.ndarray:
        """Flat grid indices of chunk ``chunk``: ``chunk, chunk + n_chunks, ...``."""
        return np.arange(chunk, self.n_cases, self.n_chunks, dtype=np.int64)

    @property
    def steps_per_case(self) -> int:
        """Integration steps of the longest case that runs to the end of its record and tail."""
        return int(np.max(self.count * self.case_column(L.P_N_SUB))) if self.n_cases else 0

    def case_params(self, cases=slice(None)) -> np.ndarray:
        """``float64[k, N_PARAMS]``: the kernel parameters of points ``cases`` (indices or a slice)."""
        return self.params[cases] if self.rows is None else self.params[self.rows[cases]]

    def case_states(self, cases=slice(None)) -> np.ndarray:
        """``float64[k, N_STATE]``: the initial states of points ``cases`` (indices or a slice)."""
        return self.states[cases] if self.rows is None else self.states[self.rows[cases]]

    def case_column(self, column: int) -> np.ndarray:
        """``float64[n]``: one kernel parameter (``L.P_...``) of every point."""
        return self.params[:, column] if self.rows is None else self.params[self.rows, column]

    def describe(self) -> str:
        """``41 mu x 37 pga = 1517 cases``."""
        dims = " x ".join(f"{len(a)} {a.name}" for a in self.axes)
        return f"{dims} = {self.n_cases} case{'s' if self.n_cases != 1 else ''}"


def case_inputs(point: Case, dt: float, start: float) -> tuple[np.ndarray, np.ndarray]:
    """The one road from a case to the kernel: its parameter row and initial state
    (`core.simulate.parameters`, `core.simulate.initial_state`) for a run without history on a
    ground motion of step ``dt`` [s] that starts at ``start`` [s]. Every planner calls it, so that a
    case key reaches the kernel the same way in a run, a sweep, a fragility analysis and an ensemble."""
    from ..core.simulate import initial_state, parameters
    from .prepare import model_for, settings_for

    settings = settings_for(point, history=False, energy=False)
    return parameters(model_for(point), dt, settings, start), initial_state(settings)


class Supports:
    """The unscaled ground motions a study's cases stand on, laid end to end in the kernel's input
    (``Plan.base``), each once (`add`); each case's window of it (first interval, intervals) is its
    motion's (`window`)."""

    def __init__(self):
        self.pieces: list[np.ndarray] = []
        self.windows: dict = {}
        self.columns = 0

    def add(self, key, piece: np.ndarray) -> None:
        """Lay the motion ``key`` (`core.simulate.ground_array`) after the others."""
        self.windows[key] = (self.columns, piece.shape[1])
        self.pieces.append(piece)
        self.columns += piece.shape[1]

    def window(self, key) -> tuple[int, int]:
        """``(first interval, intervals)`` of the motion ``key``."""
        return self.windows[key]

    def base(self) -> np.ndarray:
        """``float64[4, K]``: every motion, in the order added."""
        return self.pieces[0] if len(self.pieces) == 1 else np.concatenate(self.pieces, axis=1)


def assemble(case: Case, axes, *, params, states, factor_h, factor_v, base, first, count, record_end, records,
             chunk_size: int, rows=None, mu_kinetic_ratio=None, step: float | None = None, step_study=None,
             keyed: bool = True) -> Plan:
    """The one assembler of a `Plan` from its cases' kernel inputs (the fields of `Plan`; ``step``
    defaults to the smallest of the cases'), with its `definition_key` (unless not ``keyed``: the
    caller then sets it after changing the steps, `prepare.study_step`)."""
    plan = Plan(case=case, axes=list(axes), mu_kinetic_ratio=mu_kinetic_ratio, params=params, states=states,
                factor_h=factor_h, factor_v=factor_v, base=base, first=first, count=count, record_end=record_end,
                step=float(params[:, L.P_STEP].min()) if step is None else step, records=records,
                chunk_size=chunk_size, rows=rows, step_study=step_study)
    if keyed:
        plan.key = definition_key(plan)
    return plan


def default_chunk_size(n_cases: int) -> int:
    """About ``n / CHUNKS_WANTED`` cases per chunk, within ``[MIN_CHUNK, MAX_CHUNK]``, or more where
    that would make more than ``MAX_CHUNK_FILES`` chunks."""
    size = min(MAX_CHUNK, max(MIN_CHUNK, math.ceil(n_cases / CHUNKS_WANTED)))
    return int(max(size, math.ceil(n_cases / MAX_CHUNK_FILES)))


def check_bytes(needed: float, what: str, source: str) -> None:
    """Refuse a study that would hold ``needed`` bytes for ``what`` where this machine has less
    memory available (`available_memory`): one line naming both, before anything is built."""
    available = available_memory()
    if available is not None and needed > available:
        raise CaseError(f"{what} need about {needed / 1e9:.3g} GB of memory; {available / 1e9:.3g} GB are available "
                        "here: fewer values, a shorter record or a larger machine", source=source)


#: [bytes] Memory each distinct ground motion of a study holds per sample (`Supports`): the kernel's
#: four rows of float64, the motion itself and what computing it takes.
SUPPORT_BYTES_PER_SAMPLE = 64


def check_memory(n_cases: int, source: str) -> None:
    """Refuse a study whose client would need more memory than this machine has available
    (`available_memory`), in one line saying both figures; nothing where it cannot be told."""
    available = available_memory()
    needed = n_cases * SWEEP_BYTES_PER_CASE
    if available is not None and needed > available:
        raise CaseError(f"{n_cases} cases need about {needed / 1e6:.3g} MB of memory here ({SWEEP_BYTES_PER_CASE} "
                        f"bytes a case, with a cluster's workers or without); {available / 1e6:.3g} MB are available: "
                        "split the grid (one axis in parts) or run it on a larger machine", source=source)


def available_memory() -> int | None:
    """[bytes] Memory available to a new allocation (Linux's MemAvailable), or None where unknown."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def definition_key(plan: Plan) -> str:
    """A hash of everything that defines a sweep's results (chunks are reused only under it).

    The case text, the axes (values as given and in SI), the kinetic friction ratio, the chunk size,
    every point's kernel parameters, initial state and scale factors, the unscaled ground samples,
    the package version and the compiled core's sources (`native.source_stamp`). A plan with
    ``rows`` is hashed as it is held, its distinct rows and each point's row, which fix every
    point's parameters and state (expanding them took 0.5 s of the planning of 10^6 points).
    """
    digest = hashlib.sha256()
    header = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "rockslide": __version__,
        "case_text": plan.case.text,
        "axes": [[a.name, list(a.texts), [repr(v) for v in a.values]] for a in plan.axes],
        "mu_kinetic_ratio": repr(plan.mu_kinetic_ratio), "chunk_size": plan.chunk_size,
        "kernel_source": native.source_stamp(),
    }
    digest.update(json.dumps(header, sort_keys=True).encode())
    for array in (plan.params, plan.states):
        digest.update(np.ascontiguousarray(array, dtype=np.float64))
    if plan.rows is not None:
        digest.update(b"rows")
        digest.update(np.ascontiguousarray(plan.rows, dtype=np.int64))
    for array in (plan.factor_h, plan.factor_v, plan.base, plan.first, plan.count):
        digest.update(np.ascontiguousarray(array, dtype=np.float64))
    return digest.hexdigest()


def bytes_needed(plan: Plan, n_chunks: int) -> int:
    """Bytes on disk for ``n_chunks`` more chunk files and the result file (both uncompressed)."""
    per_case_chunk = (L.N_STATE + 1) * 8
    cases = min(n_chunks * plan.chunk_size, plan.n_cases)     # a chunk holds at most the plan's cases
    return cases * per_case_chunk + plan.n_cases * RESULT_BYTES_PER_CASE + 2**16


#: Bytes per case of the variables `sweep_variables` writes: 11 float64, one int32, 6 int8 (a test
#: keeps this in step with them).
RESULT_BYTES_PER_CASE = 8 * 11 + 4 + 6
