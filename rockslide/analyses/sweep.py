"""Parameter sweeps: one case file, a grid of values, one compiled batch (``rockslide sweep``).

A sweep replaces a few values of a case file by every combination of its axes (:data:`AXES`:
``--mu``, ``--pga``, ``--vertical-factor``, ``--restitution``, ``--height-to-width``, ``--gravity``,
for a case whose ground motion is analytic pulses ``--amplitude``, ``--period`` and
``--duration`` of the horizontal pulse, and for a case of two horizontal components ``--azimuth``,
the block's orientation: one record per orientation, the motion along it, `prepare.ground_along`)
and computes every point with the batch kernel (`batch`), without history or event log.

- **Axes.** ``start:stop:step`` (the stop is included when it falls on the grid, within 1e-9 of a
  step) or a comma list; values take units as in case files (``100gal:1000gal:25gal``; a unit on
  every value or on none, none meaning SI, except for accelerations, which need their unit).
  Ranges are computed in decimal, so ``0.30:0.70:0.01`` gives exactly the floats of ``0.37`` and
  ``125 gal`` that a case file would. Dimension ``i`` of the result is the ``i``-th axis given on
  the command line.
- **Points.** Every point is the case with the axis values replaced through `case.case_with`
  (validated like a case file, each section once per distinct combination of the values that
  change it; a bad value is a one-line `CaseError` naming the option) and its
  ground motion checked like ``rockslide run`` checks it (`prepare.check_against_ground`). ``--mu``
  sets ``mu_static`` and ``mu_kinetic = ratio * mu_static`` with the case's ratio
  ``mu_kinetic / mu_static`` (rounded to 12 significant digits, so that 0.494 / 0.52 is 0.95)
  unless ``--mu-kinetic-ratio`` gives it; ``--pga`` sets ``ground.scale.pga_horizontal`` (removing
  a ``factor``), and the vertical keeps the record's V/H ratio unless the case gives
  ``pga_vertical``; ``--height-to-width`` (h/b, the field's slenderness ratio) sets the width to
  ``height / (h/b)``, the height kept. (``--slenderness``, width / height, the inverse of the
  field's ratio, is retired: `RETIRED_AXES`.)
- **Same arithmetic as ``rockslide run``.** The records are read once; each point's scale factors
  come from `records.combine`, its parameters and initial state from `simulate.parameters` and
  `simulate.initial_state`, and the batch kernel multiplies the unscaled samples by the factors as
  `records.combine` does. A sweep point and ``rockslide run`` on the same case give identical
  numbers.
- **Pulses.** A pulse case's points hold one record per distinct pulse (shape, period or
  duration: `prepare.unit_pulses`, sampled at amplitude 1, each with its own sampling step and
  start), and the amplitudes are the scale factors, exactly as ``rockslide run`` multiplies them.
  A sweep over ``--amplitude`` and ``--period`` (or ``--duration``) is an overturning spectrum: its
  figure is drawn in the dimensionless plane of the literature (`spectrum_scales`,
  `plots.spectrum_figure`).
- **Computing.** The plan goes to the engine (`engine.execute.execute`): chunks of cases, kept on
  disk beside the result under the plan's definition key (`engine.chunks.ChunkStore`, resumable
  after Ctrl-C or a crash) or in memory, computed on threads, a dask cluster or a GPU.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import interrupts
from ..case import Case, case_with
from ..core import layout as L
from ..core.simulate import ground_array, tail_samples
from ..engine.axes import (  # noqa: F401  (the engine's vocabulary, re-exported: `sweep.AXES`, `sweep.parse_axis`...)
    _RETIRED_LABELS,
    AXES,
    PULSE_AXES,
    RECORD_SCALE_AXES,
    RETIRED_AXES,
    Axis,
    AxisKind,
    parse_axis,
)
from ..engine.outcomes import MODE_BITS, STATUS_FLAGS, sweep_variables  # noqa: F401  (re-exported)
from ..engine.plan import (
    MAX_GRID_POINTS,
    SUPPORT_BYTES_PER_SAMPLE,
    Plan,
    Supports,
    assemble,
    case_inputs,
    check_bytes,
    check_memory,
    default_chunk_size,
    definition_key,
)
from ..engine.prepare import (
    ABSURD_ACCELERATION_IN_G,
    RunWarning,
    absurd_acceleration,
    check_against_ground,
    check_parameters,
    check_size,
    coarse_step_warning,
    component_azimuths,
    flight_warning,
    floor_ground,
    ground_along,
    is_pulse_case,
    load_ground,
    model_for,
    pulse_ground,
    read_records,
    settings_for,
    still_step,
    study_step,
    unit_pulses,
)
from ..errors import CaseError, RecordError
from ..io import records as rec
from ..pulses import Pulse, linear_overturning_ratio
from ..units import STANDARD_GRAVITY, unit_factor

__all__ = ["AXES", "AxisKind", "Axis", "parse_axis", "plan_sweep", "warn_one_plane", "sweep_variables",
           "worst_azimuth", "coordinates", "table_coordinates",
           "root_attributes", "spectrum_scales", "figure", "stored_figure"]

#: Points validated between two checks for Ctrl-C (and two calls of the planning's progress).
PLAN_BATCH = 2000
#: [s] Time to plan one point of a grid (`plan_sweep`) apart from its scale axes (`_Grid`): about
#: 0.03 ms on 2 cores (10^6 points of ``--mu`` x ``--pga`` plan in 0.7 s: 1000 points and 1000
#: scales), to say how long the checks of a large grid take before they start (`planning_seconds`).
PLAN_SECONDS_PER_POINT = 3e-5


def axis_changes(axis: str, value: float, case: Case, ratio: float | None) -> dict:
    """The case changes (`case.case_with`) that put one axis at ``value``."""
    if axis == "mu":
        return {"contact.mu_static": value, "contact.mu_kinetic": ratio * value}
    if axis == "pga":
        changes = {"ground.scale.pga_horizontal": value}
        if case.ground.scale.factor is not None:
            changes["ground.scale.factor"] = None
        return changes
    if axis == "height_to_width":       # h/b = 0 is an infinitely wide block: refused as a width
        return {"block.width": case.block.height / value if value != 0 else math.inf}
    if axis in ("b1", "b2"):                 # an asymmetric body (docs/asymmetric.md), h and I kept as given
        b1, b2 = case.block.corners
        changes = {"block.half_widths": [value, b2] if axis == "b1" else [b1, value], "block.width": None}
        if case.block.centre_of_mass_height is None:
            changes.update({"block.height": None, "block.centre_of_mass_height": case.block.height / 2.0})
        return changes
    if axis == "floor_period":              # the first mode's period; a floor of one mode if there is none
        modes = [dataclasses.asdict(m) for m in case.ground.floor.horizontal] or [{}]
        modes[0] = {**modes[0], "period": value}
        return {"ground.floor.horizontal": modes}
    return {AXES[axis].key: value}


def kinetic_ratio(case: Case, given: float | None) -> float:
    """``mu_kinetic / mu_static`` for ``--mu``: ``given``, or the case's rounded to 12 digits."""
    if given is not None:
        if not (isinstance(given, (int, float)) and math.isfinite(given) and 0.0 <= given <= 1.0):
            raise CaseError(f"must be within [0, 1] (mu_kinetic = ratio * mu_static), got {given!r}",
                            source="mu_kinetic_ratio")
        return float(given)
    mu, nu = case.contact.mu_static, case.contact.mu_kinetic
    if mu == 0.0 or nu == mu:
        return 1.0
    return float(f"{nu / mu:.12g}")


