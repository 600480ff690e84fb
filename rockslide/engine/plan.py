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
from ..core import compiled
from ..core import kernel as K

if TYPE_CHECKING:
    from ..case import Case


#: Largest grid (number of cases) a sweep accepts.
MAX_POINTS = 1_000_000


#: Chunk sizes: about ``n / CHUNKS_WANTED`` cases, within these bounds (the default).
CHUNKS_WANTED = 100


MIN_CHUNK, MAX_CHUNK = 4, 256


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
    params, states : float64[n, N_PARAMS], float64[n, N_STATE]
        Each point's kernel parameters and initial state, flat in C order of the grid.
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

    @property
    def shape(self) -> tuple:
        """The grid's shape, one dimension per axis."""
        return tuple(len(a) for a in self.axes)

    @property
    def n_cases(self) -> int:
        """Number of points of the grid."""
        return int(self.params.shape[0])

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
        return int(np.max(self.count * self.params[:, K.P_N_SUB])) if self.n_cases else 0

    def describe(self) -> str:
        """``41 mu x 37 pga = 1517 cases``."""
        dims = " x ".join(f"{len(a)} {a.name}" for a in self.axes)
        return f"{dims} = {self.n_cases} case{'s' if self.n_cases != 1 else ''}"


def default_chunk_size(n_cases: int) -> int:
    """About ``n / CHUNKS_WANTED`` cases per chunk, within ``[MIN_CHUNK, MAX_CHUNK]``."""
    return int(min(MAX_CHUNK, max(MIN_CHUNK, math.ceil(n_cases / CHUNKS_WANTED))))


def definition_key(plan: Plan) -> str:
    """A hash of everything that defines a sweep's results (chunks are reused only under it).

    The case text, the axes (values as given and in SI), the kinetic friction ratio, the chunk size,
    every point's kernel parameters, initial state and scale factors, the unscaled ground samples,
    the package version and the compiled core's sources (`compiled.source_stamp`).
    """
    digest = hashlib.sha256()
    header = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "rockslide": __version__,
        "case_text": plan.case.text,
        "axes": [[a.name, list(a.texts), [repr(v) for v in a.values]] for a in plan.axes],
        "mu_kinetic_ratio": repr(plan.mu_kinetic_ratio), "chunk_size": plan.chunk_size,
        "kernel_source": compiled.source_stamp(),
    }
    digest.update(json.dumps(header, sort_keys=True).encode())
    for array in (plan.params, plan.states, plan.factor_h, plan.factor_v, plan.base, plan.first, plan.count):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    return digest.hexdigest()


def bytes_needed(plan: Plan, n_chunks: int) -> int:
    """Bytes on disk for ``n_chunks`` more chunk files and the result file (both uncompressed)."""
    per_case_chunk = (K.N_STATE + 1) * 8
    cases = min(n_chunks * plan.chunk_size, plan.n_cases)     # a chunk holds at most the plan's cases
    return cases * per_case_chunk + plan.n_cases * RESULT_BYTES_PER_CASE + 2**16


#: Bytes per case of the variables `sweep_variables` writes: 11 float64, one int32, 6 int8 (a test
#: keeps this in step with them).
RESULT_BYTES_PER_CASE = 8 * 11 + 4 + 6
