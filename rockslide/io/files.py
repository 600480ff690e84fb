"""Output files that are never half-written, never mixed, never clobbered.

- **Atomic.** A file is written to a temporary file beside it, synced, and renamed onto its name,
  so a crash, a kill or Ctrl-C leaves the previous file or none. Temporary files are named
  ``.NAME.<pid>.<place>.tmp`` (``place``: a number for this host, boot and pid namespace; a thread
  id is added when threads write at once): they start with ``.`` and end in ``.tmp``. Their owner
  holds a ``flock`` on each for its whole life. A process killed outright may leave one behind,
  never a half-written ``NAME``, and the next run of the same output removes those whose lock is
  free (`remove_stale_temporaries`: a pid alone means nothing in another container).
- **Exclusive.** Without ``overwrite``, a file is published with a hard link that fails if the name
  exists (not a check followed by a rename), so that of two runs writing the same name at once one
  wins and the other is refused, whatever the timing. Where the file system has no hard links the
  check-then-rename remains.
- **Together.** A result made of several files (``NAME.h5`` and ``NAME.png``) is staged
  (`Staging`): every file is written to its temporary first, then all are renamed in one short
  section that signals do not interrupt (`interrupts.critical`) and that other rockslide
  processes publishing in the same folder wait for (an advisory lock on the folder, POSIX), with
  stale companions removed in the same section. Ctrl-C or an error before that section leaves the
  previous set untouched.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import platform
import re
import stat
import threading
import zlib
from pathlib import Path

from .. import interrupts
from ..errors import OutputError

#: Longest file name most file systems take [bytes].
NAME_MAX = 255
#: Longest path the system takes [bytes] (Linux's PATH_MAX).
PATH_MAX = 4096
#: Room a temporary name needs beyond its file's name: ``.`` + ``.<pid>.<place>.<thread id>.tmp``.
TEMPORARY_EXTRA = 1 + 1 + 7 + 1 + 10 + 1 + 20 + 4


def check_destination(path, *, overwrite: bool = False, example: str = "out/case.h5") -> Path:
    """Refuse an existing ``path`` unless ``overwrite``; create its folder if missing.

    Call it before any long computation, so that a run is not wasted on a result it may not write.

    Raises
    ------
    OutputError
        ``path`` exists and ``overwrite`` is false, ``path`` is a folder, its name is too long or
        holds a NUL character, or its folder cannot be created.
    """
    path = Path(path)
    check_name(path)
    if path.is_dir():
        raise OutputError(f"is a folder; expected a file name such as {example}", source=str(path))
    refuse_existing(path, overwrite)
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        if not folder.exists():                       # else: not a folder, said below
            raise OutputError(f"cannot create the output folder: {exc.strerror or exc}",
                              source=str(folder)) from None
    if not folder.is_dir():
        raise OutputError("cannot create the output folder: something that is not a folder has that name",
                          source=str(folder))
    return path


def check_writable(path) -> None:
    """Refuse an output ``path`` whose folder takes no new file (no permission, a read-only file
    system, no room for a name), by creating and removing an empty temporary file there: for a
    result written after its computation, so that the refusal comes before it.

    Raises
    ------
    OutputError
        The temporary file cannot be created.
    """
    tmp = temporary_path(path)
    try:
        open_new(tmp).close()
    except OSError as exc:
        raise cannot_write_in_folder(path, exc) from None
    remove_quietly(tmp)


def cannot_write_in_folder(path, exc: OSError) -> OutputError:
    """The refusal of a new file beside ``path`` (``exc``: the system's), naming the folder."""
    return OutputError(f"cannot write in this folder ({error_reason(exc)})", source=str(Path(path).parent))


def error_reason(exc: BaseException) -> str:
    """The system's reason for ``exc`` on one line: its ``strerror``, else its text, else its type."""
    text = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
    return " ".join(str(text).split())


def check_name(path: Path) -> None:
    """Refuse a path the file system cannot take: a NUL character, or a name (or one of the
    folder names) that would be too long once made a temporary name."""
    text = str(path)
    if "\x00" in text:
        raise OutputError("the path holds a NUL character; expected a file or folder name",
                          source=text.replace("\x00", "\\x00"))
    for part in path.parts[:-1]:
        if len(os.fsencode(part)) > NAME_MAX:
            raise OutputError(f"a folder name of {len(os.fsencode(part))} bytes; file systems take at "
                              f"most {NAME_MAX}", source=_short(text))
    whole = len(os.fsencode(os.path.abspath(text))) + TEMPORARY_EXTRA
    if whole > PATH_MAX:
        raise OutputError(f"a path of {whole - TEMPORARY_EXTRA} bytes (once absolute); expected at most "
                          f"{PATH_MAX - TEMPORARY_EXTRA} (the system's {PATH_MAX} less room for the temporary "
                          "name): choose a shorter output folder", source=_short(text))
    longest = NAME_MAX - TEMPORARY_EXTRA
    if len(os.fsencode(path.name)) > longest:
        raise OutputError(f"a file name of {len(os.fsencode(path.name))} bytes; expected at most {longest} "
                          f"(the file system's {NAME_MAX} less room for the temporary name)",
                          source=_short(text))


class OutputWarning(UserWarning):
    """An output location that may not take the result (little free space)."""


def free_space(folder) -> int | None:
    """Bytes free for this user in ``folder`` (None if it cannot be told)."""
    import shutil

    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


#: Bytes of one history row of a result file before compression (five float64 columns and the int8
#: state): an upper bound of the size of a result, used to warn when the disk may be too small.
BYTES_PER_ROW = 5 * 8 + 1


def warn_free_space(folder, needed: float) -> None:
    """Warn when ``folder`` has less free space than ``needed`` bytes (an upper bound of what the
    result takes before compression); a disk that fills up is still an error at the write."""
    import warnings

    free = free_space(folder)
    if free is not None and free < needed:
        warnings.warn(f"{folder}: {free / 1e6:.3g} MB free, and the result may need up to "
                      f"{needed / 1e6:.3g} MB (less once compressed); a full disk stops the run with "
                      "nothing written", OutputWarning, stacklevel=2)


def require_free_space(folder, needed: float, what: str) -> None:
    """Refuse to start when ``folder`` has less free space than ``needed`` bytes (a size known in
    advance, such as a sweep's)."""
    free = free_space(folder)
    if free is not None and free < needed:
        raise OutputError(f"{free / 1e6:.3g} MB free; {what} needs about {needed / 1e6:.3g} MB; free some "
                          "space or choose another output folder", source=str(folder))


def refuse_existing(path: Path, overwrite: bool) -> None:
    if not overwrite and (path.exists() or path.is_symlink()):
        raise OutputError(f"{path} exists (use --overwrite to replace it)")


def expand_user(path, *, source: str) -> Path:
    """``path`` with a leading ``~`` or ``~user`` expanded, or a one-line `OutputError` naming
    ``source`` (the option, variable or key that gave it) when there is no such home folder."""
    try:
        return Path(path).expanduser()
    except RuntimeError:
        raise OutputError(f"{str(path).split('/', 1)[0]!r} names no user's home folder here", source=source) from None


def open_new(path, mode: str = "wb", *, buffering: int = -1):
    """Create ``path`` for writing as a new regular file of this process, never through a link and
    never into an existing file (``O_CREAT | O_EXCL | O_NOFOLLOW``): in an output folder that others
    can write, a link planted at the predictable name of a temporary file cannot redirect
    rockslide's writes to another file. Whatever stands at the name (a planted link, the leftover of
    a process that had this pid) is unlinked first, which removes a link, never its target; a name
    that keeps being taken is an OSError.
    """
    flags = os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    flags |= os.O_RDWR if "+" in mode else os.O_WRONLY
    for attempt in range(3):
        try:
            fd = os.open(path, flags, 0o666)
        except FileExistsError:
            if attempt == 2:
                raise
            os.unlink(path)
            continue
        if _own(path, fd):
            break
        os.close(fd)                            # a cleaner removed it before it was locked: again
    else:  # pragma: no cover - three cleaners in a row
        raise FileExistsError(errno.EEXIST, "cannot keep a temporary file", str(path))
    return os.fdopen(fd, mode, buffering=buffering)


_owned: dict[str, int] = {}     # temporary file -> a descriptor holding its flock, for its life
_owned_guard = threading.Lock()


def _own(path, fd: int) -> bool:
    """Hold an exclusive ``flock`` on the new file ``path`` (open as ``fd``) until `release`: the
    mark of a live owner that `remove_stale_temporaries` respects, whatever the pid namespace or
    host. False if a cleaner removed the file before the lock was taken (the caller makes it
    again); True, with nothing held, where locks are unavailable."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        return True
    held = os.dup(fd)                           # the lock lives while this descriptor is open
    try:
        fcntl.flock(held, fcntl.LOCK_EX)        # a cleaner holds it only to unlink, at once
    except OSError:                             # no locks on this file system: pids only
        os.close(held)
        return True
    try:
        same = os.stat(path, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
    except OSError:
        same = False
    if not same:
        os.close(held)
        return False
    with _owned_guard:
        previous = _owned.pop(str(path), None)
        _owned[str(path)] = held
    if previous is not None:
        os.close(previous)
    return True


def release(path) -> None:
    """Give up the lock that marks the temporary file ``path`` as this process's (after it was
    renamed into place or deleted)."""
    with _owned_guard:
        held = _owned.pop(str(path), None)
    if held is not None:
        os.close(held)


def temporary_path(path, *, per_thread: bool = False) -> Path:
    """The temporary file ``path`` is written to before it is renamed onto it."""
    path = Path(path)
    thread = f".{threading.get_ident()}" if per_thread else ""
    return path.with_name(f".{path.name}.{os.getpid()}.{place_token()}{thread}.tmp")


@functools.cache
def place_token() -> int:
    """A number for this host, boot and pid namespace (CRC-32 of the host name, the kernel's boot
    id and the pid namespace's inode), written in temporary names beside the pid: a pid means
    nothing in another container or on another host sharing the folder."""
    parts = [platform.node()]
    for read in (lambda: Path("/proc/sys/kernel/random/boot_id").read_text().strip(),
                 lambda: str(os.stat("/proc/self/ns/pid").st_ino)):
        try:
            parts.append(read())
        except OSError:
            parts.append("")
    return zlib.crc32("/".join(parts).encode())


def publish(tmp: Path, path: Path, *, overwrite: bool, interruptible: bool = True, sync: bool = True) -> None:
    """Sync ``tmp`` to disk (unless not ``sync``) and rename it onto ``path`` (atomic on POSIX and
    Windows).

    Raises `interrupts.Interrupted` after Ctrl-C or SIGTERM (unless not ``interruptible``: work
    to keep, such as a finished sweep chunk), and OutputError if ``path`` exists (or appeared
    meanwhile) and ``overwrite`` is false; ``tmp`` is deleted in both cases.
    """
    staging = Staging(overwrite=overwrite)
    staging.add(tmp, path)
    staging.publish(interruptible=interruptible, sync=sync)


class Staging:
    """Files written to temporaries and published together (see the module docstring).

    Parameters
    ----------
    overwrite : bool
        Replace existing files; without it a file that exists is an `OutputError` and nothing of
        the set is published.

    Notes
    -----
    ::

        with Staging(overwrite=False) as staging:
            write(staging.stage(h5_path)); write(staging.stage(png_path))
            staging.publish(remove=[stale_png])

    Leaving the block without `publish` (an exception, Ctrl-C) deletes the temporary files.
    """

    def __init__(self, *, overwrite: bool):
        self.overwrite = overwrite
        self.items: list[tuple[Path, Path]] = []
        self.published = False

    def __enter__(self) -> Staging:
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if not self.published:
            self.discard()
        return False

    def stage(self, path, *, per_thread: bool = False) -> Path:
        """Register ``path`` and return the temporary file to write it to."""
        path = Path(path)
        tmp = temporary_path(path, per_thread=per_thread)
        self.items.append((tmp, path))
        return tmp

    def add(self, tmp: Path, path: Path) -> None:
        """Register an already written temporary file ``tmp`` for ``path``."""
        self.items.append((Path(tmp), Path(path)))

    def discard(self) -> None:
        """Delete the temporary files (nothing is published)."""
        for tmp, _ in self.items:
            remove_quietly(tmp)

    def publish(self, *, remove=(), interruptible: bool = True, sync: bool = True, verify=None) -> list[Path]:
        """Sync every temporary file (unless not ``sync``), then rename them all onto their names
        and delete the files in ``remove`` (stale companions of an earlier result), in one section
        (module docstring). ``verify``, if given, is called first in that section and may raise to
        publish nothing (`Unchanged`: the file a figure was drawn from is still the one read).

        Raises
        ------
        Interrupted
            Ctrl-C or SIGTERM came before the section (and ``interruptible``): nothing was
            published.
        OutputError
            A file exists (without ``overwrite``): nothing of the set was published; or a
            temporary file cannot be synced or renamed.
        """
        try:
            if interruptible:
                interrupts.check()
            if sync:
                for tmp, _ in self.items:
                    fsync_file(tmp)
            folders = sorted({path.parent for _, path in self.items} | {Path(p).parent for p in remove})
            with folder_locks(folders), interrupts.critical():
                if verify is not None:
                    verify()                    # under the lock: no set is published meanwhile
                if self.overwrite:
                    for tmp, path in self.items:
                        os.replace(tmp, path)
                    for stale in remove:
                        remove_quietly(Path(stale))
                else:
                    self._link_all()
        except OSError as exc:
            raise OutputError(f"cannot publish the file: {exc.strerror or exc}",
                              source=str(exc.filename or self.items[0][1])) from None
        finally:
            self.discard()                      # temporaries left by a failure, or the linked ones
        self.published = True
        if sync:
            for folder in {path.parent for _, path in self.items}:
                fsync_folder(folder)
        return [path for _, path in self.items]

    def _link_all(self) -> None:
        """Create every name exclusively (a hard link fails if the name exists); on a name that
        exists, undo the links made so far and refuse."""
        done: list[Path] = []
        for tmp, path in self.items:
            try:
                _create_exclusively(tmp, path)
            except FileExistsError:
                for made in done:
                    remove_quietly(made)
                raise OutputError(f"{path} exists (use --overwrite to replace it)") from None
            done.append(path)


def _create_exclusively(tmp: Path, path: Path) -> None:
    """Give ``tmp``'s content the name ``path`` unless ``path`` exists (FileExistsError)."""
    try:
        os.link(tmp, path)
        return
    except FileExistsError:
        raise
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EXDEV, errno.EMLINK,
                             errno.ENOSYS, errno.EACCES):
            raise
    if os.path.lexists(path):                   # no hard links here: check, then rename
        raise FileExistsError(errno.EEXIST, "File exists", str(path))
    os.replace(tmp, path)


