"""The kernel against a plain compiled loop: `make bench` -> results/bench_kernel.md.

Every figure of issue 17's table, measured in this one run. The baseline is `baseline.py`'s plain
compiled RK4 loop of rocking on a record (the kernel's ground interpolation, nothing else). Each
comparison alternates the baseline and the measured code ``--repeats`` times and reports the
median of the per-repeat ratios, with their range: on a shared machine the load drifts, and a
ratio of two neighbouring measurements drifts less than either; for the same reason the baseline of
a sweep integrates as many steps as the sweep (its loop repeated), so that both last about as long.
Times are CPU times of this process (`time.process_time`, all its threads) unless a figure says wall.

- **rocking**: `simulate` on 60 s of still ground, the block started at 0.1 rad with e = 1 (it
  rocks the whole time), no history, no energy ledger, against the baseline on the same ground.
- **rest**: CPU time per second of a 100 Hz record for a block at rest (600 s of weak motion):
  the kernel alone on a prepared record (what each case of a sweep costs: the record and its REST
  index are prepared once per sweep), and `simulate` from samples to result.
- **sweep, rocking-heavy**: ``rockslide sweep --workers 1``'s work on a grid whose blocks rock
  for most of 60 s (an 8 Hz sine; plan, compute, collect and write the HDF5 file; imports and
  compilation taken off): integrated RK4 steps (time in SLIP, ROCK, ROCKSLIP over the step) per
  CPU second, against the baseline's steps per CPU second.
- **sweep, Kobe grid**: the same on the paper's grid (41 mu x 37 PGA on the 150 s JMA Kobe
  record, mostly at rest), overheads included; then with the PNG drawn as well.
- **scaling**: the wall time of a Kobe grid's computation on 1 thread over that on every core,
  on a grid of at least about 1.5 s of work per core.

Usage: python benchmarks/bench_kernel.py [--repeats N] [--quick]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import tempfile
import time
from decimal import Decimal
from pathlib import Path

import numpy as np
from baseline import plain_rk4_rocking
from bench_startup import KOBE, find_records, other_busy_processes

from rockslide.analyses import sweep as sw
from rockslide.case import parse_case
from rockslide.core import batch
from rockslide.core import kernel as K
from rockslide.core.simulate import Model, Settings, ground_array, initial_state, parameters, simulate
from rockslide.engine import chunks
from rockslide.engine import execute as ex
from rockslide.io import records as rec
from rockslide.io import results
from rockslide.plots import save_figure

REPO = Path(__file__).resolve().parents[1]
G = 9.80665
H, DT_REC = 1e-4, 0.01
GOALS = {"rocking": 0.85, "rest": 0.3, "sweep": 0.85, "kobe": 0.6, "scaling": 13.0 / 16.0}


def cpu(fn) -> float:
    started = time.process_time()
    fn()
    return time.process_time() - started


def ratios(baseline, measured, repeats: int) -> tuple[float, float, float, float]:
    """Alternate ``baseline()`` and ``measured()``; each returns its work per CPU second. Returns
    the median ratio measured / baseline, its range, and the median of ``measured``."""
    pairs = []
    for _ in range(repeats):
        pairs.append((baseline(), measured()))
    r = [m / b for b, m in pairs]
    return statistics.median(r), min(r), max(r), statistics.median(m for _, m in pairs)


def still(duration: float) -> np.ndarray:
    """A record of ``duration`` for the baseline (whose cost does not depend on the values)."""
    zeros = np.zeros(int(round(duration / DT_REC)) + 1)
    return ground_array(zeros, zeros, DT_REC)


def run_duration(case) -> float:
    """The length of a case's horizontal record [s]."""
    record = rec.load_record(case.base_dir / case.ground.horizontal.file)
    return (len(record.data) - 1) * record.dt


