"""The numerical core: equations, the state machine and the solvers, with no I/O.

Plain floats and arrays in, plain data out. Nothing here imports an outer layer of rockslide (case
files, records, result files, figures, the command line) or an I/O library; an import-linter
contract in ``pyproject.toml`` enforces it.

- `physics`: the equations of the paper, one implementation each (numba).
- `kernel`: the compiled fixed-step state machine (RK4, events located inside the step, exact REST).
- `batch`: the kernel over many cases (sweeps).
- `simulate`: ``Model`` + ground motion arrays -> ``Result``.
- `reference`: the same state machine on scipy's adaptive DOP853, for checks.
- `criteria`: mode-initiation maps (eqs. 6, 11, 26).
"""