# --------------------------------------------------------------------------------------------------
# The plan: every point's kernel inputs
# --------------------------------------------------------------------------------------------------


def plan_sweep(case: Case, axes: Sequence[Axis], *, records_dir: Path | None = None,
               mu_kinetic_ratio: float | None = None, chunk_size: int | None = None,
               progress: Callable[[int], None] | None = None, records: dict | None = None) -> Plan:
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
    records : dict, optional
        The case's records already read (`engine.prepare.read_records`): not read again.

    Returns
    -------
    Plan

    Raises
    ------
    CaseError
        No axis, an axis twice, a grid above :data:`MAX_GRID_POINTS` or the memory available
        (`check_memory`), a point that is not a valid case
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
                        source="mu_kinetic_ratio")
    ratio = kinetic_ratio(case, mu_kinetic_ratio) if "mu" in names else None
    n = math.prod(len(a) for a in axes)
    options = "/".join(a.kind.option for a in axes)
    if n > MAX_GRID_POINTS:
        raise CaseError(f"the grid has {n} points ({' x '.join(str(len(a)) for a in axes)}); at most "
                        f"{MAX_GRID_POINTS}", source=options)
    check_memory(n, options)
    if chunk_size is not None and (isinstance(chunk_size, bool) or int(chunk_size) < 1):
        raise CaseError(f"must be a whole number >= 1, got {chunk_size!r}", source="chunk_size")
    chunk_size = default_chunk_size(n) if chunk_size is None else int(chunk_size)
    pulses = is_pulse_case(case)
    for axis in axes:
        if axis.name in PULSE_AXES and not isinstance(case.ground.horizontal, Pulse):
            raise CaseError("applies to a case whose ground.horizontal is a pulse ({pulse: ..., amplitude: "
                            "...}); a record file is scaled with --pga", source=axis.kind.option)
        if axis.name in RECORD_SCALE_AXES and pulses:
            raise CaseError("scales record files; a pulse is scaled by its amplitude (--amplitude)",
                            source=axis.kind.option)
        if axis.name == "azimuth" and not case.ground.two_components:
            raise CaseError("turns a block under two horizontal components; give the case ground.horizontal_1 "
                            "and ground.horizontal_2 (files and azimuths) instead of ground.horizontal",
                            source=axis.kind.option)
    if pulses:
        if case.ground.floor.given or "floor_period" in names:
            raise CaseError("a floor's motion is computed from record files; this case's ground is an analytic "
                            "pulse: write the pulse as a record, or remove ground.floor and --floor-period",
                            source=case.source, field="ground.floor")
        plan = _plan_pulses(case, axes, ratio, chunk_size, n, progress)
    else:
        records = read_records(case, records_dir) if records is None else records    # once, for the pilot too
        plan = _plan_records(case, axes, ratio, chunk_size, records_dir, records, progress)
    # one pilot, of the case file's own case, stands for every point (docs/performance.md); at the
    # default step it only says what auto would take, and a case file that cannot run alone says nothing
    try:
        pilot = floor_ground(case, load_ground(case, records_dir, records=records))
    except (CaseError, RecordError):
        if case.solver.auto:
            raise
        pilot = None
    study_step(plan, [] if pilot is None else [(slice(None), case, pilot)], "the case file's own case")
    plan.key = definition_key(plan)
    if case.ground.two_components:
        warn_one_plane(case, "a sweep")
    return plan


