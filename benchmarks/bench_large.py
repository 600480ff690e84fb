"""Planning and collecting a sweep of 10^6 cases: time and the client's memory, outside the compute.

Prints figures (and writes them as Markdown with ``--out``), asserts nothing. A ``--mu`` x ``--pga``
grid of ``--cases`` points of the shipped example (its synthetic record) is planned
(`sweep.plan_sweep`); its chunks are then stored as a sweep stores them (`ChunkStore`), the final
states of the first ``--computed`` chunks computed on this machine's threads and the others copies
of them (computing 10^6 cases takes minutes and is what bench_sweep and bench_cluster measure); then
the engine reads them back (`execute`, every chunk reused: the collecting phase of a sweep),
`sweep_variables` makes the result's variables and `results.write_sweep` writes the file. Each phase is
timed once, in a fresh process; its resident memory (VmRSS) is read after each phase, and the peak
(ru_maxrss) at the end.

With ``--end-to-end``, also ``rockslide sweep`` of ``--cases`` points run whole, as a user runs it (a
fresh process each), on this machine's threads and on a local dask cluster of one worker process
per core (`distributed.LocalCluster`): a one-sine pulse under a 1 m x 0.25 m block at dt = 1 ms
(cheap cases, so that 10^6 of them take minutes, not hours), ``--amplitude`` x ``--period``. Reported:
the wall time, the compute time the command prints, the rest (start, planning, collecting, writing),
the command's peak memory, and whether both result files are identical.

Usage: python benchmarks/bench_large.py [--cases 1000000] [--computed 16] [--end-to-end] [--out results]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def resident_mb() -> float:
    """This process's resident memory now [MB] (Linux)."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=1_000_000)
    parser.add_argument("--computed", type=int, default=16, help="chunks computed for real")
    parser.add_argument("--end-to-end", action="store_true", help="also run whole sweeps (minutes)")
    parser.add_argument("--out", type=Path, default=None, help="write bench_large.md in this folder")
    args = parser.parse_args(argv)

    import numpy as np

    import rockslide
    from rockslide.analyses import sweep as sw
    from rockslide.core import batch
    from rockslide.engine.chunks import ChunkStore
    from rockslide.engine.execute import _chunk_inputs, execute
    from rockslide.io import results

    batch.warm_up()
    rows = [("imports and the compiled core", 0.0, resident_mb())]
    side = round(math.sqrt(args.cases))
    case = rockslide.load_case(REPO / "configs" / "example.yaml")
    axes = [sw.parse_axis("mu", f"0.3:{0.3 + 0.0004 * (side - 1):.4f}:0.0004"),
            sw.parse_axis("pga", f"100gal:{100 + side - 1}gal:1gal")]

    started = time.perf_counter()
    plan = sw.plan_sweep(case, axes)
    rows.append((f"plan {plan.describe()}", time.perf_counter() - started, resident_mb()))

    with tempfile.TemporaryDirectory() as folder:
        h5_path = Path(folder) / "example.sweep.h5"
        store = ChunkStore.beside(h5_path, plan.key)
        computed = [batch.compute(*_chunk_inputs(plan, plan.chunk_indices(c))) for c in range(args.computed)]
        started = time.perf_counter()
        for chunk in range(plan.n_chunks):
            indices = plan.chunk_indices(chunk)
            model = computed[chunk % len(computed)]
            store.save(chunk, indices, np.resize(model, (indices.size, model.shape[1])))
        rows.append((f"store {plan.n_chunks} chunks (copies of {args.computed} computed)",
                     time.perf_counter() - started, resident_mb()))

        started = time.perf_counter()
        done = execute(plan, store)
        rows.append(("collect: read and check every chunk (execute, all reused)", time.perf_counter() - started,
                     resident_mb()))
        started = time.perf_counter()
        variables = sw.sweep_variables(plan, done.states)
        done.states = None
        rows.append(("the result's variables (sweep_variables)", time.perf_counter() - started, resident_mb()))
        started = time.perf_counter()
        results.write_sweep(h5_path, sw.coordinates(plan), variables, overwrite=False,
                            attrs=sw.root_attributes(plan, "rockslide sweep (bench_large)"))
        size = os.path.getsize(h5_path) / 2**20
        rows.append((f"write the result file ({size:.0f} MB)", time.perf_counter() - started, resident_mb()))

    peak = peak_mb()
    outside = sum(r[1] for r in rows[1:] if not r[0].startswith("store"))
    lines = [f"# Planning and collecting {plan.n_cases} cases",
             "",
             f"`python benchmarks/bench_large.py --cases {args.cases}` on {platform.machine()} with "
             f"{len(os.sched_getaffinity(0))} cores, Python {platform.python_version()}, numpy {np.__version__}, "
             f"rockslide {rockslide.__version__}; each phase timed once, in one process.",
             "",
             "| phase | time [s] | resident memory after [MB] |",
             "|---|---:|---:|"]
    lines += [f"| {name} | {seconds:.2f} | {memory:.0f} |" for name, seconds, memory in rows]
    lines += ["",
              f"Planning, collecting, variables and writing: {outside:.1f} s in all; peak resident memory "
              f"{peak:.0f} MB, {(peak - rows[0][2]) * 2**20 / plan.n_cases:.0f} bytes a case "
              f"above the {rows[0][2]:.0f} MB of the libraries."]
    if args.end_to_end:
        lines += ["", *end_to_end(args.cases)]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "bench_large.md").write_text(text)
    return 0


