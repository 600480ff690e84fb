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

import gc
import json
import math
import os
import signal
import sys
import time
import warnings
from pathlib import Path

import click

from . import __version__, interrupts
from .errors import CaseError, OutputError, RockslideError

EXIT_INTERNAL_ERROR = 1
EXIT_USER_ERROR = 2
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143
EXIT_BROKEN_PIPE = 141      # 128 + SIGPIPE: what a Unix tool whose reader went away exits with
#: Longest message printed [characters]; a longer one keeps its start and its end.
MESSAGE_LIMIT = 400
#: A single run expected to take longer than this [s] says so before it starts (and shows a
#: progress bar on a terminal).
LONG_RUN = 10.0
#: A run's figure is drawn from its history kept in memory while it has at most this many rows (96
#: MB; reading the file back would take as much); a longer history is read back from the file.
KEEP_HISTORY_ROWS = 2_000_000


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
        debug = "--debug" in sys.argv[1:] or bool(ctx.params.get("debug"))
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
                click.echo(one_line(f"rockslide: error: {exc}"), err=True)
                ctx.exit(EXIT_USER_ERROR)
            except KeyboardInterrupt as exc:
                if debug:
                    raise
                stopped = exc if isinstance(exc, interrupts.Interrupted) else interrupts.Interrupted(signal.SIGINT)
                click.echo(f"rockslide: {stopped.word} (no partial result was written)", err=True)
                ctx.exit(stopped.exit_code)
            except (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort):
                raise
            except Exception as exc:  # noqa: BLE001 - anything else is a bug or a system failure
                if debug:
                    raise
                if isinstance(exc, BrokenPipeError) and _stdout_gone():   # `rockslide info r.at2 | head -1`
                    ctx.exit(EXIT_BROKEN_PIPE)
                if isinstance(exc, ValueError) and "embedded null" in str(exc):   # only from the API
                    click.echo("rockslide: error: a file or folder name holds a NUL character (\\x00)", err=True)
                    ctx.exit(EXIT_USER_ERROR)
                click.echo(one_line(f"rockslide: {_unexpected(exc)} (run again with --debug for the "
                                    "traceback)"), err=True)
                ctx.exit(EXIT_INTERNAL_ERROR)


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


def dpi_option(what: str):
    """``--dpi``: the resolution of raster figures (PNG); vector formats (PDF, SVG) ignore it. The
    default is `plots.DPI` (not imported here: matplotlib takes most of a second to load)."""
    return click.option("--dpi", type=click.IntRange(20, 1200), default=None, metavar="N",
                        help=f"Resolution of the {what} [dots per inch] (default 150).")


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path))
@records_dir_option
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder (default: the case's output.dir).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object on stdout.")
@click.option("--overwrite", is_flag=True, help="Replace existing results of this case.")
@click.option("--no-plot", is_flag=True, help="Do not draw the PNG figure (with --overwrite, an earlier "
              "figure of this case is removed: it showed the result replaced).")
@click.option("--robustness", is_flag=True,
              help="Also rerun at dt/2 and with mu 1 % lower and higher, and say whether the verdict holds.")
@dpi_option("PNG figure")
def run(case_file, records_dir, out_dir, as_json, overwrite, no_plot, robustness, dpi):
    """Compute one case: CASE_FILE (YAML) -> OUT/NAME.h5 and OUT/NAME.png.

    \b
    Example:
        rockslide run example/example.yaml --json
    """
    from . import files, records, results, runner
    from .case import load_case

    started = time.perf_counter()
    case = load_case(case_file)
    folder = (Path(out_dir) if out_dir is not None else Path(case.output.dir)).expanduser()
    h5_path = folder / f"{case.name}.h5"
    png_path = folder / f"{case.name}.png"
    prepared = runner.prepare(case, records.records_dir(records_dir))     # input errors first
    ground = prepared.ground.as_applied()
    stored = None        # this case's complete result, of which only the figure is missing
    if _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot):
        stored = _same_result(case, prepared, h5_path, robustness=robustness)
    files.remove_stale_temporaries([h5_path, png_path])
    show_warnings()
    if stored is None:
        work = runner.work(prepared, runs=4 if robustness else 1)
        if work.seconds > LONG_RUN:
            click.echo(f"rockslide: note: {work.describe()}", err=True)
        files.warn_free_space(folder, work.rows * results.BYTES_PER_ROW)
        from .core import native
        if native.ahead_of_time() is None:      # no machine code from the build: numba's JIT
            from .core import kernel
            _note_first_compile(kernel.run)
        with files.Staging(overwrite=overwrite) as staging:
            keep = 0 if no_plot else KEEP_HISTORY_ROWS
            with results.ResultWriter(h5_path, overwrite=overwrite, staging=staging, keep_rows=keep) as writer, \
                    _RunProgress(case.name, show=work.seconds > LONG_RUN) as progress:
                streamed = prepared.case.solver.method == "kernel"
                result = runner.simulate_prepared(prepared, on_chunk=writer.append_history if streamed else None,
                                                  progress=progress)
                check = (runner.verdict_robustness(prepared, result.summary.overturned, progress=progress)
                         if robustness else None)
                extra = {} if check is None else {
                    "verdict_robust": check["holds"],
                    "robustness": json.dumps(results.json_ready(check["variants"]), allow_nan=False)}
                writer.finish(result, name=case.name, case_text=case.text, case=_case_dict(case),
                              records=runner.record_entries(prepared), extra_attrs=extra, ground=ground)
            if not no_plot:
                kept = writer.written_result()
                _draw(kept if kept is not None else results.read_result(writer.tmp).result, case.name,
                      png_path, overwrite=overwrite, dpi=dpi, staging=staging)
            staging.publish(remove=[png_path] if no_plot else [])
        written = f"{h5_path}" + ("" if no_plot else f" and {png_path}")
    else:
        with files.Staging(overwrite=False) as staging:
            _draw(stored.result, stored.name, png_path, overwrite=False, dpi=dpi, staging=staging)
            staging.publish()
        result = stored.result
        check = None if not robustness else {
            "holds": bool(stored.attrs["verdict_robust"]), "overturned": result.summary.overturned,
            "variants": json.loads(stored.attrs["robustness"])}
        written = f"{png_path} (the missing figure of the complete {h5_path})"
    elapsed = time.perf_counter() - started
    summary = result.summary
    if as_json:
        payload = {"name": case.name, **results.summary_to_json_dict(summary, result.events),
                   "ground": ground, "robustness": results.json_ready(check),
                   "files": {"hdf5": str(h5_path), "png": None if no_plot else str(png_path)},
                   "elapsed_s": round(elapsed, 3)}
        click.echo(json.dumps(payload, allow_nan=False, default=_json_default))
    else:
        click.echo(human_summary(case.name, summary, ground=ground, units=case.units))
        if check is not None:
            flips = [name for name, v in check["variants"].items() if v["overturned"] != summary.overturned]
            click.echo("  verdict robust: holds at dt/2 and mu +-1 %" if check["holds"] else
                       f"  verdict NOT robust (knife edge): flips with {', '.join(flips)}")
        click.echo(f"  wrote {written} in {elapsed:.2f} s")


