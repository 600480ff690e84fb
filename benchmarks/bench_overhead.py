"""What a study costs beyond its compute (issue 41, item 4): ``sweep``, ``fragility``, ``run
--ensemble`` and ``risk``, each without its figure, as a user types them.

The goal: each takes at most its compute + 0.5 s of wall time on a quiet 2-core machine, i.e.
start-up, imports, reading the case and the records, planning, loading the kernel, collecting the
results and writing the HDF5 file together take 0.5 s or less. The commands (`STUDIES`):

- the paper's Kobe grid (Figure 9(b)'s case, 41 mu x 37 PGA = 1517 cases, 150 s of record at
  dt = 0.1 ms), on one core (``--workers 1``) and on all cores (the default);
- ``run --ensemble 200`` of the shipped example (200 neighbours of the case, all cores);
- ``fragility`` of the example over the synthetic suite at 15 PGA levels (90 runs, all cores);
- ``risk`` of a given fragility (median, beta) on the shipped hazard curve (no compute).

Each runs ``--repeat`` times (default 7), each in a fresh process as a user types it (byte code
written: PYTHONDONTWRITEBYTECODE unset; one untimed run first), the studies taking turns. "compute"
is the time the process spent computing cases: the kernel's time of every `engine.execute.execute`
(its ``Execution.seconds``, which leaves out loading a JIT) plus, for a run, its nominal case
(`engine.prepare.simulate_prepared`), summed by a wrapper the process starts with (`PROBE`);
"beyond" is wall - compute per run. "fits" is the part of "beyond" a fragility analysis spends
fitting its curves (`analyses.fragility.analyse`: the probit fits, their 1000-resample bootstrap,
the goodness of fit): statistics, not overhead, shown apart. The medians and ranges are printed,
and the floor no command can go below: a bare ``python``, ``import numpy``, the libraries a
study needs (numpy, h5py for its file, yaml for its case, click for its command line; their start
and exit), and ``import numpy, numba`` (what a study would pay before anything if it loaded numba's JIT instead of the
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
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_startup import KOBE_CASE, find_records, machine, spread, timed, user_env

REPO = Path(__file__).resolve().parents[1]
GRID = ("--mu", "0.40:0.80:0.01", "--pga", "100gal:1000gal:25gal")
EXAMPLE = "configs/example.yaml"
#: (what, the command's arguments after ``rockslide``): each also gets ``--out-dir``, ``--overwrite``.
STUDIES = (
    ("Kobe grid, 1517 cases, one core", ["sweep", KOBE_CASE.as_posix(), *GRID, "--workers", "1", "--no-plot"]),
    ("Kobe grid, 1517 cases, all cores", ["sweep", KOBE_CASE.as_posix(), *GRID, "--no-plot"]),
    ("ensemble of 200 of the example", ["run", EXAMPLE, "--ensemble", "200", "--no-plot"]),
    ("fragility of the example, 6 records x 15 levels", [
        "fragility", EXAMPLE, "--suite", "records/suite-synthetic.yaml", "--levels", "0.1g:1.5g:0.1g",
        "--no-plot"]),
    ("risk of a given fragility", ["risk", "--median", "0.5g", "--beta", "0.4", "--hazard",
                                   "rockslide/hazard-example-PGA.csv", "--no-plot"]),
)
GOAL = 0.5          # [s] wall - compute, issue 41 item 4
#: The wrapper each command runs in: it sums the compute time (module docstring) and prints it as
#: the last line of stderr, then runs the command as ``rockslide`` would. The wrapped functions are
#: replaced before any rockslide module binds them.
PROBE = """
import atexit, importlib.abc, importlib.machinery, sys, time
spent, fits = [0.0], [0.0]
atexit.register(lambda: print(f"compute-seconds {spent[0]!r} fits-seconds {fits[0]!r}", file=sys.stderr))
def timing(function, total):
    def timed(*args, **kwargs):
        began = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            total[0] += time.perf_counter() - began
    return timed
from rockslide.engine import execute as _ex, prepare as _pr
_execute = _ex.execute
def execute(*args, **kwargs):
    done = _execute(*args, **kwargs)
    spent[0] += done.seconds
    return done
_ex.execute, _pr.simulate_prepared = execute, timing(_pr.simulate_prepared, spent)
class TimeTheFits(importlib.abc.MetaPathFinder):
    # fragility.analyse wrapped as its module loads (importing it here would charge a sweep for it)
    def find_spec(self, name, path, target=None):
        if name != "rockslide.analyses.fragility":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        load = spec.loader.exec_module
        def exec_module(module):
            load(module)
            module.analyse = timing(module.analyse, fits)
        spec.loader.exec_module = exec_module
        return spec
