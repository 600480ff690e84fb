"""``rockslide run`` (one case: its result file, figure and printout) and ``rockslide plot``."""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import click

from .. import interrupts
from ..errors import CaseError, OutputError
from .app import _json_default, _result_set, dpi_option, main, records_dir_option, show_warnings, size_option

#: A single run expected to take longer than this [s] says so before it starts (and shows a
#: progress bar on a terminal).
LONG_RUN = 10.0


#: Largest ``plot --time-shift`` [s]: the bound of a case's start time (``ground.start``).
MAX_TIME_SHIFT = 1e6

#: A run's figure is drawn from its history kept in memory while it has at most this many rows (96
#: MB; reading the file back would take as much); a longer history is read back from the file.
KEEP_HISTORY_ROWS = 2_000_000


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path))
@records_dir_option
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder (default: the case's output.dir).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object on stdout.")
@click.option("--overwrite", is_flag=True, help="Replace existing results of this case.")
@click.option("--no-plot", is_flag=True, help="Do not draw the PNG figure (with --overwrite, an earlier "
              "figure of this case is removed: it showed the result replaced).")
@click.option("--ensemble", "members", type=int, default=None, metavar="N",
              help="Also run N neighbours of the case, drawn over what is uncertain (the case's uncertain "
                   "section, or intensity +-5 %, restitution +-0.05, friction +-5 %, size and slenderness "
                   "+-2 %), and report the probability of overturning with its 95 % interval.")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=1, show_default=True,
              help="Seed of the ensemble's Latin hypercube.")
@click.option("--robustness", is_flag=True,
              help="The verdict's robustness: an ensemble of 200 neighbours (--ensemble 200); robust when "
                   "none of them flips it.")