@main.command()
@click.argument("result_file", type=click.Path(path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Figure to write; the format follows its extension: .png, .pdf, .svg, .eps... "
                   "(default: the result's name with .png, next to it).")
@click.option("--time-shift", default="0 s", show_default=True, metavar="TIME",
              help="Time added to the time axis, with a unit as in case files (e.g. '-25 s'; a bare "
                   "number is in s), to lay the figure beside another's.")
@click.option("--window", default="auto", show_default=True, metavar="START:END|auto|none",
              help="The magnified window, in the figure's time (e.g. 30:36 or '30 s:36 s'); none: no "
                   "magnified panel.")
@click.option("--crop", default="auto", show_default=True, metavar="START:END|auto|all",
              help="Time range of the response and ground panels (auto: where the ground or the block "
                   "moves; all: the whole record).")
@click.option("--overwrite", is_flag=True,
              help="Replace the file given with -o if it exists (the result's own figure is always "
                   "redrawn).")
@dpi_option("figure (PNG)")
def plot(result_file, output, time_shift, window, crop, dpi, overwrite):
    """Redraw the figure of a result, sweep or fragility file (replaces it).

    \b
    Example:
        rockslide plot out/example.h5
        rockslide plot out/example.h5 --window 6.6:7.2 -o out/example-impact.pdf
        rockslide plot out/example.sweep.h5
        rockslide plot out/example.fragility.h5
    """
    from . import results
    from .units import parse_quantity

    shift = parse_quantity(time_shift, "time", source="--time-shift")
    zoom = _time_range(window, "--window", {"auto": "auto", "none": None})
    span = _time_range(crop, "--crop", {"auto": "auto", "all": None})
    own = Path(result_file).with_suffix(".png")
    png = output if output is not None else own
    # the result's own figure is the one redrawn; another file is replaced only when asked to
    replace = overwrite or png.resolve() == own.resolve()
    kind = results.file_format(result_file)
    if kind == results.SWEEP_FORMAT:
        from .plots import save_figure
        from .sweep import stored_figure
        given = [option for option, value, default in (("--time-shift", shift, 0.0), ("--window", zoom, "auto"),
                                                       ("--crop", span, "auto")) if value != default]
        if given:
            raise CaseError("applies to result files, not to sweep files", source=given[0])
        save_figure(stored_figure(results.read_sweep(result_file)), png, overwrite=replace, dpi=dpi)
    elif kind == results.FRAGILITY_FORMAT:
        from .fragility import stored_figure as stored_fragility_figure
        from .plots import save_figure
        given = [option for option, value, default in (("--time-shift", shift, 0.0), ("--window", zoom, "auto"),
                                                       ("--crop", span, "auto")) if value != default]
        if given:
            raise CaseError("applies to result files, not to fragility files", source=given[0])
        stored = results.read_dataset(result_file, format=results.FRAGILITY_FORMAT)
        save_figure(stored_fragility_figure(stored), png, overwrite=replace, dpi=dpi)
    else:
        stored = results.read_result(result_file)
        times = stored.result.ground_time
        if times.size:
            first, last = float(times[0]) + shift, float(times[-1]) + shift
            for option, pair in (("--window", zoom), ("--crop", span)):
                if isinstance(pair, tuple) and (pair[1] <= first or pair[0] >= last):
                    raise CaseError(f"{pair[0]:g} to {pair[1]:g} s is outside the result, which runs from "
                                    f"{first:g} to {last:g} s (in the figure's time)", source=option)
        _draw(stored.result, stored.name, png, overwrite=replace, time_shift=shift, zoom=zoom, crop=span, dpi=dpi)
    click.echo(f"redrew {png}")


def _time_range(text: str, option: str, words: dict):
    """``START:END`` (times with units as in case files, bare numbers in s) as a pair of seconds,
    or the value of one of ``words``."""
    from .units import parse_quantity

    key = text.strip().lower()
    if key in words:
        return words[key]
    parts = text.split(":")
    if len(parts) != 2:
        raise CaseError(f"expected START:END (e.g. 30:36 or '30 s:36 s') or one of "
                        f"{', '.join(words)}, got {text!r}", source=option)
    start, end = (parse_quantity(p.strip(), "time", source=option) for p in parts)
    if not end > start:
        raise CaseError(f"the end must come after the start, got {text!r}", source=option)
    return start, end


@main.command()
@click.argument("record", type=click.Path(path_type=Path))
@click.option("--format", "fmt", default=None,
              help="File format (default: detected): at2, knet, column, values, or an obspy format.")
@click.option("--units", default=None,
              help="Acceleration unit of the values (g, gal, m/s^2) where the file does not say.")
@click.option("--time-column", default=None,
              help="Column text: 1-based number or header name of the time column.")
@click.option("--column", default=None,
              help="Column text: 1-based number or header name of the acceleration column.")
@click.option("--dt", type=float, default=None, help="Sampling step [s] for the values format.")
@click.option("--skip-lines", type=int, default=0, help="Header lines to skip (values format).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def info(record, fmt, units, time_column, column, dt, skip_lines, as_json):
    """Describe an accelerogram: format, dt, duration, units and peaks.

    \b
    Example:
        rockslide info example/synthetic_kt_h.at2
    """
    from .records import record_info

    details = record_info(record, format=fmt, units=units, time_column=_column(time_column),
                          column=_column(column), dt=dt, skip_lines=skip_lines)
    if as_json:
        click.echo(json.dumps(details, default=_json_default))
        return
    click.echo(f"{record}")
    click.echo(f"  format    {details['format']}")
    click.echo(f"  units     {details['units']} (converted to m/s^2)")
    click.echo(f"  samples   {details['npts']}, dt = {details['dt']:g} s, "
               f"duration {details['duration']:g} s, starts at {details['start']:g} s")
    click.echo(f"  peak      {details['peak_gal']:.2f} gal = {details['peak_g']:.4f} g "
               f"({'+' if details['peak_signed'] > 0 else '-'}) at t = {details['peak_time']:g} s")
    click.echo(f"  mean      {details['mean'] / 0.01:.3f} gal")
    click.echo(f"  sha256    {details['sha256']}")


@main.command()
@records_dir_option
@click.option("--configs", type=click.Path(file_okay=False, path_type=Path), default=Path("configs/table1"),
              show_default=True, help="Folder of the Table 1 case files.")
@click.option("--out-dir", "out", type=click.Path(file_okay=False, path_type=Path),
              default=Path("results"), show_default=True,
              help="Where table1.md, table1.csv and fig05-fig10.png go (replaced).")
@click.option("--out", "old_out", type=click.Path(file_okay=False, path_type=Path), default=None,
              hidden=True, help="The former name of --out-dir.")
def table1(records_dir, configs, out, old_out):
    """Reproduce the paper's Table 1 and Figures 5-10 from its records (make table1), from the
    repository's root (the case files are in configs/table1).

    \b
    Example:
        rockslide table1 --records-dir ../shared/records --out-dir results
    """
    from . import records
    from .table1 import reproduce

    if old_out is not None:
        from click.core import ParameterSource

        if click.get_current_context().get_parameter_source("out") is ParameterSource.COMMANDLINE:
            raise CaseError("--out is the former name of --out-dir: give one of them", source="--out")
        out = old_out
    if not configs.is_dir():
        raise CaseError("folder not found; expected the folder of the Table 1 case files "
                        "(configs/table1 in the repository)", source=str(configs), field="--configs")
    report = reproduce(configs, records.records_dir(records_dir), out)
    for gravity, s in report["summary"].items():
        click.echo(f"g = {gravity}: {s['verdicts']}/{s['rows']} verdicts match the paper, "
                   f"{s['all']}/{s['rows']} verdicts and descriptions")
    click.echo(f"wrote {', '.join(str(p) for p in report['files'])} and {len(report['figures'])} figures "
               f"in {report['elapsed']:.1f} s")


@main.command()
@click.argument("folder", type=click.Path(file_okay=False, path_type=Path), default=Path("example"),
                required=False)
@click.option("--overwrite", is_flag=True, help="Replace the files if they exist.")
def example(folder, overwrite):
    """Write the shipped example into FOLDER (default: ./example): example.yaml, the paper's block on
    the project's own synthetic records, and those two records (synthetic_kt_h.at2,
    synthetic_kt_v.at2); suite-synthetic.yaml, a suite of six synthetic record pairs (in
    suite-synthetic/) for 'rockslide fragility'; spectrum-one-sine.yaml, a block under a one-sine
    pulse for overturning spectra. The examples of every command's --help work anywhere after it.

    \b
    Example:
        rockslide example
        rockslide run example/example.yaml
    """
    from .example import write_example

    paths = write_example(folder, overwrite=overwrite)
    click.echo(f"wrote {', '.join(str(p) for p in paths)}")
    click.echo(f"next: rockslide run {paths[0]}")


@main.command()
@click.option("--height", type=str, default="0.2 m", show_default=True, help="Block height.")
@click.option("--width", type=str, default="0.1 m", show_default=True, help="Block width.")
@click.option("--av", "vertical", type=str, default="-0.5g,0g,0.5g", show_default=True,
              help="Vertical accelerations with units (g, gal, m/s^2), comma separated (one panel each).")
@click.option("--ah-max", type=str, default="1.5g", show_default=True,
              help="Largest |A_h| on the map, with a unit (g, gal, m/s^2).")
@click.option("--mu-max", type=float, default=1.2, show_default=True, help="Largest mu on the map.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=Path("criteria.png"),
              show_default=True, help="PNG to write.")
@click.option("--overwrite", is_flag=True, help="Replace an existing PNG.")
@dpi_option("PNG")
def criteria(height, width, vertical, ah_max, mu_max, output, overwrite, dpi):
    """Draw the mode-initiation map (rest / slip / liftoff / liftoff-slip) of a block, from eqs. 6, 11, 26.

    \b
    Example:
        rockslide criteria --height 0.2m --width 0.1m --av=-0.5g,0g,0.5g -o criteria.png
    """
    import numpy as np

    from .core import criteria as crit
    from .plots import criteria_figure, save_figure
    from .units import STANDARD_GRAVITY, parse_quantity

    h = parse_quantity(height, "length", source="--height")
    w = parse_quantity(width, "length", source="--width")
    if h <= 0 or w <= 0:
        raise CaseError("height and width must be positive lengths", source="--height/--width")
    avs = [parse_quantity(v, "acceleration", source="--av") / STANDARD_GRAVITY
           for v in vertical.split(",") if v.strip()]
    ah_max = parse_quantity(ah_max, "acceleration", source="--ah-max") / STANDARD_GRAVITY
    for option, value in (("--ah-max", ah_max), ("--mu-max", mu_max)):
        if not (math.isfinite(value) and value > 0):
            raise CaseError(f"expected a positive finite value, got {value:g}", source=option)
    if not avs or any(not -1.0 < a for a in avs):
        raise CaseError("each vertical acceleration must be above -1 g (the block would fly)", source="--av")
    if not overwrite and (output.exists() or output.is_symlink()):
        raise OutputError(f"{output} exists (use --overwrite to replace it)")
    ah = np.linspace(0.0, ah_max, 301)
    mu = np.linspace(0.0, mu_max, 241)
    maps = [(f"A_v = {a:+.2f} g", crit.mode_map(ah, mu, a, w / 2, h / 2)) for a in avs]
    figure = criteria_figure(ah, mu, maps, title=f"modes initiated from rest: {w:g} m wide, {h:g} m high")
    save_figure(figure, output, overwrite=overwrite, dpi=dpi)
    click.echo(f"wrote {output}")


def _axis_option(name: str, kind: str, what: str, example: str):
    """An axis option of `sweep`; the order the axes are given in is kept (dimension order)."""
    def remember(ctx, param, values):
        if len(values) > 1:       # click would keep the last silently
            raise click.BadParameter(f"given {len(values)} times; give it once (a comma list holds several "
                                     "values, e.g. 0.5,0.6)")
        value = values[0] if values else None
        if value is not None:
            ctx.meta.setdefault("rockslide.sweep.axes", []).append((name, value))
        return value

    units = ""
    if kind == "acceleration":
        units = " Values need a unit (g, gal, cm/s^2, m/s^2) as in case files; one unit for a range."
    elif kind == "time":
        units = " Values may carry units as in case files (one unit for a range)."
    return click.option(f"--{name.replace('_', '-')}", name, multiple=True, metavar="SPEC", callback=remember,
                        help=f"{what}: START:STOP:STEP or a comma list, e.g. {example}.{units}")


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path))
@_axis_option("mu", "dimensionless", "Static friction coefficient mu_static (mu_kinetic follows by the "
              "case's ratio mu_kinetic/mu_static, or --mu-kinetic-ratio)", "0.30:0.70:0.01")
