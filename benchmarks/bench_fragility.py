"""Speed of `rockslide fragility`: the 18-record suite x 15 PGA levels (270 runs), for the paper's
block and for a 1.2 m x 0.3 m cabinet, at dt = 0.1 ms.

Prints figures, asserts nothing (speed goals live here, never in the tests). The goal: the 270
runs in under 10 s on a 2-core machine, start-up included, i.e. the whole command

    rockslide fragility CASE --suite ../shared/records/suite-slammer --units g --levels 0.1g:1.5g:0.1g

in a new process. Each command is timed ``--repeat`` times (the machine may be shared: the median
and the range are given), then its phases once more inside this process: reading and measuring the
records (plan), computing the runs (chunks stored), the fits with their 1000 bootstrap resamples,
writing the HDF5 file and drawing the PNG, and the batch kernel alone on the same runs.

The CPU time of the command (user and system, all its threads) is given beside its wall time: on a
shared machine it is disturbed less, and on an idle one the wall time is about the CPU time of the
serial phases plus the kernel's CPU time divided by the cores.

The suite is looked for in ``$ROCKSLIDE_RECORDS``, then ``../shared/records`` beside the repository;
without it the project's synthetic suite (6 records) is used, with a note.

Usage: python benchmarks/bench_fragility.py [--repeat N] [--workers N] [--levels SPEC]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_sweep import Clock

REPO = Path(__file__).resolve().parents[1]
DAMAGE = ("rotation>0.5alpha", "slip>50mm")
BLOCKS = {
    "paper-block": ("the paper's block: 0.2 m x 0.1 m, 10 kg, mu 0.52, nu 0.494, e 0.8",
                    "{height: 0.2 m, width: 0.1 m, mass: 10 kg}", "{mu_static: 0.52, mu_kinetic: 0.494, "
                    "restitution: 0.8}"),
    "cabinet": ("a cabinet: 1.2 m x 0.3 m, 200 kg, mu 0.5, nu 0.475, e 0.91 (Housner's 1 - 1.5 sin^2 alpha)",
                "{height: 1.2 m, width: 0.3 m, mass: 200 kg}", "{mu_static: 0.5, mu_kinetic: 0.475, "
                "restitution: 0.91}"),
}
CASE = """\
# {what}
name: {name}
block:   {block}
contact: {contact}
ground:
  horizontal: {{file: {record}}}     # replaced by each record of the suite