def warn_one_plane(case: Case, study: str) -> None:
    """Say that ``study`` screens a box's or a mesh's width plane only (`case.Block.both_planes`):
    ``rockslide run`` and ensembles over an uncertain orientation screen both."""
    if case.block.both_planes:
        warnings.warn(f"{case.source}: block.{'mesh' if case.block.mesh is not None else 'depth'}: {study} screens "
                      "the width plane only (the block as oriented); rockslide run, and run --ensemble over "
                      "uncertain.orientation, screen both planes (an uncoupled screening)", RunWarning, stacklevel=3)


def _plan_records(case: Case, axes, ratio, chunk_size: int, records_dir, records, progress) -> Plan:
    """`plan_sweep` for a case of record files (its key made by the caller)."""
    records, entries = _read_records(case, records_dir, records)
    _check_supports(case, axes, records)
    # what the block stands on, unscaled: the record (with two horizontal components, the motion
    # along the block's orientation), or each floor's motion from it; one per distinct orientation
    # and floor of the grid (--azimuth, --floor-period), laid end to end in the kernel's input
    read = None if case.ground.two_components else rec.combine(records["horizontal"], records["vertical"],
                                                              source=case.source, still_dt=still_step(case))
    grid = _Grid(axes, RECORD_SCALE_AXES)                    # the scale axes planned apart
    n_other = grid.size(grid.other)
    supports, grounds_of = Supports(), {}        # (orientation, floor) -> the ground the block stands on
    params, states = np.empty((n_other, L.N_PARAMS)), np.empty((n_other, L.N_STATE))
    first, count = np.empty(n_other, dtype=np.int64), np.empty(n_other, dtype=np.int64)
    record_end = np.empty(n_other)
    for j, combo, point in _points(case, grid.other_axes, ratio, grid.scaled_progress(progress), grid.named()):
        floor = point.ground.floor
        orientation = point.block.orientation if point.ground.two_components else None
        try:
            if (orientation, floor) not in grounds_of:
                unscaled = ground_along(point, records, scaled=False)[0] if read is None else read
                grounds_of[(orientation, floor)] = support = floor_ground(point, unscaled)
                check_size(point, support, history=False)
                # the point's own tail: a floor of modes carries its free vibration (`floor_carries_tail`)
                tail = settings_for(point, history=False, energy=False).tail
                supports.add((orientation, floor), ground_array(support.horizontal, support.vertical, support.dt, tail))
        except CaseError as exc:
            raise _point_error(exc, *grid.named()(combo)) from None
        support = grounds_of[(orientation, floor)]
        first[j], count[j] = supports.window((orientation, floor))
        grid.add_context((orientation, floor, point.gravity), point, combo)
        start = support.start + case.ground.time_shift
        params[j], states[j] = case_inputs(point, support.dt, start)
        record_end[j] = start + count[j] * support.dt

    # the scaled motion: factors and checks once per scale and context (orientation, floor, gravity)
    factors = np.empty((2, grid.size(grid.scale), len(grid.contexts)))
    peaks = np.zeros(factors.shape[1:])
    flights = np.full(factors.shape[1:], None, dtype=object)
    grounds: dict[tuple, rec.GroundMotion] = {}         # a few scaled supports
    for c, (rep, rep_combo) in enumerate(grid.contexts.values()):
        orientation = rep.block.orientation if rep.ground.two_components else None
        for k, combo, point in _points(rep, grid.scale_axes, ratio, named=grid.named(rep_combo)):
            s, floor = point.ground.scale, point.ground.floor
            scale = (s.pga_horizontal, s.factor, s.pga_vertical, s.vertical_factor, orientation)
            if (scale, floor) not in grounds:
                if len(grounds) >= 16:
                    grounds.clear()
                if point.ground.two_components:
                    scaled = ground_along(point, records)[0]
                else:
                    scaled = rec.combine(records["horizontal"], records["vertical"], pga_horizontal=scale[0],
                                         factor=scale[1], pga_vertical=scale[2], vertical_factor=scale[3],
                                         source=case.source, still_dt=still_step(case))
                grounds[(scale, floor)] = floor_ground(point, scaled)
            ground = grounds[(scale, floor)]
            try:
                peaks[k, c] = check_against_ground(point, ground, warn=False)
            except CaseError as exc:
                raise _point_error(exc, axes, grid.combo(rep_combo, combo)) from None
            flights[k, c] = flight_warning(point, ground)
            factors[:, k, c] = ground.horizontal_factor, ground.vertical_factor

    other, scale = grid.indices(grid.other), grid.indices(grid.scale)
    context = grid.context_of[other]
    _warn_flights(axes, flights, scale, context)
    point_peaks = peaks[scale, context]
    highest = int(np.argmax(point_peaks))
    if point_peaks[highest] > ABSURD_ACCELERATION_IN_G * STANDARD_GRAVITY:
        warnings.warn(f"{absurd_acceleration(case.source, float(point_peaks[highest]))} "
                      f"[at {_point_text(axes, np.unravel_index(highest, grid.shape))}]", RunWarning, stacklevel=2)
    _warn_coarse_step(case, grid.other_axes, params)
    return assemble(case, axes, mu_kinetic_ratio=ratio, params=params, states=states,
                    factor_h=factors[0][scale, context], factor_v=factors[1][scale, context], base=supports.base(),
                    first=first[other], count=count[other], record_end=record_end[other], records=entries,
                    chunk_size=chunk_size, rows=other, keyed=False)


