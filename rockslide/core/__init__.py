"""The numerical core: equations, the state machine and the solvers, with no I/O.

Plain floats and arrays in, plain data out. Nothing here imports an outer layer of rockslide (case
files, records, result files, figures, the command line) or an I/O library; an import-linter
contract in ``pyproject.toml`` enforces it.

- `layout`: state codes and the layout of the arrays the compiled code shares with its callers.
- `physics`: the equations of the paper, one implementation each (numba).
- `kernel`: the compiled fixed-step state machine (RK4, events located inside the step, exact REST).
- `batch`: the kernel over many cases (sweeps, fragility); `gpu`: the same on an NVIDIA GPU.
- `simulate`: ``Model`` + ground motion arrays -> ``Result``.
- `native`: the kernel's entry points compiled ahead of time by the package build (no numba at run
  time); `compiled`: numba's cache of the core, kept fresh.
- `reference`: the same state machine on scipy's adaptive DOP853, for checks.
- `criteria`: mode-initiation maps (eqs. 6, 11, 26).
- `intensity`: intensity measures of a record (PGA, PGV, Sa(T, 5 %)).
- `normal`: the normal distribution's CDF, log-CDF and quantile and the chi-square tail, on numpy
  (the fits' and the ensembles' statistics, without scipy.special).
"""

import os


def local_threads() -> int:
    """Threads to run on by default: every core this process may run on (a study's batches, a
    file's compression)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                    # not on Linux
        return os.cpu_count() or 1