@dpi_option("PNG figure")
@size_option
def run(case_file, records_dir, out_dir, as_json, overwrite, no_plot, members, seed, robustness, dpi, size):
    """Compute one case: CASE_FILE (YAML) -> OUT/NAME.h5 and OUT/NAME.png.

    \b
    Example:
        rockslide run example/example.yaml --json
        rockslide run example/example.yaml --ensemble 200
        rockslide run example/spectrum-one-sine.yaml --size column
    """
    from ..case import case_to_dict, load_case
    from ..engine import prepare as runner
    from ..engine.step import choice_attributes
    from ..io import files, records, results

    started = time.perf_counter()
    case = load_case(case_file)
    folder = files.expand_user(out_dir if out_dir is not None else case.output.dir,
                               source="--out-dir" if out_dir is not None else f"{case.source}: output.dir")
    h5_path = folder / f"{case.name}.h5"
    png_path = folder / f"{case.name}.png"
    prepared = runner.prepare(case, records.records_dir(records_dir))     # input errors first
    ens = eplan = None
    if members is not None or robustness:       # the ensemble's modules (numba's JIT) only when asked
        from ..analyses import ensemble as ens
        members = ens.DEFAULT_MEMBERS if members is None else members
        eplan = ens.plan_ensemble(case, members, seed=seed, records_dir=records.records_dir(records_dir))
    ground = runner.applied_ground(prepared)
    stored = None        # this case's complete result, of which only the figure is missing
    if _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot):
        stored = _same_result(case, prepared, h5_path, eplan=eplan)
    files.remove_stale_temporaries([h5_path, png_path])
    show_warnings()
    if stored is None:
        work = runner.work(prepared)
        if work.seconds > LONG_RUN:
            click.echo(f"rockslide: note: {work.describe()}", err=True)
        files.warn_free_space(folder, work.rows * results.BYTES_PER_ROW)
        from ..core import native
        if native.ahead_of_time() is None:      # no machine code from the build: numba's JIT
            from ..core import kernel
            from ..engine.execute import first_compile_note
            note = first_compile_note(kernel.run)
            if note:
                click.echo(note, err=True)
        with files.Staging(overwrite=overwrite) as staging:
            keep = 0 if no_plot else KEEP_HISTORY_ROWS
            with results.ResultWriter(h5_path, overwrite=overwrite, staging=staging, keep_rows=keep) as writer, \
                    _RunProgress(case.name, show=work.seconds > LONG_RUN) as progress:
                streamed = prepared.case.solver.method == "kernel"
                result = runner.simulate_prepared(prepared, on_chunk=writer.append_history if streamed else None,
                                                  progress=progress)
                neighbourhood = group = None
                if eplan is not None:               # on this machine's cores, in memory
                    neighbourhood, dimension, group = ens.compute(eplan, result.summary.overturned,
                                                                  progress=lambda cases: interrupts.check())
                writer.finish(result, name=case.name, case_text=case.text, case=case_to_dict(case, case_file=False),
                              records=runner.record_entries(prepared), ground=ground,
                              extra_attrs={**({} if neighbourhood is None else ens.attributes(neighbourhood)),
                                           **choice_attributes(prepared.step_choice)},
                              extra_groups={**(runner.base_motion(prepared) or {}),
                                            **({} if group is None else {"ensemble": (dimension, group)})} or None)
            ensemble_png = folder / f"{case.name}.ensemble.png"
            if not no_plot:
                kept = writer.written_result()
                _draw(kept if kept is not None else results.read_result(writer.tmp).result, case.name,
                      png_path, overwrite=overwrite, dpi=dpi, staging=staging, size=size,
                      about=_run_about(case, prepared, result.step),
                      base=_base_of(runner.base_motion(prepared)))
                if neighbourhood is not None:
                    _draw_ensemble(neighbourhood, group, result.summary, case.name, ensemble_png,
                                   overwrite=overwrite, dpi=dpi, staging=staging, size=size,
                                   about=_run_about(case, prepared, result.step))
            stale = [png_path] if no_plot else []
            if overwrite and (no_plot or neighbourhood is None):
                stale.append(ensemble_png)          # it showed the neighbourhood of the result replaced
            staging.publish(remove=stale)
        written = f"{h5_path}" + ("" if no_plot else f" and {png_path}")
        if neighbourhood is not None and not no_plot:
            written += f" and {ensemble_png}"
    else:
        with files.Staging(overwrite=False) as staging:
            _draw(stored, stored.name, png_path, overwrite=False, dpi=dpi, staging=staging, size=size)
            staging.publish()
        result = stored.result
        neighbourhood = None if eplan is None else json.loads(stored.attrs["ensemble"])
        written = f"{png_path} (the missing figure of the complete {h5_path})"
    elapsed = time.perf_counter() - started
    summary = result.summary
    floor_peaks = None if prepared.base is None else \
        runner.floor_peaks(result.ground_time, result.ground_horizontal, prepared.base.horizontal)
    if as_json:
        payload = {"name": case.name, **results.summary_to_json_dict(summary, result.events),
                   "ground": ground, "floor": None if floor_peaks is None else
                   {"description": runner.floor_text(case), **floor_peaks},
                   "ensemble": results.json_ready(neighbourhood),
                   "integration": results.json_ready(runner.step_report(prepared, result.step)),
                   "files": {"hdf5": str(h5_path), "png": None if no_plot else str(png_path)},
                   "elapsed_s": round(elapsed, 3)}
        click.echo(json.dumps(payload, allow_nan=False, default=_json_default))
    else:
        click.echo(run_text(case.name, summary, neighbourhood, ground=ground, units=case.units))
        if prepared.step_choice is not None:
            click.echo(f"  solver.dt: {prepared.step_choice.describe()}")
        floor = runner.floor_text(case)
        if floor:
            click.echo(f"  {floor}")
            click.echo(f"  {runner.floor_peaks_text(floor_peaks)}")
        click.echo(f"  wrote {written} in {elapsed:.2f} s")


@main.command()
@click.argument("result_files", nargs=-1, required=True, type=click.Path(path_type=Path), metavar="RESULT_FILE...")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Figure to write; the format follows its extension: .png, .pdf, .svg, .eps... "
                   "(default: the result's name with .png, next to it; for several files, their names joined "
                   "by -vs- with .png, next to the first).")
