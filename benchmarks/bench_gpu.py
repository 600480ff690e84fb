"""Speed of ``--device gpu`` against all CPU cores of the same machine: steps/s and cases/s.

Two grids, each computed through `sweep.compute` (chunks stored, as the commands do) on the CPU
(the threaded local path, every core) and on the GPU (`core.gpu`):

- the fragility benchmark's grid (`bench_fragility`: the suite x 15 PGA levels, the paper's block,
  dt = 0.1 ms): short records, many cases at rest or overturning early;
- a rocking-heavy grid: a 2.5 m block that cannot slip (mu 0.9) on the 150 s Kobe record (N-S +
  U-D; the synthetic record without it) over PGA 0.3 - 0.8 g x b/h 0.15 - 0.3 (--height-to-width), most cases
  rocking through the strong motion (5 - 15 s each) and few overturning.

The steps are the RK4 steps integrated (time in the moving states over the step, from the CPU's
final states); useful / issued steps is what the warps of the device spent on their cases, from the
launch order (`gpu.warp_efficiency`). The verdicts (overturned, status), the impacts and the largest
rotation and slip of the two devices are compared: the device contracts multiply-adds (FMA) and its
libdevice sine and cosine may differ from the CPU's libm in the last bit, so the extremes are
compared with a relative tolerance of 1e-9 (a trajectory that stays away from the thresholds keeps
such differences near 1e-13), and a case near an overturning threshold may change its verdict.

Writes results/bench_gpu.md (``--out``) from what it measured; ``--auto`` runs the grids with
``solver.dt: auto`` (the device's launch order weighs each case's step count, `gpu.launch_order`).
Without a GPU (or without numba-cuda) it prints why, writes nothing and exits with status 0;
``--cpu-only`` measures the CPU side alone (and, given ``--out``, writes the file with the device's
columns empty, which is how the writing is tested on a machine without a GPU; without ``--out`` it
writes nothing, so as not to replace the device's figures in results/). Asserts nothing.

Usage: python benchmarks/bench_gpu.py [--cases N] [--grid fragility|rocking|both] [--auto] [--cpu-only]
                                      [--out results]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_fragility import BLOCKS, CASE, find_suite
from bench_startup import KOBE, find_records

REPO = Path(__file__).resolve().parents[1]
ROCKING_CASE = """\
name: rocking
block:   {{height: 2.5 m, width: 0.5 m, mass: 500 kg}}
contact: {{mu_static: 0.9, mu_kinetic: 0.855, restitution: 0.9}}
ground:
  horizontal: {{file: {horizontal}}}
{vertical}  scale: {{pga_horizontal: 500 gal}}
solver:  {{dt: 0.1 ms, events: located}}
"""
EXTREME_TOLERANCE = 1e-9


def kobe_records() -> tuple[Path, Path | None, str]:
    folder = find_records()
    if folder is not None:
        return folder / KOBE[0], folder / KOBE[1], "the 150 s Kobe record (N-S + U-D)"
    return REPO / "records" / "synthetic_kt_h.at2", None, "the synthetic record (Kobe not found)"


def fragility_plan(tmp: Path, auto: bool = False):
    from rockslide.analyses import fragility as fr
    from rockslide.case import case_with, load_case

    suite, suite_options, what = find_suite()
    description, block, contact = BLOCKS["paper-block"]
    case_file = tmp / "paper-block.yaml"
    case_file.write_text(CASE.format(what=description, name="paper-block", block=block, contact=contact,
                                     record=REPO / "records" / "synthetic_kt_h.at2"))
    im = fr.parse_im("pga")
    units = suite_options[1] if suite_options else None
    case = load_case(case_file)
    if auto:
        case = case_with(case, {"solver.dt": "auto"})
    fplan = fr.plan_fragility(case, fr.suite_from(suite, units=units), im,
                              fr.parse_levels("0.1g:1.5g:0.1g", im))
    return fplan.plan, f"fragility grid: {what} x 15 PGA levels, the paper's block"


def rocking_plan(tmp: Path, cases: int, auto: bool = False):
    from rockslide.analyses import sweep as sw
    from rockslide.case import case_with, load_case

    horizontal, vertical, what = kobe_records()
    case_file = tmp / "rocking.yaml"
    case_file.write_text(ROCKING_CASE.format(
        horizontal=horizontal, vertical=f"  vertical: {{file: {vertical}}}\n" if vertical else ""))
    side = max(2, int(math.sqrt(cases)))
    axes = [sw.parse_axis("pga", f"{', '.join(f'{v:.4f}g' for v in np.linspace(0.3, 0.8, side))}"),
            sw.parse_axis("height_to_width", ",".join(f"{1 / v:.4f}" for v in np.linspace(0.15, 0.3, side)))]
    case = load_case(case_file)
    plan = sw.plan_sweep(case_with(case, {"solver.dt": "auto"}) if auto else case, axes)
    return plan, f"rocking-heavy grid: {plan.n_cases} cases, 2.5 m blocks (mu 0.9) on {what}"


def timed_sweep(plan, out: Path, device: str):
    """The compute of ``plan`` on ``device`` as `rockslide sweep` makes it (chunk files included; on
    the GPU, chunks of a launch: `execute.device_chunks`): its wall time and the final states."""
    from rockslide.core import kernel as K
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex

    if device == "gpu":
        plan = ex.device_chunks(plan)
    store = chunks.ChunkStore.beside(out / f"{device}.sweep.h5", plan.key).for_device(device)
    store.remove()
    states = np.empty((plan.n_cases, K.N_STATE))
    started = time.perf_counter()
    ex.compute(plan, store, range(plan.n_chunks), device=device, out=states)
    wall = time.perf_counter() - started
    store.remove()
    return wall, states


def compare(cpu, device) -> str:
    from rockslide.core import kernel as K

    verdict = [K.S_MODE, K.S_STATUS]
    verdicts = int((cpu[:, verdict] != device[:, verdict]).any(axis=1).sum())
    impacts = int((cpu[:, K.S_IMPACTS] != device[:, K.S_IMPACTS]).sum())
    far = 0
    for column in (K.S_MAX_THETA, K.S_MAX_X):
        a, b = cpu[:, column], device[:, column]
        far += int((np.abs(a - b) > EXTREME_TOLERANCE * np.maximum(np.abs(a), 1e-300)).sum())
    identical = int(np.all((cpu == device) | (np.isnan(cpu) & np.isnan(device)), axis=1).sum())
    return (f"{identical} of {len(cpu)} final states bit-identical; {verdicts} verdicts and {impacts} impact "
            f"counts differ; {far} extremes differ by more than {EXTREME_TOLERANCE:g} (relative)")


def bench(plan, title: str, out: Path, cpu_only: bool = False) -> dict:
    """Compute ``plan`` on the CPU (every core) and, unless ``cpu_only``, on the GPU; what was measured."""
    from rockslide.core import batch, gpu
    from rockslide.core import kernel as K

    print(f"\n## {title}\n")
    batch.warm_up()
    compiled = None
    if not cpu_only:
        started = time.perf_counter()
        gpu.warm_up()
        compiled = time.perf_counter() - started
        print(f"device kernel compiled or loaded in {compiled:.1f} s")
    cpu_wall, cpu = timed_sweep(plan, out, "cpu")
    gpu_wall, device = timed_sweep(plan, out, "gpu") if not cpu_only else (None, None)
    moving = cpu[:, K.S_T_SLIP] + cpu[:, K.S_T_ROCK] + cpu[:, K.S_T_ROCKSLIP]
    params = plan.case_params()
    steps = float((moving / params[:, K.P_STEP]).sum())
    order = gpu.launch_order(params, plan.base, plan.first, plan.count, plan.factor_h)
    useful, issued = gpu.warp_efficiency(cpu, params, order)
    measured = {"title": title, "n_cases": plan.n_cases, "steps": steps, "cpu_wall": cpu_wall, "gpu_wall": gpu_wall,
                "compiled": compiled, "warp_efficiency": useful / max(issued, 1.0),
                "step": f"{plan.step * 1e3:.4g} ms" + ("" if plan.step_study is None or not plan.case.solver.auto
                                                       else " (auto)"),
                "comparison": None if device is None else compare(cpu, device)}
    print("\n".join(table_lines(measured)))
    return measured


def table_lines(m: dict) -> list[str]:
    """A grid's measurements as markdown lines."""
    lines = ["| where | wall [s] | cases/s | steps/s |", "|---|---:|---:|---:|"]
    rows = [(f"CPU, {os.cpu_count()} cores (threaded sweep)", m["cpu_wall"]), ("GPU", m["gpu_wall"])]
    for where, wall in rows:
        if wall is None:
            lines.append(f"| {where} | not measured | | |")
        else:
            lines.append(f"| {where} | {wall:.2f} | {m['n_cases'] / wall:.3g} | {m['steps'] / wall:.3g} |")
    speed = "" if m["gpu_wall"] is None else f"; GPU / CPU speed {m['cpu_wall'] / m['gpu_wall']:.2f}x"
    lines += ["", f"{m['n_cases']} cases at {m['step']}, {m['steps']:.3g} RK4 steps{speed}; useful / issued steps "
              f"in the warps {m['warp_efficiency']:.2f} (launch order by work, the step count included; upper "
              "bound: divergence not counted)"]
    if m["compiled"] is not None:
        lines.append(f"device kernel compiled or loaded in {m['compiled']:.1f} s")
    if m["comparison"] is not None:
        lines += ["", m["comparison"]]
    return lines


