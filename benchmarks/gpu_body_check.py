"""The asymmetric body (docs/asymmetric.md) on a real GPU against the CPU cores of the same machine.

A sweep of the contract's rock (b1 = 0.044 m, b2 = 0.129 m, h = 0.294 m; model-asymmetric.md) and
of the same rock with its own radius of gyration, over PGA x restitution on the Kobe record (the
synthetic record without it), computed by the threaded CPU path and by `core.gpu`; the final states
are compared as `bench_gpu.compare` does (verdicts, impacts, extremes within 1e-9 relative: the
device contracts multiply-adds, so bit-identity is the simulator's test, tests/test_asymmetric.py).

Without a GPU (or without numba-cuda) it prints why and exits with status 0. Prints what it
measured, asserts nothing.

Usage: python benchmarks/gpu_body_check.py [--side N]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_gpu import compare, kobe_records, timed_sweep

BODY_CASE = """\
name: rock
block:   {{centre_of_mass_height: 0.294 m, half_widths: [0.044 m, 0.129 m], mass: 330 kg{gyration}}}
contact: {{mu_static: 0.9, mu_kinetic: 0.855, restitution: 0.85}}
ground:
  horizontal: {{file: {horizontal}}}
{vertical}  scale: {{pga_horizontal: 300 gal}}
solver:  {{dt: 0.1 ms, events: located}}
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=64, help="values per axis (default 64: 4096 cases a body)")
    args = parser.parse_args(argv)
    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case
    from rockslide.core import gpu

    try:
        gpu.require_device()
    except gpu.DeviceUnavailable as exc:
        print(f"no GPU check: {exc}")
        return 0
    horizontal, vertical, what = kobe_records()
    axes = [sw.parse_axis("pga", ",".join(f"{v:.4f}g" for v in np.linspace(0.05, 0.6, args.side))),
            sw.parse_axis("restitution", ",".join(f"{v:.4f}" for v in np.linspace(0.5, 0.95, args.side)))]
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        for label, gyration in (("default inertia", ""), ("radius of gyration 0.18 m", ", radius_of_gyration: 0.18 m")):
            case_file = tmp / "rock.yaml"
            case_file.write_text(BODY_CASE.format(
                gyration=gyration, horizontal=horizontal,
                vertical=f"  vertical: {{file: {vertical}}}\n" if vertical else ""))
            plan = sw.plan_sweep(load_case(case_file), axes)
            gpu.warm_up()
            cpu_wall, cpu = timed_sweep(plan, tmp, "cpu")
            gpu_wall, device = timed_sweep(plan, tmp, "gpu")
            over = int((cpu[:, 0] == 4).sum())
            print(f"rock ({label}) on {what}: {plan.n_cases} cases, {over} overturned on the CPU; "
                  f"CPU {cpu_wall:.2f} s, GPU {gpu_wall:.2f} s; {compare(cpu, device)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