PULSE_CASE = """name: pulse
block:   {height: 1.0 m, width: 0.25 m, mass: 100 kg}
contact: {mu_static: 0.7, restitution: 0.912}
ground:
  horizontal: {pulse: one-sine, amplitude: 1.0 g, period: 0.5 s}
  tail: 0.2 s
solver:  {dt: 1 ms}
"""

#: Runs the command in this interpreter and prints its peak resident memory [kB] last, on stderr.
MEASURED = ("import resource, runpy, sys\n"
            "sys.argv = ['rockslide', *sys.argv[1:]]\n"
            "try:\n    runpy.run_module('rockslide', run_name='__main__')\n"
            "finally:\n    print('peak-kb', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)\n")


def end_to_end(cases: int) -> list[str]:
    """``rockslide sweep`` of about ``cases`` pulse cases on threads and on a local dask cluster."""
    import distributed
    import h5py

    side = round(math.sqrt(cases))
    axes = ["--amplitude", f"0.1g:{0.1 + 0.001 * (side - 1):.3f}g:0.001g",
            "--period", f"0.1:{0.1 + 0.001 * (side - 1):.3f}:0.001"]
    cores = len(os.sched_getaffinity(0))
    rows, files = [], []
    with tempfile.TemporaryDirectory() as folder:
        case = Path(folder) / "pulse.yaml"
        case.write_text(PULSE_CASE)
        with distributed.LocalCluster(n_workers=cores, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=":0", silence_logs=50) as cluster:
            runs = (("threads", []), (f"dask, {cores} workers", ["--scheduler", cluster.scheduler_address]))
            for name, where in runs:
                out = Path(folder) / name.split(",")[0]
                started = time.perf_counter()
                done = subprocess.run([sys.executable, "-c", MEASURED, "sweep", str(case), *axes, "--out-dir", str(out),
                                       "--no-plot", "--no-progress", *where], capture_output=True, text=True)
                wall = time.perf_counter() - started
                if done.returncode != 0:
                    raise SystemExit(f"{name}: {done.stderr}")
                compute = float(re.search(r"computed \d+ cases in ([\d.]+) s", done.stdout).group(1))
                peak = int(re.search(r"peak-kb (\d+)", done.stderr).group(1)) / 1024
                rows.append(f"| {name} | {wall:.1f} | {compute:.1f} | {wall - compute:.1f} | {peak:.0f} |")
                files.append(out / "pulse.sweep.h5")
                print(f"{name}: {wall:.1f} s", file=sys.stderr)
        with h5py.File(files[0], "r", locking=False) as a, h5py.File(files[1], "r", locking=False) as b:
            same = all(a[k][()].tobytes() == b[k][()].tobytes() for k in a if isinstance(a[k], h5py.Dataset))
    return [f"## rockslide sweep of {side * side} cases, whole",
            "",
            f"`rockslide sweep pulse.yaml {' '.join(axes)} --no-plot` (a one-sine pulse, dt = 1 ms), each in a "
            f"fresh process; the cluster's {cores} workers started before and not timed. Results identical: "
            f"{'yes' if same else 'NO'}.",
            "",
            "| where | wall [s] | compute [s] | the rest [s] | peak memory of the command [MB] |",
            "|---|---:|---:|---:|---:|",
            *rows]


if __name__ == "__main__":
    sys.exit(main())
