"""Case -> records -> checks -> simulation: the one orchestrator behind `run`, `sweep` and `table1`.

It reads the records a case names (`records.py`), scales and aligns them, or samples its analytic
pulses (`pulses.py`), checks what can only be checked with the ground motion at hand (the step
against the record's sampling, flight before the run), builds the `Model` and `Settings` of the
pure core and calls `simulate` (or the reference solver).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import pulses
from . import records as rec
from .case import Case
from .core.simulate import Model, Result, Settings, simulate, substeps
from .errors import CaseError, RecordError
from .pulses import Pulse


@dataclass(frozen=True)
class Prepared:
    """A case with its ground motion loaded: everything needed to simulate it."""

    case: Case
    ground: rec.GroundMotion
    model: Model
    settings: Settings


def load_ground(case: Case, records_dir: Path | None = None) -> rec.GroundMotion:
    """Read, scale and align the case's records (``ground.horizontal`` and ``ground.vertical``), or
    sample its pulses (`pulse_ground`); without either, the still ground sampled at ``solver.dt`` (a
    free vibration over ``ground.tail``)."""
    if is_pulse_case(case):
        return pulse_ground(case)
    folder = records_dir if records_dir is not None else rec.records_dir()
    traces = {}
    for role in ("horizontal", "vertical"):
        spec = getattr(case.ground, role)
        if spec is None:
            traces[role] = None
            continue
        field = f"ground.{role}.file"
        path = rec.resolve_record_path(spec.file, case_dir=case.base_dir, records_dir=folder,
                                       source=case.source, field=field)
        traces[role] = rec.read_record(path, format=spec.format, units=spec.units,
                                       time_column=spec.time_column, column=spec.column, dt=spec.dt,
                                       skip_lines=spec.skip_lines)
    scale = case.ground.scale
    try:
        return rec.combine(traces["horizontal"], traces["vertical"], pga_horizontal=scale.pga_horizontal,
                           factor=scale.factor, pga_vertical=scale.pga_vertical,
                           vertical_factor=scale.vertical_factor, source=case.source,
                           still_dt=case.solver.dt)
    except RecordError as exc:
        if exc.field is None:
            raise
        # combine names its scale options; in the case file they are keys of ground.scale
        raise RecordError(exc.message, source=exc.source, field=f"ground.scale.{exc.field}") from None


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


def model_for(case: Case) -> Model:
    return Model.from_block(case.block.height, case.block.width, case.contact.mu_static,
                            case.contact.mu_kinetic, case.contact.restitution, case.gravity,
                            case.block.mass)


def settings_for(case: Case, *, history: bool = True, energy: bool = True) -> Settings:
    every = 0
    if history:
        interval = case.output.interval
        every = 1 if interval is None else max(1, round(interval / case.solver.dt))
    return Settings(dt=case.solver.dt, events=case.solver.events, tail=case.ground.tail,
                    rotation=case.initial.rotation, rotation_rate=case.initial.rotation_rate,
                    slip_rate=case.initial.slip_rate, history_every=every, energy=energy)


def check_against_ground(case: Case, ground: rec.GroundMotion) -> None:
    """Checks that need the records: the step is not coarser than the record's sampling
    (`check_step`), and the scaled vertical motion never lifts the block off the ground (``g + av >
    0``, model.md's 'no free flight'), reported before any computation."""
    check_step(case, ground)
    if ground.vertical.size:
        lowest = float(np.min(ground.vertical))
        if case.gravity + lowest <= 0.0:
            # samples (n,), or interval end values (2, n): the end of interval k is sample k + 1
            if ground.vertical.ndim == 2:
                row, k = np.unravel_index(int(np.argmin(ground.vertical)), ground.vertical.shape)
            else:
                row, k = 0, int(np.argmin(ground.vertical))
            pulse = isinstance(case.ground.vertical, Pulse)
            raise CaseError(
                f"the scaled vertical acceleration reaches {lowest / 0.01:.1f} gal at "
                f"t = {ground.start + (k + row) * ground.dt:.3f} s, so g + av = {case.gravity + lowest:.3f} m/s^2 "
                f"<= 0 (the block would fly, outside the model); lower "
                f"{'ground.vertical.amplitude' if pulse else 'ground.scale'}",
                source=case.source, field="ground.vertical.amplitude" if pulse else "ground.scale")


def check_step(case: Case, ground: rec.GroundMotion) -> None:
    """The case's ``solver.dt`` is not coarser than the record's sampling step (a pulse is sampled
    at most ``solver.dt`` apart, `pulses.sample`)."""
    if case.solver.dt > ground.dt * (1.0 + 1e-9) and not is_pulse_case(case):
        raise CaseError(f"dt = {case.solver.dt:g} s is larger than the record's sampling step "
                        f"{ground.dt:g} s; expected dt <= {ground.dt:g} s",
                        source=case.source, field="solver.dt")


#: Sizes beyond these are mistakes (a slip of unit in ``tail`` or ``dt``), reported before the run
#: instead of failing for want of memory or running for days.
MAX_GROUND_SAMPLES = 10**8    # record and tail samples (0.8 GB per component)
MAX_STEPS = 10**11            # integration steps (hours of computing)
MAX_HISTORY_ROWS = 10**8      # output rows (4.8 GB before compression)


def check_size(case: Case, ground: rec.GroundMotion, *, history: bool = True) -> None:
    """Refuse a tail, step or output interval that would need absurd memory, time or disk."""
    dt_record, tail, dt = ground.dt, case.ground.tail, case.solver.dt
    n_tail = math.ceil(tail / dt_record - 1e-9) if tail > 0 else 0
    # samples (n,), or interval end values (2, n) of a pulse: n intervals, n + 1 samples
    given = ground.horizontal.shape[-1] + (1 if ground.horizontal.ndim == 2 else 0)
    samples = given + n_tail
    if samples > MAX_GROUND_SAMPLES:
        longest = (MAX_GROUND_SAMPLES - given) * dt_record
        raise CaseError(f"a tail of {tail:g} s adds {n_tail:.3g} samples at the record's step "
                        f"{dt_record:g} s; expected at most {MAX_GROUND_SAMPLES:.0e} samples in all "
                        f"(a tail of at most {longest:.6g} s)", source=case.source, field="ground.tail")
    steps = (samples - 1) * substeps(dt_record, dt)
    if steps > MAX_STEPS:
        raise CaseError(f"dt = {dt:g} s gives {steps:.3g} integration steps over "
                        f"{(samples - 1) * dt_record:g} s of ground motion; expected at most "
                        f"{MAX_STEPS:.0e} (hours of computing): use a larger dt",
                        source=case.source, field="solver.dt")
    every = settings_for(case, history=history, energy=False).history_every
    if every > 0 and steps // every + 1 > MAX_HISTORY_ROWS:
        raise CaseError(f"output every {every * dt:g} s gives {steps // every + 1:.3g} rows of results; "
                        f"expected at most {MAX_HISTORY_ROWS:.0e}: set a larger output.interval "
                        "(e.g. 0.01 s)", source=case.source, field="output.interval")


def prepare(case: Case, records_dir: Path | None = None, *, history: bool = True) -> Prepared:
    ground = load_ground(case, records_dir)
    check_against_ground(case, ground)
    check_size(case, ground, history=history)
    return Prepared(case, ground, model_for(case), settings_for(case, history=history))


def start_time(prepared: Prepared) -> float:
    """Time of the first sample on the case's time axis (``ground.time_shift`` added)."""
    return prepared.ground.start + prepared.case.ground.time_shift


def simulate_prepared(prepared: Prepared, on_chunk=None) -> Result:
    """Run the prepared case with the method its solver section asks for."""
    g = prepared.ground
    if prepared.case.solver.method == "reference":
        from .core.reference import simulate_reference
        return simulate_reference(prepared.model, g.dt, g.horizontal, g.vertical, prepared.settings,
                                  start=start_time(prepared))
    return simulate(prepared.model, g.dt, g.horizontal, g.vertical, prepared.settings,
                    start=start_time(prepared), on_chunk=on_chunk)


def run_case(case: Case, records_dir: Path | None = None, *, history: bool = True) -> tuple[Prepared, Result]:
    prepared = prepare(case, records_dir, history=history)
    return prepared, simulate_prepared(prepared)


def record_entries(prepared: Prepared) -> list[dict]:
    """The records' provenance for the result file (file name only, checksum, format, scale)."""
    out = []
    for entry in prepared.ground.files:
        role = entry["role"]
        ground = prepared.ground
        factor = ground.horizontal_factor if role == "horizontal" else ground.vertical_factor
        out.append({**entry, "path": Path(str(entry["path"])).name, "scale_factor": float(factor)})
    return out


__all__ = ["Prepared", "load_ground", "is_pulse_case", "unit_pulses", "pulse_ground", "model_for",
           "settings_for", "check_against_ground", "check_step", "check_size", "prepare", "simulate_prepared",
           "run_case", "record_entries", "start_time", "verdict_robustness"]


ROBUSTNESS_VARIANTS = (("dt/2", 0.5, 1.0), ("mu-1%", 1.0, 0.99), ("mu+1%", 1.0, 1.01))


def verdict_robustness(prepared: Prepared, overturned: bool) -> dict:
    """Rerun a case at half the step and with the friction coefficients 1 % lower and higher
    (``mu_kinetic`` scaled with ``mu_static``), and say whether its verdict ``overturned`` (from
    the run the caller already has) holds.

    Returns ``{"holds": bool, "overturned": bool, "variants": {name: {"overturned": bool,
    "overturn_time": float|None, "max_rotation": float, "residual_slip": float}}}``. A verdict
    that does not hold sits on a knife edge: a fraction of a percent in friction, or the step,
    decides it.
    """
    from dataclasses import replace

    g = prepared.ground
    variants = {}
    for name, dt_factor, mu_factor in ROBUSTNESS_VARIANTS:
        model = replace(prepared.model, mu_static=prepared.model.mu_static * mu_factor,
                        mu_kinetic=prepared.model.mu_kinetic * mu_factor)
        settings = replace(prepared.settings, dt=prepared.settings.dt * dt_factor, history_every=0,
                           energy=False)
        s = simulate(model, g.dt, g.horizontal, g.vertical, settings, start=start_time(prepared)).summary
        variants[name] = {"overturned": s.overturned, "overturn_time": s.overturn_time,
                          "max_rotation": s.max_rotation, "residual_slip": s.residual_slip}
    holds = all(v["overturned"] == overturned for v in variants.values())
    return {"holds": holds, "overturned": overturned, "variants": variants}