solver:  {{dt: 0.1 ms, events: located}}
"""


def find_suite() -> tuple[str, list[str], str]:
    """The shared 18-record suite (as --suite and --units options), or the synthetic suite."""
    candidates = []
    if os.environ.get("ROCKSLIDE_RECORDS"):
        candidates.append(Path(os.environ["ROCKSLIDE_RECORDS"]))
    candidates.append(REPO.parent / "shared" / "records")
    for folder in candidates:
        if (folder / "suite-slammer").is_dir():
            return str(folder / "suite-slammer"), ["--units", "g"], "the shared 18-record suite (suite-slammer)"
    print("note: suite-slammer was not found in $ROCKSLIDE_RECORDS or ../shared/records; using the "
          "project's synthetic suite (6 records, not comparable with the goal)\n")
    return str(REPO / "records" / "suite-synthetic.yaml"), [], "the synthetic suite (6 records)"


def run_command(case_file: Path, suite: str, suite_options: list[str], levels: str, workers, out: Path):
    command = [sys.executable, "-m", "rockslide.cli", "fragility", str(case_file), "--suite", suite,
               *suite_options, "--levels", levels, *[x for d in DAMAGE for x in ("--damage", d)],
               "--out-dir", str(out), "--overwrite", "--no-progress"]
    if workers:
        command += ["--workers", str(workers)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, done


def phases(case_file: Path, suite: str, suite_options: list[str], levels: str, workers, out: Path) -> dict:
    """Each phase of the command, timed inside this process (the kernel already loaded)."""
    import numba

    from rockslide.analyses import fragility as fr
    from rockslide.case import load_case
    from rockslide.core import batch
    from rockslide.core import kernel as K
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex
    from rockslide.io import results
    from rockslide.plots import save_figure

    clocks = {}
    case = load_case(case_file)
    im = fr.parse_im("pga")
    with Clock() as clocks["plan: read and measure the records, build the runs"]:
        units = suite_options[1] if suite_options else None
        fplan = fr.plan_fragility(case, fr.suite_from(suite, units=units), im, fr.parse_levels(levels, im))
    plan = fplan.plan
    store = chunks.ChunkStore.beside(out / "bench.fragility.h5", plan.key)
    with Clock() as clocks["compute the runs (chunks stored)"]:
        ex.compute(plan, store, range(plan.n_chunks), workers=workers)
    states = chunks.collect(plan, store)
    with Clock() as clocks["fits: maximum likelihood, moments, 1000 bootstrap resamples"]:
        analysis = fr.analyse(fplan, states, fr.damage_states(DAMAGE))
    with Clock() as clocks["write HDF5"]:
        coords, variables, attrs = fr.dataset(fplan, analysis, "benchmark")
        results.write_dataset(out / "bench.fragility.h5", coords, variables, format=results.FRAGILITY_FORMAT,
                              attrs=attrs, overwrite=True)
    with Clock() as clocks["draw PNG"]:
        save_figure(fr.figure(fplan, analysis), out / "bench.fragility.png", overwrite=True)
    store.remove()
    if workers:
        numba.set_num_threads(workers)
    with Clock() as clocks["batch kernel alone, same runs"]:
        batch.compute(plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
                      plan.factor_v)
    moving = states[:, K.S_T_SLIP] + states[:, K.S_T_ROCK] + states[:, K.S_T_ROCKSLIP]
    steps = float((moving / plan.case_column(K.P_STEP)).sum())
    over = int(analysis.variables["overturned"][0].sum())
    return {"clocks": clocks, "steps": steps, "overturned": over, "runs": plan.n_cases,
            "fits": [fr.describe_fit(s, f, im) for s, f in zip(analysis.states, analysis.fits, strict=True)],
            "record_seconds": float(fplan.measures["duration"].sum())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="times each command is run (default 3)")
    parser.add_argument("--workers", type=int, default=None, help="numba threads (default: all cores)")
    parser.add_argument("--levels", default="0.1g:1.5g:0.1g")
    args = parser.parse_args()

    import numba

    suite, suite_options, what = find_suite()
    print(f"rockslide fragility benchmark: {what} x levels {args.levels} of PGA; dt = 0.1 ms, located "
          f"events; damage states overturn, {', '.join(DAMAGE)}")
    print(f"machine: {os.cpu_count()} cores, {args.workers or numba.config.NUMBA_NUM_THREADS} numba threads; "
          "shared with other work, so timings are noisy: medians of the repeats")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        record = REPO / "records" / "synthetic_kt_h.at2"
        for name, (description, block, contact) in BLOCKS.items():
            case_file = tmp / f"{name}.yaml"
            case_file.write_text(CASE.format(what=description, name=name, block=block, contact=contact,
                                             record=record))
            walls, cpus, done = [], [], None
            for _ in range(max(1, args.repeat)):
                wall, cpu, done = run_command(case_file, suite, suite_options, args.levels, args.workers, tmp)
                walls.append(wall)
                cpus.append(cpu)
                if done.returncode:
                    break
            print()
            print(f"## {description}")
            print()
            if done.returncode:
                print(f"the command failed (exit {done.returncode}):\n{done.stderr}")
                continue
            median = statistics.median(walls)
            print(f"`rockslide fragility` as a command (new process, start-up included): median {median:.1f} s "
                  f"wall of {len(walls)} (range {min(walls):.1f} to {max(walls):.1f} s), median "
                  f"{statistics.median(cpus):.1f} s of CPU (all threads); goal under 10 s -> "
                  f"{'met' if median < 10 else 'NOT met'}")
            print("    " + done.stdout.strip().replace(str(tmp), "OUT").replace("\n", "\n    "))
            figures = phases(case_file, suite, suite_options, args.levels, args.workers, tmp)
            print()
            print("| phase (inside one process) | wall [s] | CPU [s] |")
            print("|---|---:|---:|")
            for phase, clock in figures["clocks"].items():
                print(f"| {phase} | {clock.wall:.2f} | {clock.cpu:.2f} |")
            kernel = figures["clocks"]["batch kernel alone, same runs"]
            print()
            print(f"{figures['runs']} runs over {figures['record_seconds']:.0f} s of records x 15 levels; "
                  f"{figures['overturned']} overturned; {figures['steps']:.3g} RK4 steps integrated "
                  f"({figures['steps'] / max(kernel.wall, 1e-9):.3g} steps/s wall in the kernel alone)")


if __name__ == "__main__":
    main()