@_axis_option("pga", "acceleration", "Peak horizontal ground acceleration (ground.scale.pga_horizontal; "
              "the vertical keeps the record's V/H ratio unless the case gives pga_vertical)",
              "100gal:1000gal:25gal")
@_axis_option("vertical_factor", "dimensionless", "Factor on the vertical record "
              "(ground.scale.vertical_factor)", "0,0.5,1")
@_axis_option("restitution", "dimensionless", "Coefficient of restitution (contact.restitution)",
              "0.6:0.9:0.1")
@_axis_option("slenderness", "dimensionless", "Width / height of the block (the height kept)",
              "0.3:0.6:0.05")
@_axis_option("gravity", "acceleration", "Gravitational acceleration (gravity)", "9.8m/s^2,9.80665m/s^2")
@_axis_option("amplitude", "acceleration", "Amplitude of the horizontal pulse of a pulse case "
              "(ground.horizontal.amplitude)", "0.2g:3g:0.1g")
@_axis_option("period", "time", "Period of the horizontal pulse (ground.horizontal.period); with "
              "--amplitude, an overturning spectrum", "0.1:1:0.05")
@_axis_option("duration", "time", "Duration of a rectangular or half-sine horizontal pulse "
              "(ground.horizontal.duration)", "0.05:0.5:0.01")
