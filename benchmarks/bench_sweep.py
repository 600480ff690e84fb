"""Speed of `rockslide sweep`: a 41 x 37 grid (1517 cases) on the full Kobe record at dt = 0.1 ms.

Prints figures, asserts nothing (speed goals live here, never in the tests). The goal: the grid
``--mu 0.40:0.80:0.01 --pga 100gal:1000gal:25gal`` on the JMA Kobe record (N-S and U-D, PEER RSN1106,
150 s) in under 20 s on a 2-core machine.

Every phase is timed with the wall clock and with `time.process_time` (the CPU time of all threads
of this process, which other processes on a shared machine disturb less). "steps" are the RK4 steps
actually integrated: the time spent in SLIP, ROCK and ROCKSLIP (the kernel's time-in-state slots)
divided by the step; REST costs no steps (its exits are solved exactly per record interval). The
per-mode shares say where the work goes.

The records are looked for in ``$ROCKSLIDE_RECORDS``, then ``../shared/records`` beside the
repository; without them the shipped synthetic record is used (with a note), which is shorter.

Usage: python benchmarks/bench_sweep.py [--workers N] [--mu SPEC] [--pga SPEC] [--cli]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
KOBE = ("kobe_jma_1995_ns_peer_rsn1106_kjm000.at2", "kobe_jma_1995_ud_peer_rsn1106_kjmup.at2")
SYNTHETIC = ("synthetic_kt_h.at2", "synthetic_kt_v.at2")
CASE = """\
# The paper's block (0.2 m x 0.1 m, 10 kg, e = 0.8, nu = 0.95 mu) on {what}
name: bench-sweep
block:   {{height: 0.2 m, width: 0.1 m, mass: 10 kg}}
contact: {{mu_static: 0.52, mu_kinetic: 0.494, restitution: 0.8}}
ground:
  horizontal: {{file: {h}}}
  vertical:   {{file: {v}}}
  scale: {{pga_horizontal: 800 gal}}
