"""Opening the files a user gives (cases, suites, records, results): regular files only.

Reading a FIFO, a device or a socket blocks (a FIFO without a writer waits forever, in a call no
signal handler of Python can cut short) or never ends (``/dev/zero``). So every input file is
checked with ``os.stat`` before it is opened, opened with ``O_NONBLOCK`` (an open of a FIFO never
waits), and checked again with ``fstat`` on what was opened (the name may have been swapped in
between): anything but a regular file is one line naming the file, exit 2. Its size (``st_size``)
is then compared with the bound of its kind before a byte is read (`regular_size`).
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

__all__ = ["regular_size", "open_regular", "kind_of", "printable"]

# Control characters (C0 but newline and tab, DEL, C1) and the bidirectional overrides, which
# would drive the terminal that prints them (an escape sequence sets its title).
_UNSAFE = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def printable(text: str) -> str:
    """``text`` with its control characters written as escapes (``\\x1b``), newlines (``\\r\\n``
    made ``\\n``) and tabs kept: text read from a file, made safe to print and draw where it is read
    (a station's name, a hazard curve's kind, a result file's attributes)."""
    text = text.replace("\r\n", "\n")          # a file written on Windows: its line ends, not a control
    return _UNSAFE.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text)


def kind_of(mode: int) -> str:
    """What a file of ``mode`` (``st_mode``) is, in words (for messages)."""
    for test, word in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return word
    return "not a regular file"


def _refuse(mode: int, what: str, error, source: str):
    if stat.S_ISDIR(mode):
        return error(f"is a folder, expected a {what}", source=source)
    return error(f"is {kind_of(mode)}, not a regular file; expected a {what} (rockslide reads only "
                 "regular files: a pipe or device could block it or never end)", source=source)


def regular_size(path, *, what: str, error, limit: int | None = None, bound_text: str = "") -> int:
    """The size [bytes] of ``path`` if it is a regular file (links followed) of at most ``limit``
    bytes; else ``error`` (a `errors.RockslideError` class) with one line naming ``path``.

    Parameters
    ----------
    path : str or Path
    what : str
        What the file should be ("case file", "record file", "result file").
    error : type
        The exception raised.
    limit : int, optional
        The largest size accepted [bytes].
    bound_text : str
        How to change the bound, appended to the message (an option), if it can be changed.

    Raises
    ------
    error
        Not found, not a regular file (folder, FIFO, device, socket), or larger than ``limit``.
    """
    source = str(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise error(f"{what} not found", source=source) from None
    except OSError as exc:
        raise error(f"cannot read the {what}: {exc.strerror or exc}", source=source) from None
    if not stat.S_ISREG(info.st_mode):
        raise _refuse(info.st_mode, what, error, source)
    if limit is not None and info.st_size > limit:
        raise error(f"the {what} has {info.st_size} bytes; rockslide reads at most {limit} "
                    f"(about {limit / 1e6:.3g} MB){bound_text}", source=source)
    return info.st_size


def open_regular(path, *, what: str, error, limit: int | None = None, bound_text: str = ""):
    """Open ``path`` for reading in binary mode if it is a regular file within ``limit`` bytes
    (`regular_size`), checked again on the open file (``fstat``): a binary file object.

    Raises
    ------
    error
        As `regular_size`, or the file cannot be opened (permission denied...).
    """
    regular_size(path, what=what, error=error, limit=limit, bound_text=bound_text)
    source = str(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(Path(path), flags)
    except PermissionError:
        raise error(f"cannot read the {what}: permission denied", source=source) from None
    except OSError as exc:
        raise error(f"cannot read the {what}: {exc.strerror or exc}", source=source) from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode) or (limit is not None and info.st_size > limit):
        os.close(fd)
        regular_size(path, what=what, error=error, limit=limit, bound_text=bound_text)   # says why
        raise _refuse(info.st_mode, what, error, source)           # swapped back meanwhile
    if hasattr(os, "set_blocking"):
        os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")