@click.option("--time-shift", default="0 s", show_default=True, metavar="TIME",
              help="Time added to the time axis, with a unit as in case files (e.g. '-25 s'; a bare "
                   "number is in s), to lay the figure beside another's.")
@click.option("--window", default="auto", show_default=True, metavar="START:END|auto|none",
              help="The magnified window of one result file, in the figure's time (e.g. 30:36 or '30 s:36 s'); "
                   "none: no magnified panel.")
@click.option("--crop", default="auto", show_default=True, metavar="START:END|auto|all",
              help="Time range of the response and ground panels (auto: where the ground or the block "
                   "moves; all: the whole record).")
@click.option("--overwrite", is_flag=True,
              help="Replace the file given with -o if it exists (the result's own figure, and the default "
                   "figure of several files, is always redrawn).")
@dpi_option("figure (PNG)")
@size_option
def plot(result_files, output, time_shift, window, crop, dpi, overwrite, size):
    """Redraw the figure of a result, sweep or fragility file (replaces it), or overlay several
    files of one kind: runs (rotation, slip and ground motion on shared axes), sweeps (side by
    side on one colour scale) or fragility analyses (their curves and bands), named after their
    cases.

    \b
    Example:
        rockslide plot out/example.h5
        rockslide plot out/example.h5 --window 6.6:7.2 -o out/example-impact.pdf
        rockslide plot out/example.sweep.h5 --size column
        rockslide plot out/example.fragility.h5
        rockslide plot out/example.h5 out/spectrum-one-sine.h5 --size page -o out/two-runs.pdf
    """
    from ..io import files
    from ..units import parse_quantity

    shift = parse_quantity(time_shift, "time", source="--time-shift")
    if not abs(shift) <= MAX_TIME_SHIFT:
        raise CaseError(f"{time_shift!r} is beyond +-{MAX_TIME_SHIFT:g} s, where float64 still resolves "
                        "a record's samples on the time axis", source="--time-shift")
    zoom = _time_range(window, "--window", {"auto": "auto", "none": None})
    span = _time_range(crop, "--crop", {"auto": "auto", "all": None})
    if len(result_files) > 1:
        from ..api import plot_results

        if zoom != "auto":
            raise CaseError("applies to one result file, not to several overlaid", source="--window")
        stems = [Path(f).name.split(".")[0] for f in result_files]
        own = Path(result_files[0]).parent / ("-vs-".join(stems[:3]) + ("-etc" if len(stems) > 3 else "") + ".png")
        png = output if output is not None else own
        plot_results(result_files, size=size, time_shift=shift, crop=span, path=png, dpi=dpi,
                     overwrite=overwrite or png.resolve() == own.resolve())
        click.echo(f"drew {png}")
        return
    result_file = result_files[0]
    own = Path(result_file).with_suffix(".png")
    png = output if output is not None else own
    # the result's own figure is the one redrawn; another file is replaced only when asked to
    replace = overwrite or png.resolve() == own.resolve()
    read = files.Unchanged(result_file)        # a figure of what was read, or nothing (issue 28.6)
    with files.Staging(overwrite=replace) as staging:
        _draw_stored(result_file, png, shift=shift, zoom=zoom, span=span, dpi=dpi, replace=replace,
                     staging=staging, size=size)
        staging.publish(verify=read)
    click.echo(f"redrew {png}")