def _check_supports(case: Case, axes, records: dict) -> None:
    """Refuse a grid whose orientations and floors (each a ground motion of its own: `Supports`)
    would hold more memory than the machine has, before any is computed (10^6 orientations of a
    long record ran out of memory)."""
    varied = [a for a in axes if a.name in ("azimuth", "floor_period")]
    n = math.prod(len(a) for a in varied)
    horizontal = records.get("horizontal")
    if n < 2 or horizontal is None:
        return
    samples = horizontal.data.size + tail_samples(case.ground.tail, horizontal.dt)
    check_bytes(n * samples * SUPPORT_BYTES_PER_SAMPLE, f"{n} ground motions of {samples} samples (one per "
                f"{' and '.join(a.name.replace('_', ' ') for a in varied)})", "/".join(a.kind.option for a in varied))


class _Grid:
    """A grid's dimensions split in two: the scale axes (``--pga``, ``--vertical-factor``;
    ``--amplitude`` of a pulse), which change only the scale factors of the ground motion and the
    checks of the scaled motion, and the other axes, which change the kernel's parameters, initial
    state and support. Each half is planned on its own (a 1000 x 1000 ``--mu`` x ``--pga`` grid is
    1000 points of parameters and 1000 scales, not 10^6 points), and `indices` spreads the halves
    over the grid with numpy.

    The checks of the scaled motion depend on the scale and a point's *context* (its orientation,
    floor and gravity; for a pulse, its pulse at amplitude 1 and gravity): `add_context` keeps the
    first point of each, in flat order, to stand for it.
    """

    def __init__(self, axes, scale_names):
        self.axes = list(axes)
        self.shape = tuple(len(a) for a in self.axes)
        self.scale = [d for d, a in enumerate(self.axes) if a.name in scale_names]
        self.other = [d for d in range(len(self.axes)) if d not in self.scale]
        self.other_axes = [self.axes[d] for d in self.other]
        self.scale_axes = [self.axes[d] for d in self.scale]
        self.contexts: dict = {}                  # context -> (its first point, that point's combo)
        self._context_index: dict = {}
        self.context_of = np.empty(self.size(self.other), dtype=np.int64)
        self._seen = 0

    def size(self, dims) -> int:
        """Points of the sub-grid of dimensions ``dims``."""
        return math.prod(self.shape[d] for d in dims)

    def scaled_progress(self, progress):
        """``progress`` for the other half: each of its points stands for every scale."""
        n_scales = self.size(self.scale)
        return None if progress is None else (lambda done: progress(done * n_scales))

    def add_context(self, context, point, combo) -> None:
        """Record the context of the next point of the other half (in its flat order)."""
        if context not in self.contexts:
            self.contexts[context] = (point, combo)
            self._context_index[context] = len(self._context_index)
        self.context_of[self._seen] = self._context_index[context]
        self._seen += 1

    def named(self, other_combo=None):
        """For `_points` over one half: the grid's axes and combo of a point of the other half
        (``other_combo`` None; its scale axes at their first values, the first such point in flat
        order), or of the scale half at ``other_combo``."""
        if other_combo is None:
            return lambda combo: (self.axes, self.combo(combo, (0,) * len(self.scale)))
        return lambda combo: (self.axes, self.combo(other_combo, combo))

    def combo(self, other_combo, scale_combo) -> tuple:
        """The grid's combo of a point from its two halves."""
        full = [0] * len(self.axes)
        for dims, part in ((self.other, other_combo), (self.scale, scale_combo)):
            for d, j in zip(dims, part, strict=True):
                full[d] = j
        return tuple(full)

    def indices(self, dims) -> np.ndarray:
        """``int64[n]``: each point's index in the sub-grid of dimensions ``dims``, in flat C order."""
        kept = tuple(self.shape[d] if d in dims else 1 for d in range(len(self.shape)))
        sub = np.arange(self.size(dims), dtype=np.int64).reshape(kept)
        return np.broadcast_to(sub, self.shape).reshape(-1)