def baseline_on(ground: np.ndarray, model: Model, steps: float = 0.0):
    """The baseline's steps per CPU second on ``ground``, rocking from 0.1 rad with e = 1.

    The loop runs as many times over ``ground`` as it takes to integrate ``steps`` (once at
    least), so that a measurement of the baseline lasts about as long as one of the work it is
    compared with: on a shared machine whose speed drifts within seconds, a 40 ms baseline next to
    a 1.3 s sweep compares two different machines."""
    R, alpha, _ = model.constants
    n_sub = round(DT_REC / H)
    per_pass = ground.shape[1] * n_sub
    passes = max(1, round(steps / per_pass))
    plain_rk4_rocking(ground[:, :1], n_sub, H, DT_REC, R, alpha, G, 1.0, 0.1, 0.0, 1.0)   # compile or load

    def all_passes():
        for _ in range(passes):
            plain_rk4_rocking(ground, n_sub, H, DT_REC, R, alpha, G, 1.0, 0.1, 0.0, 1.0)
    return lambda: passes * per_pass / cpu(all_passes)


# --------------------------------------------------------------------------------------------------
# Single cases
# --------------------------------------------------------------------------------------------------

def rocking(repeats: int, duration: float) -> dict:
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 1.0)          # no slip; e = 1: rocks throughout
    zeros = np.zeros(int(round(duration / DT_REC)) + 1)
    ground = still(duration)
    out = {}
    for label, settings in (("no history, no energy ledger", Settings(rotation=0.1, history_every=0, energy=False)),
                            ("energy ledger, no history", Settings(rotation=0.1, history_every=0)),
                            ("defaults: history every step, energy ledger", Settings(rotation=0.1))):
        simulate(model, DT_REC, zeros[:11], zeros[:11], settings)        # compile or load

        def kernel(settings=settings):
            seconds = cpu(lambda: simulate(model, DT_REC, zeros, zeros, settings))
            return duration / H / seconds
        result = simulate(model, DT_REC, zeros, zeros, settings).summary
        assert result.time_in_state["ROCK"] > 0.999 * duration, result.time_in_state
        out[label] = ratios(baseline_on(ground, model), kernel, repeats)
    return out


def rest(repeats: int) -> dict:
    """CPU microseconds per second of record at rest: the kernel on a prepared record, and
    `simulate` from the samples."""
    t = np.arange(0.0, 600.0, DT_REC)
    weak = 0.5 * np.sin(2 * np.pi * 2.0 * t)                      # 0.05 g: far below mu g, g tan(alpha)
    model = Model.from_block(0.1, 0.2, 0.5, 0.5, 0.8)
    settings = Settings(history_every=0)
    ground = ground_array(weak, 0.3 * weak, DT_REC)
    bounds = K.rest_bounds(ground)
    p = parameters(model, DT_REC, settings)
    history = np.empty((len(K.HISTORY_COLUMNS), 0))
    events = np.zeros((16, len(K.EVENT_COLUMNS)))

    def kernel_only():
        st = initial_state(settings)
        K.run(p, ground, bounds, st, history, 0, 0, events, ground.shape[1])
        assert st[K.S_T_REST] > 599.0 and st[K.S_N_EVENTS] == 0
    kernel_only()
    simulate(model, DT_REC, weak[:100], 0.3 * weak[:100], settings)
    assert simulate(model, DT_REC, weak, 0.3 * weak, settings).summary.states_seen == ["REST"]
    seconds = 600.0
    k = statistics.median(cpu(kernel_only) for _ in range(max(repeats, 5)))
    s = statistics.median(cpu(lambda: simulate(model, DT_REC, weak, 0.3 * weak, settings))
                          for _ in range(max(repeats, 5)))
    return {"kernel, prepared record": k / seconds * 1e6, "simulate, from samples": s / seconds * 1e6}


# --------------------------------------------------------------------------------------------------
# Sweeps
# --------------------------------------------------------------------------------------------------

CASE = """\
name: bench-kernel
block:   {{height: 0.2 m, width: 0.1 m, mass: 10 kg}}
contact: {{mu_static: {mu}, mu_kinetic: {nu}, restitution: 0.8}}
ground:
  horizontal: {{file: {h}}}
  vertical:   {{file: {v}}}
  scale: {{pga_horizontal: 800 gal}}
solver:  {{dt: 0.1 ms, events: located}}
"""