@click.option("--mu-kinetic-ratio", type=float, default=None, metavar="R",
              help="mu_kinetic = R * mu_static for --mu (default: the case's ratio).")
@records_dir_option
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder (default: the case's output.dir).")
@click.option("--overwrite", is_flag=True, help="Replace an existing result of this sweep.")
@click.option("--no-plot", is_flag=True, help="Do not draw the PNG maps (with --overwrite, earlier maps "
              "of this sweep are removed).")
@click.option("--workers", type=int, default=None, metavar="N",
              help="Threads for a local run (default: all cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Compute the chunks on this dask.distributed scheduler (e.g. tcp://10.0.0.5:8786), "
                   "one task per chunk.")
@click.option("--device", type=click.Choice(["cpu", "gpu"]), default="cpu", show_default=True,
              help="Compute a local run on the CPU's cores or on an NVIDIA GPU (needs the extra: "
                   "pip install 'rockslide[gpu]'; README, 'GPU').")
@click.option("--chunk-size", type=int, default=None, metavar="N",
              help="Cases per chunk (default: about 1/100 of the grid, 4 to 256). Part of the sweep's "
                   "definition: a different size does not resume an interrupted run.")
@click.option("--no-progress", is_flag=True,
              help="No progress bar on stderr (there is none anyway when stderr is not a terminal).")
@dpi_option("PNG maps")
def sweep(case_file, mu, pga, vertical_factor, restitution, slenderness, gravity, amplitude, period, duration,
          mu_kinetic_ratio, records_dir, out_dir, overwrite, no_plot, workers, scheduler, device, chunk_size,
          no_progress, dpi):
    """Grid of cases over friction, intensity, vertical factor, restitution, slenderness or gravity,
    or over a pulse's amplitude and period or duration: CASE_FILE (YAML) -> OUT/NAME.sweep.h5 and
    OUT/NAME.sweep.png.

    Every point is the case file with the axis values replaced (and validated as a case file), run
    with the compiled kernel on all cores (or a dask cluster), without history. Dimension i of the
    result is the i-th axis option given. Finished chunks are kept in OUT/.NAME.sweep.chunks: after
    Ctrl-C or a crash, the same command resumes where it stopped. --amplitude with --period (or
    --duration) of a pulse case draws an overturning spectrum.

    \b
    Example:
        rockslide sweep example/example.yaml --mu 0.30:0.70:0.01 --pga 100gal:1000gal:25gal
        rockslide sweep example/spectrum-one-sine.yaml --amplitude 0.25g:2.5g:0.25g --period 0.2:1.6:0.2
    """
    from tqdm import tqdm

    from . import files, records, results
    from . import sweep as sw
    from .case import load_case
    from .plots import save_figure
    from .runner import duration_text

    ctx = click.get_current_context()
    started = time.perf_counter()
    case = load_case(case_file)
    axes = [sw.parse_axis(name, text) for name, text in ctx.meta.get("rockslide.sweep.axes", [])]
    _check_where(workers, scheduler, device)
    if scheduler:
        scheduler = sw.scheduler_address(scheduler)
    folder = (Path(out_dir) if out_dir is not None else Path(case.output.dir)).expanduser()
    h5_path = folder / f"{case.name}.sweep.h5"
    png_path = folder / f"{case.name}.sweep.png"
    finishing = _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot, example="out/case.sweep",
                            leftovers=sw.ChunkStore.beside(h5_path, "").root.exists())
    n_points = math.prod(len(a) for a in axes) if axes else 0
    if n_points * sw.PLAN_SECONDS_PER_POINT > 10:
        click.echo(f"sweep {case.name}: checking the {n_points} points of the grid first (about "
                   f"{duration_text(n_points * sw.PLAN_SECONDS_PER_POINT)})")
    with tqdm(total=n_points, unit="case", file=sys.stderr, desc=f"{case.name}: checking",
              disable=no_progress or n_points < 10 * sw.PLAN_BATCH or not sys.stderr.isatty(),
              dynamic_ncols=True, leave=False) as bar:
        plan = sw.plan_sweep(case, axes, records_dir=records.records_dir(records_dir),
                             mu_kinetic_ratio=mu_kinetic_ratio, chunk_size=chunk_size, progress=bar.update)
    if finishing:
        _finish_sweep(plan, sw.ChunkStore.beside(h5_path, plan.key), h5_path, png_path, no_plot=no_plot,
                      started=started, dpi=dpi)
        return
    files.remove_stale_temporaries([h5_path, png_path])
    store, states, n_new, computed = _compute_plan(
        ctx, plan, h5_path, what="sweep", description=plan.describe(), label=case.name, unit="case",
        workers=workers, scheduler=scheduler, device=device, no_progress=no_progress)
    variables = sw.sweep_variables(plan, states)
    with files.Staging(overwrite=overwrite) as staging:
        results.write_sweep(h5_path, sw.coordinates(plan), variables, overwrite=overwrite, staging=staging,
                            attrs=sw.root_attributes(plan, _command_line(ctx, case_file)))
        if not no_plot:
            save_figure(sw.figure(plan, variables), png_path, overwrite=overwrite, dpi=dpi, staging=staging)
        staging.publish(remove=[png_path] if no_plot else [])
    store.remove()
    over = int(variables["overturned"][0].sum())
    outside = int((variables["status"][0] != 0).sum())
    undecided = int(variables["undecided"][0].sum())
    rate = f" ({n_new / computed:.0f} cases/s)" if n_new and computed > 0 else ""
    click.echo(f"  {over} of {plan.n_cases} overturned, {outside} outside the model; computed {n_new} "
               f"cases in {computed:.1f} s{rate}")
    if undecided:
        click.echo(f"  {undecided} undecided: still moving at the end with the energy to overturn "
                   "(give the case a ground.tail for their free motion)")
    written = f"{h5_path}" + ("" if no_plot else f" and {png_path}")
    click.echo(f"  wrote {written} in {time.perf_counter() - started:.1f} s")


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--suite", "suite_spec", required=True, metavar="SUITE",
              help="The records: a suite file (YAML: records: [{name:, horizontal:, vertical:}, ...]), a "
                   "folder of horizontal records, or a quoted glob of them ('records/*.csv').")
