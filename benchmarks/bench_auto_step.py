"""``solver.dt: auto`` against the default 0.1 ms where verdicts are chaotic: statistics, not trajectories.

Writes results/bench_auto_step.md. Where a block rocks through many impacts its trajectory is
chaotic: a change of the step in the 12th digit moves a late impact, and a verdict near the edge
may flip; per-trajectory error is then not the measure. The measure is the statistic the study
reports, which must agree within its own sampling interval:

(a) the statue (1.8 m x 0.45 m, friction 0.6, e = 0.85) under Kobe N-S + U-D at 0.5 g, an
    ensemble of N members (the default neighbourhood; the same members at both steps): the
    probability of overturning at ``auto`` within 3 standard errors ``sqrt(p (1 - p) / N)`` of the
    one at 0.1 ms, at >= 5x fewer steps;
(b) the paper's block (0.2 m x 0.1 m, e = 0.8, mu 0.52) over the 18-record SLAMMER suite,
    fragility of overturning against PGA: the median at ``auto`` within the 95 % bootstrap interval
    of the median at 0.1 ms;
(c) a rocking-heavy grid (the paper's block on Kobe, --pga x --restitution): the share of
    overturned points at ``auto`` within 3 binomial standard errors of the one at 0.1 ms, and how
    many points flip.

Records: ``$ROCKSLIDE_RECORDS``, else ``../shared/records`` beside the repository (third-party;
never copied here). Speed-ups are wall and CPU times of the computation (the pilot included for
``auto``) on this machine (2 cores, shared). Asserts nothing.

Usage: python benchmarks/bench_auto_step.py [--members 2000] [--quick] [--out results]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from rockslide.analyses import ensemble as ens
from rockslide.analyses import fragility as fr
from rockslide.analyses import sweep as sw
from rockslide.case import parse_case
from rockslide.core import layout as L
from rockslide.engine.execute import execute

REPO = Path(__file__).resolve().parents[1]

STATUE = """\
name: statue
block:   {{height: 1.8 m, width: 0.45 m, mass: 500 kg}}
contact: {{mu_static: 0.6, restitution: 0.85}}
ground:
  horizontal: {{file: kobe_jma_1995_ns_peer_rsn1106_kjm000.at2}}
  vertical:   {{file: kobe_jma_1995_ud_peer_rsn1106_kjmup.at2}}
  scale: {{pga_horizontal: 0.5 g}}
  tail: 5 s
solver:  {{dt: {dt}}}
"""

PAPER = """\
name: paper-block
block:   {{height: 0.2 m, width: 0.1 m, mass: 10 kg}}
contact: {{mu_static: 0.52, mu_kinetic: 0.494, restitution: 0.8}}
ground:
  horizontal: {{file: kobe_jma_1995_ns_peer_rsn1106_kjm000.at2}}
  vertical:   {{file: kobe_jma_1995_ud_peer_rsn1106_kjmup.at2}}
  scale: {{pga_horizontal: 800 gal}}
  tail: 2 s