def sweep_work(case, axes, folder: Path, *, workers: int = 1, figure: bool = False) -> dict:
    """One sweep's work after start-up: plan, compute (chunks stored), collect, write the HDF5
    file (and draw the PNG). Returns CPU and wall seconds and the integrated steps."""
    wall, started = time.perf_counter(), time.process_time()
    plan = sw.plan_sweep(case, axes, records_dir=folder)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        store = chunks.ChunkStore.beside(out / "b.sweep.h5", plan.key)
        computing = time.perf_counter()
        ex.compute(plan, store, range(plan.n_chunks), workers=workers)
        computing = time.perf_counter() - computing
        states = chunks.collect(plan, store)
        variables = sw.sweep_variables(plan, states)
        results.write_sweep(out / "b.sweep.h5", sw.coordinates(plan), variables,
                            attrs=sw.root_attributes(plan, "benchmark"))
        if figure:
            save_figure(sw.figure(plan, variables), out / "b.sweep.png")
        store.remove()
    moving = states[:, K.S_T_SLIP] + states[:, K.S_T_ROCK] + states[:, K.S_T_ROCKSLIP]
    return {"cpu": time.process_time() - started, "wall": time.perf_counter() - wall,
            "compute_wall": computing, "steps": float(moving.sum() / plan.step), "cases": plan.n_cases,
            "shares": sw.time_shares(states), "duration": plan.base.shape[1] * float(plan.params[0, K.P_DT_REC])}


def rocking_grid(folder: Path):
    """A grid of blocks that rock for most of 60 s: an 8 Hz sine, no slip (mu = 1)."""
    t = np.arange(0.0, 60.0 + DT_REC / 2, DT_REC)
    rec.write_at2(folder / "sine8.at2", np.sin(2 * np.pi * 8.0 * t), DT_REC, title="8 Hz sine", component="h")
    rec.write_at2(folder / "still.at2", 0.0 * t, DT_REC, title="still", component="v")
    case = parse_case(CASE.format(mu=1.0, nu=0.95, h="sine8.at2", v="still.at2"), source="rocking.yaml",
                      base_dir=folder)
    axes = [sw.parse_axis("restitution", "0.7:0.85:0.05"), sw.parse_axis("pga", "0.6g:1.2g:0.1g")]
    return case, axes


def kobe_grid(folder: Path, mu_step: str = "0.01"):
    case = parse_case(CASE.format(mu=0.52, nu=0.494, h=KOBE[0], v=KOBE[1]), source="kobe.yaml", base_dir=folder)
    axes = [sw.parse_axis("mu", f"0.40:0.80:{mu_step}"), sw.parse_axis("pga", "100gal:1000gal:25gal")]
    return case, axes


def sweep_ratio(case, axes, folder: Path, ground: np.ndarray, model: Model, repeats: int, figure: bool = False):
    """`ratios` of the sweep's steps per CPU second to the baseline's on ``ground``, the baseline
    measured over as many steps as the sweep integrates (after one untimed sweep)."""
    runs = [sweep_work(case, axes, folder, figure=figure)]
    baseline = baseline_on(ground, model, runs[0]["steps"])

    def measured():
        runs.append(sweep_work(case, axes, folder, figure=figure))
        return runs[-1]["steps"] / runs[-1]["cpu"]
    return ratios(baseline, measured, repeats), runs[-1]


# --------------------------------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------------------------------

