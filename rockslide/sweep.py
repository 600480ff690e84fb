"""Parameter sweeps: one case file, a grid of values, one compiled batch (``rockslide sweep``).

A sweep replaces a few values of a case file by every combination of its axes (:data:`AXES`:
``--mu``, ``--pga``, ``--vertical-factor``, ``--restitution``, ``--slenderness``, ``--gravity``,
and for a case whose ground motion is analytic pulses ``--amplitude``, ``--period`` and
``--duration`` of the horizontal pulse) and computes every point with the batch kernel (`batch`),
without history or event log.

- **Axes.** ``start:stop:step`` (the stop is included when it falls on the grid, within 1e-9 of a
  step) or a comma list; values take units as in case files (``100gal:1000gal:25gal``; a unit on
  every value or on none, none meaning SI, except for accelerations, which need their unit).
  Ranges are computed in decimal, so ``0.30:0.70:0.01`` gives exactly the floats of ``0.37`` and
  ``125 gal`` that a case file would. Dimension ``i`` of the result is the ``i``-th axis given on
  the command line.
- **Points.** Every point is the case with the axis values replaced through `case.case_with`
  (validated like a case file, each section once per distinct combination of the values that
  change it; a bad value is a one-line `CaseError` naming the option) and its
  ground motion checked like ``rockslide run`` checks it (`runner.check_against_ground`). ``--mu``
  sets ``mu_static`` and ``mu_kinetic = ratio * mu_static`` with the case's ratio
  ``mu_kinetic / mu_static`` (rounded to 12 significant digits, so that 0.494 / 0.52 is 0.95)
  unless ``--mu-kinetic-ratio`` gives it; ``--pga`` sets ``ground.scale.pga_horizontal`` (removing
  a ``factor``), and the vertical keeps the record's V/H ratio unless the case gives
  ``pga_vertical``; ``--slenderness`` sets the width to ``slenderness * height``.
- **Same arithmetic as ``rockslide run``.** The records are read once; each point's scale factors
  come from `records.combine`, its parameters and initial state from `simulate.parameters` and
  `simulate.initial_state`, and the batch kernel multiplies the unscaled samples by the factors as
  `records.combine` does. A sweep point and ``rockslide run`` on the same case give identical
  numbers.
- **Pulses.** A pulse case's points hold one record per distinct pulse (shape, period or
  duration: `runner.unit_pulses`, sampled at amplitude 1, each with its own sampling step and
  start), and the amplitudes are the scale factors, exactly as ``rockslide run`` multiplies them.
  A sweep over ``--amplitude`` and ``--period`` (or ``--duration``) is an overturning spectrum: its
  figure is drawn in the dimensionless plane of the literature (`spectrum_scales`,
  `plots.spectrum_figure`).
- **Chunks.** The grid is cut into chunks of ``chunk_size`` cases, chunk ``c`` holding the flat
  indices ``c, c + n_chunks, c + 2 n_chunks, ...`` (a mix of cheap and costly cases in each).
  Each finished chunk is saved at once (`ChunkStore`: ``.NAME.sweep.chunks/KEY/chunk-NNNNNN.npz``
  beside the result, written to a temporary name and renamed), ``KEY`` being a hash of the sweep's
  definition (:func:`definition_key`: case text, axes, ratio, chunk size, every point's kernel
  inputs, the ground samples, the package version and the kernel's source). A rerun of the same
  definition computes only the missing chunks; another definition never sees them. The chunk
  folder is removed once the result file is written.
- **Where.** Locally on a pool of threads, one chunk per task (`batch.compute`, which releases the
  GIL; a thread takes the next chunk as soon as it is done), or
  on a dask.distributed cluster: one task per chunk (`batch.compute`)
  returning plain numpy arrays. Both give identical results. Or on an NVIDIA GPU (``--device gpu``,
  the optional extra ``rockslide[gpu]``: `core.gpu`, the same kernel compiled for the device),
  many chunks per launch (`DEVICE_CASES_PER_LAUNCH`); the device may round the last bits
  differently (fused multiply-adds).
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import json
import math
import os
import re
import shutil
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np

from . import __version__, interrupts
from . import records as rec
from .case import Case, case_with
from .core import batch, compiled
from .core import kernel as K
from .core.physics import OVERTURNED
from .core.simulate import ground_array, initial_state, may_still_overturn, parameters
from .errors import CaseError, OutputError
from .files import atomic_write, remove_stale_temporaries
from .plots import spectrum_category, spectrum_figure, sweep_category, sweep_figure
from .pulses import Pulse, linear_overturning_ratio
from .runner import (
    ABSURD_ACCELERATION_IN_G,
    STEPS_PER_SECOND,
    RunWarning,
    absurd_acceleration,
    check_against_ground,
    check_parameters,
    check_size,
    is_pulse_case,
    model_for,
    pulse_ground,
    read_records,
    settings_for,
    step_warning,
    unit_pulses,
)
from .units import STANDARD_GRAVITY, UNIT_REQUIRED, parse_quantity

__all__ = ["AXES", "AxisKind", "Axis", "Plan", "ChunkStore", "parse_axis", "plan_sweep",
           "definition_key", "compute", "collect", "sweep_variables", "spectrum_scales", "MAX_POINTS"]

#: Largest grid (number of cases) a sweep accepts.
MAX_POINTS = 1_000_000
#: Chunk sizes: about ``n / CHUNKS_WANTED`` cases, within these bounds (the default).
CHUNKS_WANTED = 100
MIN_CHUNK, MAX_CHUNK = 4, 256
#: Points validated between two checks for Ctrl-C (and two calls of the planning's progress).
PLAN_BATCH = 2000
#: [s] Time to plan one point of a grid (`plan_sweep`; 0.025-0.03 ms measured on 2 cores), to say
#: how long the checks of a large grid take before they start.
PLAN_SECONDS_PER_POINT = 3e-5
#: Ranges include their stop when it is within this fraction of a step of the grid.
RANGE_TOLERANCE = 1e-9

#: The sweep file's format, part of a chunk's definition key: `results.SWEEP_FORMAT` and
#: `results.SWEEP_FORMAT_VERSION`, not imported from there (that would load h5py); a test keeps them equal.
FORMAT = "rockslide-sweep"
FORMAT_VERSION = 1


@dataclass(frozen=True)
class AxisKind:
    """What a sweep axis changes.

    Attributes
    ----------
    name : str
        Dimension name in the result file (``mu``, ``pga``...).
    option : str
        The command-line option (``--mu``).
    kind : str
        Unit kind of its values (a key of `units.UNITS`).
    key : str
        The case key it sets (dotted).
    long_name, units : str
        The dimension's ``long_name`` and ``units`` attributes (SI; ``1`` for dimensionless).
    label : str
        Axis label in figures; ``display_scale`` divides the SI values for it.
    """

    name: str
    option: str
    kind: str
    key: str
    long_name: str
    units: str
    label: str
    display_scale: float = 1.0


#: The axes a sweep can vary, in the order of ``rockslide sweep --help``.
AXES: dict[str, AxisKind] = {a.name: a for a in (
    AxisKind("mu", "--mu", "dimensionless", "contact.mu_static", "static friction coefficient",
             "1", "static friction coefficient μ"),
    AxisKind("pga", "--pga", "acceleration", "ground.scale.pga_horizontal",
             "peak horizontal ground acceleration", "m/s^2", "peak horizontal acceleration [gal]",
             0.01),
    AxisKind("vertical_factor", "--vertical-factor", "dimensionless", "ground.scale.vertical_factor",
             "factor on the vertical record", "1", "vertical factor"),
    AxisKind("restitution", "--restitution", "dimensionless", "contact.restitution",
             "coefficient of restitution", "1", "coefficient of restitution e"),
    AxisKind("slenderness", "--slenderness", "dimensionless", "block.width",
             "slenderness: width / height (the height kept)", "1", "width / height (b/h)"),
    AxisKind("gravity", "--gravity", "acceleration", "gravity", "gravitational acceleration",
             "m/s^2", "gravity g [m/s²]"),
    AxisKind("amplitude", "--amplitude", "acceleration", "ground.horizontal.amplitude",
             "amplitude of the horizontal pulse", "m/s^2", "pulse amplitude a_p [g]", STANDARD_GRAVITY),
    AxisKind("period", "--period", "time", "ground.horizontal.period", "period of the horizontal pulse",
             "s", "pulse period T_p [s]"),
    AxisKind("duration", "--duration", "time", "ground.horizontal.duration",
             "duration of the horizontal pulse", "s", "pulse duration t_d [s]"),
)}
#: The axes that change the horizontal pulse of a pulse case (and only there).
PULSE_AXES = ("amplitude", "period", "duration")
#: The axes that scale record files (a pulse is scaled by its amplitude).
RECORD_SCALE_AXES = ("pga", "vertical_factor")


@dataclass(frozen=True)
class Axis:
    """One axis of a sweep: its kind and its values.

    Attributes
    ----------
    name : str
        A key of :data:`AXES`.
    values : tuple of float
        SI values, in the order given.
    texts : tuple of str
        The values as written (``"125gal"``), for messages.
    spec : str
        The option's text as given.
    given_kind : AxisKind, optional
        What the axis is, for an axis that is not one of :data:`AXES` (``rockslide fragility``'s
        levels).
    """

    name: str
    values: tuple
    texts: tuple
    spec: str
    given_kind: AxisKind | None = None

    @property
    def kind(self) -> AxisKind:
        """What the axis changes (:data:`AXES`, or ``given_kind``)."""
        return self.given_kind if self.given_kind is not None else AXES[self.name]

    def __len__(self) -> int:
        return len(self.values)


# --------------------------------------------------------------------------------------------------
# Axes
# --------------------------------------------------------------------------------------------------

_PIECE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/^*0-9]*?)\s*$")


def parse_axis(name: str, spec: str, kind: AxisKind | None = None) -> Axis:
    """Read an axis option: ``start:stop:step``, a comma list, or one value.

    Parameters
    ----------
    name : str
        A key of :data:`AXES`, or any name with ``kind``.
    spec : str
        The option's text, e.g. ``"0.30:0.70:0.01"``, ``"100gal:1000gal:25gal"``, ``"0.5,0.52,0.55"``.
    kind : AxisKind, optional
        What the axis is when it is not one of :data:`AXES` (its ``option`` and unit ``kind``).

    Returns
    -------
    Axis

    Raises
    ------
    CaseError
        Naming the option: not a range or list of numbers, unknown unit, a unit on some values
        only, a step that is not positive, a stop below the start, repeated values, too many values.
    """
    given = kind
    kind = AXES[name] if given is None else given
    option = kind.option
    text = str(spec).strip()
    if not text:
        raise CaseError("expected start:stop:step or a comma list of values, got an empty text",
                        source=option)
    if ":" in text:
        pieces = text.split(":")
        if len(pieces) != 3:
            raise CaseError(f"expected start:stop:step (three values), got {text!r}", source=option)
        texts = _range_texts(option, kind.kind, text, [_split(option, kind.kind, p) for p in pieces])
    else:
        parts = [_split(option, kind.kind, p) for p in text.split(",")]
        units = {unit for _, unit in parts}
        if len(units) > 1 and "" in units:
            none = "" if kind.kind in UNIT_REQUIRED else " or on none (none means SI)"
            raise CaseError(f"give a unit on every value{none}, got {text!r}", source=option)
        texts = [f"{number}{unit}" for number, unit in parts]
    values = [parse_quantity(t, kind.kind, source=option) for t in texts]
    seen = {}
    for t, v in zip(texts, values, strict=True):
        if v in seen:
            raise CaseError(f"{t} repeats {seen[v]} (each value once)", source=option)
        seen[v] = t
    return Axis(name, tuple(values), tuple(texts), text, given)


def _split(option: str, kind: str, piece: str) -> tuple[Decimal, str]:
    """A piece of an axis option as (number, unit text)."""
    match = _PIECE.match(piece)
    if not match:
        what = "a number" if kind == "dimensionless" else "a number with an optional unit"
        example = {"dimensionless": "0.5", "time": "0.4s"}.get(kind, "800gal")
        raise CaseError(f"cannot read {piece.strip()!r} as {what} (like {example})", source=option)
    number, unit = match.group(1), match.group(2)
    if unit:
        parse_quantity(f"1 {unit}", kind, source=option)     # an unknown unit fails here
    try:
        return Decimal(number), unit
    except InvalidOperation:  # pragma: no cover - the pattern only lets numbers through
        raise CaseError(f"cannot read {piece!r} as a number", source=option) from None


def _range_texts(option: str, kind: str, text: str, pieces) -> list[str]:
    """The values of ``start:stop:step`` as texts with their unit, computed in decimal."""
    (start, u0), (stop, u1), (step, u2) = pieces
    if len({u0, u1, u2}) != 1:
        none = "" if kind in UNIT_REQUIRED else ", or all without unit (SI)"
        raise CaseError(f"give start, stop and step in one unit{none}, got {text!r}", source=option)
    if step <= 0:
        raise CaseError(f"the step must be positive, got {text!r}", source=option)
    if stop < start:
        raise CaseError(f"the stop is below the start in {text!r} (expected start <= stop)",
                        source=option)
    q = (stop - start) / step
    n = int(q)
    if q - n >= 1 - Decimal(RANGE_TOLERANCE):
        n += 1
    if n + 1 > MAX_POINTS:
        raise CaseError(f"{text!r} has {n + 1} values; at most {MAX_POINTS} points in a sweep",
                        source=option)
    numbers = [start + i * step for i in range(n + 1)]
    if abs(numbers[-1] - stop) <= Decimal(RANGE_TOLERANCE) * step:
        numbers[-1] = stop                               # on the grid: exactly the stop
    return [f"{_plain(x)}{u0}" for x in numbers]


def _plain(number: Decimal) -> str:
    """A decimal as short plain text (``0.37``, ``125``, ``1E-7``)."""
    if number == number.to_integral_value() and abs(number) < Decimal("1e15"):
        return str(number.quantize(Decimal(1)))
    return str(number.normalize())


def axis_changes(axis: str, value: float, case: Case, ratio: float | None) -> dict:
    """The case changes (`case.case_with`) that put one axis at ``value``."""
    if axis == "mu":
        return {"contact.mu_static": value, "contact.mu_kinetic": ratio * value}
    if axis == "pga":
        changes = {"ground.scale.pga_horizontal": value}
        if case.ground.scale.factor is not None:
            changes["ground.scale.factor"] = None
        return changes
    if axis == "slenderness":
        return {"block.width": value * case.block.height}
    return {AXES[axis].key: value}


def kinetic_ratio(case: Case, given: float | None) -> float:
    """``mu_kinetic / mu_static`` for ``--mu``: ``given``, or the case's rounded to 12 digits."""
    if given is not None:
        if not (isinstance(given, (int, float)) and math.isfinite(given) and 0.0 <= given <= 1.0):
            raise CaseError(f"must be within [0, 1] (mu_kinetic = ratio * mu_static), got {given!r}",
                            source="--mu-kinetic-ratio")
        return float(given)
    mu, nu = case.contact.mu_static, case.contact.mu_kinetic
    if mu == 0.0 or nu == mu:
        return 1.0
    return float(f"{nu / mu:.12g}")


