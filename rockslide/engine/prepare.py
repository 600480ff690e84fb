"""Case -> records -> checks -> simulation: the one orchestrator behind `run`, `sweep` and `table1`.

It reads the records a case names (`records.py`), scales and aligns them, or samples its analytic
pulses (`pulses.py`), checks what can only be checked with the ground motion at hand (the step
against the record's sampling, flight before the run), builds the `Model` and `Settings` of the
pure core and calls `simulate` (or the reference solver).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..case import Case, floor_text
from ..core.layout import P_P2_1, P_P2_2, P_STEP
from ..core.simulate import Model, Result, Settings, interval_count, parameters, simulate, substeps, tail_samples
from ..errors import CaseError
from ..io import records as rec
from ..pulses import Pulse
from ..units import STANDARD_GRAVITY
from .ground import (  # noqa: F401  (the ground motion's functions, used here and re-exported)
    MAX_GROUND_SAMPLES,
    ORTHOGONALITY_TOLERANCE,
    Components,
    component_azimuths,
    floor_carries_tail,
    floor_ground,
    floor_peaks,
    floor_peaks_text,
    ground_along,
    is_pulse_case,
    load_ground,
    pulse_ground,
    read_records,
    still_step,
    unit_pulses,
)
from .step import MAX_P_DT, StepChoice, choose_step


@dataclass(frozen=True)
class Prepared:
    """A case with its ground motion loaded: everything needed to simulate it. ``ground`` is the
    motion the block stands on (the floor's, with ``ground.floor``); ``base`` the ground motion under
    the building when there is a floor (else None)."""

    case: Case
    ground: rec.GroundMotion
    model: Model
    settings: Settings
    components: Components | None = None
    base: rec.GroundMotion | None = None
    records: dict | None = None
    step_choice: StepChoice | None = None       # with solver.dt: auto, the step chosen and its error


def base_motion(prepared: Prepared) -> dict | None:
    """The ground motion under the building of a case on a floor, as the result file's ``/base`` group
    holds it (`results.ResultWriter.finish`'s ``extra_groups``): ``{"base": (time, variables)}`` with
    the times [s] (``ground.time_shift`` added, as the run's) and the scaled horizontal and vertical
    ground accelerations [m/s^2]; None without a floor."""
    base = prepared.base
    if base is None:
        return None
    time = start_time(prepared) + base.dt * np.arange(base.horizontal.size)
    words = {"horizontal": "horizontal", "vertical": "vertical (up positive)"}
    return {"base": (("time", time, {"units": "s", "long_name": "time"}),
                     {role: (("time",), getattr(base, role), {
                         "units": "m/s^2", "long_name": f"{words[role]} ground acceleration under the building "
                         "(scaled), the input of the floor the block stands on (/ground)"})
                      for role in ("horizontal", "vertical")})}


def model_for(case: Case) -> Model:
    block = case.block
    if block.half_widths is None and block.radius_of_gyration is None:
        return Model.from_block(block.width, block.height, case.contact.mu_static,
                                case.contact.mu_kinetic, case.contact.restitution, case.gravity,
                                block.mass)
    b1, b2 = block.corners        # an asymmetric body (docs/model-asymmetric.md)
    return Model(b1, block.height / 2.0, case.contact.mu_static, case.contact.mu_kinetic, case.contact.restitution,
                 case.gravity, block.mass, half_width_2=b2, radius_of_gyration=block.radius_of_gyration)


def settings_for(case: Case, *, history: bool = True, energy: bool = True, step: float | None = None) -> Settings:
    """The core's settings for ``case``; ``step`` [s] instead of ``solver.dt`` (the step `auto` chose:
    ``output.interval`` is then rounded to a whole number of steps)."""
    dt = case.solver.dt if step is None else step
    every = 0
    if history:
        interval = case.output.interval
        every = 1 if interval is None else max(1, round(interval / dt))
    return Settings(dt=dt, events=case.solver.events,
                    tail=0.0 if floor_carries_tail(case) else case.ground.tail,
                    rotation=case.initial.rotation, rotation_rate=case.initial.rotation_rate,
                    slip_rate=case.initial.slip_rate, history_every=every, energy=energy)


#: Bounds that keep every number of a run finite in float64 (docs: "What rockslide promises").
#: The kernel's largest quantities are energies, about ``M (A T)^2`` for a ground acceleration ``A``
#: over a duration ``T``, and the rocking frequency ``p^2 = 3 g / (4 R)``; within these bounds they
#: stay below 1e80 (``M <= 1e20 kg``, ``A <= 1e6 g``, ``T <= 1e9 s``: ``1e20 (1e7 * 1e9)^2 = 1e52``;
#: ``g <= 1e3``, ``R >= 1e-12 m``: ``p^2 <= 1e15 /s^2``), far from float64's 1.8e308, while their
#: ratios stay far from its 2.2e-16 resolution. No physical case comes near them: ground motions
#: stay below 5 g, blocks between millimetres and tens of metres.
MAX_ACCELERATION_IN_G = 1e6        # |scaled ground acceleration| / g
LENGTH_RANGE = (1e-12, 1e6)        # [m] block height and width
MASS_RANGE = (1e-20, 1e20)         # [kg]
GRAVITY_RANGE = (1e-3, 1e3)        # [m/s^2]
MAX_INITIAL_RATE = 1e6             # [rad/s] and [m/s]: |initial.rotation_rate|, |initial.slip_rate|
#: [s] Largest |time of the first sample| (record start plus ``ground.time_shift``): times near 1e6 s
#: still resolve a step of 1e-9 s (relative 1e-15, above float64's 2.2e-16).
MAX_START_TIME = 1e6
#: A scaled ground motion above this many g is accepted with a warning (a unit mistake, most likely).
ABSURD_ACCELERATION_IN_G = 10.0


def within_acceleration_bound(peak, gravity: float):
    """Whether a peak scaled ground acceleration ``peak`` [m/s^2] (a number or an array) is one the
    model computes: finite and at most :data:`MAX_ACCELERATION_IN_G` times ``gravity`` [m/s^2] (a
    scale to the bound itself rounds, hence the 1e-12). NaN and infinity are not."""
    return peak <= MAX_ACCELERATION_IN_G * gravity * (1.0 + 1e-12)


def check_parameters(case: Case) -> None:
    """Refuse a block, gravity or initial state outside the ranges float64 represents safely
    (the bounds above), with one line naming the key."""
    checks = (("block.height", case.block.height, LENGTH_RANGE, "m"),
              ("block.width", case.block.width, LENGTH_RANGE, "m"),
              ("block.mass", case.block.mass, MASS_RANGE, "kg"),
              ("gravity", case.gravity, GRAVITY_RANGE, "m/s^2"),
              ("initial.rotation_rate", abs(case.initial.rotation_rate), (0.0, MAX_INITIAL_RATE), "rad/s"),
              ("initial.slip_rate", abs(case.initial.slip_rate), (0.0, MAX_INITIAL_RATE), "m/s"))
    for key, value, (low, high), unit in checks:
        if not low <= value <= high:
            what = "in absolute value " if key.startswith("initial.") else ""
            raise CaseError(f"{value:g} {unit} is outside what rockslide computes reliably; expected "
                            f"{what}{low:g} to {high:g} {unit}", source=case.source, field=key)


def check_against_ground(case: Case, ground: rec.GroundMotion, *, warn: bool = True) -> float:
    """Checks that need the records: the step is not coarser than the record's sampling
    (`check_step`), the first sample's time is one float64 resolves the step at, and the scaled
    motion stays within :data:`MAX_ACCELERATION_IN_G`; with ``warn``, a warning when it passes
    :data:`ABSURD_ACCELERATION_IN_G` (`absurd_acceleration`) and when the scaled vertical motion
    lifts the block off the ground (`flight_warning`: the run then ends 'outside the model', a
    status, as in sweeps and fragility analyses).

    Returns the peak scaled acceleration [m/s^2] (``warn=False``: the caller warns, once).
    """
    check_step(case, ground)
    start = ground.start + case.ground.time_shift
    if not abs(start) <= MAX_START_TIME:
        raise CaseError(f"the ground motion starts at t = {start:g} s; expected a time within "
                        f"+-{MAX_START_TIME:g} s, where float64 still resolves the integration step (shift "
                        "the record's times with ground.time_shift)", source=case.source,
                        field="ground.time_shift")
    peak = max(float(np.max(np.abs(ground.horizontal), initial=0.0)),
               float(np.max(np.abs(ground.vertical), initial=0.0)))
    if not within_acceleration_bound(peak, case.gravity):
        raise CaseError(f"the scaled ground motion reaches {peak:.3g} m/s^2 = {peak / case.gravity:.3g} g; "
                        f"expected at most {MAX_ACCELERATION_IN_G:.0e} g (beyond, the computation "
                        "cannot stay finite); check the record's units and ground.scale",
                        source=case.source, field="ground.scale")
    if warn:
        if peak > ABSURD_ACCELERATION_IN_G * STANDARD_GRAVITY:
            warnings.warn(absurd_acceleration(case.source, peak), RunWarning, stacklevel=2)
        text = flight_warning(case, ground)
        if text:
            warnings.warn(text, RunWarning, stacklevel=2)
    return peak


def flight_warning(case: Case, ground: rec.GroundMotion) -> str | None:
    """The warning when the scaled vertical acceleration lifts the block off the ground (``g + av
    <= 0``, model.md's 'no free flight'): the run stops there with the status ``flight``, outside
    the model. None when it never does."""
    if not ground.vertical.size:
        return None
    lowest = float(np.min(ground.vertical))
    if case.gravity + lowest > 0.0:
        return None
    # samples (n,), or interval end values (2, n): the end of interval k is sample k + 1
    if ground.vertical.ndim == 2:
        row, k = np.unravel_index(int(np.argmin(ground.vertical)), ground.vertical.shape)
    else:
        row, k = 0, int(np.argmin(ground.vertical))
    start = ground.start + case.ground.time_shift
    pulse = isinstance(case.ground.vertical, Pulse)
    key = "ground.vertical.amplitude" if pulse else "ground.scale"
    return (f"{case.source}: {key}: the scaled vertical acceleration reaches {lowest / 0.01:.1f} gal at "
            f"t = {start + (k + row) * ground.dt:.3f} s, so g + av = {case.gravity + lowest:.3f} m/s^2 <= 0: "
            "the block would fly, outside the model, and the run stops there with the status 'flight'")


def absurd_acceleration(source: str, peak: float) -> str:
    """The warning for a scaled ground motion above :data:`ABSURD_ACCELERATION_IN_G`."""
    return (f"{source}: ground.scale: the scaled ground motion reaches {peak / STANDARD_GRAVITY:.4g} g "
            f"(above {ABSURD_ACCELERATION_IN_G:g} g); check the scale and the record's units")


class RunWarning(UserWarning):
    """A case that runs but is likely not what was meant: a step too coarse for the block, an
    absurd ground motion, a run of hours."""


def check_step(case: Case, ground: rec.GroundMotion) -> None:
    """The case's ``solver.dt`` is not coarser than the record's sampling step (a pulse is sampled
    at most ``solver.dt`` apart, `pulses.sample`)."""
    if case.solver.dt > ground.dt * (1.0 + 1e-9) and not is_pulse_case(case) and not case.solver.auto:
        raise CaseError(f"dt = {case.solver.dt:g} s is larger than the record's sampling step "
                        f"{ground.dt:g} s; expected dt <= {ground.dt:g} s",
                        source=case.source, field="solver.dt")


#: Sizes beyond these are mistakes (a slip of unit in ``tail`` or ``dt``), reported before the run
#: instead of failing for want of memory or running for days.
MAX_STEPS = 10**11            # integration steps (hours of computing)
MAX_HISTORY_ROWS = 10**8      # output rows (4.8 GB before compression)


def check_size(case: Case, ground: rec.GroundMotion, *, history: bool = True) -> None:
    """Refuse a tail, step or output interval that would need absurd memory, time or disk."""
    dt_record, tail, dt = ground.dt, case.ground.tail, case.solver.dt
    n_tail = tail / dt_record if tail / dt_record > MAX_GROUND_SAMPLES else tail_samples(tail, dt_record)
    given = interval_count(ground.horizontal, dt_record, 0.0) + 1
    samples = given + n_tail
    if samples > MAX_GROUND_SAMPLES:
        longest = (MAX_GROUND_SAMPLES - given) * dt_record
        raise CaseError(f"a tail of {tail:g} s adds {n_tail:.3g} samples at the record's step "
                        f"{dt_record:g} s; expected at most {MAX_GROUND_SAMPLES:.0e} samples in all "
                        f"(a tail of at most {longest:.6g} s)", source=case.source, field="ground.tail")
    duration = (samples - 1) * dt_record
    if duration / dt > MAX_STEPS:          # before counting substeps: dt may be 5e-324
        raise CaseError(f"dt = {dt:g} s gives {duration / dt:.3g} integration steps over "
                        f"{duration:g} s of ground motion; expected at most "
                        f"{MAX_STEPS:.0e} (hours of computing): use a larger dt",
                        source=case.source, field="solver.dt")
    interval = case.output.interval
    if history and interval is not None and interval > duration:
        raise CaseError(f"{interval:g} s is longer than the run ({duration:g} s of ground motion and "
                        "tail); expected at most the run's duration", source=case.source,
                        field="output.interval")
    steps = (samples - 1) * substeps(dt_record, dt)
    every = settings_for(case, history=history, energy=False).history_every
    if every > 0 and steps // every + 1 > MAX_HISTORY_ROWS:
        raise CaseError(f"output every {every * dt:g} s gives {steps // every + 1:.3g} rows of results; "
                        f"expected at most {MAX_HISTORY_ROWS:.0e}: set a larger output.interval "
                        "(e.g. 0.01 s)", source=case.source, field="output.interval")


#: Speeds behind the estimate of a run's time (results/bench.md, 2 cores): integration steps per
#: second while the block moves (at rest it is about 3000 times cheaper), and history rows written
#: per second (compressed HDF5).
STEPS_PER_SECOND = 9e6
ROWS_PER_SECOND = 1e6
# MAX_P_DT, the largest ``p dt`` without a warning (`step_warning`), lives in `step` (auto's coarsest step)


@dataclass(frozen=True)
class Work:
    """What a run will compute: ``steps`` integration steps (for each of ``runs`` runs), ``rows``
    history rows, ``seconds`` an upper estimate of the time it takes [s] (the block moving all
    along; at rest it goes much faster)."""

    steps: int
    rows: int
    runs: int
    seconds: float

    def describe(self) -> str:
        """``2.2e+09 integration steps and 2.2e+08 history rows: up to about 5 min``."""
        runs = f" in each of {self.runs} runs" if self.runs > 1 else ""
        rows = f" and {self.rows:.3g} history rows" if self.rows else ""
        return f"{self.steps:.3g} integration steps{runs}{rows}: up to about {duration_text(self.seconds)}"


def work(prepared: Prepared, *, runs: int = 1) -> Work:
    """The work of ``runs`` runs of ``prepared`` (the robustness check makes 3 more, one at dt/2)."""
    s = prepared.settings
    steps = interval_count(prepared.ground.horizontal, prepared.ground.dt, s.tail) * substeps(prepared.ground.dt, s.dt)
    rows = steps // s.history_every + 1 if s.history_every > 0 else 0
    seconds = steps * (runs + (1 if runs > 1 else 0)) / STEPS_PER_SECOND + rows / ROWS_PER_SECOND
    return Work(steps=int(steps), rows=int(rows), runs=runs, seconds=seconds)


def duration_text(seconds: float) -> str:
    """``45 s``, ``12 min``, ``3.5 h`` or ``4 days``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.0f} days"


def step_warning(source: str, p: float, step: float) -> str | None:
    """A warning when the integration step ``step`` [s] is too coarse for a block whose rocking
    frequency is ``p = sqrt(3 g / (4 R))`` [rad/s]; ``source`` is the case file.

    Rocking about an edge grows and decays like ``exp(+-p t)``; RK4's error per step on it is
    ``(p dt)^5 / 120``, and the event times it locates err by about ``0.09 (p dt)^4 / p``
    (results/bench.md, free rocking: 4.9e-11 s at ``p dt = 8.1e-3``, the paper's block at 1 ms).
    Above ``p dt`` = :data:`MAX_P_DT` that is 1e-5 of the rocking time scale ``1/p`` and more (10 %
    at ``p dt = 1``, and RK4 itself is unstable beyond 2.8), so the verdict cannot be trusted.
    """
    if p * step <= MAX_P_DT:
        return None
    return (f"{source}: solver.dt: the step {step:.3g} s is too coarse for this block (rocking "
            f"frequency p = {p:.3g} rad/s, p dt = {p * step:.3g} > {MAX_P_DT:g}): the rocking is not "
            f"resolved and the verdict may be wrong; use dt <= {MAX_P_DT / p:.2g} s")


def coarse_step_warning(source: str, params: np.ndarray, where=None) -> str | None:
    """`step_warning` for the case of ``params`` (kernel parameter vectors, one per row) whose
    rocking is fastest (the largest ``p dt``), or None when every step is fine; ``where(i)`` names
    case ``i`` in the message (``[at --mu 0.5, --pga 800gal]``). The one check of the step behind
    runs, sweeps and fragility analyses."""
    params = np.atleast_2d(params)
    p2 = np.maximum(params[:, P_P2_1], params[:, P_P2_2])    # p^2 = 3 g / (4 R), model.md; per pivot
    i = int(np.argmax(p2))
    warning = step_warning(source, math.sqrt(p2[i]), float(params[i, P_STEP]))
    if warning and where is not None:
        warning += f" [at {where(i)}]"
    return warning


def prepare(case: Case, records_dir: Path | None = None, *, history: bool = True) -> Prepared:
    """Load the case's records and run every check that needs no computation (the parameters'
    ranges, the ground motion, the sizes), warning when the step is too coarse for the block."""
    check_parameters(case)
    components = None
    records = None if is_pulse_case(case) else read_records(case, records_dir)
    if case.ground.two_components:
        base, components = ground_along(case, records)
    else:
        base = load_ground(case, records_dir, records=records)
    check_step(case, base)
    ground = floor_ground(case, base)
    check_against_ground(case, ground)
    check_size(case, ground, history=history)
    model = model_for(case)
    settings = settings_for(case, history=history)
    choice = None
    if case.solver.auto and case.solver.method == "kernel":
        choice = auto_step(case, model, ground, settings)
        settings = settings_for(case, history=history, step=choice.step)
    warning = coarse_step_warning(case.source, parameters(model, ground.dt, settings))
    if warning:
        warnings.warn(warning, RunWarning, stacklevel=2)
    return Prepared(case, ground, model, settings, components, base=base if ground is not base else None,
                    records=records, step_choice=choice)


def study_step(plan, pilots, sample: str):
    """The one step of a study: ``pilots`` are ``(rows, case, ground)`` (the rows of ``plan.params``
    a pilot stands for, the case piloted and its scaled ground motion); each is piloted (`auto_step`)
    and, with ``solver.dt: auto``, its rows take the step it chose (`step.apply_step`; the plan's
    ``step`` follows; the caller computes its ``key`` after). ``sample`` says what was piloted, for
    the note. Sets and returns ``plan.step_study`` (`step.StudyStep`)."""
    from .step import StudyStep, apply_step

    choices = []
    for rows, case, ground in pilots:
        settings = settings_for(case, history=False, energy=False)
        choice = auto_step(case, model_for(case), ground, settings)
        choices.append(choice)
        if plan.case.solver.auto:
            apply_step(plan.params, choice.step, rows)
    default = choices[0].default_step if choices else plan.case.solver.dt
    plan.step_study = StudyStep(plan.case.solver.auto, tuple(choices), sample, default)
    if plan.case.solver.auto and choices:
        plan.step = float(plan.params[:, P_STEP].min())
    return plan.step_study


def step_report(prepared: Prepared, step: float) -> dict:
    """The step a run used, for ``rockslide run --json`` and its result file: ``step`` [s], ``mode``
    (``auto`` or ``fixed``) and, with ``auto``, the estimate (`step.StepChoice.as_dict`: errors
    [s] and [rad], tolerance, ``met``)."""
    choice = prepared.step_choice
    return {"step": float(step), "mode": "fixed" if choice is None else "auto",
            **({} if choice is None else choice.as_dict()), "note": "" if choice is None else choice.describe()}


def auto_step(case: Case, model: Model, ground: rec.GroundMotion, settings: Settings) -> StepChoice:
    """`step.choose_step` for ``case`` on ``ground`` (scaled, what the block stands on) with the
    case's ``solver.tolerance``: the one call behind runs, sweeps, ensembles and fragility analyses."""
    return choose_step(model, ground.dt, ground.horizontal, ground.vertical, settings,
                       tolerance_time=case.solver.tolerance_time, tolerance_rotation=case.solver.tolerance_rotation,
                       start=ground.start + case.ground.time_shift)


def start_time(prepared: Prepared) -> float:
    """Time of the first sample on the case's time axis (``ground.time_shift`` added)."""
    return prepared.ground.start + prepared.case.ground.time_shift


def simulate_prepared(prepared: Prepared, on_chunk=None, progress=None) -> Result:
    """Run the prepared case with the method its solver section asks for; ``on_chunk`` and
    ``progress`` as in `simulate` (the reference solver keeps its history and calls ``progress``
    every hundred record intervals)."""
    g = prepared.ground
    if prepared.case.solver.method == "reference":
        from ..core.reference import simulate_reference
        return simulate_reference(prepared.model, g.dt, g.horizontal, g.vertical, prepared.settings,
                                  start=start_time(prepared), progress=progress)
    return simulate(prepared.model, g.dt, g.horizontal, g.vertical, prepared.settings,
                    start=start_time(prepared), on_chunk=on_chunk, progress=progress)


def run_case(case: Case, records_dir: Path | None = None, *, history: bool = True) -> tuple[Prepared, Result]:
    prepared = prepare(case, records_dir, history=history)
    return prepared, simulate_prepared(prepared)


def applied_ground(prepared: Prepared) -> dict:
    """The ground motion as applied (`records.GroundMotion.as_applied`), with two horizontal
    components also ``components`` (`Components.as_dict`)."""
    ground = prepared.ground.as_applied()
    if prepared.components is not None:
        ground["components"] = prepared.components.as_dict()
    return ground


def record_entries(prepared: Prepared) -> list[dict]:
    """The records' provenance for the result file (file name only, checksum, format, scale)."""
    out = []
    for entry in prepared.ground.files:
        role = entry["role"]
        ground = prepared.ground
        factor = ground.vertical_factor if role == "vertical" else ground.horizontal_factor
        out.append({**entry, "path": Path(str(entry["path"])).name, "scale_factor": float(factor)})
    return out


__all__ = ["Prepared", "Components", "component_azimuths", "ground_along",
           "load_ground", "floor_ground", "floor_text", "floor_peaks", "floor_peaks_text", "base_motion",
           "is_pulse_case", "unit_pulses", "pulse_ground", "model_for", "settings_for", "check_parameters",
           "check_against_ground", "check_step", "check_size", "prepare", "simulate_prepared", "run_case",
           "applied_ground", "record_entries", "auto_step", "still_step", "study_step", "step_report", "start_time",
           "verdict_robustness", "work", "Work", "step_warning", "RunWarning"]


ROBUSTNESS_VARIANTS = (("dt/2", 0.5, 1.0), ("mu-1%", 1.0, 0.99), ("mu+1%", 1.0, 1.01))


def verdict_robustness(prepared: Prepared, overturned: bool, progress=None) -> dict:
    """Rerun a case at half the step and with the friction coefficients 1 % lower and higher
    (``mu_kinetic`` scaled with ``mu_static``), and say whether its verdict ``overturned`` (from
    the run the caller already has) holds.

    Returns ``{"holds": bool, "overturned": bool, "variants": {name: {"overturned": bool,
    "overturn_time": float|None, "max_rotation": float, "residual_slip": float}}}``. A verdict
    that does not hold sits on a knife edge: a fraction of a percent in friction, or the step,
    decides it. ``progress`` is passed to each `simulate`. The variants run on the compiled kernel,
    whatever ``solver.method`` the case asks for.
    """
    from dataclasses import replace

    g = prepared.ground
    variants = {}
    for name, dt_factor, mu_factor in ROBUSTNESS_VARIANTS:
        model = replace(prepared.model, mu_static=prepared.model.mu_static * mu_factor,
                        mu_kinetic=prepared.model.mu_kinetic * mu_factor)
        settings = replace(prepared.settings, dt=prepared.settings.dt * dt_factor, history_every=0,
                           energy=False)
        s = simulate(model, g.dt, g.horizontal, g.vertical, settings, start=start_time(prepared),
                     progress=progress).summary
        variants[name] = {"overturned": s.overturned, "overturn_time": s.overturn_time,
                          "max_rotation": s.max_rotation, "residual_slip": s.residual_slip}
    holds = all(v["overturned"] == overturned for v in variants.values())
    return {"holds": holds, "overturned": overturned, "variants": variants}