@click.option("--im", "im_text", default="pga", show_default=True, metavar="IM",
              help="Intensity measure each record is scaled to: pga, pgv, pga_rocking (PGA / (g tan "
                   "alpha)) or sa(T) (5 %-damped spectral acceleration, e.g. 'sa(0.5s)').")
@click.option("--levels", "levels_text", required=True, metavar="SPEC",
              help="Levels of the IM: START:STOP:STEP or a comma list, with units as in case files, "
                   "e.g. 0.1g:1.5g:0.1g (pgv: 10cm/s:100cm/s:10cm/s; pga_rocking: no unit).")
@click.option("--damage", "damage_texts", multiple=True, metavar="STATE",
              help="A damage state besides overturning (repeat for more): 'rotation>0.5alpha', "
                   "'rotation>10deg', 'slip>50mm', 'residual>10mm'.")
@click.option("--units", default=None, metavar="UNIT",
              help="Acceleration unit of a folder's or glob's record files that do not state theirs "
                   "(g, gal, m/s^2).")
@click.option("--bootstrap", "resamples", type=click.IntRange(0, 100_000), default=1000, show_default=True,
              metavar="N", help="Bootstrap resamples of the records for the confidence intervals (0: none).")
@records_dir_option
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder (default: the case's output.dir).")
@click.option("--json", "as_json", is_flag=True, help="Print the fits as one JSON object on stdout.")
@click.option("--overwrite", is_flag=True, help="Replace an existing result of this analysis.")
@click.option("--no-plot", is_flag=True, help="Do not draw the PNG figure.")
@click.option("--workers", type=int, default=None, metavar="N",
              help="Threads for a local run (default: all cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Compute the chunks on this dask.distributed scheduler (e.g. tcp://10.0.0.5:8786).")
@click.option("--device", type=click.Choice(["cpu", "gpu"]), default="cpu", show_default=True,
              help="Compute a local run on the CPU's cores or on an NVIDIA GPU (needs the extra: "
                   "pip install 'rockslide[gpu]'; README, 'GPU').")
@click.option("--chunk-size", type=int, default=None, metavar="N",
              help="Runs per chunk (default: about 1/100 of them, 4 to 256); part of the definition.")
@click.option("--no-progress", is_flag=True, help="No progress bar on stderr.")
@dpi_option("figure (PNG)")
def fragility(case_file, suite_spec, im_text, levels_text, damage_texts, units, resamples, records_dir,
              out_dir, as_json, overwrite, no_plot, workers, scheduler, device, chunk_size, no_progress, dpi):
    """Fragility curves of a block over a record suite scaled to levels of an intensity measure:
    CASE_FILE (YAML) -> OUT/NAME.fragility.h5 and OUT/NAME.fragility.png.

    Every record of the suite is scaled (horizontal and vertical by one factor) so that its
    intensity measure equals each level, and the case file's block is run under it with the
    compiled kernel, as 'rockslide sweep' runs its grids (all cores or a dask cluster, resumable
    after Ctrl-C). Lognormal fragility curves are fitted per damage state by maximum likelihood
    over the stripes, with bootstrap confidence intervals over the records, and by the method of
    moments on each record's first exceedance. Runs that leave the model (flight, Painleve) are
    counted and left out of the fits.

    \b
    Example:
        rockslide fragility example/example.yaml --suite example/suite-synthetic.yaml --levels 0.1g:1.5g:0.1g
        rockslide fragility example/example.yaml --suite example/suite-synthetic.yaml --json \\
            --im 'sa(0.3s)' --levels 0.25g:3g:0.25g --damage 'rotation>0.5alpha' --damage 'slip>50mm'
    """
    from . import files, records, results
    from . import fragility as fr
    from . import sweep as sw
    from .case import load_case
    from .plots import save_figure

    ctx = click.get_current_context()
    started = time.perf_counter()
    case = load_case(case_file)
    im = fr.parse_im(im_text)
    levels = fr.parse_levels(levels_text, im)
    states = fr.damage_states(damage_texts)
    _check_where(workers, scheduler, device)
    if scheduler:
        scheduler = sw.scheduler_address(scheduler)
    suite = fr.suite_from(suite_spec, units=units)
    fplan = fr.plan_fragility(case, suite, im, levels, records_dir=records.records_dir(records_dir),
                              chunk_size=chunk_size)
    folder = (Path(out_dir) if out_dir is not None else Path(case.output.dir)).expanduser()
    h5_path = folder / f"{case.name}.fragility.h5"
    png_path = folder / f"{case.name}.fragility.png"
    if _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot, example="out/case.fragility"):
        files.refuse_existing(h5_path, overwrite=False)           # input errors first, then outputs
    files.remove_stale_temporaries([h5_path, png_path])
    plan = fplan.plan
    store, final_states, n_new, computed = _compute_plan(
        ctx, plan, h5_path, what="fragility", description=fplan.describe(), label=case.name, unit="run",
        workers=workers, scheduler=scheduler, device=device, no_progress=no_progress, err=as_json)
    analysis = fr.analyse(fplan, final_states, states, resamples=resamples)
    coords, variables, attrs = fr.dataset(fplan, analysis, _command_line(ctx, case_file))
    with files.Staging(overwrite=overwrite) as staging:
        results.write_dataset(h5_path, coords, variables, format=results.FRAGILITY_FORMAT, attrs=attrs,
                              overwrite=overwrite, staging=staging)
        if not no_plot:
            save_figure(fr.figure(fplan, analysis), png_path, overwrite=overwrite, dpi=dpi, staging=staging)
        staging.publish(remove=[png_path] if no_plot else [])
    store.remove()
    elapsed = time.perf_counter() - started
    if as_json:
        payload = {**fr.json_summary(fplan, analysis),
                   "files": {"hdf5": str(h5_path), "png": None if no_plot else str(png_path)},
                   "elapsed_s": round(elapsed, 3)}
        click.echo(json.dumps(payload, allow_nan=False, default=_json_default))
        return
    outside = int((analysis.variables["status"][0] != 0).sum())
    rate = f" ({n_new / computed:.0f} runs/s)" if n_new and computed > 0 else ""
    click.echo(f"  computed {n_new} runs in {computed:.1f} s{rate}; {outside} of {plan.n_cases} outside the "
               "model (left out of the fits)")
    undecided = int(analysis.variables["undecided"][0].sum())
    if undecided:
        click.echo(f"  {undecided} undecided: still moving at the end with the energy to overturn, counted as "
                   "not overturned (give the case a ground.tail for their free motion)")
    for state, fit in zip(analysis.states, analysis.fits, strict=True):
        click.echo("  " + fr.describe_fit(state, fit, im))
    written = f"{h5_path}" + ("" if no_plot else f" and {png_path}")
    click.echo(f"  wrote {written} in {elapsed:.1f} s")