def _warn_flights(axes, flights: np.ndarray, *index) -> None:
    """One warning for the points whose scaled vertical motion lifts the block off the ground (they
    run and end with the status ``flight``, outside the model, as a run of the same case does),
    naming the first in flat order (`prepare.flight_warning`). ``flights[index]`` is each point's
    warning or None."""
    flying = np.not_equal(flights, None)[index]
    if flying.any():
        first = int(np.argmax(flying))
        shape = tuple(len(a) for a in axes)
        text = flights[tuple(i[first] for i in index)]
        warnings.warn(f"{text} [at {_point_text(axes, np.unravel_index(first, shape))}; "
                      f"{int(np.count_nonzero(flying))} of {flying.size} points fly]", RunWarning, stacklevel=3)


def planning_seconds(case: Case, axes) -> float:
    """[s] About how long `plan_sweep` takes for ``axes`` (the points apart from the scale axes)."""
    grid = _Grid(axes, ("amplitude",) if is_pulse_case(case) else RECORD_SCALE_AXES)
    return grid.size(grid.other) * PLAN_SECONDS_PER_POINT


def _points(case: Case, axes, ratio, progress=None, named=None):
    """Every point of the grid in flat C order: ``(index, combo, case)``, validated as a case file
    (`case_with`) and by `prepare.check_parameters` (a bad point is a CaseError naming the options
    responsible, and the point: ``named(combo)`` gives the axes and combo to name it by, for a
    half of a larger grid, `_Grid.named`). Ctrl-C is noticed, and ``progress`` told, every
    `PLAN_BATCH` points.

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
                    raise _point_error(exc, *(named(combo) if named else (axes, combo))) from None
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
    pulse shape and length (the amplitudes are the scale factors, as `prepare.pulse_ground` applies
    them), each with its own sampling step and start. ``--amplitude`` is a scale axis (`_Grid`): the
    motion is checked once per pulse at the largest amplitude of the grid."""
    grid = _Grid(axes, ("amplitude",))
    n_other = grid.size(grid.other)
    params, states = np.empty((n_other, L.N_PARAMS)), np.empty((n_other, L.N_STATE))
    factor_v, record_end = np.empty(n_other), np.empty(n_other)
    first, count = np.empty(n_other, dtype=np.int64), np.empty(n_other, dtype=np.int64)
    records: dict[tuple, object] = {}         # (pulses at amplitude 1, dt, tail) -> the pulses sampled
    supports = Supports()
    for j, combo, point in _points(case, grid.other_axes, ratio, grid.scaled_progress(progress), grid.named()):
        h, v = point.ground.horizontal, point.ground.vertical
        shape = tuple(None if p is None else replace(p, amplitude=1.0) for p in (h, v))
        key = (shape, point.solver.dt, point.ground.tail)
        try:
            if key not in records:
                records[key] = unit = unit_pulses(point)
                check_size(point, pulse_ground(point, unit), history=False)
                supports.add(key, ground_array(unit.horizontal, unit.vertical, unit.dt, point.ground.tail))
        except CaseError as exc:
            raise _point_error(exc, *grid.named()(combo)) from None
        unit = records[key]
        grid.add_context((key, None if v is None else v.amplitude, point.gravity), point, combo)
        start = unit.start + point.ground.time_shift
        params[j], states[j] = case_inputs(point, unit.dt, start)
        factor_v[j] = 1.0 if v is None else v.amplitude
        first[j], count[j] = supports.window(key)
        record_end[j] = start + count[j] * unit.dt

    # each amplitude once; each pulse checked at the largest (flight depends on the vertical alone)
    first_point, first_combo = next(iter(grid.contexts.values()))
    amplitudes = np.array([1.0 if p.ground.horizontal is None else p.ground.horizontal.amplitude
                           for _, _, p in _points(first_point, grid.scale_axes, ratio, named=grid.named(first_combo))])
    largest = int(np.argmax(np.abs(amplitudes)))
    flights = np.full(len(grid.contexts), None, dtype=object)
    for c, ((key, _, _), (rep, rep_combo)) in enumerate(grid.contexts.items()):
        point = rep
        if grid.scale:
            point = replace(rep, ground=replace(rep.ground, horizontal=replace(rep.ground.horizontal,
                                                                               amplitude=amplitudes[largest])))
        ground = pulse_ground(point, records[key])
        try:
            check_against_ground(point, ground, warn=False)
        except CaseError as exc:            # the scaled pulse out of bounds: the amplitude is responsible
            scale_combo = np.unravel_index(largest, tuple(len(a) for a in grid.scale_axes))
            raise CaseError(f"{exc.message} [at {_point_text(axes, grid.combo(rep_combo, scale_combo))}]",
                            source="amplitude" if grid.scale else exc.source,
                            field="ground.horizontal.amplitude" if grid.scale else exc.field) from None
        flights[c] = flight_warning(point, ground)

    other, scale = grid.indices(grid.other), grid.indices(grid.scale)
    _warn_flights(axes, flights, grid.context_of[other])
    _warn_coarse_step(case, grid.other_axes, params)
    return assemble(case, axes, mu_kinetic_ratio=ratio, params=params, states=states, factor_h=amplitudes[scale],
                    factor_v=factor_v[other], base=np.concatenate(supports.pieces, axis=1), first=first[other],
                    count=count[other], record_end=record_end[other], records=[], chunk_size=chunk_size, rows=other,
                    keyed=False)


