"""Scaling on a dask.distributed cluster against local threads, on the same machine.

Prints figures (and writes them as Markdown with ``--out``), asserts nothing. For N = 1, 2, 4 ...
up to the cores present, one sweep is computed by N local threads and by a real local cluster of N
worker processes of one thread each (`distributed.LocalCluster`, started once per N, its startup not
timed); each timing is the median of ``--repeat`` runs. Reported: the speed-up of each over one
thread, and dask's overhead per task, ``(t_dask - t_threads) / tasks``. Both results are checked to be
identical (the dask path must give the local result bit for bit). A first run per cluster warms
its workers (their compiled core loads once); it is not timed.

The sweep is the shipped example block under the shipped synthetic record (so that it runs
anywhere), ``--cases`` cases in chunks of ``--chunk-size``.

Usage: python benchmarks/bench_cluster.py [--cases 4096] [--chunk-size 64] [--repeat 3] [--out results]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def grid(cases: int) -> dict:
    """mu x pga axes of about ``cases`` points."""
    side = max(2, round(math.sqrt(cases)))
    return {"mu": [round(0.30 + 0.40 * k / (side - 1), 6) for k in range(side)],
            "pga": [f"{100 + 900 * k / (side - 1):.6g}gal" for k in range(side)]}


def timed(function, repeat: int):
    times, result = [], None
    for _ in range(repeat):
        started = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - started)
    return statistics.median(times), result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=4096)
    parser.add_argument("--chunk-size", type=int, default=64)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None, help="write bench_cluster.md in this folder")
    args = parser.parse_args(argv)

    import distributed

    import rockslide

    case = rockslide.load_case(REPO / "configs" / "example.yaml")
    axes = grid(args.cases)
    n_cases = len(axes["mu"]) * len(axes["pga"])
    tasks = math.ceil(n_cases / args.chunk_size)
    cores = os.cpu_count() or 1
    counts = [n for n in (1, 2, 4, 8, 16, 32, 64) if n <= cores] or [1]

    def sweep(**where):
        return rockslide.sweep(case, chunk_size=args.chunk_size, records_dir=REPO / "records", **where, **axes)

    sweep(workers=1)                                            # compile or load the core once
    rows = []
    base = None
    for n in counts:
        local_t, local = timed(lambda n=n: sweep(workers=n), args.repeat)
        with distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=":0", silence_logs=50) as cluster:
            address = cluster.scheduler_address
            sweep(scheduler=address)                            # the workers load the core: not timed
            dask_t, remote = timed(lambda address=address: sweep(scheduler=address), args.repeat)
        same = all(np.array_equal(local[v].values, remote[v].values, equal_nan=True) for v in local.data_vars)
        base = base or local_t
        rows.append((n, local_t, dask_t, base / local_t, base / dask_t, (dask_t - local_t) / tasks * 1e3, same))
        print(f"N={n}: threads {local_t:.2f} s, dask {dask_t:.2f} s, identical: {same}", file=sys.stderr)

    lines = [
        "# Scaling: local threads and a local dask cluster",
        "",
        f"{n_cases} cases of the shipped example (synthetic record) in {tasks} chunks of {args.chunk_size}; "
        f"median of {args.repeat} runs each; {cores} cores; rockslide {rockslide.__version__}, "
        f"dask.distributed {distributed.__version__}. Speed-ups are over one local thread; the overhead is "
        "(dask - threads) / tasks. Measured while other work may run on the machine: compare within one table.",
        "",
        "| N | threads [s] | dask, N workers [s] | speed-up, threads | speed-up, dask | dask overhead per task [ms] "
        "| identical |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [f"| {n} | {a:.2f} | {b:.2f} | {sa:.2f} | {sb:.2f} | {o:.1f} | {'yes' if same else 'NO'} |"
              for n, a, b, sa, sb, o, same in rows]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "bench_cluster.md").write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
