"""``solver.dt: auto``: the integration step chosen from a tolerance by a pilot with step doubling.

The one place a step is chosen (`choose_step`); `prepare.prepare` calls it for a run, and the
planners of sweeps, ensembles and fragility analyses for the cases they pilot
(docs/performance.md, 'Choosing the step').

Method (Richardson's extrapolation on the kernel as a black box). The kernel's step is ``h =
dt_record / n`` for a whole ``n`` (the record's kinks stay on step ends). For ``n = n0, 2 n0, 4 n0,
...`` the case runs at ``h`` and at ``h / 2``; a method of order ``q`` (4: RK4 with located events;
1: step-end switching) errs at ``h`` by about ``|y_h - y_{h/2}| 2^q / (2^q - 1)`` (16/15 for RK4),
for ``y`` each event time and the largest rotation. The first ``n`` whose estimates are within
:data:`SAFETY` times both tolerances is taken (the largest step of the series that does), with its
estimate. The estimate is infinite when the two runs do not pass through the same sequence of events
(then the step does not resolve the case yet). ``n0`` is the smallest ``n`` with ``p h <=
MAX_P_DT`` (a coarser step is not resolved, `prepare.step_warning`); the series stops at the
default step (0.1 ms): when even that does not meet the tolerance (a chaotic trajectory, where per-
trajectory error is not the measure: docs/performance.md), the default step is kept and ``met`` is
False.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.simulate import Model, Settings, simulate, substeps

#: [s] The default step, ``solver.dt``'s default (the paper's 0.1 ms).
DEFAULT_STEP = 1e-4

#: Largest ``p dt`` without a warning (`prepare.step_warning`), and the coarsest step auto tries: RK4
#: resolves rocking (``exp(+-p t)``) to 1e-5 of its time scale there.
MAX_P_DT = 0.1

#: Share of the tolerance the estimate must stay within: Richardson's estimate is itself an estimate
#: (on free rocking it was 1-10 % below the exact error), so half the tolerance keeps the error within it.
SAFETY = 0.5

#: [s] The sampling step of the still ground (a case without records, free vibration) when the
#: step is ``auto``: the still ground has no kinks, so any step divides it.
AUTO_STILL_STEP = 0.01


@dataclass(frozen=True)
class StepChoice:
    """The step `choose_step` took, and why.

    Attributes
    ----------
    step : float
        [s] the integration step, ``dt_record / n_sub``.
    n_sub : int
        Steps per record interval.
    error_time : float
        [s] estimated error of the event times at ``step`` (the largest over the events; 0 without
        events; inf when the pilot's two runs saw different event sequences).
    error_rotation : float
        [rad] estimated error of the largest rotation at ``step``.
    met : bool
        Whether both estimates are within :data:`SAFETY` times the tolerance.
    tolerance_time, tolerance_rotation : float
        [s], [rad] the tolerance asked for.
    default_step : float
        [s] the step the default ``solver.dt`` (0.1 ms) gives on this record.
    pilot_steps : int
        Integration steps the pilot computed (all its runs).
    """

    step: float
    n_sub: int
    error_time: float
    error_rotation: float
    met: bool
    tolerance_time: float
    tolerance_rotation: float
    default_step: float
    pilot_steps: int

    @property
    def saving(self) -> float:
        """How many times fewer steps than the default step: ``step / default_step``."""
        return self.step / self.default_step

    def describe(self) -> str:
        """``auto (tolerance 1e-06 s, 0.0001 rad) takes 0.8 ms here: 8x fewer steps than 0.1 ms
        (estimated errors 3e-09 s, 1e-07 rad)``."""
        if self.met:
            how = f"takes {self.step * 1e3:.4g} ms here: {self.saving:.3g}x fewer steps than " \
                  f"{self.default_step * 1e3:.4g} ms"
        else:
            how = f"is not met by any step down to {self.default_step * 1e3:.4g} ms, which it keeps"
        return (f"auto (tolerance {self.tolerance_time:.3g} s, {self.tolerance_rotation:.3g} rad) {how} "
                f"(estimated errors {self.error_time:.2g} s, {self.error_rotation:.2g} rad)")

    def as_dict(self) -> dict:
        """The fields by name, for JSON and result files' attributes (``[s]``, ``[rad]``)."""
        return {"step": self.step, "n_sub": self.n_sub, "error_time": self.error_time,
                "error_rotation": self.error_rotation, "met": self.met, "tolerance_time": self.tolerance_time,
                "tolerance_rotation": self.tolerance_rotation, "default_step": self.default_step,
                "pilot_steps": self.pilot_steps}


def richardson_factor(events: str) -> float:
    """``2^q / (2^q - 1)`` for the order ``q`` of the kernel's error: 4 with located events
    (docs/performance.md: fourth-order convergence), 1 with step-end switching."""
    q = 4 if events == "located" else 1
    return 2.0 ** q / (2.0 ** q - 1.0)


def _pilot(model: Model, dt_record: float, horizontal, vertical, settings: Settings, n: int,
           start: float) -> tuple[np.ndarray, np.ndarray, float, int]:
    """One pilot run at ``dt_record / n``: (event times, event kinds, largest rotation, steps)."""
    run = Settings(dt=dt_record / n, events=settings.events, tail=settings.tail, rotation=settings.rotation,
                   rotation_rate=settings.rotation_rate, slip_rate=settings.slip_rate, history_every=0,
                   energy=False)
    result = simulate(model, dt_record, horizontal, vertical, run, start=start)
    ev = result.events
    kinds = np.array([(e["from"], e["to"], e["cause"], e["edge"]) for e in ev], dtype=object) \
        if ev.size else np.empty((0, 4), dtype=object)
    steps = int(round((result.summary.end_time - start) / run.dt)) + 1
    return np.asarray(ev["time"], dtype=np.float64), kinds, float(result.summary.max_rotation), steps


def step_errors(coarse, fine, factor: float) -> tuple[float, float]:
    """Richardson's estimates ``(error_time [s], error_rotation [rad])`` of the coarse of two pilot
    runs (`_pilot`'s tuples at ``h`` and ``h / 2``): ``factor`` times their largest difference;
    the time estimate is inf when the event sequences differ."""
    t1, k1, r1, _ = coarse
    t2, k2, r2, _ = fine
    if t1.size != t2.size or (t1.size and not (k1 == k2).all()):
        error_time = math.inf
    else:
        error_time = factor * float(np.max(np.abs(t1 - t2), initial=0.0))
    return error_time, factor * abs(r1 - r2)


def choose_step(model: Model, dt_record: float, horizontal, vertical, settings: Settings, *,
                tolerance_time: float, tolerance_rotation: float, start: float = 0.0,
                default_step: float = DEFAULT_STEP) -> StepChoice:
    """The largest step ``dt_record / n`` (``n = n0 2^k``) whose estimated errors meet the tolerance.

    Parameters
    ----------
    model : Model
    dt_record : float
        [s] sampling step of the ground motion.
    horizontal, vertical : array_like
        [m/s^2] the ground motion as `simulate` takes it (scaled).
    settings : Settings
        The case's settings (events, tail, initial state); their ``dt`` is not used.
    tolerance_time : float
        [s] allowed error on every event time.
    tolerance_rotation : float
        [rad] allowed error on the largest rotation ``max |phi|``.
    start : float
        [s] time of the first sample.
    default_step : float
        [s] the finest step tried (the default ``solver.dt``).

    Returns
    -------
    StepChoice
        The step and its error estimate (the module's docstring gives the method).
    """
    _, _, p2 = model.constants
    n = max(1, math.ceil(dt_record * math.sqrt(p2) / MAX_P_DT * (1.0 - 1e-9)))
    n_default = substeps(dt_record, default_step)
    factor = richardson_factor(settings.events)
    total = 0
    coarse = _pilot(model, dt_record, horizontal, vertical, settings, n, start)
    total += coarse[3]
    while n < n_default:
        fine = _pilot(model, dt_record, horizontal, vertical, settings, 2 * n, start)
        total += fine[3]
        error_time, error_rotation = step_errors(coarse, fine, factor)
        if error_time <= SAFETY * tolerance_time and error_rotation <= SAFETY * tolerance_rotation:
            return StepChoice(dt_record / n, n, error_time, error_rotation, True, tolerance_time,
                              tolerance_rotation, dt_record / n_default, total)
        n, coarse = 2 * n, fine
    # the default step: its estimate against half of it
    if n != n_default:
        coarse = _pilot(model, dt_record, horizontal, vertical, settings, n_default, start)
        total += coarse[3]
    fine = _pilot(model, dt_record, horizontal, vertical, settings, 2 * n_default, start)
    total += fine[3]
    error_time, error_rotation = step_errors(coarse, fine, factor)
    met = error_time <= SAFETY * tolerance_time and error_rotation <= SAFETY * tolerance_rotation
    return StepChoice(dt_record / n_default, n_default, error_time, error_rotation, met, tolerance_time,
                      tolerance_rotation, dt_record / n_default, total)


def stable_substeps(params: np.ndarray) -> np.ndarray:
    """Each row's fewest steps per record interval with ``p h <= MAX_P_DT``."""
    from ..core import layout as L

    p = np.sqrt(0.75 * params[:, L.P_G] / params[:, L.P_R])
    return np.maximum(1, np.ceil(params[:, L.P_DT_REC] * p / MAX_P_DT * (1.0 - 1e-9)))


def apply_step(params: np.ndarray, step: float, rows=slice(None)) -> None:
    """Set the kernel's step of ``params[rows]`` (in place) to the largest whole divisor of each row's
    record step not above ``step`` [s] (and fine enough for the row's block: `stable_substeps`).
    The only columns changed are ``P_STEP`` and ``P_N_SUB``; the kernel's equations are untouched."""
    from ..core import layout as L

    part = params[rows]
    dt_record = part[:, L.P_DT_REC]
    n = np.maximum(np.maximum(1.0, np.ceil(dt_record / step * (1.0 - 1e-9))), stable_substeps(part))
    part[:, L.P_N_SUB] = n
    part[:, L.P_STEP] = dt_record / n
    params[rows] = part


def keep_resolved(params: np.ndarray) -> None:
    """Refine (in place) the step of rows whose block it does not resolve (`stable_substeps`): the
    members of an ensemble or a fragility analysis's parameter samples keep their pilot's step
    unless their block is smaller."""
    from ..core import layout as L

    n = np.maximum(params[:, L.P_N_SUB], stable_substeps(params))
    params[:, L.P_STEP] = params[:, L.P_DT_REC] / n
    params[:, L.P_N_SUB] = n


@dataclass(frozen=True)
class StudyStep:
    """The step of a study (sweep, ensemble, fragility analysis): its pilots' `StepChoice` and what
    they ran (``sample``), whether the study takes their steps (``auto``, ``solver.dt: auto``) or
    only says what they would save (the default step)."""

    auto: bool
    choices: tuple
    sample: str
    default_step: float

    @property
    def saving(self) -> float:
        """Fewer steps than the default, over the pilots (their records' steps weighed equally)."""
        return float(np.mean([c.saving for c in self.choices])) if self.choices else 1.0

    def note(self) -> str:
        """One line for the console: the step taken and what ``auto`` saves or would save."""
        if not self.choices:
            return ""
        steps = sorted({c.step for c in self.choices})
        steps_text = f"{steps[0] * 1e3:.4g} ms" if len(steps) == 1 else \
            f"{steps[0] * 1e3:.4g}-{steps[-1] * 1e3:.4g} ms"
        c = self.choices[0]
        tolerance = f"tolerance {c.tolerance_time:.3g} s, {c.tolerance_rotation:.3g} rad"
        errors = (f"estimated errors up to {max(x.error_time for x in self.choices):.2g} s, "
                  f"{max(x.error_rotation for x in self.choices):.2g} rad; piloted on {self.sample}")
        unmet = sum(not x.met for x in self.choices)
        if unmet:
            errors += f"; the tolerance not met by {unmet} of {len(self.choices)} pilots, which keep the default step"
        if self.auto:
            return f"solver.dt: auto ({tolerance}) takes {steps_text} here: {self.saving:.3g}x fewer steps " \
                   f"than {self.default_step * 1e3:.4g} ms ({errors})"
        return (f"solver.dt: {self.default_step * 1e3:.4g} ms; auto ({tolerance}) would take {steps_text} here: "
                f"{self.saving:.3g}x fewer steps ({errors})")

    def attributes(self) -> dict:
        """Result files' attributes: ``step_mode`` (auto or fixed), ``step_auto`` (the step auto takes
        or would take [s], the smallest of the pilots'), ``step_error_time`` [s] and
        ``step_error_rotation`` [rad] (the pilots' largest estimates), ``step_tolerance_time``,
        ``step_tolerance_rotation``, ``step_saving`` and ``step_note``."""
        if not self.choices:
            return {"step_mode": "auto" if self.auto else "fixed"}
        c = self.choices
        return {"step_mode": "auto" if self.auto else "fixed", "step_auto": min(x.step for x in c),
                "step_error_time": max(x.error_time for x in c),
                "step_error_rotation": max(x.error_rotation for x in c),
                "step_tolerance_time": c[0].tolerance_time, "step_tolerance_rotation": c[0].tolerance_rotation,
                "step_saving": self.saving, "step_note": self.note()}


def choice_attributes(choice: StepChoice | None) -> dict:
    """A run's result-file attributes for its step: ``step_mode`` and, with ``auto``, the estimate
    (as `StudyStep.attributes`)."""
    if choice is None:
        return {"step_mode": "fixed"}
    return StudyStep(True, (choice,), "the case", choice.default_step).attributes()


__all__ = ["StepChoice", "StudyStep", "apply_step", "keep_resolved", "stable_substeps", "choice_attributes",
           "choose_step", "step_errors", "richardson_factor", "DEFAULT_STEP", "AUTO_STILL_STEP", "SAFETY",
           "MAX_P_DT"]