def _draw_stored(result_file, png, *, shift, zoom, span, dpi, replace, staging, size=None):
    """The figure of a result, sweep, fragility or risk file (`plot`) at ``size``, staged in ``staging``."""
    from ..io import results

    kind = results.file_format(result_file)
    if kind in (results.SWEEP_FORMAT, results.FRAGILITY_FORMAT, results.RISK_FORMAT):
        from ..api import plot_results
        from ..plots import save_figure
        what = {results.SWEEP_FORMAT: "sweep", results.FRAGILITY_FORMAT: "fragility"}.get(kind, "risk")
        _only_for_results(shift, zoom, span, f"{what} files")
        save_figure(plot_results([result_file], size=size), png, overwrite=replace, dpi=dpi, staging=staging)
    else:
        stored = results.read_result(result_file)
        times = stored.result.ground_time
        if times.size:
            first, last = float(times[0]) + shift, float(times[-1]) + shift
            for option, pair in (("--window", zoom), ("--crop", span)):
                if isinstance(pair, tuple) and (pair[1] <= first or pair[0] >= last):
                    raise CaseError(f"{pair[0]:g} to {pair[1]:g} s is outside the result, which runs from "
                                    f"{first:g} to {last:g} s (in the figure's time)", source=option)
        _draw(stored, stored.name, png, overwrite=replace, time_shift=shift, zoom=zoom, crop=span, dpi=dpi,
              size=size, staging=staging)


def _only_for_results(shift, zoom, span, what: str) -> None:
    """Refuse ``--time-shift``, ``--window`` and ``--crop`` given for ``what`` (a study's file)."""
    given = [option for option, value, default in (("--time-shift", shift, 0.0), ("--window", zoom, "auto"),
                                                   ("--crop", span, "auto")) if value != default]
    if given:
        raise CaseError(f"applies to result files, not to {what}", source=given[0])


def _time_range(text: str, option: str, words: dict):
    """``START:END`` (times with units as in case files, bare numbers in s) as a pair of seconds,
    or the value of one of ``words``."""
    from ..units import parse_quantity

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


def _draw(result, name, path, *, overwrite, dpi=None, time_shift=0.0, zoom="auto", crop="auto", staging=None,
          size=None, about=None, base=None):
    """Draw the figure of one run (`plots.response_figure`) and save it (`plots.save_figure`).
    ``result``: a run's `Result`, or a result file read back (`results.read_result`: it gives its
    own caption, unit and ground under the building). ``about`` of a `Result`: (case text, record
    entries, integration step [s], version or None: this one, the two horizontal components'
    azimuths [rad] or None), for its caption (`plots.case_caption`) and the unit of its ground
    motion; ``base``: the ground under the building of a case on a floor."""
    from .._version import __version__
    from ..plots import along_the_block, case_caption, pga_unit, response_figure, save_figure

    caption, unit, horizontal = None, None, None
    if about is not None:
        text, entries, step, version, azimuths = about
        caption = case_caption(text, records=entries, step=step, version=version or __version__, azimuths=azimuths)
        unit, horizontal = pga_unit(text), along_the_block(text)
    figure = response_figure(result, title=name, time_shift=time_shift, zoom=zoom, crop=crop, size=size,
                             caption=caption, unit=unit, horizontal=horizontal, base=base)
    save_figure(figure, path, overwrite=overwrite, dpi=dpi, staging=staging)


def _run_about(case, prepared, step: float) -> tuple:
    """`_draw`'s ``about`` of a run just computed."""
    from ..engine import prepare as runner

    components = prepared.components
    return (case.text, runner.record_entries(prepared), step, None,
            None if components is None else (components.azimuth_1, components.azimuth_2))


def _base_of(group: dict | None) -> dict | None:
    """``{time, horizontal, vertical}`` of `prepare.base_motion`'s group (None without a floor)."""
    if group is None:
        return None
    (_, time, _), variables = group["base"]
    return {"time": time, **{role: values for role, (_, values, _) in variables.items()}}


def _same_result(case, prepared, h5_path: Path, *, eplan=None):
    """The stored result at ``h5_path`` if it is this case's (same case text, same records, the
    same ensemble if one is asked), else an OutputError: it exists."""
    from ..engine import prepare as runner
    from ..io import files, results

    try:
        stored = results.read_result(h5_path)
    except OutputError:
        stored = None
    same = (stored is not None and stored.case_text == case.text
            and [r.get("sha256") for r in stored.records]
            == [r.get("sha256") for r in runner.record_entries(prepared)]
            and (eplan is None or _same_ensemble(stored.attrs.get("ensemble"), eplan)))
    if not same:
        files.refuse_existing(h5_path, overwrite=False)
    return stored


