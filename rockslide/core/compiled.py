"""The compiled core on disk: numba's cache of `physics`, `kernel`, `batch` and `gpu`, kept fresh.

numba keys the cached machine code of a function on the content of the function's own source file.
The kernel's code includes the physics functions it calls, and the batch driver's code the kernel's,
so an edited ``physics.py`` would leave a stale compiled kernel behind. `freshen` therefore
compares a hash of their sources (`source_stamp`) with the one recorded beside the cache, and
removes the core's cached code when they differ; the next call compiles it again.

The package build compiles the core into this cache before installation (`build.precompile`,
called by ``setup.py``), so that the first command after ``pip install`` loads machine code instead of
spending a minute compiling it. Where no folder numba would cache in can be written (a read-only
installation and a read-only home), the core caches in a temporary folder that the process
removes at exit: it compiles in memory, once per process (`CACHE_IS_TEMPORARY`), instead of
failing at import. Where numba is told to cache elsewhere (``NUMBA_CACHE_DIR``, or the user's
cache under a read-only installation), `freshen` first copies the shipped compiled core there
(`shipped_folder`), so that those installations do not compile either.

The stamp also identifies the compiled code elsewhere: a sweep's chunks are reused only under the
same stamp (`sweep.definition_key`).
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from pathlib import Path

from .native import COMPILED_MODULES, source_stamp

STAMP_FILE = "rockslide-core.stamp"


def _cache_is_temporary() -> bool:
    """Make sure numba has a folder to cache the core in (module docstring); True when it is a
    temporary one."""
    from numba.core import caching, config

    if config.CACHE_DIR:
        return False
    for locator in (caching.InTreeCacheLocator, caching.UserWideCacheLocator):
        try:
            if locator.from_function(cache_folder, __file__) is not None:   # any function of this file
                return False
        except OSError:
            pass
    config.CACHE_DIR = tempfile.mkdtemp(prefix="rockslide-numba-")
    atexit.register(shutil.rmtree, config.CACHE_DIR, ignore_errors=True)
    return True


def cache_folder(dispatcher) -> Path | None:
    """The folder numba caches ``dispatcher``'s compiled code in (None: caching is off)."""
    folder = getattr(getattr(dispatcher, "_cache", None), "_cache_path", None)
    return Path(folder) if folder else None


def freshen(dispatcher) -> bool:
    """Remove the core's cached compiled code beside ``dispatcher``'s if the core's sources changed
    since it was written, and record the new stamp. Returns True when the cache was (or is now)
    fresh, False when it could not be checked (no cache, or a folder that cannot be written)."""
    folder = cache_folder(dispatcher)
    if folder is None:
        return False
    stamp = source_stamp()
    recorded = folder / STAMP_FILE
    try:
        if recorded.read_text() == stamp:
            return True
    except OSError:
        pass
    try:
        for path in folder.iterdir():
            if path.suffix in (".nbi", ".nbc") and path.name.split(".", 1)[0] in COMPILED_MODULES:
                path.unlink(missing_ok=True)
        _copy_shipped(folder, stamp)
        temporary = folder / f".{STAMP_FILE}.{os.getpid()}.tmp"
        temporary.write_text(stamp)
        os.replace(temporary, recorded)
    except OSError:
        return False
    return True


def shipped_folder() -> Path:
    """The folder the package build compiled the core into (`build.precompile`): numba's in-tree
    cache beside these modules."""
    return Path(__file__).resolve().parent / "__pycache__"


def _copy_shipped(folder: Path, stamp: str) -> bool:
    """Copy the compiled core the package ships (`shipped_folder`, when its stamp is ``stamp``) into
    ``folder``, the cache numba was told to use instead: ``NUMBA_CACHE_DIR`` (containers, HPC
    modules) or the user's cache under a read-only installation. numba checks each cached function
    against its source file's time and size, the same file's here, so the copies load as they
    are and the first run compiles nothing. Returns whether files were copied."""
    shipped = shipped_folder()
    try:
        if folder.resolve() == shipped or (shipped / STAMP_FILE).read_text() != stamp:
            return False
        files = [path for path in shipped.iterdir() if path.suffix in (".nbi", ".nbc")]
        for path in files:
            temporary = folder / f".{path.name}.{os.getpid()}.tmp"
            shutil.copyfile(path, temporary)
            os.replace(temporary, folder / path.name)
    except OSError:
        return False
    return bool(files)


def discard(dispatcher) -> bool:
    """Delete the core's cached compiled code beside ``dispatcher``'s (a damaged cache: a truncated
    or altered file that numba cannot load), by forgetting its stamp so that `freshen` removes it;
    the next call compiles afresh. Returns whether the cache could be cleared."""
    folder = cache_folder(dispatcher)
    if folder is None:
        return False
    try:
        (folder / STAMP_FILE).unlink(missing_ok=True)
    except OSError:
        return False
    return freshen(dispatcher)


def is_warm(dispatcher) -> bool:
    """Whether ``dispatcher``'s compiled code is in the cache and fresh (no compile at first call)."""
    folder = cache_folder(dispatcher)
    if folder is None:
        return False
    name = dispatcher.py_func.__qualname__
    module = dispatcher.py_func.__module__.rsplit(".", 1)[-1]
    try:
        fresh = (folder / STAMP_FILE).read_text() == source_stamp()
    except OSError:
        return False
    return fresh and any(folder.glob(f"{module}.{name}-*.nbi"))


#: True when no folder numba caches in can be written: the core compiles in memory, in every process.
CACHE_IS_TEMPORARY = _cache_is_temporary()

__all__ = ["COMPILED_MODULES", "CACHE_IS_TEMPORARY", "source_stamp", "cache_folder", "freshen", "discard",
           "is_warm", "shipped_folder"]
