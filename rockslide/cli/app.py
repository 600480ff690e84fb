"""The command line: a thin click layer over the library.

Every `RockslideError` (bad case, record, option or output) becomes one line on stderr,
``rockslide: error: <file>: <field>: <what is wrong and what is expected>``, and exit code 2, here
and nowhere else; so do click's usage errors. ``--debug`` shows the traceback instead. Any other
exception is a bug: one line ``rockslide: internal error: ...`` and exit code 1. Messages are one
readable line: control characters escaped, at most :data:`MESSAGE_LIMIT` characters.

Ctrl-C and SIGTERM only set a flag (`interrupts`), checked between kernel chunks, between sweep
chunks and before every write; the command then ends with exit code 130 (143) and the previous
result intact, since results are published only once complete (`files`).
"""

from __future__ import annotations

import atexit
import errno
import gc
import os
import signal
import sys
import threading
import warnings
from pathlib import Path

import click

from .. import interrupts
from .._version import __version__
from ..errors import RockslideError

EXIT_INTERNAL_ERROR = 1
EXIT_USER_ERROR = 2
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143
EXIT_BROKEN_PIPE = 141      # 128 + SIGPIPE: what a Unix tool whose reader went away exits with
#: Longest message printed [characters]; a longer one keeps its start and its end.
MESSAGE_LIMIT = 400


#: click >= 8.2 raises this (a UsageError) for a group called without a command.
_NO_ARGS_IS_HELP = getattr(click.exceptions, "NoArgsIsHelpError", ())


