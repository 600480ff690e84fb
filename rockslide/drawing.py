"""A run's figure drawn by a helper process that imports matplotlib while the run computes.

A warm ``rockslide run`` of the example spends about 0.3 s importing matplotlib and 0.4 s drawing,
next to about 0.35 s for everything else (imports, records, the kernel, the HDF5 file), one after
the other on one core. `FigureProcess` forks when ``run`` starts: the child imports `plots` at
once, on the second core, then waits for the result, draws it and sends the PNG's bytes back; the
parent computes meanwhile and writes the bytes like any output (staged, atomic, `files`).

The child is only a head start, never a second way of drawing:
- it runs the same `plots.response_figure` and `plots.render_png` on the same result, so the PNG is
  the same to the byte (tested);
- it writes no file and prints nothing (its standard streams go to ``/dev/null``);
- whatever goes wrong in it (killed, an exception in matplotlib, a broken pipe, a truncated reply)
  makes `FigureProcess.png` return None, and the caller draws in its own process as before, with
  the same errors;
- it dies with Ctrl-C (the default action of SIGINT, as the whole foreground group gets it); the
  parent kills it when it leaves the ``with`` block for any reason; if the parent is killed
  outright, the child reads the end of its input and exits.

It forks only on Linux, with at least two cores for this process, and in a process with a single
thread (`available`): there a fork is cheap and safe. Elsewhere the figure is drawn in-process.
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
import sys

__all__ = ["FigureProcess", "available"]

_LENGTH = struct.Struct(">Q")        # the reply: the PNG's length, then its bytes


def available() -> bool:
    """Whether a helper process can be forked here: Linux, at least two cores this process may
    use, and no thread but the main one (a fork copies only the calling thread; locks held by
    others would stay held in the child)."""
    if sys.platform != "linux":
        return False
    try:
        return len(os.sched_getaffinity(0)) >= 2 and len(os.listdir("/proc/self/task")) == 1
    except OSError:
        return False


class FigureProcess:
    """``with FigureProcess(wanted) as helper: ... helper.png(result, name, dpi=...)``.

    Forks on entry if ``wanted`` and `available`; otherwise does nothing and `png` returns None.
    """

    def __init__(self, wanted: bool = True):
        self.wanted = wanted
        self.pid = None
        self._job = None          # write end: the result to draw
        self._reply = None        # read end: the PNG

    def __enter__(self) -> FigureProcess:
        if not (self.wanted and available()):
            return self
        job_read, job_write = os.pipe()
        reply_read, reply_write = os.pipe()
        pid = os.fork()
        if pid == 0:                                         # the child
            try:
                os.close(job_write)
                os.close(reply_read)
                _serve(job_read, reply_write)
            finally:
                os._exit(0)                                  # no exit handlers, no flush of the parent's buffers
        os.close(job_read)
        os.close(reply_write)
        self.pid, self._job, self._reply = pid, job_write, reply_read
        return self

    def png(self, result, name: str, *, dpi=None, **options) -> bytes | None:
        """The PNG of `plots.response_figure` ``(result, title=name, **options)`` at ``dpi``, drawn
        by the child; None if there is no child or it did not deliver (draw it in-process then)."""
        if self.pid is None or self._job is None:
            return None
        try:
            with os.fdopen(self._job, "wb") as pipe:
                self._job = None
                pickle.dump((result, name, dpi, options), pipe, protocol=pickle.HIGHEST_PROTOCOL)
            with os.fdopen(self._reply, "rb") as pipe:
                self._reply = None
                head = pipe.read(_LENGTH.size)
                if len(head) != _LENGTH.size:
                    return None
                data = pipe.read(_LENGTH.unpack(head)[0] + 1)
        except OSError:                                      # the child is gone (broken pipe)
            return None
        expected = _LENGTH.unpack(head)[0]
        return data if len(data) == expected else None

    def __exit__(self, *exc) -> bool:
        for fd in (self._job, self._reply):
            if fd is not None:
                os.close(fd)
        self._job = self._reply = None
        if self.pid is not None:
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            os.waitpid(self.pid, 0)
            self.pid = None
        return False


def _serve(job_fd: int, reply_fd: int) -> None:
    """The child: import `plots`, read one job, reply with the PNG. Any failure ends it quietly
    (the parent then draws in-process)."""
    try:
        for signum in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(signum) != signal.SIG_IGN:       # ignored by the run's parent: stays so
                signal.signal(signum, signal.SIG_DFL)
        quiet = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(quiet, fd)
        from . import plots  # the head start: ~0.3 s on 2 cores

        with os.fdopen(job_fd, "rb") as pipe:
            result, name, dpi, options = pickle.load(pipe)
        data = plots.render_png(plots.response_figure(result, title=name, **options), dpi=dpi)
        with os.fdopen(reply_fd, "wb") as pipe:
            pipe.write(_LENGTH.pack(len(data)))
            pipe.write(data)
    except BaseException:        # noqa: BLE001 - the parent draws instead; nothing to report here
        pass