def _warn_coarse_step(case: Case, axes, params: np.ndarray) -> None:
    """`prepare.coarse_step_warning` for the point with the fastest rocking."""
    shape = tuple(len(a) for a in axes)
    warning = coarse_step_warning(case.source, params,
                                  lambda i: _point_text(axes, np.unravel_index(i, shape)))
    if warning:
        warnings.warn(warning, RunWarning, stacklevel=3)


def _point_text(axes, combo) -> str:
    """``--mu 0.5, --pga 800gal``: a point of the grid as given."""
    return ", ".join(f"{a.kind.option} {a.texts[j]}" for a, j in zip(axes, combo, strict=True))


def _read_records(case: Case, records_dir: Path | None, records: dict | None = None):
    """The case's records, read once (`prepare.read_records`, unless given), and the provenance entry
    of each; with two horizontal components, each one's azimuth [rad] as used (given, or from its
    AT2 header: `prepare.component_azimuths`)."""
    records = read_records(case, records_dir) if records is None else records
    entries = [{"role": role, "path": Path(record.path).name, "sha256": record.sha256}
               for role, record in records.items() if record is not None]
    if case.ground.two_components:
        azimuths = dict(zip(("horizontal", "horizontal_2"), component_azimuths(case, records), strict=True))
        for entry in entries:
            if entry["role"] in azimuths:
                entry["azimuth"] = azimuths[entry["role"]]
    return records, entries


def _point_error(exc: CaseError, axes, combo) -> CaseError:
    """A point's CaseError, naming the option(s) responsible and the point."""
    field_name = exc.field or ""
    options = [a.kind.option for a in axes
               if field_name and (field_name.startswith(_key_root(a.name))
                                  or _key_root(a.name).startswith(field_name))]
    if not options:              # no axis changes that key: the case file's own error, as run gives it
        return exc
    return CaseError(f"{exc.message} [at {_point_text(axes, combo)}]", source="/".join(options), field=exc.field)


def _key_root(axis: str) -> str:
    return {"mu": "contact.mu", "pga": "ground.scale", "vertical_factor": "ground.scale",
            "height_to_width": "block", "amplitude": "ground.horizontal", "period": "ground.horizontal",
            "duration": "ground.horizontal"}.get(axis, AXES[axis].key)


# --------------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------------

def coordinates(plan: Plan) -> list:
    """``[(name, SI values, attributes)]`` of the axes, in dimension order."""
    out = []
    for axis in plan.axes:
        kind = axis.kind
        attrs = {"units": kind.units, "long_name": kind.long_name, "option": kind.option,
                 "given_as": axis.spec}
        if axis.name == "height_to_width":
            attrs["height"] = float(plan.case.block.height)
        out.append((axis.name, np.asarray(axis.values, dtype=np.float64), attrs))
    return out