solver:  {{dt: {dt}}}
"""

STEPS = {"0.1 ms": "0.1 ms", "auto": "auto"}


def records_dir() -> Path:
    env = os.environ.get("ROCKSLIDE_RECORDS")
    for folder in ([Path(env)] if env else []) + [REPO.parent / "shared" / "records"]:
        if (folder / "kobe_jma_1995_ns_peer_rsn1106_kjm000.at2").is_file():
            return folder
    sys.exit("needs the Kobe records (set ROCKSLIDE_RECORDS)")


def timed(fn):
    wall, cpu = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - wall, time.process_time() - cpu


def steps_of(plan) -> float:
    """Integration steps the plan asks for (record intervals times steps per interval, every case)."""
    return float(np.sum(plan.count * plan.case_column(L.P_N_SUB)))


def statue(folder: Path, members: int) -> dict:
    out = {}
    for name, dt in STEPS.items():
        case = parse_case(STATUE.format(dt=dt), source="statue.yaml")

        def run(case=case):
            eplan = ens.plan_ensemble(case, members, seed=1, records_dir=folder)
            done = execute(eplan.plan, None)
            return eplan, sw.sweep_variables(eplan.plan, done.states)
        (eplan, variables), wall, cpu = timed(run)
        overturned = np.ravel(variables["overturned"][0]).astype(bool)
        status = np.ravel(variables["status"][0])
        ok = status == 0
        p = float(overturned[ok].mean())
        out[name] = {"p": p, "se": math.sqrt(p * (1 - p) / ok.sum()), "n": int(ok.sum()), "wall": wall, "cpu": cpu,
                     "steps": steps_of(eplan.plan), "step": eplan.plan.step, "overturned": overturned,
                     "note": eplan.plan.step_study.note()}
    fixed, auto = out["0.1 ms"], out["auto"]
    out["flips"] = int(np.sum(fixed["overturned"] != auto["overturned"]))
    out["within"] = abs(auto["p"] - fixed["p"]) <= 3 * fixed["se"]
    return out


def paper_fragility(folder: Path, quick: bool) -> dict:
    suite = fr.suite_from(str(folder / "suite-slammer"), units="g")
    im = fr.parse_im("pga")
    levels = fr.parse_levels("0.1g:1.5g:0.1g" if not quick else "0.2g:1.4g:0.2g", im)
    out = {}
    for name, dt in STEPS.items():
        case = parse_case(PAPER.format(dt=dt), source="paper.yaml")

        def run(case=case):
            fplan = fr.plan_fragility(case, suite, im, levels, records_dir=folder)
            done = execute(fplan.plan, None)
            analysis = fr.analyse(fplan, done.states, fr.damage_states(), resamples=1000)
            return fplan, fr.json_summary(fplan, analysis)
        (fplan, summary), wall, cpu = timed(run)
        fit = summary["damage_states"]["overturn"]
        out[name] = {"median": fit["median"], "ci": fit["median_ci"], "beta": fit["beta"], "wall": wall,
                     "cpu": cpu, "steps": steps_of(fplan.plan), "note": fplan.plan.step_study.note()}
    low, high = out["0.1 ms"]["ci"]
    out["within"] = low is not None and low <= out["auto"]["median"] <= high
    return out


def rocking_grid(folder: Path, quick: bool) -> dict:
    axes = [sw.parse_axis("pga", "400gal:1000gal:50gal" if quick else "300gal:1000gal:25gal"),
            sw.parse_axis("restitution", "0.70:0.90:0.04" if quick else "0.70:0.90:0.01")]
    out = {}
    for name, dt in STEPS.items():
        case = parse_case(PAPER.format(dt=dt), source="paper.yaml")

        def run(case=case):
            plan = sw.plan_sweep(case, axes, records_dir=folder)
            done = execute(plan, None)
            return plan, sw.sweep_variables(plan, done.states)
        (plan, variables), wall, cpu = timed(run)
        overturned = np.ravel(variables["overturned"][0]).astype(bool)
        impacts = np.ravel(variables["impacts"][0])
        p = float(overturned.mean())
        out[name] = {"share": p, "se": math.sqrt(p * (1 - p) / overturned.size), "n": overturned.size,
                     "wall": wall, "cpu": cpu, "steps": steps_of(plan), "overturned": overturned,
                     "impacts": float(np.median(impacts)), "note": plan.step_study.note()}
    fixed, auto = out["0.1 ms"], out["auto"]
    out["flips"] = int(np.sum(fixed["overturned"] != auto["overturned"]))
    out["within"] = abs(auto["share"] - fixed["share"]) <= 3 * max(fixed["se"], 1.0 / fixed["n"])
    return out


def speed_line(r: dict) -> str:
    f, a = r["0.1 ms"], r["auto"]
    return (f"steps {f['steps']:.3g} at 0.1 ms, {a['steps']:.3g} at auto: **{f['steps'] / a['steps']:.1f}x fewer**; "
            f"wall {f['wall']:.1f} s -> {a['wall']:.1f} s ({f['wall'] / a['wall']:.1f}x), CPU {f['cpu']:.1f} s -> "
            f"{a['cpu']:.1f} s ({f['cpu'] / a['cpu']:.1f}x), pilot included")


def markdown(args, s, frag, grid) -> str:
    f, a = s["0.1 ms"], s["auto"]
    lines = ["# `solver.dt: auto` against 0.1 ms: statistics where verdicts are chaotic", "",
             f"`python benchmarks/bench_auto_step.py --members {args.members}{' --quick' if args.quick else ''}`; "
             f"{os.cpu_count()} cores (shared with other work), Python {sys.version.split()[0]}. Default tolerance "
             "of auto (1e-6 s on event times, 1e-4 rad on the largest rotation). See docs/performance.md, "
             "'Choosing the step'.", "",
             f"## (a) The statue: 1.8 m x 0.45 m, mu 0.6, e 0.85, Kobe N-S + U-D at 0.5 g, ensemble of {f['n']}", "",
             "| step | P(overturn) | standard error | step [ms] |", "|---|---|---|---|",
             f"| 0.1 ms | {f['p']:.4f} | {f['se']:.4f} | {f['step'] * 1e3:.4g} |",
             f"| auto | {a['p']:.4f} | {a['se']:.4f} | {a['step'] * 1e3:.4g} |", "",
             f"|difference| = {abs(a['p'] - f['p']):.4f} = {abs(a['p'] - f['p']) / f['se']:.2f} standard errors "
             f"({'within' if s['within'] else 'NOT within'} 3); {s['flips']} of {f['n']} members flip their verdict. "
             + speed_line(s) + ".", "", f"auto: {a['note']}", "",
             "## (b) The paper's block over the 18-record SLAMMER suite: fragility of overturning (PGA)", "",
             "| step | median [m/s^2] | 95 % interval | beta |", "|---|---|---|---|"]
    for name in STEPS:
        r = frag[name]
        ci = ", ".join("-" if c is None else f"{c:.3f}" for c in r["ci"])
        lines.append(f"| {name} | {r['median']:.3f} | [{ci}] | {r['beta']:.3f} |")
    lines += ["", f"The median at auto is {'within' if frag['within'] else 'NOT within'} the 95 % interval at "
              f"0.1 ms. " + speed_line(frag) + ".", "", f"auto: {frag['auto']['note']}", "",
              f"## (c) A rocking-heavy grid: the paper's block on Kobe, --pga x --restitution ({grid['0.1 ms']['n']} "
              f"points, median {grid['0.1 ms']['impacts']:.0f} impacts)", "",
              "| step | share overturned | standard error |", "|---|---|---|"]
    for name in STEPS:
        r = grid[name]
        lines.append(f"| {name} | {r['share']:.4f} | {r['se']:.4f} |")
    lines += ["", f"{'Within' if grid['within'] else 'NOT within'} 3 standard errors; {grid['flips']} of "
              f"{grid['0.1 ms']['n']} points flip. " + speed_line(grid) + ".", "",
              f"auto: {grid['auto']['note']}", ""]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=2000)
    parser.add_argument("--quick", action="store_true", help="coarser fragility levels and grid")
    parser.add_argument("--out", type=Path, default=REPO / "results")
    args = parser.parse_args(argv)
    folder = records_dir()
    warnings.simplefilter("ignore")
    s = statue(folder, args.members)
    print(f"statue: p {s['0.1 ms']['p']:.4f} at 0.1 ms, {s['auto']['p']:.4f} at auto; " + speed_line(s))
    frag = paper_fragility(folder, args.quick)
    print(f"fragility: median {frag['0.1 ms']['median']:.3f} {frag['0.1 ms']['ci']} at 0.1 ms, "
          f"{frag['auto']['median']:.3f} at auto; " + speed_line(frag))
    grid = rocking_grid(folder, args.quick)
    print(f"grid: share {grid['0.1 ms']['share']:.4f} at 0.1 ms, {grid['auto']['share']:.4f} at auto, "
          f"{grid['flips']} flips; " + speed_line(grid))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_auto_step.md").write_text(markdown(args, s, frag, grid))
    print(f"wrote {args.out / 'bench_auto_step.md'}")


if __name__ == "__main__":
    main()
