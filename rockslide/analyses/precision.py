"""Speed against error on the user's own case (``rockslide work-precision CASE``).

The case runs at a few steps, each a whole divisor of its record's step (the kinks of the input stay
on step ends), and each run's event times, largest rotation and verdict are compared with a
reference: the reference solver (`core.reference`, DOP853 at rtol 1e-12 with located events) when
the case is short enough (:data:`REFERENCE_MAX_INTERVALS` record intervals), else the kernel at the
finest step of the list halved. The CPU time of each run is its best of a few
(`time.process_time`). The figure is `plots.work_precision_figure`, which benchmarks/bench.py also
draws.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..core.simulate import Result, interval_count, simulate, substeps
from ..engine.prepare import Prepared, start_time
from ..engine.step import DEFAULT_STEP, step_errors

#: The reference solver (Python in the loop, about 1e4 record intervals a second while the block
#: moves) is used up to this many record intervals (tail included); beyond, the finest step.
REFERENCE_MAX_INTERVALS = 3000

#: Steps per record interval tried by default: from the record's step down to about 0.05 ms.
DEFAULT_DIVISORS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)


@dataclass
class PrecisionTable:
    """The runs of `work_precision`.

    Attributes
    ----------
    name : str
        The case's name.
    reference : str
        What the errors are measured against.
    rows : list of dict
        One per step: ``step`` [s], ``n_sub``, ``mode``, ``cpu`` [s], ``steps`` (integration
        steps), ``verdict``, ``verdict_ok``, ``events`` (their number), ``same_events`` (the
        reference's sequence), ``errors`` {``event times`` [s] (the largest over the events; NaN
        when the sequences differ), ``max rotation`` [rad]}.
    reference_values : dict
        ``verdict``, ``events``, ``max_rotation`` [rad] of the reference.
    figure_path : Path or None
        Where its figure was written (`api.work_precision`).
    """

    name: str
    reference: str
    rows: list
    reference_values: dict
    figure_path: object = None

    def as_table(self) -> list[dict]:
        """The rows for `plots.work_precision_figure` (``case`` set)."""
        return [{**row, "case": f"{self.name}: error against {self.reference}"} for row in self.rows]

    def text(self) -> str:
        """The printout: a line per step."""
        lines = [f"work-precision of {self.name}, errors against {self.reference} "
                 f"({self.reference_values['verdict']}, {self.reference_values['events']} events, max rotation "
                 f"{self.reference_values['max_rotation']:.6g} rad)",
                 f"  {'step [ms]':>10} {'steps':>10} {'CPU [s]':>9} {'event times [s]':>16} "
                 f"{'max rotation [rad]':>19}  verdict"]
        for r in self.rows:
            e = r["errors"]
            times = f"{e['event times']:.2e}" if math.isfinite(e["event times"]) else "other sequence"
            lines.append(f"  {r['step'] * 1e3:>10.4g} {r['steps']:>10d} {r['cpu']:>9.4f} {times:>16} "
                         f"{e['max rotation']:>19.2e}  {r['verdict']}{'' if r['verdict_ok'] else ' (differs)'}")
        return "\n".join(lines)


def _events(result: Result):
    ev = result.events
    kinds = np.array([(e["from"], e["to"], e["cause"], e["edge"]) for e in ev], dtype=object) \
        if ev.size else np.empty((0, 4), dtype=object)
    return np.asarray(ev["time"], dtype=np.float64), kinds, float(result.summary.max_rotation), 0


def best_cpu_time(fn, repeat: int = 3):
    """The best CPU time [s] of ``repeat`` calls of ``fn``, and its last result."""
    best, result = math.inf, None
    for _ in range(repeat):
        t = time.process_time()
        result = fn()
        best = min(best, time.process_time() - t)
    return best, result


def work_precision(prepared: Prepared, *, divisors=DEFAULT_DIVISORS, modes=("located",), repeat: int = 2,
                   reference: str = "auto") -> PrecisionTable:
    """Run ``prepared`` at the steps ``dt_record / n`` (``n`` in ``divisors``, those of at least
    0.01 ms) and measure error against CPU time.

    Parameters
    ----------
    prepared : engine.prepare.Prepared
    divisors : sequence of int
        Steps per record interval.
    modes : sequence of str
        Event schemes: ``located`` and/or ``step-end``.
    repeat : int
        Runs per step; the CPU time is the best.
    reference : {"auto", "solver", "finest"}
        ``auto``: the reference solver when the case has at most :data:`REFERENCE_MAX_INTERVALS`
        record intervals, else the finest step halved.

    Returns
    -------
    PrecisionTable
    """
    g = prepared.ground
    start = start_time(prepared)
    base = replace(prepared.settings, history_every=0, energy=False)
    ns = {*divisors, substeps(g.dt, DEFAULT_STEP)}          # the default step among them
    dts = sorted({g.dt / n for n in ns if g.dt / n >= 1e-5 * (1 - 1e-9)}, reverse=True)
    intervals = interval_count(g.horizontal, g.dt, base.tail)
    if reference == "auto":
        reference = "solver" if intervals <= REFERENCE_MAX_INTERVALS else "finest"
    if reference == "solver":
        from ..core.reference import simulate_reference
        ref = simulate_reference(prepared.model, g.dt, g.horizontal, g.vertical, base, start=start)
        what = "the reference solver (DOP853, rtol 1e-12)"
    else:
        finest = dts[-1] / 2.0
        ref = simulate(prepared.model, g.dt, g.horizontal, g.vertical, replace(base, dt=finest), start=start)
        what = f"the kernel at {finest * 1e3:.4g} ms"
    ref_events = _events(ref)
    rows = []
    for mode in modes:
        for dt in dts:
            settings = replace(base, dt=dt, events=mode)
            seconds, result = best_cpu_time(
                lambda s=settings: simulate(prepared.model, g.dt, g.horizontal, g.vertical, s, start=start), repeat)
            error_time, error_rotation = step_errors(_events(result), ref_events, 1.0)
            n = substeps(g.dt, dt)
            rows.append({"step": g.dt / n, "n_sub": n, "mode": mode, "cpu": seconds, "steps": intervals * n,
                         "verdict": result.summary.verdict, "verdict_ok": result.summary.verdict == ref.summary.verdict,
                         "events": int(result.events.size), "same_events": math.isfinite(error_time),
                         "errors": {"event times": error_time if math.isfinite(error_time) else math.nan,
                                    "max rotation": error_rotation}})
    return PrecisionTable(name=prepared.case.name, reference=what, rows=rows,
                          reference_values={"verdict": ref.summary.verdict, "events": int(ref.events.size),
                                            "max_rotation": float(ref.summary.max_rotation)})


def figure(table: PrecisionTable, size=None):
    """`plots.work_precision_figure` of the table."""
    from ..plots import work_precision_figure

    return work_precision_figure(table.as_table(), size=size,
                                 title=f"{table.name}: error against CPU time, steps {table.rows[0]['step'] * 1e3:.4g}"
                                       f" ... {table.rows[-1]['step'] * 1e3:.4g} ms (left: coarse)")


__all__ = ["work_precision", "PrecisionTable", "figure", "REFERENCE_MAX_INTERVALS", "DEFAULT_DIVISORS"]