class RockslideGroup(click.Group):
    """Turns the one exception family, click's usage errors and signals into messages, once;
    takes ``--debug`` anywhere."""

    def parse_args(self, ctx, args):
        # --debug is the group's option, but a user adds it to the command that failed: move it
        # before the command (not past a "--", after which everything is an argument)
        end = args.index("--") if "--" in args else len(args)
        if "--debug" in args[1:end]:
            args = ["--debug"] + [a for a in args[:end] if a != "--debug"] + args[end:]
        return super().parse_args(ctx, args)

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            with interrupts.handling_signals():
                code = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except _NO_ARGS_IS_HELP as exc:       # `rockslide` alone: the help, as click shows it
            exc.show()
            sys.exit(exc.exit_code)
        except click.UsageError as exc:
            words = exc.ctx.command_path.split()[1:] if exc.ctx is not None else []
            command = " ".join(["rockslide", *words])
            click.echo(one_line(f"rockslide: error: {command}: {exc.format_message()} "
                                f"(see '{command} --help')"), err=True)
            sys.exit(exc.exit_code)
        except click.ClickException as exc:
            click.echo(one_line(f"rockslide: error: {exc.format_message()}"), err=True)
            sys.exit(exc.exit_code)
        except click.Abort:
            click.echo("rockslide: interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)
        sys.exit(code if isinstance(code, int) else 0)

    def invoke(self, ctx):
        given = sys.argv[1:]
        given = given[:given.index("--")] if "--" in given else given    # after "--", "--debug" is an argument
        debug = "--debug" in given or bool(ctx.params.get("debug"))
        with warnings.catch_warnings():
            warnings.showwarning = _hold_warning
            _held.clear()
            try:
                value = super().invoke(ctx)
                show_warnings()
                return value
            except RockslideError as exc:
                if debug:
                    raise
                click.echo(one_line(f"rockslide: error: {in_flags(exc)}"), err=True)
                ctx.exit(EXIT_USER_ERROR)
            except KeyboardInterrupt as exc:
                if debug:
                    raise
                stopped = exc if isinstance(exc, interrupts.Interrupted) else interrupts.Interrupted(signal.SIGINT)
                kept = getattr(stopped, "kept", None)
                click.echo(f"rockslide: {stopped.word}: {kept}" if kept else
                           f"rockslide: {stopped.word} (no partial result was written)", err=True)
                ctx.exit(stopped.exit_code)
            except (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort):
                raise
            except Exception as exc:  # noqa: BLE001 - anything else is a bug or a system failure
                if debug:
                    raise
                if isinstance(exc, BrokenPipeError) and _stdout_gone():   # `rockslide info r.at2 | head -1`
                    ctx.exit(EXIT_BROKEN_PIPE)
                failed = _stdout_failed(exc) if isinstance(exc, OSError) else None
                if failed is not None:                # stdout on a full disk or /dev/full
                    click.echo(one_line(f"rockslide: error: cannot write to standard output: {failed}; "
                                        "the files the command wrote are complete"), err=True)
                    ctx.exit(EXIT_USER_ERROR)
                if isinstance(exc, OSError) and exc.errno in _ENVIRONMENT_ERRORS:   # the user's paths
                    where = f"{_short_path(exc.filename)}: " if exc.filename else ""
                    click.echo(one_line(f"rockslide: error: {where}{exc.strerror or exc}"
                                        f"{_ENVIRONMENT_ERRORS[exc.errno]}"), err=True)
                    ctx.exit(EXIT_USER_ERROR)
                if isinstance(exc, ValueError) and "embedded null" in str(exc):   # only from the API
                    click.echo("rockslide: error: a file or folder name holds a NUL character (\\x00)", err=True)
                    ctx.exit(EXIT_USER_ERROR)
                click.echo(one_line(f"rockslide: {_unexpected(exc)} (run again with --debug for the "
                                    "traceback)"), err=True)
                ctx.exit(EXIT_INTERNAL_ERROR)


#: The command-line option of each argument of the API whose error names it (`in_flags`): an
#: argument ``a_b`` is option ``--a-b`` unless named here.
FLAGS = {name: "--" + name.replace("_", "-") for name in (
    "mu", "pga", "vertical_factor", "restitution", "height_to_width", "gravity", "amplitude", "period", "duration",
    "azimuth", "floor_period", "mu_kinetic_ratio", "chunk_size", "device", "workers", "scheduler", "wait_workers",
    "shard", "tls_ca_file", "confidence", "life", "age", "median", "beta", "hazard", "damage", "im", "levels",
    "units", "suite", "samples", "case_vertical", "export", "export_family", "records_dir", "size", "out_dir",
    "density", "b1", "b2",
    "name", "seed", "dpi", "time_shift", "crop", "height", "width", "ah_max", "mu_max", "hazard_units", "configs")}
FLAGS.update({"n": "--ensemble", "member": "--ensemble", "ensemble": "--ensemble", "model": "--model",
              "fragility_table": "--fragility-table", "level": "--levels", "record": "--suite",
              "sample": "--samples", "tls_client_cert": "--tls-cert", "tls_client_key": "--tls-key",
              "resamples": "--bootstrap", "zoom": "--window", "vertical": "--av",
              "fragility": "FRAGILITY"})


def in_flags(exc: RockslideError) -> RockslideError:
    """``exc`` with the API's argument names it is about (``mu``, ``n``, ``beta``) as the command
    line's options (``--mu``, ``--ensemble``, ``--beta``): the library speaks of its arguments, the
    command line of its flags."""
    def flags(words):
        if words is None or not all(part in FLAGS for part in words.split("/")):
            return words
        return "/".join(FLAGS[part] for part in words.split("/"))

    source = flags(exc.source)
    return exc if source == exc.source else type(exc)(exc.message, source=source, field=exc.field)


def _stdout_gone() -> bool:
    """Whether the reader of standard output went away (a pipe without reader reports an error
    to `select.poll`). If so, standard output is pointed at the null device, so that the
    interpreter's last flush does not complain of it: the command stops quietly, as Unix tools
    do, and its files are as they would be after Ctrl-C."""
    import select

    try:
        fd = sys.stdout.fileno()
        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        gone = any(event & select.POLLERR for _, event in poller.poll(0))
    except (AttributeError, OSError, ValueError):     # no real file, or no poll on this system
        return False
    if gone:
        os.dup2(os.open(os.devnull, os.O_WRONLY), fd)
    return gone


#: System errors about the paths the user gave (not bugs): one line and exit 2, with what to do.
_ENVIRONMENT_ERRORS = {
    errno.ENAMETOOLONG: " (a file or folder name takes at most 255 bytes, a path at most 4096): give a shorter one",
    errno.EACCES: ": check the permissions of the file and of its folders, or choose another folder",
    errno.EPERM: ": check the permissions of the file and of its folders, or choose another folder",
    errno.EROFS: ": choose an output folder on a writable file system",
    errno.ELOOP: ": a chain of symbolic links that does not end; give the file itself",
    errno.ENOTDIR: ": a part of the path is a file, not a folder",
}


def _short_path(name) -> str:
    """A path for a message: its start and end when it is long."""
    text = os.fsdecode(name) if isinstance(name, bytes) else str(name)
    return text if len(text) <= 120 else f"{text[:58]}...{text[-59:]}"


def _stdout_failed(exc: OSError) -> str | None:
    """Why standard output could not be written (a full disk, ``/dev/full``), if ``exc`` came from
    writing it (raised inside `click.echo`); else None. Standard output is then pointed at the null
    device, so that the interpreter's last flush does not fail too."""
    frames, tb = [], exc.__traceback__
    while tb is not None:
        frames.append(tb.tb_frame)
        tb = tb.tb_next
    if exc.filename is not None or not any(frame.f_code is click.echo.__code__ for frame in frames):
        return None
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # pragma: no cover - no real stream
        pass
    return exc.strerror or str(exc)


def one_line(text: str, limit: int = MESSAGE_LIMIT) -> str:
    """``text`` as one readable line: control characters escaped (``\\x00``), runs of white space
    made one space, and at most ``limit`` characters (the middle of a longer text left out)."""
    text = " ".join("".join(c if c.isprintable() or c in " \t\n" else ascii(c)[1:-1] for c in str(text)).split())
    if len(text) > limit:
        tail = limit // 4
        text = f"{text[:limit - tail - 5]} ... {text[-tail:]}"
    return text


def _unexpected(exc: Exception) -> str:
    """One line about an exception that is not a RockslideError."""
    if isinstance(exc, OSError) and exc.strerror:
        where = f"{exc.filename}: " if exc.filename else ""
        return f"error: {where}{exc.strerror}"
    if isinstance(exc, MemoryError):
        return ("error: out of memory (a larger solver.dt or output.interval, or a shorter ground.tail, "
                "needs less)")
    text = " ".join(str(exc).split())
    if len(text) > 200:
        text = text[:197] + "..."
    detail = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return f"internal error: {detail}; this is a bug in rockslide, please report it"


_held: list[str] = []


def _hold_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings wait until the input is accepted (`show_warnings`): a command that ends in an
    input error prints that one line only."""
    _held.append(one_line(f"rockslide: warning: {message}"))


def show_warnings() -> None:
    """Print the warnings held so far (call it when the input is accepted, before the work)."""
    for line in _held:
        click.echo(line, err=True)
    _held.clear()


@click.group(cls=RockslideGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show Python tracebacks instead of one-line errors.")
@click.version_option(__version__, prog_name="rockslide")
def main(debug):
    """Nonlinear seismic response of free-standing rectangular rigid blocks.

    Rest, slip, liftoff (rocking with impacts), liftoff-slip interaction and overturning of a block
    on a rigid foundation shaken horizontally and vertically.

    \b
    Example:
        rockslide example
        rockslide run example/example.yaml
    """


records_dir_option = click.option(
    "--records-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
    help="Folder of accelerograms (default: $ROCKSLIDE_RECORDS, else ./records). Record files "
         "resolve against the case file's folder first.")


def size_option(function):
    """``--size``: the figure's size (`units.parse_figure_size`), checked before anything is computed."""
    from ..units import parse_figure_size

    return click.option("--size", default=None, metavar="column|page|slide|WxH",
                        callback=lambda ctx, param, value: parse_figure_size(value),
                        help="Figure size: column (3.5 in wide), page (7 in wide), slide (10 x 5.6 in) or "
                             "WIDTHxHEIGHT in inches (e.g. 6x4); fonts follow it (default: the figure's own "
                             "size).")(function)


def dpi_option(what: str):
    """``--dpi``: the resolution of raster figures (PNG); vector formats (PDF, SVG) ignore it. The
    default is `plots.DPI` (not imported here: matplotlib takes most of a second to load)."""
    return click.option("--dpi", type=click.IntRange(20, 1200), default=None, metavar="N",
                        help=f"Resolution of the {what} [dots per inch] (default 150).")


def json_line(payload: dict) -> str:
    """A JSON object on one line (numpy numbers as numbers, paths as text; NaN refused)."""
    import json

    return json.dumps(payload, allow_nan=False, default=_json_default)


def _json_default(value):
    if hasattr(value, "item"):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot serialise {type(value).__name__}")


def entry() -> None:
    """The ``rockslide`` script and ``python -m rockslide``: `main`, in a process of its own.

    A command is a short-lived process, which allows two settings of the garbage collector that
    save 0.2-0.3 s of a warm run: rarer collections (the libraries loaded make hundreds of
    thousands of objects that live to the end, and each collection walks them again), and none at
    the exit (`gc.freeze`: the interpreter's last collections took 0.2 s to walk every object only
    to free what the process gives back anyway). The exit itself skips the interpreter's teardown
    when nothing is left to finish (`leave`): another 0.06-0.1 s.

    numpy's OpenBLAS gets one thread unless ``OPENBLAS_NUM_THREADS`` says otherwise (set before
    numpy loads): its worker threads spin for about 0.1 s of CPU after loading, a third of a run
    without figure, and rockslide has no linear algebra large enough for threads (the sweep's
    threads are its own). matplotlib's backend is Agg, whatever ``MPLBACKEND`` says.
    """
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # rockslide draws on matplotlib's Agg canvas only: a backend named in the environment (a GUI one,
    # or a misspelt one, which stops matplotlib's import) has nothing to do with its figures
    os.environ["MPLBACKEND"] = "agg"
    gc.set_threshold(10_000, 50, 50)
    try:
        main(prog_name="rockslide")
    except SystemExit as exc:
        ending = exc
    else:
        ending = SystemExit(0)
    finally:
        gc.freeze()
    leave(ending)


def leave(ending: SystemExit) -> None:
    """End the process as ``ending`` says, without the interpreter's teardown when nothing is left
    to finish.

    Unloading the modules of numpy, h5py, click and rockslide took 0.06-0.1 s at every exit, to
    free memory the process gives back anyway. When the main thread is the only one and no HDF5
    file is open (HDF5 flushes files from a C exit handler, which ``os._exit`` skips), the exit
    handlers registered in Python run, standard output and error are flushed, and the process
    ends with ``os._exit``. Otherwise (a thread still running, a file open, output that cannot be
    flushed, an exit with a message), ``ending`` is raised: the usual exit.
    """
    code = ending.code
    if code is None:
        code = 0
    if not isinstance(code, int) or threading.active_count() > 1 or _hdf5_files_open():
        raise ending
    atexit._run_exitfuncs()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):            # a reader gone, a closed stream: the usual exit reports it
        raise ending from None
    os._exit(code)


def _hdf5_files_open() -> bool:
    """Whether h5py is loaded with a file still open."""
    h5py = sys.modules.get("h5py")
    return h5py is not None and h5py.h5f.get_obj_count(h5py.h5f.OBJ_ALL, h5py.h5f.OBJ_FILE) > 0