# --------------------------------------------------------------------------------------------------
# The plan: every point's kernel inputs
# --------------------------------------------------------------------------------------------------


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


def plan_sweep(case: Case, axes: Sequence[Axis], *, records_dir: Path | None = None,
               mu_kinetic_ratio: float | None = None, chunk_size: int | None = None,
               progress: Callable[[int], None] | None = None) -> Plan:
    """Validate every point of the grid and build its kernel inputs.

    Parameters
    ----------
    case : Case
        The case file the points start from.
    axes : sequence of Axis
        At least one, each name once; dimension ``i`` is ``axes[i]``.
    records_dir : Path, optional
        Where records are looked for (`records.records_dir`).
    mu_kinetic_ratio : float, optional
        ``mu_kinetic / mu_static`` for ``--mu`` (default: the case's).
    chunk_size : int, optional
        Cases per chunk (default `default_chunk_size`).
    progress : callable, optional
        Called with the number of points validated, every few thousand points (a large grid takes
        minutes to validate).

    Returns
    -------
    Plan

    Raises
    ------
    CaseError
        No axis, an axis twice, a grid above :data:`MAX_POINTS`, a point that is not a valid case
        or whose ground motion fails the checks of ``rockslide run`` (naming the option).
    RecordError
        A record cannot be read or scaled.
    """
    axes = list(axes)
    if not axes:
        raise CaseError("give at least one axis: " + ", ".join(a.option for a in AXES.values()),
                        source="rockslide sweep")
    names = [a.name for a in axes]
    for name in names:
        if names.count(name) > 1:
            raise CaseError("given twice", source=AXES[name].option)
    if case.solver.method != "kernel":
        raise CaseError(f"a sweep runs the compiled kernel; got method {case.solver.method!r} "
                        "(use 'kernel', or 'rockslide run' for the reference solver)",
                        source=case.source, field="solver.method")
    if mu_kinetic_ratio is not None and "mu" not in names:
        raise CaseError("applies to --mu; give --mu too (or change mu_kinetic in the case file)",
                        source="--mu-kinetic-ratio")
    ratio = kinetic_ratio(case, mu_kinetic_ratio) if "mu" in names else None
    n = math.prod(len(a) for a in axes)
    if n > MAX_POINTS:
        raise CaseError(f"the grid has {n} points ({' x '.join(str(len(a)) for a in axes)}); at most "
                        f"{MAX_POINTS}", source="/".join(a.kind.option for a in axes))
    if chunk_size is not None and (isinstance(chunk_size, bool) or int(chunk_size) < 1):
        raise CaseError(f"must be a whole number >= 1, got {chunk_size!r}", source="--chunk-size")
    chunk_size = default_chunk_size(n) if chunk_size is None else int(chunk_size)
    pulses = is_pulse_case(case)
    for axis in axes:
        if axis.name in PULSE_AXES and not isinstance(case.ground.horizontal, Pulse):
            raise CaseError("applies to a case whose ground.horizontal is a pulse ({pulse: ..., amplitude: "
                            "...}); a record file is scaled with --pga", source=axis.kind.option)
        if axis.name in RECORD_SCALE_AXES and pulses:
            raise CaseError("scales record files; a pulse is scaled by its amplitude (--amplitude)",
                            source=axis.kind.option)
    if pulses:
        return _plan_pulses(case, axes, ratio, chunk_size, n, progress)

    records, entries = _read_records(case, records_dir)
    unscaled = rec.combine(records["horizontal"], records["vertical"], source=case.source,
                           still_dt=case.solver.dt)
    check_size(case, unscaled, history=False)

    settings = settings_for(case, history=False, energy=False)
    base = ground_array(unscaled.horizontal, unscaled.vertical, unscaled.dt, settings.tail)
    start = unscaled.start + case.ground.time_shift
    record_end = start + base.shape[1] * unscaled.dt

    params = np.empty((n, K.N_PARAMS))
    states = np.empty((n, K.N_STATE))
    factor_h = np.empty(n)
    factor_v = np.empty(n)
    factors: dict[tuple, tuple[float, float]] = {}     # scale section -> (kh, kv)
    checked: set[tuple] = set()                         # (scale section, gravity) checked
    highest = (0.0, None)                               # the largest scaled peak, at this point
    grounds: dict[tuple, rec.GroundMotion] = {}         # a few scaled records, for the checks
    for i, combo, point in _points(case, axes, ratio, progress):
        s = point.ground.scale
        scale = (s.pga_horizontal, s.factor, s.pga_vertical, s.vertical_factor)
        if (scale, point.gravity) not in checked:
            if scale not in grounds:
                if len(grounds) >= 16:
                    grounds.clear()
                grounds[scale] = rec.combine(records["horizontal"], records["vertical"],
                                             pga_horizontal=scale[0], factor=scale[1],
                                             pga_vertical=scale[2], vertical_factor=scale[3],
                                             source=case.source, still_dt=case.solver.dt)
            ground = grounds[scale]
            try:
                peak = check_against_ground(point, ground, warn=False)
            except CaseError as exc:
                raise _point_error(exc, axes, combo) from None
            if peak > highest[0]:
                highest = (peak, combo)
            checked.add((scale, point.gravity))
            factors[scale] = (ground.horizontal_factor, ground.vertical_factor)
        point_settings = settings_for(point, history=False, energy=False)
        params[i] = parameters(model_for(point), unscaled.dt, point_settings, start)
        states[i] = initial_state(point_settings)
        factor_h[i], factor_v[i] = factors[scale]
    _warn_coarse_step(case, axes, params)
    if highest[0] > ABSURD_ACCELERATION_IN_G * STANDARD_GRAVITY:
        warnings.warn(f"{absurd_acceleration(case.source, highest[0])} [at {_point_text(axes, highest[1])}]",
                      RunWarning, stacklevel=2)
    plan = Plan(case=case, axes=axes, mu_kinetic_ratio=ratio, params=params, states=states,
                factor_h=factor_h, factor_v=factor_v, base=base, first=np.zeros(n, dtype=np.int64),
                count=np.full(n, base.shape[1], dtype=np.int64), record_end=np.full(n, record_end),
                step=float(params[0, K.P_STEP]), records=entries, chunk_size=chunk_size)
    plan.key = definition_key(plan)
    return plan


