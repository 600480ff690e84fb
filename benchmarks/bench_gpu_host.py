"""The host's part of a GPU study, measured without a GPU (issue 41, item 5): what a ``rockslide
sweep --device gpu`` of 10^6 cases spends on the CPU around the device.

On a lent H200 the 10^6-case rocking sweep at ``solver.dt: auto`` took 19.7 s from start to end,
of which 11.3 s "computing" (2026-11-28), then 8.9-10.3 s, of which 5.4-5.8 s (2026-11-29,
`results/bench_gpu.md`): the host's work is a large share of what a user waits for, and it can be
measured on any machine. Here the device is replaced by an instant stand-in (``numba.cuda``'s
``to_device``, the kernel launch and ``copy_to_host`` do nothing but copy; the states come back as
they went, the initial ones, whose variables and file cost less than a real run's: 0.05 and 0.17
s here against 0.08 and 0.45 s with a real run's states), so the command's wall time is the host's alone:
planning, the launches' inputs and their order by work, the chunk files, collecting the states,
the labelled file. The same command, case and grid as on the H200 (the rocking-heavy 2.5 m block,
mu 0.9, on the 150 s Kobe record N-S + U-D at ``dt: auto``; 1000 ``--pga`` x 1001
``--height-to-width``). Each run is in a fresh process; the stand-in is installed before the
command starts. Prints a timeline per run and the medians; asserts nothing.

A real device run imports numba and numba-cuda while it loads its kernel, before its clock starts;
the stand-in's run imports them first too, and that time is shown apart ("numba import").

Usage: python benchmarks/bench_gpu_host.py [--cases N] [--repeat N] [--out results]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_gpu import ROCKING_CASE, kobe_records
from bench_startup import KOBE, machine

REPO = Path(__file__).resolve().parents[1]
#: The child: installs the stand-in device, times the command's steps, prints them as JSON last.
CHILD = r"""
import json, sys, time, types
started = time.perf_counter()
spent = {}
def timing(owner, name, label):
    function = getattr(owner, name)
    def timed(*args, **kwargs):
        began = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            spent[label] = spent.get(label, 0.0) + time.perf_counter() - began
    setattr(owner, name, timed)
from rockslide.core import gpu
class Copy:
    def __init__(self, array):
        self.array = array
    def copy_to_host(self):
        return self.array.copy()
class Kernel:
    def __getitem__(self, config):
        return lambda *arrays: None
stand_in = types.SimpleNamespace(to_device=Copy, is_available=lambda: True)
gpu.require_device = lambda: stand_in
gpu.cuda = stand_in
gpu.device_kernel = lambda: Kernel()
gpu.cuda_simulator = lambda: False
from rockslide.core import kernel
from rockslide.engine import chunks, execute
from rockslide.analyses import sweep
from rockslide.api import studies
execute.warm_up = lambda device, say: None
began = time.perf_counter()
kernel.rest_bounds(__import__("numpy").zeros((4, 8)))      # numba and numba-cuda: what a device run
with __import__("warnings").catch_warnings():              # loads first, with its kernel
    gpu._ignore_performance_warnings()
numba_seconds = time.perf_counter() - began
timing(sweep, "plan_sweep", "planning")
timing(gpu, "prepare", "launch inputs and order")
timing(gpu.Launch, "__init__", "launches")
timing(gpu.Launch, "result", "launches")
timing(execute, "_chunk_inputs", "launch inputs and order")
timing(chunks.ChunkStore, "save", "chunk files")
timing(execute, "collect", "reading chunks back")
timing(execute, "compute", "computing (host)")
timing(sweep, "sweep_variables", "variables")
timing(studies, "_write", "file")
from rockslide.cli.app import main
try:
    main(sys.argv[1:], standalone_mode=False)
finally:
    spent["wall"] = time.perf_counter() - started - numba_seconds
    spent["numba import"] = numba_seconds
    print(json.dumps(spent))
"""
ORDER = ("planning", "launches", "launch inputs and order", "chunk files", "reading chunks back", "computing (host)",
         "variables", "file", "wall", "numba import")


def grid(cases: int) -> list[str]:
    """The axes: PGA 0.3 to 0.8 g in ``n`` steps, height/width 3.3 to 6.6 in ``n + 1`` values; ``n =
    1000`` is the H200's grid (``--pga 0.3g:0.7995g:0.0005g --height-to-width 3.3:6.6:0.0033``)."""
    n = max(2, round(math.sqrt(cases)))
    return ["--pga", f"0.3g:{0.3 + 0.5 * (n - 1) / n:.6g}g:{0.5 / n:.6g}g",
            "--height-to-width", f"3.3:6.6:{3.3 / n:.6g}"]


def run(folder: Path, cases: int) -> dict:
    args = ["sweep", str(folder / "rocking.yaml"), *grid(cases), "--device", "gpu", "--no-plot", "--no-progress",
            "--out-dir", str(folder / "out"), "--overwrite"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    done = subprocess.run([sys.executable, "-c", CHILD, *args], cwd=REPO, env=env, capture_output=True,
                          text=True, timeout=1200)
    if done.returncode != 0:
        raise SystemExit(done.stderr[-3000:])
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    figures["cases"] = int(re.search(r"= (\d+) cases", done.stdout).group(1))
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=1_000_000, help="about this many cases (default 10^6)")
    parser.add_argument("--repeat", type=int, default=3, help="runs (default 3)")
    parser.add_argument("--out", type=Path, default=None, help="also write FOLDER/bench_gpu_host.md")
    args = parser.parse_args()
    horizontal, vertical, _ = kobe_records()
    if vertical is None:
        raise SystemExit(f"needs the Kobe records ({KOBE[0]}, {KOBE[1]}): set ROCKSLIDE_RECORDS")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        case = ROCKING_CASE.format(horizontal=horizontal, vertical=f"  vertical: {{file: {vertical}}}\n")
        (folder / "rocking.yaml").write_text(case.replace("dt: 0.1 ms", "dt: auto"))
        runs = [run(folder, args.cases) for _ in range(args.repeat)]
    lines = ["# The host's part of a GPU study (the device an instant stand-in)", "",
             *(f"{line}  " for line in machine()), "",
             f"`python benchmarks/bench_gpu_host.py --cases {args.cases} --repeat {args.repeat}`: `rockslide sweep "
             f"--device gpu` of {runs[0]['cases']} cases (the rocking-heavy grid of `results/bench_gpu.md`, "
             "`dt: auto`), each run in a fresh process; seconds, median (range) of the runs", "",
             "| step | seconds |", "|---|---:|"]
    for step in ORDER:
        values = [r.get(step, 0.0) for r in runs]
        lines.append(f"| {step} | {statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f}) |")
    lines += ["", "'computing (host)' holds the launch inputs, the chunk files and the copies; 'wall' is the "
              "command from its start to its end, without the numba import, which a device run makes before "
              "it starts (loading the device kernel)."]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "bench_gpu_host.md").write_text(text)


if __name__ == "__main__":
    main()
