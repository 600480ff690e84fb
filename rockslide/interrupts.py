"""Ctrl-C and SIGTERM as a flag, checked where stopping is safe.

A Python signal handler that raises lands wherever the interpreter happens to be, for instance
inside a weakref callback of h5py, which swallows the exception ("Exception ignored in: ...") and
lets the run go on. So the handlers installed by `handling_signals` only record the signal, and
the code calls `check` where stopping is safe: between kernel chunks (`simulate`'s ``progress``
callback), between the chunk groups of a sweep, and before every write and every publication of
a file (`files.publish`). `check` raises `Interrupted`, a `KeyboardInterrupt`, so that the
``except BaseException`` clean-ups delete temporary files on the way out; the command line turns
it into exit code 130 (SIGINT) or 143 (SIGTERM).

A second signal while the first is still pending (a run stuck in a long call that cannot be
checked, such as the first compilation of the kernel) ends the process at once with the default
action of that signal, except while a set of files is being renamed into place (`critical`).
The previous result is then intact as well (files are only ever renamed into place); temporary
files it leaves are removed by the next run of the same output (`files.remove_stale_temporaries`).
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading

__all__ = ["Interrupted", "handling_signals", "check", "requested", "critical"]

#: Signals handled, with the exit code of a command they stop (128 + the signal's number).
HANDLED = tuple(s for s in (getattr(signal, "SIGINT", None), getattr(signal, "SIGTERM", None)) if s)

_pending: list[int] = []      # signals received and not yet acted on (first one counts)
_critical = 0                 # depth of `critical` sections (renames that must not be cut short)


class Interrupted(KeyboardInterrupt):
    """Raised by `check` after SIGINT or SIGTERM.

    Attributes
    ----------
    signum : int
        The signal received first.
    """

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        """130 for SIGINT, 143 for SIGTERM (128 + the signal's number, as shells report it)."""
        return 128 + int(self.signum)

    @property
    def word(self) -> str:
        """``interrupted`` (Ctrl-C) or ``terminated`` (SIGTERM)."""
        return "terminated" if self.signum == getattr(signal, "SIGTERM", None) else "interrupted"


def _record(signum, frame) -> None:
    """The signal handler: remember the signal, never raise (see the module docstring)."""
    if _pending and not _critical:
        signal.signal(signum, signal.SIG_DFL)          # a second signal: stop now, by the signal
        os.kill(os.getpid(), signum)
        return
    _pending.append(signum)


@contextlib.contextmanager
def handling_signals():
    """Install the recording handlers for SIGINT and SIGTERM (main thread only; elsewhere, where
    signals cannot be set, and for a signal ignored by the parent process, nothing changes), and
    restore the previous ones afterwards."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    try:
        for signum in HANDLED:
            if signal.getsignal(signum) == signal.SIG_IGN:
                continue                        # ignored by whoever started us (a background job)
            try:
                previous[signum] = signal.signal(signum, _record)
            except (OSError, ValueError):  # pragma: no cover - a platform without it
                pass
        _pending.clear()
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        _pending.clear()


def requested() -> int | None:
    """The signal received and not yet acted on, or None."""
    return _pending[0] if _pending else None


def check() -> None:
    """Raise `Interrupted` if SIGINT or SIGTERM was received."""
    if _pending:
        raise Interrupted(_pending[0])


@contextlib.contextmanager
def critical():
    """A short section that a second signal does not cut short (renaming a set of files)."""
    global _critical
    _critical += 1
    try:
        yield
    finally:
        _critical -= 1