sys.meta_path.insert(0, TimeTheFits())
from rockslide import cli
sys.argv[0] = "rockslide"
cli.entry()
"""


def compute_seconds(stderr: str) -> tuple[float, float]:
    """The compute time and the fits' time the wrapper printed (`PROBE`)."""
    for line in reversed(stderr.splitlines()):
        if line.startswith("compute-seconds "):
            words = line.split()
            return float(words[1]), float(words[3])
    raise SystemExit(f"no compute time from the wrapper:\n{stderr[-3000:]}")


#: A fixed piece of plain Python: its time says how fast the machine is while the figures are taken
#: (a shared virtual machine's speed drifts; on the development machine the same loop took 1.9 s in
#: one hour and 2.9 s in the next, with nothing else running).
SPEED_PROBE = "s = 0\nfor i in range(20_000_000):\n    s += i"


def speed_probe() -> float:
    """[s] The wall time of `SPEED_PROBE` in a fresh process, best of three."""
    code = f"import time\nt = time.perf_counter()\n{SPEED_PROBE}\nprint(time.perf_counter() - t)"
    return min(float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                    check=True).stdout) for _ in range(3))


def start_hooks() -> str:
    """The ``.pth`` files of this interpreter's site-packages that run code at every start (an
    editable install's finder, numba-cuda's redirector: 0.04 s of ``python -c pass`` on the
    development machine): part of the floor, which a plain ``pip install`` without the test extra
    does not pay."""
    import site

    hooks = sorted(pth.name for folder in site.getsitepackages() for pth in Path(folder).glob("*.pth")
                   if any(line.startswith(("import ", "import\t"))
                          for line in pth.read_text(errors="replace").splitlines()))
    return ", ".join(hooks) or "none"


def measure(repeat: int) -> None:
    records = find_records()
    if records is None:
        raise SystemExit("needs the Kobe records ($ROCKSLIDE_RECORDS or ../shared/records)")
    env = user_env(ROCKSLIDE_RECORDS=str(records.resolve()),
                   PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    out = Path(tempfile.mkdtemp(prefix="rockslide-overhead-"))
    commands = [[sys.executable, "-c", PROBE, *arguments, "--out-dir", str(out / str(i)), "--overwrite"]
                for i, (_, arguments) in enumerate(STUDIES)]
    print("# What a study costs beyond its compute (no figure)\n")
    for line in machine():
        print(line + "  ")
    print(f"`.pth` files that run code at every start of this Python: {start_hooks()}  ")
    print(f"speed probe (20 million additions in plain Python, best of 3) at the start: {speed_probe():.2f} s  ")
    print(f"\nEach command {repeat} times in a fresh process after one untimed run, the commands taking turns; "
          "median (range) in seconds\n")
    for command in commands:
        timed(command, cwd=REPO, env=env)
    walls, cpus, computes, fits = ([[] for _ in STUDIES] for _ in range(4))
    for _ in range(repeat):
        for i, command in enumerate(commands):
            wall, cpu, done = timed(command, cwd=REPO, env=env)
            walls[i].append(wall)
            cpus[i].append(cpu)
            compute, fit = compute_seconds(done.stderr)
            computes[i].append(compute)
            fits[i].append(fit)
    print("| study | `rockslide ...` | wall [s] | CPU [s] | compute [s] | wall - compute [s] | goal | fits [s] |")
    print("|---|---|---:|---:|---:|---:|---|---:|")
    for i, (what, arguments) in enumerate(STUDIES):
        beyond = [w - c for w, c in zip(walls[i], computes[i], strict=True)]
        verdict = "met" if statistics.median(beyond) <= GOAL else "not met"
        print(f"| {what} | `{' '.join(arguments)}` | {spread(walls[i])} | {spread(cpus[i])} | {spread(computes[i])} | "
              f"{spread(beyond)} | <= {GOAL:.1f}: {verdict} | {spread(fits[i]) if any(fits[i]) else '-'} |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\nload average at the end: {load:.2f}; speed probe at the end: {speed_probe():.2f} s\n")
    print(f"## The floor: a process that only starts ({repeat} times each)\n")
    print("| command | wall [s] |")
    print("|---|---:|")
    for what, code in (("`python -c pass`", "pass"), ("`python -c 'import numpy'`", "import numpy"),
                       ("`python -c 'import numpy, h5py, yaml, click'` (what a study must load)",
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
