"""The ground motion a case's block stands on: its records read and scaled (`read_records`,
`load_ground`), two horizontal components turned to the block's direction (`ground_along`), a
floor's motion computed from the ground's (`floor_ground`), or analytic pulses sampled
(`pulse_ground`). Every run and study gets its motion here."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import pulses
from ..case import Case, Scale
from ..core.simulate import tail_samples
from ..errors import CaseError, RecordError
from ..io import records as rec
from ..pulses import Pulse
from ..units import STANDARD_GRAVITY

#: Record and tail samples of one ground motion, at most (0.8 GB per component): more is a mistake
#: (a slip of unit in ``tail`` or ``dt``), reported before the run (`prepare.check_size`).
MAX_GROUND_SAMPLES = 10**8


@dataclass(frozen=True)
class Components:
    """Two horizontal components and the direction the block feels (`ground_along`).

    Attributes
    ----------
    azimuth_1, azimuth_2 : float
        [rad] the components' directions, clockwise from north (from the case or the AT2 headers).
    orientation : float
        [rad] the block's ``block.orientation`` (the first component's azimuth when not given).
    pga_1, pga_2 : float
        [m/s^2] the scaled components' peaks.
    pga_along, pga_across : float
        [m/s^2] the peaks of the scaled motion along the block's direction (what drives the model)
        and across it, along the rocking axis (what the planar model ignores).
    ignored_share : float
        [-] the share of the horizontal motion's Arias intensity (the sum of the squared
        accelerations) that lies across the block's direction: ``sum(a_across^2) / sum(a1^2 + a2^2)``.
    """

    azimuth_1: float
    azimuth_2: float
    orientation: float
    pga_1: float
    pga_2: float
    pga_along: float
    pga_across: float
    ignored_share: float

    def as_dict(self) -> dict:
        """The fields by name, angles [rad], accelerations [m/s^2]."""
        return dataclasses.asdict(self)


def read_records(case: Case, records_dir: Path | None = None) -> dict[str, rec.Record | None]:
    """The case's records as they are in their files, by role (``horizontal``, ``vertical``; None
    where the case has none), found through `records.resolve_record_path`."""
    folder = records_dir if records_dir is not None else rec.records_dir()
    records = {}
    for role in ("horizontal", "vertical", "horizontal_2"):
        spec = getattr(case.ground, role)
        if spec is None:
            records[role] = None
            continue
        key = "horizontal_1" if role == "horizontal" and case.ground.two_components else role
        path = rec.resolve_record_path(spec.file, case_dir=case.base_dir, records_dir=folder,
                                       source=case.source, field=f"ground.{key}.file")
        records[role] = rec.load_record(path, format=spec.format, units=spec.units,
                                        time_column=spec.time_column, column=spec.column, dt=spec.dt,
                                        skip_lines=spec.skip_lines)
    return records


def load_ground(case: Case, records_dir: Path | None = None, *, records: dict | None = None) -> rec.GroundMotion:
    """Read, scale and align the case's records (``ground.horizontal`` and ``ground.vertical``), or
    sample its pulses (`pulse_ground`); without either, the still ground sampled at ``solver.dt`` (a
    free vibration over ``ground.tail``). ``records``: the case's records already read
    (`read_records`)."""
    if is_pulse_case(case):
        return pulse_ground(case)
    records = read_records(case, records_dir) if records is None else records
    if case.ground.two_components:
        return ground_along(case, records)[0]
    scale = case.ground.scale
    try:
        return rec.combine(records["horizontal"], records["vertical"], pga_horizontal=scale.pga_horizontal,
                           factor=scale.factor, pga_vertical=scale.pga_vertical,
                           vertical_factor=scale.vertical_factor, source=case.source,
                           still_dt=still_step(case))
    except RecordError as exc:
        if exc.field is None:
            raise
        # combine names its scale options; in the case file they are keys of ground.scale
        raise RecordError(exc.message, source=exc.source, field=f"ground.scale.{exc.field}") from None


#: Largest difference from 90 degrees between two components' azimuths [rad] (a millidegree: the
#: headers and case files give whole degrees).
ORTHOGONALITY_TOLERANCE = math.radians(1e-3)


def component_azimuths(case: Case, records: dict) -> tuple[float, float]:
    """The azimuths [rad] of a case's two horizontal components: ``ground.horizontal_i.azimuth``,
    else the PEER AT2 header's (`records.at2_azimuth`); they must be 90 degrees apart.

    Raises
    ------
    CaseError
        An azimuth neither given nor in the header, or components that are not orthogonal.
    """
    azimuths = []
    for role, key in (("horizontal", "horizontal_1"), ("horizontal_2", "horizontal_2")):
        azimuth = getattr(case.ground, role).azimuth
        if azimuth is None and records[role].format == "at2":
            azimuth = rec.at2_azimuth(records[role].path)
        if azimuth is None:
            raise CaseError(f"the azimuth of {Path(str(records[role].path)).name} is not given and its header "
                            f"names none; give it, e.g. 'ground: {{{key}: {{file: ..., azimuth: 90 deg}}}}'",
                            source=case.source, field=f"ground.{key}.azimuth")
        azimuths.append(azimuth)
    from ..core import intensity  # numba and scipy: only for two components (`rockslide run` stays light)

    difference = abs(intensity.direction_cosines(azimuths[1] - azimuths[0])[0])
    if difference > math.sin(ORTHOGONALITY_TOLERANCE):
        raise CaseError(f"the components' azimuths {math.degrees(azimuths[0]):g} deg and "
                        f"{math.degrees(azimuths[1]):g} deg are not 90 deg apart; expected two orthogonal "
                        "horizontal components", source=case.source, field="ground.horizontal_2.azimuth")
    return azimuths[0], azimuths[1]


def ground_along(case: Case, records: dict, *, scaled: bool = True) -> tuple[rec.GroundMotion, Components]:
    """The ground motion of a case with two horizontal components: the motion along
    ``block.orientation`` (`intensity.along`) as its horizontal record, scaled.

    ``ground.scale.factor`` multiplies both components; ``pga_horizontal`` scales both by one
    factor, to make the larger of the two components' peaks that value (so the scale does not
    depend on the block's orientation); the vertical is scaled as with one component
    (`records.combine`). With ``block.orientation`` equal to the first component's azimuth the
    result is that of the first component alone, bit for bit. ``scaled=False``: the records as
    they are (factors 1).
    """
    from ..core import intensity  # numba and scipy: only for two components (`rockslide run` stays light)

    first, second = records["horizontal"], records["horizontal_2"]
    rec.check_same_grid(first, second, case.source, roles=("horizontal_1", "horizontal_2"))
    azimuth_1, azimuth_2 = component_azimuths(case, records)
    orientation = azimuth_1 if case.block.orientation is None else case.block.orientation
    a1, a2 = np.asarray(first.data, dtype=np.float64), np.asarray(second.data, dtype=np.float64)
    scale = case.ground.scale if scaled else Scale()
    factor = scale.factor
    if scale.pga_horizontal is not None:
        peak = max(np.max(np.abs(a1), initial=0.0), np.max(np.abs(a2), initial=0.0))
        if peak == 0.0:
            raise CaseError(f"the records {first.name} and {second.name} are all zeros: they cannot be scaled "
                            "to pga_horizontal", source=case.source, field="ground.scale.pga_horizontal")
        factor = scale.pga_horizontal / float(peak)
    along_record = dataclasses.replace(first, data=intensity.along(a1, a2, azimuth_1, azimuth_2, orientation))
    try:
        ground = rec.combine(along_record, records["vertical"], factor=factor, pga_vertical=scale.pga_vertical,
                             vertical_factor=scale.vertical_factor, source=case.source)
    except RecordError as exc:
        if exc.field is None:
            raise
        raise RecordError(exc.message, source=exc.source, field=f"ground.scale.{exc.field}") from None
    k = ground.horizontal_factor
    across = intensity.along(a1, a2, azimuth_1, azimuth_2, orientation + 0.5 * math.pi)
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(np.sum(a1 * a1) + np.sum(a2 * a2))
        share = float(np.sum(across * across)) / total if total > 0.0 else 0.0
    components = Components(
        azimuth_1=azimuth_1, azimuth_2=azimuth_2, orientation=orientation,
        pga_1=k * float(np.max(np.abs(a1), initial=0.0)), pga_2=k * float(np.max(np.abs(a2), initial=0.0)),
        pga_along=float(np.max(np.abs(ground.horizontal), initial=0.0)),
        pga_across=k * float(np.max(np.abs(across), initial=0.0)), ignored_share=share)
    files = ground.files + ({"role": "horizontal_2", "path": second.path, "sha256": second.sha256,
                             "format": second.format, "units": second.units},)
    return dataclasses.replace(ground, files=files), components


def floor_ground(case: Case, ground: rec.GroundMotion) -> rec.GroundMotion:
    """The motion of the floor the block stands on (``ground.floor``), from the ground motion under the
    building: each component through its modes (`core.intensity.floor_acceleration`, exact for the
    piecewise-linear record) on one grid of ``dt / m``, ``m`` the steps the fastest mode needs (at
    most as many as keep the grid's step >= ``solver.dt``, `simulate.substeps`' condition); or the
    horizontal ground times the screening factor ``1 + 2 z/h`` (the code's factor is horizontal: the
    vertical is left as it is). Without a floor, ``ground`` itself.

    A building still moves when its ground stops: with a ``ground.tail``, the modes run on over the
    tail on still ground, and the floor's motion carries its free vibration there (`settings_for`
    then adds no still samples of its own: `floor_carries_tail`).

    Raises
    ------
    CaseError
        A floor under analytic pulses (sampled with jumps, not as a piecewise-linear record).
    """
    floor = case.ground.floor
    if not floor.given:
        return ground
    from ..core import intensity  # numba and scipy: only for a floor (`rockslide run` stays light)

    if np.ndim(ground.horizontal) != 1:
        raise CaseError("a floor's motion is computed from record files; this case's ground is an analytic "
                        "pulse: write the pulse as a record, or remove ground.floor", source=case.source,
                        field="ground.floor")
    if floor.z_over_h is not None:
        return dataclasses.replace(ground, horizontal=rec._frozen(floor.amplification() * ground.horizontal))
    n_tail = tail_samples(case.ground.tail, ground.dt)
    if n_tail:                      # the ground is still over the tail; the building is not
        def still_after(values):
            values = np.asarray(values)
            return np.concatenate([values, np.zeros(n_tail)]) if values.size == ground.horizontal.size else values
        ground = dataclasses.replace(ground, horizontal=still_after(ground.horizontal),
                                     vertical=still_after(ground.vertical))
    modes = {role: [(m.period, m.damping, m.participation) for m in getattr(floor, role)]
             for role in ("horizontal", "vertical")}
    needed = max(intensity.substeps_for(ground.dt, period) for role in modes for period, _, _ in modes[role])
    m = max(1, min(needed, int(ground.dt / case.solver.dt * (1.0 + 1e-9))))
    components = {}
    for role, role_modes in modes.items():
        components[role], step = intensity.floor_acceleration(getattr(ground, role), ground.dt, role_modes, m)
    return dataclasses.replace(ground, dt=step, horizontal=rec._frozen(components["horizontal"]),
                               vertical=rec._frozen(components["vertical"]))


def floor_carries_tail(case: Case) -> bool:
    """Whether `floor_ground` gives the floor's motion over ``ground.tail`` too (a floor of modes:
    their free vibration), so that the run adds no still samples after it."""
    floor = case.ground.floor
    return floor.given and floor.z_over_h is None and case.ground.tail > 0.0


def floor_peaks(time, floor_horizontal, base_horizontal) -> dict:
    """``pfa`` [m/s^2] and ``pfv`` [m/s] of the floor's horizontal motion as the block felt it
    (samples at ``time`` [s], the run's tail included; PFV baseline-corrected as PGV is) and
    ``pga_base`` [m/s^2], the peak of the ground under the building."""
    from ..core import intensity

    time = np.asarray(time)
    dt = float(time[1] - time[0]) if time.size > 1 else 1.0
    return {"pfa": intensity.peak_acceleration(floor_horizontal), "pfv": intensity.peak_velocity(floor_horizontal, dt),
            "pga_base": intensity.peak_acceleration(base_horizontal)}


def floor_peaks_text(peaks: dict) -> str:
    """`floor_peaks` in one line [g, cm/s]."""
    return (f"on a floor: PFA {peaks['pfa'] / STANDARD_GRAVITY:.3g} g, PFV {peaks['pfv'] * 100:.3g} cm/s; the "
            f"ground under the building: PGA {peaks['pga_base'] / STANDARD_GRAVITY:.3g} g")


def still_step(case: Case) -> float:
    """[s] The sampling step of the still ground (a case without records): ``solver.dt``, or with
    ``solver.dt: auto`` `step.AUTO_STILL_STEP`, which leaves the step free."""
    from .step import AUTO_STILL_STEP

    return AUTO_STILL_STEP if case.solver.auto else case.solver.dt


def is_pulse_case(case: Case) -> bool:
    """Whether the case's ground motion is analytic pulses (`case.py` does not mix them with files)."""
    return any(isinstance(r, Pulse) for r in (case.ground.horizontal, case.ground.vertical))


def unit_pulses(case: Case) -> pulses.Sampled:
    """The case's pulses at amplitude 1 on their common grid (`pulses.sample`, at most
    ``solver.dt`` apart).

    Raises
    ------
    CaseError
        The grid would need more than `MAX_GROUND_SAMPLES` samples (checked before sampling).
    """
    h, v = case.ground.horizontal, case.ground.vertical
    n, dt = pulses.grid(h, v, case.solver.dt)
    if n + 2 > MAX_GROUND_SAMPLES:
        role = "horizontal" if h is not None and (v is None or h.length >= v.length) else "vertical"
        pulse = getattr(case.ground, role)
        key = pulses.SHAPES[pulse.pulse].parameter
        raise CaseError(f"a {pulse.pulse} pulse of {pulse.length:g} s sampled every {dt:.3g} s needs {n:.3g} "
                        f"samples; expected at most {MAX_GROUND_SAMPLES:.0e}", source=case.source,
                        field=f"ground.{role}.{key}")
    return pulses.sample(h, v, case.solver.dt)


def pulse_ground(case: Case, unit: pulses.Sampled | None = None) -> rec.GroundMotion:
    """The case's pulses as applied: each pulse at amplitude 1 (`unit_pulses`, or ``unit`` given)
    times its amplitude, which is its scale factor (as a record's factor)."""
    start, dt, h, v = unit_pulses(case) if unit is None else unit
    factors = [1.0 if p is None else float(p.amplitude) for p in (case.ground.horizontal, case.ground.vertical)]
    arrays = []
    for factor, values in zip(factors, (h, v), strict=True):
        scaled = factor * values
        scaled.setflags(write=False)
        arrays.append(scaled)
    return rec.GroundMotion(dt=dt, start=start, horizontal=arrays[0], vertical=arrays[1],
                            horizontal_factor=factors[0], vertical_factor=factors[1], files=())