def verdict(value: float, goal: float, higher: bool = True) -> str:
    return "met" if (value >= goal if higher else value <= goal) else "**not met**"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9, help="alternations per figure (default 9)")
    parser.add_argument("--quick", action="store_true", help="shorter records, 3 repeats (a smoke test)")
    args = parser.parse_args(argv)
    repeats = 3 if args.quick else args.repeats
    batch.warm_up()
    cores = ex.local_threads()
    busy = other_busy_processes() or "none above 10 %"
    lines = ["# The kernel against a plain compiled loop (issue 17)", "",
             f"Machine: {os.cpu_count()} cores ({cores} usable), Python {platform.python_version()}, "
             f"numba {__import__('numba').__version__}; load average before: "
             f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}; busy processes before: {busy}. "
             f"Each ratio is the median of {repeats} alternations of the baseline (a plain compiled RK4 "
             "rocking loop on the same record, `benchmarks/baseline.py`) and the measured code, range in "
             "brackets; CPU time of this process. Generated by `make bench`.", ""]
    table = ["| figure | measured | goal | |", "|---|---|---|---|"]

    duration = 20.0 if args.quick else 60.0
    for label, (median, low, high, speed) in rocking(repeats, duration).items():
        goal = GOALS["rocking"] if label.startswith("no history") else None
        table.append(f"| kernel rocking, {label}, vs the plain loop | **{median:.3f}** ({low:.3f}-{high:.3f}); "
                     f"{speed / 1e6:.1f} M steps/s | {f'>= {goal:.2f}' if goal else '-'} | "
                     f"{verdict(median, goal) if goal else ''} |")

    at_rest = rest(repeats)
    for label, us in at_rest.items():
        goal = GOALS["rest"] if label.startswith("kernel") else None
        table.append(f"| a record at rest, {label}: CPU per second of 100 Hz record | **{us:.3f} us** | "
                     f"{f'<= {goal:.1f} us' if goal else '-'} | {verdict(us, goal, higher=False) if goal else ''} |")

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        case, axes = rocking_grid(folder)
        model = Model.from_block(0.1, 0.2, 1.0, 0.95, 0.8)
        (median, low, high, speed), run = sweep_ratio(case, axes, folder, still(60.0), model,
                                                      repeats)
        moving = 1.0 - run["shares"]["REST"] / (run["cases"] * run["duration"])
        table.append(f"| `sweep --workers 1`, rocking-heavy grid ({run['cases']} cases, moving "
                     f"{100 * moving:.0f} % of 60 s): integrated steps per CPU second vs the plain loop | "
                     f"**{median:.3f}** ({low:.3f}-{high:.3f}); {speed / 1e6:.1f} M steps/s | >= 0.85 | "
                     f"{verdict(median, GOALS['sweep'])} |")

    kobe = find_records()
    if kobe is None:
        lines.append("note: the Kobe records were not found in $ROCKSLIDE_RECORDS or ../shared/records: the "
                     "Kobe figures are left out.")
    else:
        case, axes = kobe_grid(kobe)
        kobe_model = Model.from_block(0.1, 0.2, 0.52, 0.494, 0.8)
        ground = still(run_duration(case))
        (median, low, high, speed), run = sweep_ratio(case, axes, kobe, ground, kobe_model, repeats)
        table.append(f"| `sweep --workers 1`, the paper's Kobe grid ({run['cases']} cases, {run['steps']:.3g} "
                     f"steps), planning, chunks, collecting and the HDF5 file included | **{median:.3f}** "
                     f"({low:.3f}-{high:.3f}); {speed / 1e6:.1f} M steps/s | >= 0.6 | "
                     f"{verdict(median, GOALS['kobe'])} |")
        (median, low, high, speed), drawn = sweep_ratio(case, axes, kobe, ground, kobe_model, max(3, repeats // 2),
                                                        figure=True)
        table.append(f"| the same with the PNG drawn too ({drawn['cpu'] - run['cpu']:.2f} s more) | "
                     f"**{median:.3f}** ({low:.3f}-{high:.3f}) | - | |")
        # scaling: enough work for about 1.5 s per core
        one = sweep_work(case, axes, kobe)
        finer = 2 ** max(0, math.ceil(math.log2(1.5 * cores / max(one["cpu"], 1e-3))))   # exact decimals
        case, axes = kobe_grid(kobe, str(Decimal("0.01") / finer))
        serial = sweep_work(case, axes, kobe, workers=1)
        parallel = sweep_work(case, axes, kobe, workers=cores)
        speedup = serial["compute_wall"] / parallel["compute_wall"]
        table.append(f"| sweep scaling 1 -> {cores} cores, Kobe grid of {serial['cases']} cases "
                     f"({serial['compute_wall']:.1f} s on one core): wall time of the computation | "
                     f"**{speedup:.2f}x** ({speedup / cores:.0%} of {cores}) | >= 13x on 16 cores "
                     f"(81 %) | {verdict(speedup / cores, GOALS['scaling'])} per core |")

    lines += table
    lines += ["", f"Load average after: {', '.join(f'{x:.2f}' for x in os.getloadavg())}."]
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