def run_text(name: str, summary, neighbourhood: dict | None = None, *, ground=None, units=None) -> str:
    """The printout of a run (`human_summary`); with its ensemble's summary (`ensemble.summarise`),
    led by the probability of overturning when a neighbour flips the verdict (`ensemble.describe`)."""
    lines = human_summary(name, summary, ground=ground, units=units).split("\n")
    if neighbourhood is not None:
        from ..analyses import ensemble as ens
        described = ens.describe(neighbourhood, lines[0].split(": ", 1)[1])
        lines = [f"{name}: {described[0]}", *lines[1:], *described[1:]]
    return "\n".join(lines)


def _draw_ensemble(summary: dict, variables: dict, nominal, name: str, path: Path, *, overwrite: bool, dpi,
                   staging, size=None, about=None) -> None:
    """The neighbourhood's figure (`plots.ensemble_figure`): its members' largest rotations
    (``about`` as in `_draw`)."""
    from .._version import __version__
    from ..analyses import ensemble as ens
    from ..plots import case_caption, ensemble_figure, save_figure

    ok = variables["status"][1] == 0
    ratio = variables["max_rotation_ratio"][1][ok]
    over = variables["overturned"][1][ok].astype(bool)
    headline = ens.describe(summary, nominal.verdict)[0]
    figure = ensemble_figure(ratio, over, math.inf if nominal.overturned else nominal.max_rotation_ratio,
                             summary_text=headline.split("; ", 1)[-1],
                             title=f"{name}: {summary['n']} neighbours (seed {summary['seed']})", size=size,
                             caption="" if about is None else case_caption(about[0], records=about[1], step=about[2],
                                                                           version=about[3] or __version__,
                                                                           azimuths=about[4]))
    save_figure(figure, path, overwrite=overwrite, dpi=dpi, staging=staging)


def _same_ensemble(text, eplan) -> bool:
    """Whether a result file's ``ensemble`` attribute is the ensemble ``eplan`` would compute."""
    try:
        stored = json.loads(text)
    except (TypeError, ValueError):
        return False
    quantities = {name: d.spec() for name, d in eplan.distributions.items()}
    return stored.get("n") == eplan.n and stored.get("seed") == eplan.seed and stored.get("quantities") == quantities


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
    from ..units import percent_text

    units = units or {}
    verdict = summary.verdict
    if (summary.status == "ok" and not summary.overturned and not summary.undecided
            and math.isfinite(summary.max_rotation_ratio)):
        verdict += f", {percent_text(summary.max_rotation_ratio)} of alpha"
    lines = [f"{name}: {verdict}"]
    if ground is not None:
        lines.append("  " + _ground_line(ground, units))
        if ground.get("components"):
            lines.append("  " + _components_line(ground["components"], units))
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


def _components_line(components: dict, units: dict) -> str:
    """``two components (0 deg, 90 deg), block at 30 deg: along 674 gal, across 800 gal (59 % of the
    motion ignored by the planar model)``."""
    from ..units import acceleration_text

    unit = units.get("ground.scale.pga_horizontal")
    azimuths = ", ".join(f"{math.degrees(components[k]):g}" for k in ("azimuth_1", "azimuth_2"))
    return (f"two components (azimuths {azimuths} deg), block at {math.degrees(components['orientation']):g} deg: "
            f"peak along {acceleration_text(components['pga_along'], unit)}, across "
            f"{acceleration_text(components['pga_across'], unit)} (ignored by the planar model: "
            f"{100 * components['ignored_share']:.0f} % of the horizontal Arias intensity)")


def _ground_line(ground: dict, units: dict) -> str:
    """``ground as applied: peaks 700 gal (0.714 g) H, 350 gal (0.357 g) V (records x1.19)``."""
    from ..units import acceleration_text

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
