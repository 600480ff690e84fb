"""Speed of ``--device gpu`` against all CPU cores of the same machine: steps/s and cases/s.

Two grids, each computed through `sweep.compute` (chunks stored, as the commands do) on the CPU
(the threaded local path, every core) and on the GPU (`core.gpu`):

- the fragility benchmark's grid (`bench_fragility`: the suite x 15 PGA levels, the paper's block,
  dt = 0.1 ms): short records, many cases at rest or overturning early;
- a rocking-heavy grid: a 2.5 m block that cannot slip (mu 0.9) on the 150 s Kobe record (N-S +
  U-D; the synthetic record without it) over PGA 0.3 - 0.8 g x slenderness 0.15 - 0.3, most cases
  rocking through the strong motion (5 - 15 s each) and few overturning.

The steps are the RK4 steps integrated (time in the moving states over the step, from the CPU's
final states); useful / issued steps is what the warps of the device spent on their cases, from the
launch order (`gpu.warp_efficiency`). The verdicts (overturned, status), the impacts and the largest
rotation and slip of the two devices are compared: the device contracts multiply-adds (FMA) and its
libdevice sine and cosine may differ from the CPU's libm in the last bit, so the extremes are
compared with a relative tolerance of 1e-9 (a trajectory that stays away from the thresholds keeps
such differences near 1e-13), and a case near an overturning threshold may change its verdict.

Without a GPU (or without numba-cuda) it prints why and exits with status 0. Prints figures, asserts
nothing.

Usage: python benchmarks/bench_gpu.py [--cases N] [--grid fragility|rocking|both]
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


def fragility_plan(tmp: Path):
    from rockslide.analyses import fragility as fr
    from rockslide.case import load_case

    suite, suite_options, what = find_suite()
    description, block, contact = BLOCKS["paper-block"]
    case_file = tmp / "paper-block.yaml"
    case_file.write_text(CASE.format(what=description, name="paper-block", block=block, contact=contact,
                                     record=REPO / "records" / "synthetic_kt_h.at2"))
    im = fr.parse_im("pga")
    units = suite_options[1] if suite_options else None
    fplan = fr.plan_fragility(load_case(case_file), fr.suite_from(suite, units=units), im,
                              fr.parse_levels("0.1g:1.5g:0.1g", im))
    return fplan.plan, f"fragility grid: {what} x 15 PGA levels, the paper's block"


def rocking_plan(tmp: Path, cases: int):
    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case

    horizontal, vertical, what = kobe_records()
    case_file = tmp / "rocking.yaml"
    case_file.write_text(ROCKING_CASE.format(
        horizontal=horizontal, vertical=f"  vertical: {{file: {vertical}}}\n" if vertical else ""))
    side = max(2, int(math.sqrt(cases)))
    axes = [sw.parse_axis("pga", f"{', '.join(f'{v:.4f}g' for v in np.linspace(0.3, 0.8, side))}"),
            sw.parse_axis("slenderness", ",".join(f"{v:.4f}" for v in np.linspace(0.15, 0.3, side)))]
    plan = sw.plan_sweep(load_case(case_file), axes)
    return plan, f"rocking-heavy grid: {plan.n_cases} cases, 2.5 m blocks (mu 0.9) on {what}"


def timed_sweep(plan, out: Path, device: str):
    from rockslide.engine import chunks
    from rockslide.engine import execute as ex


    store = chunks.ChunkStore.beside(out / f"{device}.sweep.h5", plan.key)
    store.remove()
    started = time.perf_counter()
    ex.compute(plan, store, range(plan.n_chunks), device=device)
    wall = time.perf_counter() - started
    states = chunks.collect(plan, store)
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


def bench(plan, title: str, out: Path) -> None:
    from rockslide.core import batch, gpu
    from rockslide.core import kernel as K

    print(f"\n## {title}\n")
    batch.warm_up()
    started = time.perf_counter()
    gpu.warm_up()
    print(f"device kernel compiled or loaded in {time.perf_counter() - started:.1f} s")
    cpu_wall, cpu = timed_sweep(plan, out, "cpu")
    gpu_wall, device = timed_sweep(plan, out, "gpu")
    moving = cpu[:, K.S_T_SLIP] + cpu[:, K.S_T_ROCK] + cpu[:, K.S_T_ROCKSLIP]
    steps = float((moving / plan.case_column(K.P_STEP)).sum())
    order = gpu.launch_order(plan.case_params(), plan.base, plan.first, plan.count, plan.factor_h)
    useful, issued = gpu.warp_efficiency(cpu, plan.case_params(), order)
    print("| where | wall [s] | cases/s | steps/s |")
    print("|---|---:|---:|---:|")
    for where, wall in ((f"CPU, {os.cpu_count()} cores (threaded sweep)", cpu_wall), ("GPU", gpu_wall)):
        print(f"| {where} | {wall:.2f} | {plan.n_cases / wall:.3g} | {steps / wall:.3g} |")
    print(f"\n{plan.n_cases} cases, {steps:.3g} RK4 steps; GPU / CPU speed {cpu_wall / gpu_wall:.2f}x; useful / "
          f"issued steps in the warps {useful / max(issued, 1.0):.2f} (upper bound: divergence not counted)")
    print(compare(cpu, device))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=4096, help="cases of the rocking-heavy grid (default 4096)")
    parser.add_argument("--grid", choices=("fragility", "rocking", "both"), default="both")
    args = parser.parse_args()

    from rockslide.core import gpu

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
    print(f"rockslide GPU benchmark: {device.name.decode() if isinstance(device.name, bytes) else device.name} "
          f"(compute capability {device.compute_capability}) against {os.cpu_count()} CPU cores")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if args.grid in ("fragility", "both"):
            bench(*fragility_plan(tmp), tmp)
        if args.grid in ("rocking", "both"):
            bench(*rocking_plan(tmp, args.cases), tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