def table_coordinates(coords) -> list:
    """`coordinates` as the ``--csv`` table writes them: an angle axis (``azimuth``) in degrees, as
    it is given and plotted (``units`` ``deg``); the others as the result file has them (SI)."""
    out = []
    for name, values, attrs in coords:
        kind = AXES.get(name)
        if kind is not None and kind.kind == "angle":
            values, attrs = np.asarray(values, dtype=np.float64) / kind.display_scale, {**attrs, "units": "deg"}
        out.append((name, values, attrs))
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
    if plan.step_study is not None:          # the step auto took or would take, and its estimate
        attrs.update(plan.step_study.attributes())
    for entry in plan.records:
        attrs[f"record_{entry['role']}"] = entry["path"]
        attrs[f"record_{entry['role']}_sha256"] = entry["sha256"]
        if "azimuth" in entry:             # as a run's file names them (`results.COMPONENT_KEYS`)
            attrs[f"ground_azimuth_{2 if entry['role'] == 'horizontal_2' else 1}"] = entry["azimuth"]
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
    from ..plots import sweep_category

    return sweep_category(variables["overturned"][0], variables["status"][0], variables["modes"][0])


def worst_azimuth(plan: Plan, variables: dict) -> dict | None:
    """The block orientation of an ``--azimuth`` sweep under which it fares worst.

    Per azimuth, the share of the other axes' points where the block overturns, then, to break
    ties, the mean of ``max_rotation_ratio`` over the points that stand, then the earliest mean
    overturning time (all overturned). Returns None without an azimuth axis, else ``{"azimuth":
    rad, "overturned": share, "max_rotation_ratio": mean or NaN, "text": one line}``.
    """
    names = [a.name for a in plan.axes]
    if "azimuth" not in names:
        return None
    d = names.index("azimuth")
    axis = plan.axes[d]
    over = np.moveaxis(np.asarray(variables["overturned"][0], dtype=bool), d, 0).reshape(len(axis), -1)
    ratio = np.moveaxis(np.asarray(variables["max_rotation_ratio"][0], dtype=np.float64), d, 0)
    ratio = np.where(over, np.nan, ratio.reshape(len(axis), -1))
    when = np.moveaxis(np.asarray(variables["overturn_time"][0], dtype=np.float64), d, 0).reshape(len(axis), -1)
    share = over.mean(axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)              # all overturned, or all standing
        standing = np.nanmean(ratio, axis=1)
        soonest = np.nanmean(when, axis=1)
    order = sorted(range(len(axis)), key=lambda k: (share[k], np.nan_to_num(standing[k], nan=np.inf),
                                                    -np.nan_to_num(soonest[k], nan=np.inf)))
    k = order[-1]
    rest = (f", at {soonest[k]:.2f} s on average" if math.isnan(standing[k])
            else f", largest rotation {100 * standing[k]:.0f} % of alpha where it stands")
    text = (f"worst azimuth {math.degrees(axis.values[k]):g} deg: overturned at {100 * share[k]:.0f} % of its "
            f"points{rest} (best {math.degrees(axis.values[order[0]]):g} deg: {100 * share[order[0]]:.0f} %)")
    return {"azimuth": float(axis.values[k]), "overturned": float(share[k]),
            "max_rotation_ratio": float(standing[k]), "text": text}


def figure(plan: Plan, variables: dict, *, size=None):
    """The PNG of a sweep: an overturning spectrum (`spectrum_scales`), else the maps of
    `plots.sweep_figure` with the axes in their display units (gal for accelerations given as
    PGA) and categories from `categories`; what was computed in its caption (`caption`)."""
    from .._version import __version__

    axes = [(a.kind.name, a.values) for a in plan.axes]
    title = f"{plan.case.name}: {plan.describe()}"
    text = caption(plan.case.text, [name for name, _ in axes], plan.records, plan.step, __version__)
    scales = spectrum_scales(plan)
    if scales is not None:
        return _spectrum(axes, variables, scales, title, size=size, caption=text)
    return _maps(axes, variables, title, size=size, caption=text, case_text=plan.case.text)


def caption(case_text: str, axes, records, step, version) -> str:
    """`plots.case_caption` of a sweep: the case's values of its ``axes`` are marked as the base
    case's."""
    from ..plots import case_caption

    return case_caption(case_text, records=[r for r in records if r.get("path")] or None, step=step,
                        version=version, varied=tuple(axes))


def stored_caption(stored) -> str:
    """`caption` of a sweep file read back."""
    from ..io.results import RECORD_ROLES  # h5py: a sweep loads it while it computes (api._shared)

    attrs = stored.attrs
    records = [{"role": role, "path": attrs[f"record_{role}"]} for role in RECORD_ROLES
               if attrs.get(f"record_{role}")]
    step = attrs.get("integration_step")
    return caption(str(attrs.get("case_text", "")), [name for name, _, _ in stored.coords], records,
                   None if step is None else float(step), str(attrs.get("rockslide_version", "?")))