#: Pause between two attempts to take a lock held by another process [s]: Ctrl-C and SIGTERM are
#: acted on between attempts (`interrupts.check`).
LOCK_RETRY = 0.05


def _say_waiting(what: str) -> None:
    import sys

    try:
        print(f"rockslide: note: waiting for {what} (Ctrl-C stops)", file=sys.stderr, flush=True)
    except (OSError, ValueError):  # pragma: no cover - stderr gone
        pass


def lock_interruptibly(fd: int, *, shared: bool = False, waiting_for: str) -> bool:
    """Take ``flock`` on ``fd`` (exclusive, or ``shared``), waiting as long as another process holds
    it, but never in a call that signals cannot cut short: a non-blocking attempt every
    `LOCK_RETRY` s, with Ctrl-C and SIGTERM acted on in between (`interrupts.check`; a
    KeyboardInterrupt where no handler is installed), and one note on stderr naming
    ``waiting_for`` the first time it has to wait. Returns whether it waited. An OSError where
    locks are not supported."""
    import fcntl
    import time

    mode = (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB
    said = False
    while True:
        try:
            fcntl.flock(fd, mode)
            return said
        except BlockingIOError:
            pass
        if not said:
            holder = _lock_holder(fd)
            _say_waiting(waiting_for if holder is None else f"{waiting_for}, process {holder}")
            said = True
        interrupts.check()
        time.sleep(LOCK_RETRY)
        interrupts.check()


def _lock_holder(fd: int) -> int | None:
    """The pid that ``/proc/locks`` gives for a FLOCK on ``fd``'s file (Linux), or None."""
    info = os.fstat(fd)
    wanted = f"{os.major(info.st_dev):02x}:{os.minor(info.st_dev):02x}:{info.st_ino}"
    try:
        with open("/proc/locks", encoding="ascii", errors="replace") as table:
            for line in table:
                fields = line.split()
                if len(fields) > 5 and fields[1] == "FLOCK" and fields[5] == wanted and fields[4].isdigit():
                    return int(fields[4]) or None
    except OSError:
        pass
    return None


@contextlib.contextmanager
def folder_locks(folders, *, shared: bool = False):
    """An advisory lock on each folder (POSIX ``flock``; exclusive, or ``shared`` for readers) while
    a set is renamed (or read and drawn by ``rockslide plot``), so that the sets of two rockslide
    processes are not interleaved; nothing where locks are unavailable. Waiting for another
    process is interruptible (`lock_interruptibly`)."""
    try:
        import fcntl  # noqa: F401
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    fds, held = [], []
    try:
        for folder in folders:
            if not shared:              # threads of this process queue here: flock would keep them apart as
                lock = _thread_lock(folder)                     # if they were processes, 50 ms at a time
                while not lock.acquire(timeout=LOCK_RETRY):
                    interrupts.check()
                held.append(lock)
            try:
                fd = os.open(folder, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
            except OSError:
                continue
            try:
                lock_interruptibly(fd, shared=shared,
                                   waiting_for=f"another process publishing in {folder} (it holds the "
                                               "folder's lock)")
            except OSError:
                os.close(fd)
                continue
            except BaseException:
                os.close(fd)
                raise
            fds.append(fd)
        yield
    finally:
        for fd in fds:
            os.close(fd)                        # closing releases the lock
        for lock in held:
            lock.release()


_THREAD_LOCKS: dict[str, threading.Lock] = {}
_THREAD_LOCKS_GUARD = threading.Lock()


def _thread_lock(folder) -> threading.Lock:
    """This process's lock of ``folder`` (`folder_locks`): its threads publish one at a time."""
    with _THREAD_LOCKS_GUARD:
        return _THREAD_LOCKS.setdefault(os.path.abspath(folder), threading.Lock())


@contextlib.contextmanager
def exclusive(lock_path, *, waiting_for: str, waited=None, shared: bool = False):
    """Hold an exclusive ``flock`` on the file ``lock_path`` (created if missing, never through a
    link) for the ``with`` block, waiting interruptibly for another process that holds it
    (`lock_interruptibly`, saying once that it waits for ``waiting_for``); the file is deleted when
    the block ends. Two sweeps (or fragility analyses) of one result file run one after the other
    this way: they share its chunk folder. A waiter that gets the lock of a file deleted meanwhile
    takes the new one (the inode at the name is checked). ``waited`` is called (with no argument)
    if another process held it. Nothing where locks are unavailable. ``shared``: a lock that others
    holding it ``shared`` too do not wait for (the shards of one study), that an exclusive holder
    waits for, and that is left in place at the end (another shard may still hold it). A link or
    anything but a file at ``lock_path`` is refused: a lock that is not taken would let two studies
    share, and remove, one chunk folder."""
    try:
        import fcntl  # noqa: F401
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    while True:
        try:
            fd = os.open(lock_path, flags, 0o666)
        except OSError as exc:
            if exc.errno in (errno.ELOOP, errno.EISDIR) or os.path.islink(lock_path):
                raise OutputError("is a link or a folder where rockslide keeps a study's lock file; remove it "
                                  "(rockslide never follows a link at a name it makes)",
                                  source=str(lock_path)) from None
            yield                                # cannot be made here: nothing to hold
            return
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):      # (closed below, as after any error)
                raise OutputError("is not a plain file where rockslide keeps a study's lock file; remove it",
                                  source=str(lock_path))
            if lock_interruptibly(fd, shared=shared, waiting_for=waiting_for) and waited is not None:
                waited()
            same = os.stat(lock_path, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        except OSError:                          # no locks on this file system
            os.close(fd)
            yield
            return
        except BaseException:
            os.close(fd)
            raise
        if same:
            break
        os.close(fd)                             # deleted by its holder meanwhile: the next one
    try:
        yield
    finally:
        if not shared:
            try:
                os.unlink(lock_path)             # while it is held: a waiter then takes a new one
            except OSError:
                pass
        os.close(fd)


class Unchanged:
    """The identity of a file read (device, inode, size, modification time), to check before a
    file derived from it is published: ``rockslide plot`` must not publish a figure of a result
    that a run replaced while it was drawn (`Staging.publish`'s ``verify``)."""

    def __init__(self, path):
        self.path = Path(path)
        self.stamp = self._stamp()

    def _stamp(self):
        try:
            info = os.stat(self.path)
        except OSError:
            return None
        return info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns

    def __call__(self) -> None:
        """Raise an `OutputError` if the file is no longer the one read."""
        if self._stamp() != self.stamp:
            raise OutputError("was replaced while its figure was drawn (another run published a new result); "
                              "nothing was written: run the command again", source=str(self.path))


@contextlib.contextmanager
def atomic_write(path, *, overwrite: bool, mode: str = "wb", per_thread: bool = False, what: str = "file",
                 staging: Staging | None = None, interruptible: bool = True, sync: bool = True):
    """Open a temporary file for writing; on success publish it onto ``path`` (or leave it to
    ``staging`` to publish with the rest of a set), on any exception delete it. OSErrors while
    writing become one-line OutputErrors naming ``path``. After Ctrl-C or SIGTERM nothing is
    written (`interrupts.Interrupted`), unless not ``interruptible`` (work to keep). Not ``sync``:
    the file is not forced to disk before the rename (for files whose damage by a power cut is
    detected when they are read, such as checksummed sweep chunks)."""
    path = Path(path)
    tmp = staging.stage(path, per_thread=per_thread) if staging is not None else \
        temporary_path(path, per_thread=per_thread)
    try:
        if interruptible:
            interrupts.check()
        try:
            with open_new(tmp, mode) as handle:
                yield handle
        except OSError as exc:
            raise OutputError(f"cannot write the {what}: {exc.strerror or exc}", source=str(path)) from None
        if staging is None:
            publish(tmp, path, overwrite=overwrite, interruptible=interruptible, sync=sync)
    except BaseException:
        remove_quietly(tmp)
        raise


_TEMPORARY = re.compile(r"\.(?P<pid>\d+)(?:\.(?P<place>\d+))?(?:\.\d+)?\.tmp")     # after ``.NAME``


def remove_stale_temporaries(paths) -> list[Path]:
    """Delete the temporary files of ``paths`` (``.NAME.<pid>[.<place>][.<thread>].tmp`` beside
    each) that no live process owns (a SIGKILL, a power cut left them), and return them.

    A temporary file's owner holds an exclusive ``flock`` on it for its whole life (`open_new`), so
    a file is removed only when that lock can be taken: the test works across pid namespaces
    (containers) on one host and, where the file system passes locks on (NFS with its lock
    manager), across hosts; a pid, which means nothing in another namespace, decides nothing. Where
    the file system has no locks, a file is removed only if it names this host, boot and pid
    namespace (`place_token`) and a pid that no longer runs. Only files of these names, only
    regular files, never through a link.
    """
    if os.name != "posix":  # pragma: no cover - no harmless way to tell an owner
        return []
    removed = []
    for path in paths:
        path = Path(path)
        try:
            candidates = list(path.parent.glob(f".{glob_escape(path.name)}.*.tmp"))
        except OSError:
            continue
        for candidate in candidates:
            match = _TEMPORARY.fullmatch(candidate.name[len(path.name) + 1:])
            if match and _remove_if_unowned(candidate, match):
                removed.append(candidate)
    return removed


def _remove_if_unowned(candidate: Path, match) -> bool:
    """Delete ``candidate`` if no live process holds its lock (see `remove_stale_temporaries`)."""
    import fcntl
    import stat

    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(candidate, flags)
    except OSError:
        return False                            # gone, a link, or not ours to read
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            return False
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False                        # its owner runs (here or in another namespace)
        except OSError:                         # no locks here: only a pid of this namespace
            pid, place = int(match["pid"]), match["place"]
            if place is None or int(place) != place_token() or pid == os.getpid() or _running(pid):
                return False
        if os.stat(candidate, follow_symlinks=False).st_ino != info.st_ino:
            return False                        # replaced meanwhile
        os.unlink(candidate)                    # with its lock held: no owner can take it now
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


def glob_escape(name: str) -> str:
    """``name`` with the glob characters ``*?[`` taken literally."""
    return re.sub(r"([*?\[])", r"[\1]", name)


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:                             # EPERM: it runs, as another user
        return True
    return True


def remove_quietly(path: Path) -> None:
    """Delete ``path`` if it exists (best effort: a leftover is named as one), and give up the lock
    that marked it as this process's temporary file (`release`)."""
    try:
        os.unlink(path)
    except OSError:
        pass
    release(path)


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


def _short(text: str, limit: int = 120) -> str:
    """A long path shortened in the middle, for messages."""
    return text if len(text) <= limit else f"{text[:limit // 2 - 2]}...{text[-(limit // 2 - 1):]}"
