"""Output files that are never half-written: check the destination before the work, write to a
temporary file beside it, sync, and rename it onto the final name.

A crash, a kill or Ctrl-C therefore leaves the previous file or none. Temporary files are named
``.NAME.<pid>.tmp`` (with a thread id when threads write at once): they start with ``.`` and end in
``.tmp``, and a killed process may leave one behind, never a half-written ``NAME``.
"""

from __future__ import annotations

import contextlib
import os
import threading
from pathlib import Path

from .errors import OutputError


def check_destination(path, *, overwrite: bool = False, example: str = "out/case.h5") -> Path:
    """Refuse an existing ``path`` unless ``overwrite``; create its folder if missing.

    Call it before any long computation, so that a run is not wasted on a result it may not write.

    Raises
    ------
    OutputError
        ``path`` exists and ``overwrite`` is false, ``path`` is a folder, or its folder cannot be
        created.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"is a folder; expected a file name such as {example}", source=str(path))
    refuse_existing(path, overwrite)
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create the output folder: {exc.strerror or exc}",
                          source=str(folder)) from None
    if not folder.is_dir():
        raise OutputError("cannot create the output folder: a file of that name exists",
                          source=str(folder))
    return path


def refuse_existing(path: Path, overwrite: bool) -> None:
    if not overwrite and (path.exists() or path.is_symlink()):
        raise OutputError(f"{path} exists (use --overwrite to replace it)")


def temporary_path(path, *, per_thread: bool = False) -> Path:
    """The temporary file ``path`` is written to before it is renamed onto it."""
    path = Path(path)
    thread = f".{threading.get_ident()}" if per_thread else ""
    return path.with_name(f".{path.name}.{os.getpid()}{thread}.tmp")


def publish(tmp: Path, path: Path, *, overwrite: bool) -> None:
    """Sync ``tmp`` to disk and rename it onto ``path`` (atomic on POSIX and Windows).

    Raises OutputError (and deletes ``tmp``) if ``path`` appeared meanwhile and ``overwrite`` is false.
    """
    try:
        refuse_existing(path, overwrite)
        fsync_file(tmp)
        os.replace(tmp, path)
    except BaseException:
        remove_quietly(tmp)
        raise
    fsync_folder(path.parent)


@contextlib.contextmanager
def atomic_write(path, *, overwrite: bool, mode: str = "wb", per_thread: bool = False, what: str = "file"):
    """Open a temporary file for writing; on success publish it onto ``path``, on any exception
    delete it. OSErrors while writing become one-line OutputErrors naming ``path``."""
    path = Path(path)
    tmp = temporary_path(path, per_thread=per_thread)
    try:
        try:
            with open(tmp, mode) as handle:
                yield handle
        except OSError as exc:
            raise OutputError(f"cannot write the {what}: {exc.strerror or exc}", source=str(path)) from None
        publish(tmp, path, overwrite=overwrite)
    except BaseException:
        remove_quietly(tmp)
        raise


def remove_quietly(path: Path) -> None:
    """Delete ``path`` if it exists (best effort: a leftover is named as one)."""
    try:
        os.unlink(path)
    except OSError:
        pass


def fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_folder(folder: Path) -> None:
    """Make a rename durable (POSIX); a no-op where folders cannot be opened."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)