def _check_where(workers, scheduler, device):
    """Refuse ``--workers``, ``--scheduler`` and ``--device`` that do not go together, a bad
    ``--workers``, and ``--device gpu`` where no GPU can be used (before any planning)."""
    from . import sweep as sw

    if workers is not None and scheduler:
        raise CaseError("sets the local threads; with --scheduler the cluster's workers compute",
                        source="--workers")
    if device != "cpu" and scheduler:
        raise CaseError("with --scheduler the cluster's workers compute, on their CPUs", source="--device")
    if device != "cpu" and workers is not None:
        raise CaseError("sets the CPU threads; with --device gpu the GPU computes", source="--workers")
    sw.check_workers(workers)
    sw.check_device(device)


def _compute_plan(ctx, plan, h5_path, *, what, description, label, unit, workers, scheduler, no_progress,
                  device="cpu", err=False):
    """Compute what a sweep plan (`sweep.Plan`) still misses, with the chunks kept beside ``h5_path``
    (`sweep.ChunkStore`): say what is reused (and which stored chunks cannot be), check the free
    space, compile the kernel, show a progress bar, and on Ctrl-C or SIGTERM keep the finished chunks
    and exit 130 or 143. ``what`` (``sweep``, ``fragility``), ``label`` (the case's name) and
    ``description`` head the messages, which go to stderr with ``err``.

    Returns ``(store, final states, cases computed now, seconds computing)``.
    """
    from tqdm import tqdm

    from . import files
    from . import sweep as sw
    from .core import batch

    store = sw.ChunkStore.beside(h5_path, plan.key)
    store.remove_stale_temporaries()
    for other in store.others():
        click.echo(f"  note: {other} holds chunks of another {what} definition (not used; delete it "
                   "to free the space)", err=err)
    missing = sw.missing_chunks(plan, store)
    for chunk, reason in sorted(store.damaged.items()):
        click.echo(f"  note: {store.path(chunk)} cannot be used ({reason}); computing it again", err=err)
    reused = plan.n_chunks - len(missing)
    reused_cases = plan.n_cases - sum(plan.chunk_indices(c).size for c in missing)
    where = (f"on the dask scheduler {scheduler}" if scheduler else
             "on this machine's GPU" if device == "gpu" else "on this machine")
    click.echo(f"{what} {label}: {description} in {plan.n_chunks} chunks, {where}", err=err)
    if reused:
        click.echo(f"  reused {reused} of {plan.n_chunks} chunks ({reused_cases} {unit}s) from {store.folder}",
                   err=err)
    if sw.work_estimate(plan, plan.n_cases - reused_cases, workers=workers) > 60:
        click.echo(f"  up to {plan.steps_per_case:.3g} integration steps per {unit} (far fewer for {unit}s at "
                   "rest or overturned): the progress bar shows the time left", err=err)
    files.require_free_space(Path(h5_path).parent, sw.bytes_needed(plan, len(missing)), f"the {what}")
    show_warnings()
    if not scheduler and missing:
        if device == "gpu":
            from .core import gpu
            compiling = time.perf_counter()
            gpu.warm_up()
            if time.perf_counter() - compiling > 3.0:
                click.echo(f"  compiled the device kernel in {time.perf_counter() - compiling:.0f} s (once after "
                           "each change of the kernel)", err=err)
        else:
            _note_first_compile(batch.run_batch, "the batch kernel")
            batch.warm_up()
    computing = time.perf_counter()
    try:
        # disable=None: tqdm draws only on a terminal, so that no frames land in log files
        with tqdm(total=plan.n_cases, initial=reused_cases, unit=unit, file=sys.stderr,
                  disable=True if no_progress else None, dynamic_ncols=True, desc=label, smoothing=0.1) as bar:
            sw.compute(plan, store, missing, workers=workers, scheduler=scheduler, progress=bar.update,
                       device=device)
    except interrupts.Interrupted as exc:
        kept = store.count()
        click.echo(f"rockslide: {exc.word}: {kept} of {plan.n_chunks} chunks are kept in {store.folder}; "
                   "the same command resumes from them", err=True)
        ctx.exit(exc.exit_code)
    computed = time.perf_counter() - computing
    return store, sw.collect(plan, store), plan.n_cases - reused_cases, computed