def markdown(device: str, measured: list[dict], command: str) -> str:
    """results/bench_gpu.md: the machine, the command, each grid's table."""
    out = ["# rockslide on the GPU against the CPU cores of the same machine", "",
           f"`{command}` on {device}; {os.cpu_count()} CPU cores; Python {sys.version.split()[0]}. Written by the "
           "benchmark from what it measured (benchmarks/bench_gpu.py).", ""]
    for m in measured:
        out += [f"## {m['title']}", "", *table_lines(m), ""]
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=4096, help="cases of the rocking-heavy grid (default 4096)")
    parser.add_argument("--grid", choices=("fragility", "rocking", "both"), default="both")
    parser.add_argument("--auto", action="store_true", help="solver.dt: auto instead of 0.1 ms")
    parser.add_argument("--cpu-only", action="store_true", help="the CPU side alone (no GPU needed)")
    parser.add_argument("--out", type=Path, default=None,
                        help="where bench_gpu.md goes (default results/; with --cpu-only, nowhere unless given: a "
                             "run without the device must not replace the device's figures)")
    args = parser.parse_args(argv)

    from rockslide.core import gpu

    if args.cpu_only:
        name = "no GPU (--cpu-only)"
    else:
        try:
            cuda = gpu.require_device()
        except gpu.DeviceUnavailable as exc:
            print(f"bench_gpu: no device run possible here: {exc}. Nothing measured (device figures are still "
                  "to be taken on a machine with an NVIDIA GPU and pip install 'rockslide[gpu]').")
            return 0
        if gpu.cuda_simulator():
            print("bench_gpu: NUMBA_ENABLE_CUDASIM is set: the simulator's speed means nothing; unset it.")
            return 0
        device = cuda.get_current_device()
        name = (f"{device.name.decode() if isinstance(device.name, bytes) else device.name} "
                f"(compute capability {device.compute_capability})")
    print(f"rockslide GPU benchmark: {name} against {os.cpu_count()} CPU cores")
    measured = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if args.grid in ("fragility", "both"):
            measured.append(bench(*fragility_plan(tmp, args.auto), tmp, args.cpu_only))
        if args.grid in ("rocking", "both"):
            measured.append(bench(*rocking_plan(tmp, args.cases, args.auto), tmp, args.cpu_only))
    out = args.out if args.out is not None or args.cpu_only else REPO / "results"
    if out is None:
        return 0
    out.mkdir(parents=True, exist_ok=True)
    command = "python benchmarks/bench_gpu.py " + " ".join(argv if argv is not None else sys.argv[1:])
    (out / "bench_gpu.md").write_text(markdown(name, measured, command.strip()))
    print(f"wrote {out / 'bench_gpu.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