solver:  {{dt: 0.1 ms, events: located}}
"""


class Clock:
    """Wall and CPU time of a phase."""

    def __enter__(self):
        self.wall, self.cpu = time.perf_counter(), time.process_time()
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self.wall
        self.cpu = time.process_time() - self.cpu
        return False

    def __str__(self):
        return f"{self.wall:7.2f} s wall {self.cpu:7.2f} s CPU"


def find_records() -> tuple[Path, tuple[str, str], str]:
    """The Kobe records' folder, or the shipped synthetic record's with a note."""
    candidates = []
    if os.environ.get("ROCKSLIDE_RECORDS"):
        candidates.append(Path(os.environ["ROCKSLIDE_RECORDS"]))
    candidates.append(REPO.parent / "shared" / "records")
    for folder in candidates:
        if all((folder / name).is_file() for name in KOBE):
            return folder, KOBE, "the JMA Kobe record, N-S and U-D (PEER RSN1106)"
    print("note: the Kobe records were not found in $ROCKSLIDE_RECORDS or ../shared/records; using "
          "the shipped synthetic record instead (20 s, not comparable with the goal)\n")
    return REPO / "records", SYNTHETIC, "the shipped synthetic record"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=None, help="numba threads (default: all cores)")
    parser.add_argument("--mu", default="0.40:0.80:0.01")
    parser.add_argument("--pga", default="100gal:1000gal:25gal")
    parser.add_argument("--cli", action="store_true",
                        help="also time the whole command `rockslide sweep` in a new process")
    args = parser.parse_args()

    with Clock() as imports:
        import numba
        import numpy as np

        from rockslide.analyses import sweep as sw
        from rockslide.case import parse_case
        from rockslide.core import batch
        from rockslide.core import kernel as K
        from rockslide.engine import chunks
        from rockslide.engine import execute as ex
        from rockslide.io import results
        from rockslide.plots import SWEEP_CATEGORIES, save_figure

    folder, names, what = find_records()
    text = CASE.format(what=what, h=names[0], v=names[1])
    case = parse_case(text, source="bench-sweep.yaml", base_dir=folder)
    threads = args.workers or numba.config.NUMBA_NUM_THREADS
    print(f"rockslide sweep benchmark: {what}; mu {args.mu} x pga {args.pga}; dt = 0.1 ms, located events")
    print(f"machine: {os.cpu_count()} cores, {threads} numba threads")

    with Clock() as warm:
        batch.warm_up()
    with Clock() as planning:
        plan = sw.plan_sweep(case, [sw.parse_axis("mu", args.mu), sw.parse_axis("pga", args.pga)],
                             records_dir=folder)
    duration = plan.base.shape[1] * float(plan.params[0, K.P_DT_REC])
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        store = chunks.ChunkStore.beside(out / "bench-sweep.sweep.h5", plan.key)
        with Clock() as computing:
            ex.compute(plan, store, range(plan.n_chunks), workers=args.workers)
        with Clock() as writing:
            states = chunks.collect(plan, store)
            variables = sw.sweep_variables(plan, states)
            results.write_sweep(out / "bench-sweep.sweep.h5", sw.coordinates(plan), variables,
                                attrs=sw.root_attributes(plan, "benchmark"))
        with Clock() as drawing:
            save_figure(sw.figure(plan, variables), out / "bench-sweep.sweep.png")
        store.remove()

    # the same cases without chunks, store or progress: the batch kernel alone
    with Clock() as bare:
        numba.set_num_threads(threads)
        batch.compute(plan.case_params(), plan.case_states(), plan.base, 0, plan.base.shape[1], plan.factor_h,
                      plan.factor_v)

    n = plan.n_cases
    shares = sw.time_shares(states)
    moving = shares["SLIP"] + shares["ROCK"] + shares["ROCKSLIP"]
    steps = moving / plan.step
    total = n * duration
    over = int(variables["overturned"][0].sum())
    cats = sw.categories(variables)
    print(f"grid: {plan.describe()} in {plan.n_chunks} chunks of {plan.chunk_size}; record {duration:g} s, "
          f"step {plan.step:g} s ({duration / plan.step:.3g} steps per case if it never rested)")
    print()
    print("| phase | wall [s] | CPU [s] |")
    print("|---|---:|---:|")
    for name, clock in (("imports", imports), ("compile or load the batch kernel", warm),
                        ("plan: validate the points, read the records", planning),
                        ("compute (chunks stored)", computing), ("collect + write HDF5", writing),
                        ("draw PNG", drawing), ("batch kernel alone, same cases", bare)):
        print(f"| {name} | {clock.wall:.2f} | {clock.cpu:.2f} |")
    end_to_end = planning.wall + computing.wall + writing.wall + drawing.wall
    print(f"| **plan + compute + write + draw** | **{end_to_end:.2f}** | "
          f"{planning.cpu + computing.cpu + writing.cpu + drawing.cpu:.2f} |")
    print()
    print(f"cases/s: {n / computing.wall:.0f} (wall), {n / max(computing.cpu, 1e-9):.0f} per CPU second")
    print(f"steps/s: {steps / computing.wall:.3g} (wall), {steps / max(computing.cpu, 1e-9):.3g} per CPU "
          f"second; {steps:.3g} RK4 steps in all ({steps / n:.3g} per case)")
    print(f"goal: under 20 s for the grid -> {'met' if end_to_end < 20 else 'NOT met'} "
          f"({end_to_end:.1f} s wall without imports and compilation)")
    print()
    print("where the time goes (simulated time over the grid, summed over cases):")
    print("| state | time [s] | share of simulated time | share of integrated time |")
    print("|---|---:|---:|---:|")
    for state in ("REST", "SLIP", "ROCK", "ROCKSLIP"):
        t = shares[state]
        integrated = "-" if state == "REST" else f"{100 * t / moving:.1f} %" if moving else "-"
        print(f"| {state} | {t:.1f} | {100 * t / total:.2f} % | {integrated} |")
    stopped = total - sum(shares.values())
    print(f"| (after overturning: not computed) | {stopped:.1f} | {100 * stopped / total:.2f} % | - |")
    print()
    counts = ", ".join(f"{name} {int((cats == code).sum())}" for code, name in enumerate(SWEEP_CATEGORIES))
    print(f"outcomes: {counts} ({over} overturned of {n})")
    per_case = np.sort((states[:, K.S_T_SLIP] + states[:, K.S_T_ROCK] + states[:, K.S_T_ROCKSLIP]) / plan.step)
    print(f"steps per case: median {np.median(per_case):.3g}, 90th percentile "
          f"{np.percentile(per_case, 90):.3g}, max {per_case[-1]:.3g}")

    if args.cli:
        with tempfile.TemporaryDirectory() as tmp:
            case_file = Path(tmp) / "bench-sweep.yaml"
            case_file.write_text(text)
            command = [sys.executable, "-m", "rockslide.cli", "sweep", str(case_file), "--mu", args.mu,
                       "--pga", args.pga, "--records-dir", str(folder), "--out-dir", tmp, "--no-progress"]
            if args.workers:
                command += ["--workers", str(args.workers)]
            env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
            started = time.perf_counter()
            done = subprocess.run(command, env=env, capture_output=True, text=True)
            wall = time.perf_counter() - started
            print()
            print(f"`rockslide sweep` as a command (new process, start-up included): {wall:.1f} s wall, "
                  f"exit {done.returncode}")
            print("    " + done.stdout.strip().replace("\n", "\n    "))
            if done.returncode:
                print(done.stderr)


if __name__ == "__main__":
    main()