def stored_figure(stored, *, size=None) -> object:
    """The same figure from a sweep file read back (`results.read_sweep`), for ``rockslide plot``."""
    shape = " x ".join(f"{len(values)} {name}" for name, values, _ in stored.coords)
    axes = [(name, values) for name, values, _ in stored.coords]
    title = (f"{stored.attrs.get('name', 'sweep')}: {shape} = "
             f"{int(np.prod([len(v) for _, v, _ in stored.coords]))} cases")
    scales = {key[len("spectrum_"):]: value for key, value in stored.attrs.items()
              if key.startswith("spectrum_")}
    text = stored_caption(stored)
    if scales:
        return _spectrum(axes, variables=stored.variables, scales=scales, title=title, size=size, caption=text)
    return _maps(axes, stored.variables, title, size=size, caption=text,
                 case_text=str(stored.attrs.get("case_text", "")))


def overlay_figure(stored_files, names, *, size=None):
    """Sweeps side by side (``rockslide plot A B``): the largest rotation of each over its first two
    axes, on one colour scale (`plots.sweep_overlay_figure`); the sweeps must have the same axes."""
    from ..plots import sweep_overlay_figure

    first = [name for name, _, _ in stored_files[0].coords]
    panels = []
    for stored, name in zip(stored_files, names, strict=True):
        axes = [n for n, _, _ in stored.coords]
        if axes[:2] != first[:2]:
            raise CaseError(f"{name} is over {' x '.join(axes)} and {names[0]} over {' x '.join(first)}; overlay "
                            "sweeps over the same axes", source="rockslide plot")
        # one unit for all: the first case's (the panels share their axes)
        shown = shown_axes([(n, values) for n, values, _ in stored.coords],
                           str(stored_files[0].attrs.get("case_text", "")))
        panels.append((name, shown, categories(stored.variables), np.asarray(stored.variables["max_rotation"][0])))
    text = "\n".join(f"{name}: {stored_caption(stored)}" for stored, name in zip(stored_files, names, strict=True))
    return sweep_overlay_figure(panels, title="sweeps: " + " and ".join(names), caption=text, size=size)


#: Points of the small-angle theory's curve drawn over a spectrum.
THEORY_POINTS = 40


def _spectrum(axes, variables: dict, scales: dict, title: str, *, size=None, caption: str = ""):
    """`plots.spectrum_figure` of a two-axis pulse sweep: amplitude over ``g tan(alpha)`` up the
    page, pulse frequency over ``p`` across, the categories of `plots.spectrum_category`, and
    the theory's curves where they exist: the thresholds of liftoff and slip at rest (exact), and
    the small-angle boundary of overturning without impact (`pulses.linear_overturning_ratio`;
    without a vertical pulse)."""
    from ..plots import spectrum_category, spectrum_figure

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
                           title=f"{title}: {pulse.pulse} pulse", size=size, caption=caption)


def shown_axes(axes, case_text: str = "") -> list:
    """``(label, values)`` of each ``(name, SI values)`` axis as figures show it: the PGA in the unit
    the case gives its PGA in (`plots.pga_unit`; gal when it gives none), the others in `AXES`'s
    display units."""
    from ..plots import pga_unit

    unit = pga_unit(case_text) if any(name == "pga" for name, _ in axes) else None
    shown = []
    for name, values in axes:
        label, scale = ((AXES[name].label, AXES[name].display_scale) if name in AXES
                        else (_RETIRED_LABELS.get(name, name), 1.0))   # a file of a retired axis
        if name == "pga" and unit:
            label, scale = f"peak horizontal acceleration [{unit}]", unit_factor(unit, "acceleration")
        shown.append((label, np.asarray(values) / scale))
    return shown


def _maps(axes, variables: dict, title: str, *, size=None, caption: str = "", case_text: str = ""):
    from ..plots import sweep_figure

    over = int(np.asarray(variables["overturned"][0]).sum())
    shown = shown_axes(axes, case_text)
    return sweep_figure(shown, categories(variables), variables["max_rotation"][0],
                        variables["residual_slip"][0], title=f"{title}, {over} overturned", size=size,
                        caption=caption)


def time_shares(states: np.ndarray) -> dict:
    """Total time in each moving state over the grid [s] (where a sweep's work goes)."""
    return {"SLIP": float(states[:, L.S_T_SLIP].sum()), "ROCK": float(states[:, L.S_T_ROCK].sum()),
            "ROCKSLIP": float(states[:, L.S_T_ROCKSLIP].sum()),
            "REST": float(states[:, L.S_T_REST].sum())}