def _finish_sweep(plan, store, h5_path: Path, png_path: Path, *, no_plot: bool, started: float, dpi=None) -> None:
    """``NAME.sweep.h5`` exists: if it is this sweep's result (same definition key), draw its
    missing figure and remove its chunks (a run stopped in its final phase); else refuse."""
    from . import files, results
    from .plots import save_figure
    from .sweep import stored_figure

    try:
        stored = results.read_sweep(h5_path)
    except OutputError:
        stored = None
    if stored is None or stored.attrs.get("sweep_key") != plan.key:
        files.refuse_existing(h5_path, overwrite=False)
    drawn = ""
    if not no_plot and not (png_path.exists() or png_path.is_symlink()):
        save_figure(stored_figure(stored), png_path, overwrite=False, dpi=dpi)
        drawn = f"; drew its missing figure {png_path}"
    store.remove()
    click.echo(f"sweep {plan.case.name}: {h5_path} is this sweep's complete result{drawn}; removed its "
               f"chunks ({time.perf_counter() - started:.1f} s)")


def _command_line(ctx, case_file) -> str:
    """A sweep's or fragility analysis's command line: the sweep's axes in the order given, then the
    other options given."""
    import shlex

    from click.core import ParameterSource

    axes = ctx.meta.get("rockslide.sweep.axes", [])
    words = ["rockslide", ctx.command.name, str(case_file)]
    for name, text in axes:
        words += [f"--{name.replace('_', '-')}", text]
    for param in ctx.command.params:
        if not isinstance(param, click.Option) or param.name in {n for n, _ in axes}:
            continue
        if ctx.get_parameter_source(param.name) is not ParameterSource.COMMANDLINE:
            continue
        value = ctx.params.get(param.name)
        if param.is_flag:
            words += [param.opts[0]] if value else []
        elif param.multiple:
            for item in value or ():
                words += [param.opts[0], str(item)]
        elif value is not None:
            words += [param.opts[0], str(value)]
    return shlex.join(words)


def _note_first_compile(dispatcher, what="the numerical kernel") -> None:
    """Say so before a compile: when ``dispatcher``'s machine code is not in numba's cache yet
    (`compiled.is_warm`: the package build puts it there, so this is a new CPU, a new numba or an
    edited kernel), or when no cache folder can be written at all."""
    from .core import compiled

    if compiled.CACHE_IS_TEMPORARY:
        click.echo(f"rockslide: compiling {what} in memory, for this process only (about a minute): neither "
                   "the installation nor the user's cache folder can be written; set NUMBA_CACHE_DIR to a "
                   "writable folder to keep it", err=True)
    elif not compiled.is_warm(dispatcher):
        click.echo(f"rockslide: compiling {what} for this machine (once, about a minute on 2 cores; "
                   f"cached in {compiled.cache_folder(dispatcher)})", err=True)


def _column(value):
    if value is None:
        return None
    return int(value) if str(value).isdigit() else value


def _draw(result, name, path, *, overwrite, dpi=None, time_shift=0.0, zoom="auto", crop="auto", staging=None):
    """Draw the figure of one run (`plots.response_figure`) and save it (`plots.save_figure`)."""
    from .plots import response_figure, save_figure

    figure = response_figure(result, title=name, time_shift=time_shift, zoom=zoom, crop=crop)
    save_figure(figure, path, overwrite=overwrite, dpi=dpi, staging=staging)


def _result_set(h5_path: Path, png_path: Path, *, overwrite: bool, no_plot: bool, leftovers: bool = False,
                example: str = "out/case") -> bool:
    """Check the outputs of `run`, `sweep` or `fragility` before the work: a result is the set ``NAME.h5`` and
    ``NAME.png`` (``NAME.h5`` alone with ``--no-plot``).

    Returns True when, without ``overwrite``, ``NAME.h5`` exists but its set is not complete (the
    figure is missing, or ``leftovers`` of its run remain): the caller decides whether it is this
    case's result and finishes it. False when the run is to compute (nothing there, or
    ``overwrite``).

    Raises
    ------
    OutputError
        Without ``overwrite``: the complete set exists, or a ``NAME.png`` exists without its
        ``NAME.h5`` (a figure of another result).
    """
    from . import files

    files.check_destination(h5_path, overwrite=True, example=f"{example}.h5")
    files.check_destination(png_path, overwrite=True, example=f"{example}.png")
    if overwrite:
        return False
    if not (h5_path.exists() or h5_path.is_symlink()):
        files.refuse_existing(png_path, overwrite=False)
        return False
    if (no_plot or png_path.exists() or png_path.is_symlink()) and not leftovers:
        files.refuse_existing(h5_path, overwrite=False)
    return True


