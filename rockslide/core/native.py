"""The core's entry points for one run as machine code compiled ahead of time by the package build,
so that ``rockslide run`` neither imports numba nor waits for it (issue 11; README, 'The first run').

`build` compiles, with numba's ahead-of-time compiler (`numba.pycc`), the very `kernel` and
`physics` functions that numba compiles at run time (`ENTRY_POINTS`, with the argument types
`simulate` gives them) into an extension module ``_native`` beside this file, for a generic CPU of
the build's architecture, and records the `source_stamp` of the sources it compiled beside it.
`entry_points` returns that module when it imports and its stamp is the stamp of the sources
beside it (they were not edited since), else numba's JIT dispatchers of the same functions. Both
run the same code: results are identical to the last bit (tests/test_startup.py).

The module's functions release the GIL while they run, as ``@njit(nogil=True)`` functions do
(`RELEASES_GIL`): a local study calls `run` case by case on each of its threads
(`simulate.compute_batch`, `engine.execute.local_kernel`), side by side, without numba's batch
driver (1.2-1.4 s to import and load on the 2-core development machine, more than the compute of
most studies started by hand). The dask workers and the GPU keep numba's JIT, whose cache the build
fills as well (`build.precompile`).

Plain standard library at import: numba is imported only by `build` and by the JIT fallback.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import os
import types
import warnings
from pathlib import Path

#: The modules whose functions are compiled (numba's JIT and `build`), in the order their code
#: includes each other; `layout`'s constants are compiled into them.
COMPILED_MODULES = ("layout", "physics", "kernel", "batch", "gpu")
MODULE_NAME = "_native"
STAMP_FILE = f"{MODULE_NAME}.stamp"
#: The compiled functions' Python wrappers release the GIL around the machine code (`build`): part of
#: the stamp, so that a module built before they did is not taken for one that does.
RELEASES_GIL = True

_VECTOR, _MATRIX = "f8[::1]", "f8[:, ::1]"
#: (name, module, numba signature) of each function `simulate` calls from Python.
ENTRY_POINTS = (
    ("run", "kernel", f"i8({_VECTOR}, {_MATRIX}, {_MATRIX}, {_VECTOR}, {_MATRIX}, i8, i8, {_MATRIX}, i8)"),
    ("rest_bounds", "kernel", f"{_MATRIX}({_MATRIX})"),
    ("finished", "kernel", f"b1({_VECTOR})"),
    ("block_constants", "physics", "UniTuple(f8, 3)(f8, f8, f8)"),
    ("kinetic_energy", "physics", "f8(f8, f8, f8, f8, f8, f8)"),
    ("kinetic_energy_m", "physics", "f8(f8, f8, f8, f8, f8, f8, f8)"),
    ("potential_energy", "physics", "f8(f8, f8, f8, f8)"),
    ("tilt", "physics", "UniTuple(f8, 2)(f8, f8)"),
    ("slip_liftoff_margin", "physics", "f8(f8, f8, f8, f8, f8, f8, f8)"),
)


@functools.lru_cache(maxsize=1)
def source_stamp() -> str:
    """SHA-256 of `ENTRY_POINTS` and of the sources of `COMPILED_MODULES` (stable across processes
    and machines), read once per process."""
    digest = hashlib.sha256(repr((ENTRY_POINTS, RELEASES_GIL)).encode())
    folder = Path(__file__).parent
    for name in COMPILED_MODULES:
        digest.update((folder / f"{name}.py").read_bytes())
    return digest.hexdigest()


def ahead_of_time():
    """The build's compiled module when it fits the sources beside it (module docstring), else None."""
    try:
        if (Path(__file__).with_name(STAMP_FILE)).read_text() != source_stamp():
            return None
        return importlib.import_module(f"{__package__}.{MODULE_NAME}")
    except (OSError, ImportError):
        return None


def just_in_time() -> types.SimpleNamespace:
    """`ENTRY_POINTS` as numba's JIT dispatchers (they compile, or load numba's cache, at first call)."""
    modules = {name: importlib.import_module(f"{__package__}.{name}") for name in ("kernel", "physics")}
    return types.SimpleNamespace(**{name: getattr(modules[module], name) for name, module, _ in ENTRY_POINTS})


@functools.lru_cache(maxsize=1)
def entry_points():
    """`ENTRY_POINTS` for this process: the build's machine code (`ahead_of_time`) or numba's JIT."""
    return ahead_of_time() or just_in_time()


def is_ahead_of_time() -> bool:
    """Whether `entry_points` are the build's machine code in this process (no numba needed for them)."""
    return not isinstance(entry_points(), types.SimpleNamespace)


def build(folder: Path | None = None) -> Path:
    """Compile `ENTRY_POINTS` ahead of time into ``folder`` (default: beside this file) and record
    their `source_stamp`. Returns the extension module's path. Needs numba and a C compiler.

    ``pycc`` has no option for it, but its compiler takes numba's compilation flags: with
    ``release_gil`` set (what ``nogil=True`` sets for the JIT), each function's Python wrapper
    unpacks its arguments, releases the GIL, runs the machine code and takes the GIL back
    (tests/test_startup.py finds ``PyEval_SaveThread`` in the module). The functions touch no
    Python object while they run: `batch.run_batch` calls `kernel.run` under ``nogil=True`` too."""
    with warnings.catch_warnings():      # pending deprecation since numba 0.57 (README, 'The first run')
        warnings.simplefilter("ignore", PendingDeprecationWarning)
        from numba.pycc import CC
        from numba.pycc import compiler as pycc_compiler

    class ReleasingGil(pycc_compiler.Flags):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.release_gil = RELEASES_GIL

    folder = Path(folder) if folder is not None else Path(__file__).parent
    stamp = folder / STAMP_FILE
    stamp.unlink(missing_ok=True)        # no stamp until the module beside it is complete
    compiler = CC(MODULE_NAME)
    compiler.output_dir = str(folder)
    compiler.verbose = False
    for name, module, signature in ENTRY_POINTS:
        dispatcher = getattr(importlib.import_module(f"{__package__}.{module}"), name)
        compiler.export(name, signature)(dispatcher.py_func)
    plain, pycc_compiler.Flags = pycc_compiler.Flags, ReleasingGil
    try:
        compiler.compile()
    finally:
        pycc_compiler.Flags = plain
    temporary = folder / f".{STAMP_FILE}.{os.getpid()}.tmp"
    temporary.write_text(source_stamp())
    os.replace(temporary, stamp)
    return folder / Path(compiler.output_file).name


__all__ = ["COMPILED_MODULES", "ENTRY_POINTS", "RELEASES_GIL", "source_stamp", "ahead_of_time", "just_in_time",
           "entry_points", "is_ahead_of_time", "build"]