def _points(case: Case, axes, ratio, progress=None):
    """Every point of the grid in flat C order: ``(index, combo, case)``, validated as a case file
    (`case_with`) and by `runner.check_parameters` (a bad point is a CaseError naming the options
    responsible). Ctrl-C is noticed, and ``progress`` told, every `PLAN_BATCH` points (a large grid
    takes a while).

    An axis changes one top-level section of the case (`section_of`), and no check of a case
    relates two sections (they check keys alone, or keys within one section), so a point is valid
    when its changes to each section are, and its case is the case with those sections replaced:
    each section is validated once per distinct combination of its axes' values, not once per
    point (a 41 x 37 grid: 78 validations instead of 1517).
    """
    n = math.prod(len(a) for a in axes)
    sections: dict[str, list[int]] = {}
    for d, axis in enumerate(axes):
        sections.setdefault(section_of(axis), []).append(d)
    validated: dict[str, dict[tuple, Case]] = {section: {} for section in sections}
    for i, combo in enumerate(itertools.product(*(range(len(a)) for a in axes))):
        if i % PLAN_BATCH == 0 and i:
            interrupts.check()
            if progress is not None:
                progress(PLAN_BATCH)
        replaced = {}
        for section, dims in sections.items():
            values = tuple(combo[d] for d in dims)
            changed = validated[section].get(values)
            if changed is None:
                changes = {}
                for d in dims:
                    changes.update(axis_changes(axes[d].name, axes[d].values[combo[d]], case, ratio))
                try:
                    changed = case_with(case, changes)
                    check_parameters(changed)
                except CaseError as exc:
                    raise _point_error(exc, axes, combo) from None
                validated[section][values] = changed
            replaced[section] = getattr(changed, section)
        yield i, combo, replace(case, **replaced)
    if progress is not None:
        progress(n - (n - 1) // PLAN_BATCH * PLAN_BATCH)


def section_of(axis: Axis) -> str:
    """The top-level section of the case an axis changes (``contact``, ``ground``, ``block``,
    ``gravity``)."""
    return axis.kind.key.split(".")[0]


def _plan_pulses(case: Case, axes, ratio, chunk_size: int, n: int, progress=None) -> Plan:
    """`plan_sweep` for a case whose ground motion is analytic pulses: one record per distinct
    pulse shape and length (the amplitudes are the scale factors, as `runner.pulse_ground` applies
    them), each with its own sampling step and start."""
    params = np.empty((n, K.N_PARAMS))
    states = np.empty((n, K.N_STATE))
    factor_h, factor_v, record_end = np.empty(n), np.empty(n), np.empty(n)
    first, count = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    records: dict[tuple, tuple] = {}          # (pulses at amplitude 1, dt, tail) -> (first, count, unit)
    pieces = []
    checked: set[tuple] = set()
    for i, combo, point in _points(case, axes, ratio, progress):
        h, v = point.ground.horizontal, point.ground.vertical
        shape = tuple(None if p is None else replace(p, amplitude=1.0) for p in (h, v))
        key = (shape, point.solver.dt, point.ground.tail)
        try:
            if key not in records:
                unit = unit_pulses(point)
                check_size(point, pulse_ground(point, unit), history=False)
                piece = ground_array(unit.horizontal, unit.vertical, unit.dt, point.ground.tail)
                records[key] = (sum(p.shape[1] for p in pieces), piece.shape[1], unit)
                pieces.append(piece)
            offset, length, unit = records[key]
            vertical = (key, None if v is None else v.amplitude, point.gravity)
            if vertical not in checked:               # flight: g + av > 0 (the vertical pulse)
                check_against_ground(point, pulse_ground(point, unit))
                checked.add(vertical)
        except CaseError as exc:
            raise _point_error(exc, axes, combo) from None
        point_settings = settings_for(point, history=False, energy=False)
        start = unit.start + point.ground.time_shift
        params[i] = parameters(model_for(point), unit.dt, point_settings, start)
        states[i] = initial_state(point_settings)
        factor_h[i] = 1.0 if h is None else h.amplitude
        factor_v[i] = 1.0 if v is None else v.amplitude
        first[i], count[i] = offset, length
        record_end[i] = start + length * unit.dt
    _warn_coarse_step(case, axes, params)
    plan = Plan(case=case, axes=list(axes), mu_kinetic_ratio=ratio, params=params, states=states,
                factor_h=factor_h, factor_v=factor_v, base=np.concatenate(pieces, axis=1), first=first,
                count=count, record_end=record_end, step=float(params[:, K.P_STEP].min()), records=[],
                chunk_size=chunk_size)
    plan.key = definition_key(plan)
    return plan


def _warn_coarse_step(case: Case, axes, params: np.ndarray) -> None:
    """`runner.step_warning` for the point with the fastest rocking (the largest ``p dt``)."""
    p2 = 0.75 * params[:, K.P_G] / params[:, K.P_R]          # p^2 = 3 g / (4 R)
    i = int(np.argmax(p2))
    warning = step_warning(case.source, math.sqrt(p2[i]), float(params[i, K.P_STEP]))
    if warning:
        combo = np.unravel_index(i, tuple(len(a) for a in axes))
        warnings.warn(f"{warning} [at {_point_text(axes, combo)}]", RunWarning, stacklevel=3)


def _point_text(axes, combo) -> str:
    """``--mu 0.5, --pga 800gal``: a point of the grid as given."""
    return ", ".join(f"{a.kind.option} {a.texts[j]}" for a, j in zip(axes, combo, strict=True))


def _read_records(case: Case, records_dir: Path | None):
    """The case's records, read once (`runner.read_records`), and the provenance entry of each."""
    records = read_records(case, records_dir)
    entries = [{"role": role, "path": Path(record.path).name, "sha256": record.sha256}
               for role, record in records.items() if record is not None]
    return records, entries


def _point_error(exc: CaseError, axes, combo) -> CaseError:
    """A point's CaseError, naming the option(s) responsible and the point."""
    field_name = exc.field or ""
    options = [a.kind.option for a in axes
               if field_name and (field_name.startswith(_key_root(a.name))
                                  or _key_root(a.name).startswith(field_name))]
    if not options:
        options = [a.kind.option for a in axes]
    return CaseError(f"{exc.message} [at {_point_text(axes, combo)}]", source="/".join(options), field=exc.field)


def _key_root(axis: str) -> str:
    return {"mu": "contact.mu", "pga": "ground.scale", "vertical_factor": "ground.scale",
            "slenderness": "block", "amplitude": "ground.horizontal", "period": "ground.horizontal",
            "duration": "ground.horizontal"}.get(axis, AXES[axis].key)


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


# --------------------------------------------------------------------------------------------------
# Chunks on disk
# --------------------------------------------------------------------------------------------------


class ChunkStore:
    """Finished chunks of one sweep definition: ``FOLDER/KEY16/chunk-NNNNNN.npz``.

    ``FOLDER`` is ``.NAME.sweep.chunks`` beside the result file. Each file holds the chunk's flat
    indices, final kernel states and a checksum (SHA-256 of the sweep's key, the indices and the
    states), and is written to a temporary name then renamed, so a file with the chunk's name is
    always complete. A file that cannot be read (truncated, a flipped byte, not an ``.npz``, a
    folder) or does not match the plan (another key, other indices, a wrong checksum) counts as
    missing: it is computed again, and `damaged` says which and why.
    """

    def __init__(self, folder: Path, key: str):
        self.root = Path(folder)
        self.key = key
        self.folder = self.root / key[:16]
        self.damaged: dict[int, str] = {}

    @classmethod
    def beside(cls, result_path: Path, key: str) -> ChunkStore:
        """The store for the result file ``OUT/NAME.sweep.h5``: ``OUT/.NAME.sweep.chunks``."""
        result_path = Path(result_path)
        name = result_path.name[:-len(".h5")] if result_path.name.endswith(".h5") else result_path.name
        return cls(result_path.with_name(f".{name}.chunks"), key)

    def path(self, chunk: int) -> Path:
        """The file of chunk ``chunk``."""
        return self.folder / f"chunk-{chunk:06d}.npz"

    def checksum(self, indices: np.ndarray, states: np.ndarray) -> str:
        """SHA-256 of the sweep's key, a chunk's indices and its states (as stored)."""
        digest = hashlib.sha256(self.key.encode())
        digest.update(np.ascontiguousarray(indices, dtype=np.int64).tobytes())
        digest.update(np.ascontiguousarray(states, dtype=np.float64).tobytes())
        return digest.hexdigest()

    def load(self, chunk: int, indices: np.ndarray) -> np.ndarray | None:
        """The final states of ``chunk`` if a matching, intact file is stored, else None (and, for a
        file that exists but cannot be used, the reason in ``damaged[chunk]``)."""
        path = self.path(chunk)
        if not os.path.lexists(path):
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                key, stored, states, checksum = (data["key"], data["indices"], data["states"],
                                                 data["checksum"])
                key, checksum = str(key), str(checksum)
                stored = np.array(stored)
                states = np.array(states, dtype=np.float64)
        except Exception as exc:  # noqa: BLE001 - any way of not being a readable chunk file
            self.damaged[chunk] = _one_line(exc) or type(exc).__name__
            return None
        if key != self.key:
            self.damaged[chunk] = "of another sweep definition"
        elif not np.array_equal(stored, indices) or states.shape != (indices.size, K.N_STATE):
            self.damaged[chunk] = "other cases than the plan's"
        elif checksum != self.checksum(stored, states):
            self.damaged[chunk] = "its checksum does not match its content"
        else:
            self.damaged.pop(chunk, None)
            return states
        return None

    def save(self, chunk: int, indices: np.ndarray, states: np.ndarray) -> None:
        """Store a finished chunk (atomically: a temporary file renamed; whatever was at its name,
        a damaged file or a folder, is replaced)."""
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError(f"cannot create the chunk folder: {exc.strerror or exc}",
                              source=str(self.folder)) from None
        path = self.path(chunk)
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        indices = np.ascontiguousarray(indices, dtype=np.int64)
        states = np.ascontiguousarray(states, dtype=np.float64)
        # not synced to disk: a chunk that a power cut damages fails its checksum and is computed again
        with atomic_write(path, overwrite=True, per_thread=True, what="chunk", interruptible=False,
                          sync=False) as handle:
            np.savez(handle, key=np.array(self.key), indices=indices, states=states,
                     checksum=np.array(self.checksum(indices, states)))
        self.damaged.pop(chunk, None)

    def remove_stale_temporaries(self) -> list[Path]:
        """Delete temporary chunk files of processes that are gone (`files.remove_stale_temporaries`)."""
        try:
            names = [p.name for p in self.folder.glob(".chunk-*.tmp")]
        except OSError:
            return []
        finals = {self.folder / (n.split(".npz.")[0][1:] + ".npz") for n in names if ".npz." in n}
        return remove_stale_temporaries(sorted(finals))

    def count(self) -> int:
        """Chunk files stored for this definition."""
        try:
            return sum(1 for p in self.folder.glob("chunk-*.npz"))
        except OSError:  # pragma: no cover
            return 0

    def others(self) -> list[Path]:
        """Chunk folders of other sweep definitions (never used by this one)."""
        try:
            return sorted(p for p in self.root.iterdir() if p.is_dir() and p != self.folder)
        except OSError:
            return []

    def remove(self) -> None:
        """Delete this definition's chunks, and the chunk folder if nothing else is in it."""
        shutil.rmtree(self.folder, ignore_errors=True)
        try:
            self.root.rmdir()
        except OSError:
            pass


# --------------------------------------------------------------------------------------------------
# Computing
# --------------------------------------------------------------------------------------------------


def compute(plan: Plan, store: ChunkStore, chunks: Sequence[int], *, workers: int | None = None,
            scheduler: str | None = None, progress: Callable[[int], None] | None = None,
            device: str = "cpu") -> None:
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
    scheduler : str, optional
        Address of a dask.distributed scheduler: the chunks are computed there, one task each.
    progress : callable, optional
        Called with the number of cases of each finished chunk.
    device : {"cpu", "gpu"}
        Where a local run computes (`DEVICES`): the CPU's cores, or an NVIDIA GPU (`core.gpu`).

    Raises
    ------
    CaseError
        ``workers`` out of range, the scheduler cannot be reached, is lost, or a task fails there
        (the chunks finished before are stored), or no GPU can be used (`check_device`).
    interrupts.Interrupted
        After Ctrl-C or SIGTERM, checked between chunk groups; the chunks finished before it are
        stored.
    """
    check_device(device)
    if scheduler:
        _compute_dask(plan, store, chunks, scheduler, progress)
    elif device == "gpu":
        _compute_device(plan, store, chunks, progress)
    else:
        _compute_local(plan, store, chunks, workers, progress)


#: Where a local sweep computes (``--device``).
DEVICES = ("cpu", "gpu")

#: Cases per launch of the GPU kernel: enough to fill a large GPU many times over (an H100 keeps
#: some 10^4 to 10^5 threads of a register-heavy kernel resident) and to sort by work over many
#: chunks, few enough for the progress bar and Ctrl-C to come every launch.
DEVICE_CASES_PER_LAUNCH = 1 << 16


def check_device(device: str) -> None:
    """Refuse a ``--device`` that is not one of `DEVICES`, or ``gpu`` where no GPU run can be made
    (numba-cuda not installed, no CUDA GPU or driver), with one line saying why."""
    if device not in DEVICES:
        raise CaseError(f"must be one of {', '.join(DEVICES)}, got {device!r}", source="--device")
    if device == "gpu":
        from .core import gpu
        try:
            gpu.require_device()
        except gpu.DeviceUnavailable as exc:
            raise CaseError(str(exc), source="--device gpu") from None


def _compute_device(plan, store, chunks, progress):
    """The chunks on the GPU (`core.gpu.compute`), as many per launch as make up to
    `DEVICE_CASES_PER_LAUNCH` cases (the device sorts a launch's cases by work); each chunk of a
    launch is stored when the launch is done. Ctrl-C is checked between launches."""
    from .core import gpu

    group: list[int] = []
    cases = 0
    for position, chunk in enumerate(chunks):
        group.append(chunk)
        cases += plan.chunk_indices(chunk).size
        if cases < DEVICE_CASES_PER_LAUNCH and position + 1 < len(chunks):
            continue
        interrupts.check()
        parts = [plan.chunk_indices(c) for c in group]
        final = gpu.compute(*_chunk_inputs(plan, np.concatenate(parts)))
        for c, indices, part in zip(group, parts, np.split(final, np.cumsum([p.size for p in parts])[:-1]),
                                    strict=True):
            store.save(c, indices, part)
        if progress is not None:
            progress(cases)
        group, cases = [], 0
    interrupts.check()


def check_workers(workers: int | None) -> None:
    """Refuse a ``--workers`` outside ``1 ... 4 x the cores`` (before any planning)."""
    if workers is None:
        return
    limit = 4 * local_threads()
    if isinstance(workers, bool) or not 1 <= int(workers) <= limit:
        raise CaseError(f"must be within 1 ... {limit} (4 threads per core here), got {workers!r}",
                        source="--workers")


def _compute_local(plan, store, chunks, workers, progress):
    """The chunks on a pool of threads running the compiled batch (`batch.run_batch` releases the
    GIL), one chunk per task: each thread takes the next chunk as soon as it is done, so cases that
    rock for a minute and cases at rest even out and every core is busy to the end. Each chunk is
    stored as soon as it is done; Ctrl-C is checked while waiting, and the chunks being computed
    are finished and kept."""
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    check_workers(workers)
    threads = int(workers) if workers is not None else local_threads()

    def task(chunk: int) -> int:
        if interrupts.requested() is not None:      # stopping: start no new chunk
            return 0
        indices = plan.chunk_indices(chunk)
        store.save(chunk, indices, batch.compute(*_chunk_inputs(plan, indices)))
        return indices.size

    with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="rockslide-sweep") as pool:
        pending = {pool.submit(task, chunk) for chunk in chunks}
        try:
            while pending:
                interrupts.check()
                done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                for future in done:
                    cases = future.result()
                    if progress is not None:
                        progress(cases)
        except BaseException:
            for future in pending:
                future.cancel()
            raise
    interrupts.check()


def local_threads() -> int:
    """Threads a local sweep uses by default: every core this process may run on."""
    import os

    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                    # not on Linux
        return os.cpu_count() or 1


def _chunk_inputs(plan: Plan, indices: np.ndarray):
    """`batch.compute`'s arguments for the cases ``indices``."""
    return (plan.params[indices], plan.states[indices], plan.base, plan.first[indices],
            plan.count[indices], plan.factor_h[indices], plan.factor_v[indices])


#: [s] for the connection to a dask scheduler, and for a lost one to come back.
SCHEDULER_TIMEOUT = 10.0


def _compute_dask(plan, store, chunks, address, progress):
    """One task per chunk on the cluster (`batch.compute`, serial in the task); each chunk is
    stored as its result arrives. One bounded connection attempt (`identify_scheduler`), the
    cluster's log messages kept off the terminal, Ctrl-C checked while waiting."""
    try:
        import distributed
    except ImportError:  # pragma: no cover - a declared dependency
        raise CaseError("needs dask.distributed (pip install 'dask[distributed]')",
                        source="--scheduler") from None
    address = scheduler_address(address)
    with _quiet_logs("distributed", "tornado", "asyncio"):
        identify_scheduler(address)
        try:
            client = distributed.Client(address, timeout=f"{SCHEDULER_TIMEOUT:g}s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise CaseError(f"cannot connect to the dask scheduler at {address}: {_one_line(exc)}",
                            source="--scheduler") from None
        futures = {}
        try:
            base = client.scatter(plan.base, broadcast=True)
            for chunk in chunks:
                indices = plan.chunk_indices(chunk)
                p, s, _, first, count, kh, kv = _chunk_inputs(plan, indices)
                future = client.submit(batch.compute, p, s, base, first, count, kh, kv, pure=False)
                futures[future] = (chunk, indices)
            _collect_futures(client, futures, store, address, progress)
        finally:
            with contextlib.suppress(Exception):
                if futures:
                    client.cancel(list(futures))
            with contextlib.suppress(Exception):
                client.close(timeout=2)


def _collect_futures(client, futures: dict, store: ChunkStore, address: str, progress) -> None:
    """Store each chunk as its task finishes; Ctrl-C and a lost scheduler are noticed within a
    fraction of a second and `SCHEDULER_TIMEOUT` respectively."""
    import time

    lost_since = None
    while futures:
        interrupts.check()
        finished = [f for f in futures if f.status in ("finished", "error", "cancelled", "lost")]
        for future in finished:
            chunk, indices = futures.pop(future)
            if future.status != "finished":
                if future.status == "error":
                    exc = future.exception()
                    raise CaseError(f"a task failed on the cluster: {type(exc).__name__}: {_one_line(exc)} "
                                    "(are rockslide and its dependencies installed on the workers?)",
                                    source="--scheduler")
                raise _lost(address, store)
            try:
                states = np.asarray(future.result(timeout=SCHEDULER_TIMEOUT), dtype=np.float64)
            except Exception:  # noqa: BLE001 - the result could not be fetched: the scheduler is gone
                raise _lost(address, store) from None
            store.save(chunk, indices, states)
            if progress is not None:
                progress(indices.size)
        if client.status == "running":
            lost_since = None
        elif lost_since is None:
            lost_since = time.monotonic()
        elif time.monotonic() - lost_since > SCHEDULER_TIMEOUT:
            raise _lost(address, store)
        if not finished:
            time.sleep(0.1)


def _lost(address: str, store: ChunkStore) -> CaseError:
    return CaseError(f"lost the connection to the dask scheduler at {address}; {store.count()} finished "
                     f"chunks are kept in {store.folder} and the same command resumes from them",
                     source="--scheduler")


def scheduler_address(address: str) -> str:
    """``tcp://HOST:PORT`` from ``--scheduler`` (``HOST:PORT`` taken as TCP), or a CaseError.

    Only plain TCP: ``tls://`` needs certificates rockslide takes no options for, and ``inproc://``
    exists only inside one Python process.
    """
    from urllib.parse import urlsplit

    text = str(address).strip()
    if "://" not in text:
        text = f"tcp://{text}"
    scheme = text.split("://", 1)[0].lower()
    if scheme != "tcp":
        raise CaseError(f"{scheme}:// addresses are not supported; expected tcp://HOST:PORT (a scheduler "
                        "started with 'dask scheduler'; for TLS, reach it through an SSH tunnel)",
                        source="--scheduler")
    try:
        parts = urlsplit(text)
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or not port:
        raise CaseError(f"expected an address like tcp://HOST:PORT, got {_shown(address)}",
                        source="--scheduler")
    return text


def identify_scheduler(address: str, timeout: float | None = None) -> dict:
    """Ask ``address`` who it is, within ``timeout`` seconds in all (default
    :data:`SCHEDULER_TIMEOUT`): a dask scheduler answers the ``identity`` request; anything else
    (nothing listening, an HTTP server) is a CaseError."""
    timeout = SCHEDULER_TIMEOUT if timeout is None else timeout
    import asyncio
    import socket
    from concurrent.futures import ThreadPoolExecutor
    from urllib.parse import urlsplit

    from distributed.comm import connect

    parts = urlsplit(address)
    try:
        socket.create_connection((parts.hostname, parts.port), timeout=timeout).close()
    except OSError as exc:       # refused, unreachable: at once (dask itself retries until its timeout)
        raise CaseError(f"cannot connect to the dask scheduler at {address}: "
                        f"{exc.strerror or _one_line(exc)}", source="--scheduler") from None

    async def ask():
        comm = await connect(address, timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        with ThreadPoolExecutor(1) as pool:         # its own event loop, even under a running one
            reply = pool.submit(asyncio.run, asyncio.wait_for(ask(), timeout)).result()
    except (asyncio.TimeoutError, TimeoutError):
        raise CaseError(f"no dask scheduler answered at {address} within {timeout:g} s (is something "
                        "else listening there?)", source="--scheduler") from None
    except Exception as exc:  # noqa: BLE001 - refused, reset, closed, a bad handshake
        reason = getattr(exc, "strerror", None) or _one_line(exc)
        raise CaseError(f"cannot connect to the dask scheduler at {address}: {reason}",
                        source="--scheduler") from None
    if not (isinstance(reply, dict) and reply.get("type") == "Scheduler"):
        raise CaseError(f"{address} answers, but not as a dask scheduler", source="--scheduler")
    return reply


@contextlib.contextmanager
def _quiet_logs(*prefixes: str):
    """Keep the log messages of these libraries off the terminal (errors are reported in one line)."""
    import logging

    names = [n for n in list(logging.root.manager.loggerDict) if n.split(".")[0] in prefixes]
    loggers = [logging.getLogger(n) for n in {*names, *prefixes}]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


def _shown(text: str, limit: int = 80) -> str:
    text = repr(str(text))
    return text if len(text) <= limit else text[:limit - 4] + "...'"


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def work_estimate(plan: Plan, n_cases: int, *, workers: int | None = None) -> float:
    """An upper estimate [s] of the time ``n_cases`` cases of ``plan`` take on this machine's
    threads (every case moving until the end; cases at rest go about 3000 times faster)."""
    threads = workers or local_threads()
    return n_cases * plan.steps_per_case / (STEPS_PER_SECOND * threads)


def bytes_needed(plan: Plan, n_chunks: int) -> int:
    """Bytes on disk for ``n_chunks`` more chunk files and the result file (both uncompressed)."""
    per_case_chunk = (K.N_STATE + 1) * 8
    return n_chunks * plan.chunk_size * per_case_chunk + plan.n_cases * RESULT_BYTES_PER_CASE + 2**16


#: Bytes per case of the variables `sweep_variables` writes: 11 float64, one int32, 6 int8 (a test
#: keeps this in step with them).
RESULT_BYTES_PER_CASE = 8 * 11 + 4 + 6


def missing_chunks(plan: Plan, store: ChunkStore) -> list[int]:
    """The chunks of ``plan`` that ``store`` does not hold (a damaged file counts as missing)."""
    return [c for c in range(plan.n_chunks) if store.load(c, plan.chunk_indices(c)) is None]


def collect(plan: Plan, store: ChunkStore) -> np.ndarray:
    """The final states of every case, ``float64[n, N_STATE]`` (flat C order), from the store.

    Raises
    ------
    OutputError
        A chunk is missing or damaged (it was deleted meanwhile): rerun to compute it.
    """
    out = np.empty((plan.n_cases, K.N_STATE))
    for chunk in range(plan.n_chunks):
        indices = plan.chunk_indices(chunk)
        states = store.load(chunk, indices)
        if states is None:
            raise OutputError(f"chunk {chunk} is missing or damaged; rerun the same command to "
                              "compute it", source=str(store.folder))
        out[indices] = states
    return out


# --------------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------------

#: Bits of the ``modes`` variable.
MODE_BITS = {"slip": 1, "liftoff": 2, "liftoff_slip": 4}

STATUS_FLAGS = {"flag_values": np.arange(len(K.STATUS_NAMES), dtype=np.int8),
                "flag_meanings": " ".join(K.STATUS_NAMES)}


def sweep_variables(plan: Plan, states: np.ndarray) -> dict:
    """The result variables on the grid, from the final kernel states.

    Returns
    -------
    dict
        ``name -> (array shaped like the grid, attributes)``; attributes ``units`` and
        ``long_name`` (and CF ``flag_*`` for the coded ones). Same values as the summary of
        ``rockslide run`` (`simulate.summarise`, which reads one state vector the same way: a change
        there is a change here; tests/test_sweep.py compares points with runs).
    """
    shape = plan.shape
    st = states
    overturned = st[:, K.S_MODE] == OVERTURNED
    status = st[:, K.S_STATUS].astype(np.int8)
    t_slip, t_rock, t_rockslip = st[:, K.S_T_SLIP], st[:, K.S_T_ROCK], st[:, K.S_T_ROCKSLIP]
    modes = ((t_slip > 0) * MODE_BITS["slip"] + (t_rock > 0) * MODE_BITS["liftoff"]
             + (t_rockslip > 0) * MODE_BITS["liftoff_slip"]).astype(np.int8)
    end = np.where(np.isnan(st[:, K.S_END_TIME]), plan.record_end, st[:, K.S_END_TIME])
    alpha = plan.params[:, K.P_ALPHA]
    undecided = np.zeros(len(st), dtype=bool)
    for i in np.flatnonzero(st[:, K.S_MODE] != K.REST):              # a block at rest stands
        undecided[i] = may_still_overturn(st[i], plan.params[i, K.P_R], alpha[i], plan.params[i, K.P_G],
                                          plan.params[i, K.P_NU], plan.params[i, K.P_TAN_ALPHA])

    def grid(values, dtype):
        return np.asarray(values, dtype=dtype).reshape(shape)

    nan = np.nan
    out = {
        "overturned": (grid(overturned, np.int8),
                       {"units": "1", "long_name": "overturned (1) or standing (0)",
                        "flag_values": np.array([0, 1], dtype=np.int8),
                        "flag_meanings": "standing overturned"}),
        "overturn_time": (grid(np.where(overturned, st[:, K.S_OVERTURN_TIME], nan), np.float64),
                          {"units": "s", "long_name": "time the rotation reached pi/2 (NaN: standing)"}),
        "direction": (grid(np.where(overturned, st[:, K.S_DIRECTION], 0.0), np.int8),
                      {"units": "1", "long_name": "sign of the rotation at overturning (0: standing)",
                       "flag_values": np.array([-1, 0, 1], dtype=np.int8),
                       "flag_meanings": "negative standing positive"}),
        "fall_start_time": (grid(np.where(overturned, st[:, K.S_FALL_START], nan), np.float64),
                            {"units": "s", "long_name": "time the rotation last passed alpha before "
                             "overturning (NaN: standing)"}),
        "max_rotation": (grid(st[:, K.S_MAX_THETA], np.float64),
                         {"units": "rad", "long_name": "largest rotation |phi|"}),
        "alpha": (grid(alpha, np.float64),
                  {"units": "rad", "long_name": "alpha = atan(b/h): the rotation past which gravity "
                   "tips the block over"}),
        "max_rotation_ratio": (grid(st[:, K.S_MAX_THETA] / alpha, np.float64),
                               {"units": "1", "long_name": "largest rotation / alpha: how near "
                                "overturning (above 1: past alpha)"}),
        "max_slip": (grid(st[:, K.S_MAX_X], np.float64),
                     {"units": "m", "long_name": "largest slip displacement |x|"}),
        "residual_slip": (grid(st[:, K.S_X], np.float64),
                          {"units": "m", "long_name": "slip displacement x at the end"}),
        "impacts": (grid(st[:, K.S_IMPACTS], np.int32),
                    {"units": "1", "long_name": "number of rocking impacts"}),
        # the run stops at overturning, so the impacts counted are those before it
        "overturn_mode": (grid(np.where(overturned, np.where(st[:, K.S_IMPACTS] > 0, 2, 1), 0), np.int8),
                          {"units": "1", "long_name": "how the block overturned: without any impact "
                           "before, or after one or more impacts (0: standing)",
                           "flag_values": np.array([0, 1, 2], dtype=np.int8),
                           "flag_meanings": "standing without_impact after_impact"}),
        "undecided": (grid(undecided, np.int8),
                      {"units": "1", "long_name": "still moving at the end with the energy or tilt to "
                       "overturn afterwards: 'standing' not decided (give ground.tail)",
                       "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "decided undecided"}),
        "status": (grid(status, np.int8),
                   {"units": "1", "long_name": "ok, or where the computation left the model",
                    **STATUS_FLAGS}),
        "modes": (grid(modes, np.int8),
                  {"units": "1", "long_name": "modes that occurred (bit mask)",
                   "flag_masks": np.array(list(MODE_BITS.values()), dtype=np.int8),
                   "flag_meanings": " ".join(MODE_BITS)}),
        "end_time": (grid(end, np.float64),
                     {"units": "s", "long_name": "time the computation ended (overturning, leaving "
                      "the model, or the end of the record and tail)"}),
        "time_slip": (grid(t_slip, np.float64),
                      {"units": "s", "long_name": "time spent slipping (SLIP)"}),
        "time_liftoff": (grid(t_rock, np.float64),
                         {"units": "s", "long_name": "time spent lifted off without slip (ROCK)"}),
        "time_liftoff_slip": (grid(t_rockslip, np.float64),
                              {"units": "s", "long_name": "time spent lifted off and slipping "
                               "(ROCKSLIP)"}),
    }
    return out


def coordinates(plan: Plan) -> list:
    """``[(name, SI values, attributes)]`` of the axes, in dimension order."""
    out = []
    for axis in plan.axes:
        kind = axis.kind
        attrs = {"units": kind.units, "long_name": kind.long_name, "option": kind.option,
                 "given_as": axis.spec}
        if axis.name == "slenderness":
            attrs["height"] = float(plan.case.block.height)
        out.append((axis.name, np.asarray(axis.values, dtype=np.float64), attrs))
    return out


def root_attributes(plan: Plan, command_line: str) -> dict:
    """Root attributes of the result file: provenance of the sweep, and the scales of an
    overturning spectrum (`spectrum_scales`, as ``spectrum_*``)."""
    attrs = {
        "title": f"rockslide sweep of {plan.case.name}: {plan.describe()}",
        "name": plan.case.name,
        "case_text": plan.case.text,
        "case_file": Path(plan.case.source).name,
        "command_line": command_line,
        "axes": " ".join(a.name for a in plan.axes),
        "sweep_key": plan.key,
        "integration_step": plan.step,
        "events": plan.case.solver.events,
        "mu_kinetic_ratio": math.nan if plan.mu_kinetic_ratio is None else plan.mu_kinetic_ratio,
        "chunk_size": plan.chunk_size,
    }
    for entry in plan.records:
        attrs[f"record_{entry['role']}"] = entry["path"]
        attrs[f"record_{entry['role']}_sha256"] = entry["sha256"]
    scales = spectrum_scales(plan)
    for key, value in (scales or {}).items():
        attrs[f"spectrum_{key}"] = value
    return attrs


#: Each pair of axes that makes an overturning spectrum (amplitude against frequency).
SPECTRUM_AXES = ({"amplitude", "period"}, {"amplitude", "duration"})


def spectrum_scales(plan: Plan) -> dict | None:
    """The scales of an overturning spectrum, or None when the sweep is not one.

    A sweep is an overturning spectrum when its two axes are ``--amplitude`` and ``--period`` (or
    ``--duration``) of the horizontal pulse. Its figure is drawn in the literature's dimensionless
    plane: ``a_p / (g tan(alpha))`` against ``w_p / p`` (Housner 1963; Zhang and Makris 2001).

    Returns
    -------
    dict
        ``rocking_frequency`` ``p = sqrt(3 g / (4 R))`` [rad/s], ``liftoff_acceleration``
        ``g tan(alpha)`` [m/s^2], ``slip_acceleration`` ``mu g`` [m/s^2] (both thresholds of
        eqs. 6 and 11 at rest), ``alpha`` [rad], ``pulse`` (the shape), ``cycles``, and
        ``vertical`` (1 when a vertical pulse acts too, which the small-angle theory leaves out).
    """
    if {a.name for a in plan.axes} not in SPECTRUM_AXES or len(plan.axes) != 2:
        return None
    case = plan.case
    _, alpha, p2 = model_for(case).constants
    return {"rocking_frequency": math.sqrt(p2), "alpha": alpha,
            "liftoff_acceleration": case.gravity * case.block.width / case.block.height,
            "slip_acceleration": case.gravity * case.contact.mu_static,
            "pulse": case.ground.horizontal.pulse, "cycles": int(case.ground.horizontal.cycles),
            "vertical": int(case.ground.vertical is not None)}


def categories(variables: dict) -> np.ndarray:
    """The map's category of each point (`plots.sweep_category`) from the result variables."""
    return sweep_category(variables["overturned"][0], variables["status"][0], variables["modes"][0])


def figure(plan: Plan, variables: dict):
    """The PNG of a sweep: an overturning spectrum (`spectrum_scales`), else the maps of
    `plots.sweep_figure` with the axes in their display units (gal for accelerations given as
    PGA) and categories from `categories`."""
    axes = [(a.kind.name, a.values) for a in plan.axes]
    title = f"{plan.case.name}: {plan.describe()}"
    scales = spectrum_scales(plan)
    if scales is not None:
        return _spectrum(axes, variables, scales, title)
    return _maps(axes, variables, title)


def stored_figure(stored) -> object:
    """The same figure from a sweep file read back (`results.read_sweep`), for ``rockslide plot``."""
    shape = " x ".join(f"{len(values)} {name}" for name, values, _ in stored.coords)
    axes = [(name, values) for name, values, _ in stored.coords]
    title = (f"{stored.attrs.get('name', 'sweep')}: {shape} = "
             f"{int(np.prod([len(v) for _, v, _ in stored.coords]))} cases")
    scales = {key[len("spectrum_"):]: value for key, value in stored.attrs.items()
              if key.startswith("spectrum_")}
    if scales:
        return _spectrum(axes, variables=stored.variables, scales=scales, title=title)
    return _maps(axes, stored.variables, title)


#: Points of the small-angle theory's curve drawn over a spectrum.
THEORY_POINTS = 40


def _spectrum(axes, variables: dict, scales: dict, title: str):
    """`plots.spectrum_figure` of a two-axis pulse sweep: amplitude over ``g tan(alpha)`` up the
    page, pulse frequency over ``p`` across, the categories of `plots.spectrum_category`, and
    the theory's curves where they exist: the thresholds of liftoff and slip at rest (exact), and
    the small-angle boundary of overturning without impact (`pulses.linear_overturning_ratio`;
    without a vertical pulse)."""
    names = [name for name, _ in axes]
    a = names.index("amplitude")
    other = 1 - a
    pulse = Pulse(str(scales["pulse"]), 1.0, cycles=int(scales["cycles"]))
    p = float(scales["rocking_frequency"])
    lift, slip = float(scales["liftoff_acceleration"]), float(scales["slip_acceleration"])
    period_or_duration = np.asarray(axes[other][1], dtype=float)
    frequency = np.array([replace(pulse, **{names[other]: t}).frequency for t in period_or_duration]) / p
    amplitude = np.asarray(axes[a][1], dtype=float) / lift

    def grid(name):                                   # [amplitude, frequency]
        values = np.asarray(variables[name][0])
        return values if a == 0 else values.T

    category = spectrum_category(grid("overturned"), grid("status"), grid("modes"), grid("impacts"))
    rotation = grid("max_rotation") / float(scales["alpha"])
    curves = []
    if slip < lift:
        curves.append((f"slip starts at rest: a_p = μ g ({slip / lift:.3g} g tan α)", None, slip / lift))
    else:
        curves.append(("liftoff: a_p = g tan α", None, 1.0))
    if not int(scales["vertical"]) and frequency.size > 1:
        betas = np.geomspace(frequency.min(), frequency.max(), THEORY_POINTS)
        ratios = np.array([linear_overturning_ratio(pulse, b) for b in betas])
        curves.append(("overturning without impact, small-angle theory", betas, ratios))
    return spectrum_figure(frequency, amplitude, category, rotation, curves,
                           xlabel=f"ω_p / p   (p = {p:.3g} rad/s)",
                           ylabel=f"a_p / (g tan α)   (g tan α = {lift / STANDARD_GRAVITY:.3g} g)",
                           title=f"{title}: {pulse.pulse} pulse")


def _maps(axes, variables: dict, title: str):
    over = int(np.asarray(variables["overturned"][0]).sum())
    shown = [(AXES[name].label, np.asarray(values) / AXES[name].display_scale) for name, values in axes]
    return sweep_figure(shown, categories(variables), variables["max_rotation"][0],
                        variables["residual_slip"][0], title=f"{title}, {over} overturned")


def time_shares(states: np.ndarray) -> dict:
    """Total time in each moving state over the grid [s] (where a sweep's work goes)."""
    return {"SLIP": float(states[:, K.S_T_SLIP].sum()), "ROCK": float(states[:, K.S_T_ROCK].sum()),
            "ROCKSLIP": float(states[:, K.S_T_ROCKSLIP].sum()),
            "REST": float(states[:, K.S_T_REST].sum())}