def _same_result(case, prepared, h5_path: Path, *, robustness: bool):
    """The stored result at ``h5_path`` if it is this case's (same case text, same records,
    robustness if asked), else an OutputError: it exists."""
    from . import files, results, runner

    try:
        stored = results.read_result(h5_path)
    except OutputError:
        stored = None
    same = (stored is not None and stored.case_text == case.text
            and [r.get("sha256") for r in stored.records]
            == [r.get("sha256") for r in runner.record_entries(prepared)]
            and (not robustness or "robustness" in stored.attrs))
    if not same:
        files.refuse_existing(h5_path, overwrite=False)
    return stored


class _RunProgress:
    """The ``progress`` callback of a single run: checks for Ctrl-C between kernel chunks and, on
    a terminal, shows a bar of the simulated time (a new pass, the robustness runs, restarts it)."""

    def __init__(self, name: str, *, show: bool):
        self.name = name
        self.show = show and sys.stderr.isatty()
        self.bar = None
        self.last = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.close()
        return False

    def __call__(self, reached: float, end: float) -> None:
        interrupts.check()
        if not self.show:
            return
        from tqdm import tqdm

        if self.bar is None or (self.last is not None and reached < self.last):
            if self.bar is not None:
                self.bar.close()
            self.bar = tqdm(total=round(end - reached, 3), unit="s", file=sys.stderr, desc=self.name,
                            dynamic_ncols=True, bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} s simulated "
                            "[{elapsed}<{remaining}]")
            self.start = reached
        self.bar.update(round(reached - self.start, 3) - self.bar.n)
        self.last = reached


def _case_dict(case):
    from .case import case_to_dict
    return case_to_dict(case)


def _json_default(value):
    if hasattr(value, "item"):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot serialise {type(value).__name__}")


def human_summary(name, summary, *, ground=None, units=None) -> str:
    """A short text summary of one run.

    Parameters
    ----------
    name : str
    summary : Summary
    ground : dict, optional
        The ground motion as applied (`records.GroundMotion.as_applied`).
    units : dict, optional
        The case's units as written (`case.Case.units`): peaks are shown in the unit of
        ``ground.scale.pga_horizontal`` (the vertical: of ``pga_vertical`` if given), else in gal,
        and in g.
    """
    from .units import percent_text

    units = units or {}
    verdict = summary.verdict
    if (summary.status == "ok" and not summary.overturned and not summary.undecided
            and math.isfinite(summary.max_rotation_ratio)):
        verdict += f", {percent_text(summary.max_rotation_ratio)} of alpha"
    lines = [f"{name}: {verdict}"]
    if ground is not None:
        lines.append("  " + _ground_line(ground, units))
    if summary.overturned:
        direction = "+" if summary.direction > 0 else "-"
        fall = ("" if summary.fall_start_time is None
                else f", falling since {summary.fall_start_time:.4f} s (rotation past alpha)")
        lines.append(f"  overturned at {summary.overturn_time:.4f} s, rotation {direction}pi/2{fall}")
    alpha = (f" (alpha {summary.alpha:.4f} rad, {math.degrees(summary.alpha):.2f} deg)"
             if math.isfinite(summary.alpha) else "")
    lines.append(f"  max rotation {summary.max_rotation:.5f} rad "
                 f"({math.degrees(summary.max_rotation):.3f} deg)"
                 f" at {summary.max_rotation_time:.3f} s{alpha}; impacts {summary.impacts}")
    lines.append(f"  max slip {1000 * summary.max_slip:.2f} mm; "
                 f"residual slip {1000 * summary.residual_slip:.2f} mm")
    seen = ", ".join(f"{s} {summary.time_in_state.get(s, 0.0):.2f} s" if s != "OVERTURNED" else s
                     for s in summary.states_seen)
    lines.append(f"  states: {seen}")
    return "\n".join(lines)


def _ground_line(ground: dict, units: dict) -> str:
    """``ground as applied: peaks 700 gal (0.714 g) H, 350 gal (0.357 g) V (records x1.19)``."""
    from .units import acceleration_text

    h_unit = units.get("ground.scale.pga_horizontal")
    v_unit = units.get("ground.scale.pga_vertical", h_unit)
    scales = [(role, ground[f"scale_{role}"]) for role in ("horizontal", "vertical")
              if ground.get(f"scale_{role}") is not None]
    peaks = (f"peaks {acceleration_text(ground['pga_horizontal'], h_unit)} H, "
             f"{acceleration_text(ground['pga_vertical'], v_unit)} V")
    if not scales:
        if ground["pga_horizontal"] == 0.0 and ground["pga_vertical"] == 0.0:
            return "ground as applied: still (no record: a free vibration)"
        return f"ground as applied: {peaks} (analytic pulses, not scaled)"
    if len(scales) == 2 and f"{scales[0][1]:.4g}" == f"{scales[1][1]:.4g}":
        factors = f"x{scales[0][1]:.4g}"
    else:
        factors = ", ".join(f"x{factor:.4g} {role[0].upper()}" for role, factor in scales)
    return f"ground as applied: {peaks} (records {factors})"


def entry() -> None:
    """The ``rockslide`` script and ``python -m rockslide``: `main`, in a process of its own.

    A command is a short-lived process, which allows two settings of the garbage collector that
    save 0.2-0.3 s of a warm run: rarer collections (the libraries loaded make hundreds of
    thousands of objects that live to the end, and each collection walks them again), and none at
    the exit (`gc.freeze`: the interpreter's last collections took 0.2 s to walk every object only
    to free what the process gives back anyway). Every file is closed and published before (or
    removed); exit handlers still run.

    numpy's OpenBLAS gets one thread unless ``OPENBLAS_NUM_THREADS`` says otherwise (set before
    numpy loads): its worker threads spin for about 0.1 s of CPU after loading, a third of a run
    without figure, and rockslide has no linear algebra large enough for threads (the sweep's
    threads are its own).
    """
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    gc.set_threshold(10_000, 50, 50)
    try:
        main(prog_name="rockslide")
    finally:
        gc.freeze()


if __name__ == "__main__":  # pragma: no cover
    entry()
