"""What a study costs beyond its compute (issue 41, item 4): the paper's Kobe grid on one core.

The goal: ``rockslide sweep`` of the Kobe grid (Figure 9(b)'s case, 41 mu x 37 PGA = 1517 cases,
150 s of record at dt = 0.1 ms) with ``--workers 1 --no-plot`` takes at most its compute + 0.5 s of
wall time, i.e. start-up, imports, reading the case and the records, planning, loading the kernel,
collecting the chunks and writing the HDF5 file together take 0.5 s or less:

    rockslide sweep configs/table1/fig09b-mu052.yaml --mu 0.40:0.80:0.01 --pga 100gal:1000gal:25gal \\
        --workers 1 --no-plot

The command runs ``--repeat`` times (default 7), each in a fresh process as a user types it (byte
code written: PYTHONDONTWRITEBYTECODE unset; one untimed run first). "compute" is the command's own
figure ("computed 1517 cases in 1.2 s (1264 cases/s)": cases / rate, which keeps four digits);
"beyond" is wall - compute per run. The medians and ranges are printed, and the floor no command
can go below: a bare ``python``, ``import numpy``, the libraries a sweep needs (numpy, h5py for
its file, yaml for its case, click for its command line; their start and exit), and ``import
numpy, numba`` (what a study pays before anything when it loads numba's JIT instead of the
build's machine code). Asserts nothing: the goals live here, never in the tests.

The machine is shared: the load average and the other busy processes are printed with the figures.
Prints Markdown; ``--out FOLDER`` also writes it to ``FOLDER/bench_overhead.md``.

Usage: python benchmarks/bench_overhead.py [--repeat N] [--out results]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import re
import statistics
import sys
import tempfile
from pathlib import Path

from bench_startup import KOBE_CASE, find_records, machine, spread, timed, user_env

REPO = Path(__file__).resolve().parents[1]
GRID = ("--mu", "0.40:0.80:0.01", "--pga", "100gal:1000gal:25gal")
GOAL = 0.5          # [s] wall - compute, issue 41 item 4
_COMPUTED = re.compile(r"computed (\d+) cases in [\d.]+ s \((\d+) cases/s\)")


def compute_seconds(stdout: str) -> float:
    """The compute time the command printed, from its case count and rate (more digits than its
    seconds)."""
    match = _COMPUTED.search(stdout)
    if match is None:
        raise SystemExit(f"no compute time in the command's printout:\n{stdout}")
    return int(match.group(1)) / int(match.group(2))


def measure(repeat: int) -> None:
    records = find_records()
    if records is None:
        raise SystemExit("needs the Kobe records ($ROCKSLIDE_RECORDS or ../shared/records)")
    env = user_env(ROCKSLIDE_RECORDS=str(records.resolve()),
                   PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    out = Path(tempfile.mkdtemp(prefix="rockslide-overhead-"))
    command = [sys.executable, "-m", "rockslide", "sweep", str(KOBE_CASE), *GRID, "--workers", "1", "--no-plot",
               "--out-dir", str(out), "--overwrite"]
    print("# What the Kobe grid costs beyond its compute (one core, no figure)\n")
    for line in machine():
        print(line + "  ")
    print(f"\n`rockslide sweep {KOBE_CASE.as_posix()} {' '.join(GRID)} --workers 1 --no-plot` (1517 cases), "
          f"{repeat} times in a fresh process after one untimed run; median (range) in seconds\n")
    timed(command, cwd=REPO, env=env)
    walls, cpus, computes = [], [], []
    for _ in range(repeat):
        wall, cpu, done = timed(command, cwd=REPO, env=env)
        walls.append(wall)
        cpus.append(cpu)
        computes.append(compute_seconds(done.stdout))
    beyond = [w - c for w, c in zip(walls, computes, strict=True)]
    verdict = "met" if statistics.median(beyond) <= GOAL else "not met"
    print("| wall [s] | CPU [s] | compute [s] | wall - compute [s] | goal |")
    print("|---:|---:|---:|---:|---|")
    print(f"| {spread(walls)} | {spread(cpus)} | {spread(computes)} | {spread(beyond)} | "
          f"<= {GOAL:.1f}: {verdict} |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\nload average at the end: {load:.2f}\n")
    print(f"## The floor: a process that only starts ({repeat} times each)\n")
    print("| command | wall [s] |")
    print("|---|---:|")
    for what, code in (("`python -c pass`", "pass"), ("`python -c 'import numpy'`", "import numpy"),
                       ("`python -c 'import numpy, h5py, yaml, click'` (what a sweep must load)",
                        "import numpy, h5py, yaml, click"),
                       ("`python -c 'import numpy, numba'`", "import numpy, numba")):
        floor = [timed([sys.executable, "-c", code], cwd=REPO, env=env)[0] for _ in range(repeat)]
        print(f"| {what} | {spread(floor)} |")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7, help="runs of the command (default 7)")
    parser.add_argument("--out", type=Path, default=None, help="also write FOLDER/bench_overhead.md")
    args = parser.parse_args()
    with contextlib.redirect_stdout(io.StringIO()) as text:
        measure(args.repeat)
    sys.stdout.write(text.getvalue())
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "bench_overhead.md").write_text(text.getvalue())


if __name__ == "__main__":
    main()
