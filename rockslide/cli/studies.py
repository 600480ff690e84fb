"""``rockslide sweep`` and ``rockslide fragility``: studies of many cases, each one engine plan
(`engine.plan.Plan`) computed by `engine.execute.execute` with its chunks kept beside the result
(resumable after Ctrl-C or a crash), then its statistics written and drawn."""

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



class _SweepCommand(click.Command):
    """``rockslide sweep``, which answers an axis no longer offered (`sweep.RETIRED_AXES`) with one
    line naming what replaces it, exit 2, before anything else is read. Not an option of its own:
    the help and the command reference list only the axes offered."""

    def parse_args(self, ctx, args):
        known = {option for param in self.get_params(ctx) for option in getattr(param, "opts", ())}
        for arg in args:
            if arg == "--":
                break
            name = arg.split("=", 1)[0]
            if name.startswith("--") and name not in known:      # (the sweep module only then: --help stays light)
                from ..analyses.sweep import RETIRED_AXES

                if name[2:].replace("-", "_") in RETIRED_AXES:
                    raise CaseError(RETIRED_AXES[name[2:].replace("-", "_")], source=name)
        return super().parse_args(ctx, args)


def where_options(what: str, unit: str):
    """The options every study shares: where it computes, how it is chunked, its outputs."""
    options = [
        click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
                     help="Output folder (default: the case's output.dir)."),
        click.option("--overwrite", is_flag=True, help=f"Replace an existing result of this {what}."),
        click.option("--no-plot", is_flag=True, help=f"Do not draw the PNG figure (with --overwrite, an "
                     f"earlier figure of this {what} is removed)."),
        click.option("--workers", type=int, default=None, metavar="N",
                     help="Threads for a local run (default: all cores)."),
        click.option("--scheduler", default=None, metavar="ADDRESS",
                     help="Compute the chunks on this dask.distributed scheduler (e.g. tcp://10.0.0.5:8786, or "
                          "tls://10.0.0.5:8786 with the TLS options), one task per chunk; it is asked who it is "
                          "before anything is planned."),
        click.option("--tls-ca-file", type=click.Path(dir_okay=False, path_type=Path), default=None, metavar="PEM",
                     help="With a tls:// --scheduler: the cluster's CA certificate (default: dask's configuration "
                          "distributed.comm.tls.ca-file)."),
        click.option("--tls-cert", type=click.Path(dir_okay=False, path_type=Path), default=None, metavar="PEM",
                     help="With a tls:// --scheduler: this client's certificate, signed by the cluster's CA "
                          "(default: distributed.comm.tls.client.cert)."),
        click.option("--tls-key", type=click.Path(dir_okay=False, path_type=Path), default=None, metavar="PEM",
                     help="With a tls:// --scheduler: the key of --tls-cert, unless it is in that file (default: "
                          "distributed.comm.tls.client.key)."),
        click.option("--device", type=click.Choice(["cpu", "gpu", "auto"]), default="cpu", show_default=True,
                     help="Compute a local run on the CPU's cores or on an NVIDIA GPU (needs the extra: "
                          "pip install 'rockslide[gpu]'; docs/guide/gpu.md); auto: the GPU when one is usable "
                          "and the study has 10000 cases or more, else the CPU (the printout says why)."),
        click.option("--chunk-size", type=int, default=None, metavar="N",
                     help=f"{unit.capitalize()}s per chunk (default: about 1/100 of them, 4 to 256). Part of the "
                          f"{what}'s definition: a different size does not resume an interrupted run."),
        click.option("--wait-workers", type=click.FloatRange(0, 86400), default=None, metavar="SECONDS",
                     help="With --scheduler: how long to wait for a first worker to join the scheduler "
                          "(default 120 s; on SLURM or Kubernetes the workers start after it)."),
        click.option("--shard", default=None, metavar="I/N",
                     help=f"Compute only share I of N of the {what}'s chunks into its chunk folder and stop (N "
                          "processes, e.g. a SLURM job array, sharing the output folder); the same command "
                          "without --shard then collects them into the result (docs/clusters.md)."),
        click.option("--no-progress", is_flag=True,
                     help="No progress bar on stderr (there is none anyway when stderr is not a terminal)."),
        dpi_option("PNG figure"),
        size_option,
        click.option("--csv", "as_csv", is_flag=True,
                     help=f"Also write OUT/NAME.{'sweep' if what == 'sweep' else 'fragility'}.csv: one row per "
                          f"{unit} with its coordinates and results (units in the header), for a spreadsheet or "
                          "pandas."),
    ]

    def decorate(command):
        for option in reversed(options):
            command = option(command)
        return command
    return decorate


def _tls_files(ca_file, cert, key) -> dict:
    """The TLS options as `engine.execute.TLS_OPTIONS` names them (None: not given)."""
    return {"tls_ca_file": ca_file, "tls_client_cert": cert, "tls_client_key": key}


@main.command(cls=_SweepCommand)
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
@_axis_option("height_to_width", "dimensionless", "Height / width h/b of the block, the slenderness ratio "
              "of the field (the height kept; the width is height / (h/b))", "2:6:0.5")
@_axis_option("gravity", "acceleration", "Gravitational acceleration (gravity)", "9.8m/s^2,9.80665m/s^2")
@_axis_option("amplitude", "acceleration", "Amplitude of the horizontal pulse of a pulse case "
              "(ground.horizontal.amplitude)", "0.2g:3g:0.1g")
@_axis_option("period", "time", "Period of the horizontal pulse (ground.horizontal.period); with "
              "--amplitude, an overturning spectrum", "0.1:1:0.05")
@_axis_option("duration", "time", "Duration of a rectangular or half-sine horizontal pulse "
              "(ground.horizontal.duration)", "0.05:0.5:0.01")
@_axis_option("azimuth", "angle", "Azimuth of the block's width, clockwise from north, for a case with two "
              "horizontal components (block.orientation; degrees unless a unit is given)", "0:180:5")
@_axis_option("floor_period", "time", "Period of the first horizontal mode of the floor the block stands on "
              "(ground.floor.horizontal; a floor of one mode, 5 % damping and participation 1 when the case "
              "has none): the block's response over the building's period", "0.1s:3s:0.1s")
@click.option("--mu-kinetic-ratio", type=float, default=None, metavar="R",
              help="mu_kinetic = R * mu_static for --mu (default: the case's ratio).")
@records_dir_option
@where_options("sweep", "case")
def sweep(case_file, mu_kinetic_ratio, records_dir, out_dir, overwrite, no_plot, workers, scheduler, tls_ca_file,
          tls_cert, tls_key, device, chunk_size, no_progress, dpi, size, as_csv, shard, wait_workers, **_axes):
    """Grid of cases over friction, intensity, vertical factor, restitution, height/width (h/b), gravity or
    the period of the floor the block stands on, over a pulse's amplitude and period or duration,
    or over the block's orientation under two horizontal components (--azimuth,
    docs/two-components.md): CASE_FILE (YAML) -> OUT/NAME.sweep.h5 and OUT/NAME.sweep.png.

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

    from ..analyses import sweep as sw
    from ..case import load_case
    from ..engine.chunks import ChunkStore
    from ..engine.execute import check_where, parse_shard
    from ..engine.prepare import duration_text
    from ..io import files, records, results
    from ..plots import save_figure

    ctx = click.get_current_context()
    started = time.perf_counter()
    case = load_case(case_file)
    # the axes in the order given (dimension order): `_axis_option` keeps them; **_axes is unordered
    axes = [sw.parse_axis(name, text) for name, text in ctx.meta.get("rockslide.sweep.axes", [])]
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers,
                            tls=_tls_files(tls_ca_file, tls_cert, tls_key))
    shard = parse_shard(shard)
    h5_path, png_path = _outputs(case, out_dir, ".sweep")
    finishing = _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot, example="out/case.sweep",
                            leftovers=ChunkStore.beside(h5_path, "").root.exists())
    if _one_at_a_time(ctx, h5_path, "sweep"):         # another sweep of this file ran meanwhile
        finishing = _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot, example="out/case.sweep",
                                leftovers=ChunkStore.beside(h5_path, "").root.exists())
    n_points = math.prod(len(a) for a in axes) if axes else 0
    if axes and sw.planning_seconds(case, axes) > 10:
        click.echo(f"sweep {case.name}: checking the {n_points} points of the grid first (about "
                   f"{duration_text(sw.planning_seconds(case, axes))})")
    with tqdm(total=n_points, unit="case", file=sys.stderr, desc=f"{case.name}: checking",
              disable=no_progress or n_points < 10 * sw.PLAN_BATCH or not sys.stderr.isatty(),
              dynamic_ncols=True, leave=False) as bar:
        plan = sw.plan_sweep(case, axes, records_dir=records.records_dir(records_dir),
                             mu_kinetic_ratio=mu_kinetic_ratio, chunk_size=chunk_size, progress=bar.update)
    if finishing:
        _finish_sweep(plan, ChunkStore.beside(h5_path, plan.key), h5_path, png_path, no_plot=no_plot,
                      started=started, dpi=dpi, size=size)
        return
    files.remove_stale_temporaries([h5_path, png_path])
    done = _compute(ctx, plan, h5_path, what="sweep", description=plan.describe(), label=case.name, unit="case",
                    workers=workers, scheduler=scheduler, device=device, no_progress=no_progress, shard=shard,
                    wait_workers=wait_workers)
    variables = sw.sweep_variables(plan, done.states)
    done.states = None                      # 288 bytes a case: not held while the file is written
    with files.Staging(overwrite=overwrite) as staging:
        results.write_sweep(h5_path, sw.coordinates(plan), variables, overwrite=overwrite, staging=staging,
                            attrs=sw.root_attributes(plan, _command_line(ctx, case_file)))
        if not no_plot:
            save_figure(sw.figure(plan, variables, size=size), png_path, overwrite=overwrite, dpi=dpi, staging=staging)
        if as_csv:
            from ..io.datasets import sweep_dataset
            _write_csv(sweep_dataset(sw.table_coordinates(sw.coordinates(plan)), variables),
                       [a.name for a in plan.axes], h5_path.with_suffix(".csv"), overwrite=overwrite, staging=staging)
        staging.publish(remove=_stale_figure(h5_path, png_path, staging, no_plot=no_plot,
                                             format=results.SWEEP_FORMAT))
    done.store.remove()
    over = int(variables["overturned"][0].sum())
    outside = int((variables["status"][0] != 0).sum())
    undecided = int(variables["undecided"][0].sum())
    click.echo(f"  {over} of {plan.n_cases} overturned, {outside} outside the model; computed "
               f"{_rate(done, 'cases')}")
    worst = sw.worst_azimuth(plan, variables)
    if worst is not None:
        click.echo(f"  {worst['text']}")
    if undecided:
        click.echo(f"  {undecided} undecided: still moving at the end with the energy to overturn "
                   "(give the case a ground.tail for their free motion)")
    _step_note(plan)
    click.echo(f"  wrote {_written(h5_path, png_path, no_plot, as_csv)} in {time.perf_counter() - started:.1f} s")


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--suite", "suite_spec", required=True, metavar="SUITE",
              help="The records: a suite file (YAML: records: [{name:, horizontal:, vertical:}, ...]), a "
                   "folder of horizontal records, or a quoted glob of them ('records/*.csv').")
@click.option("--im", "im_text", default="pga", show_default=True, metavar="IM",
              help="Intensity measure each record is scaled to: pga, pgv, pga_rocking (PGA / (g tan "
                   "alpha)) or sa(T) (5 %-damped spectral acceleration, e.g. 'sa(0.5s)') of the records; "
                   "pfa, pfv of the floor the block stands on (the case's ground.floor); for a suite of two "
                   "horizontal components also rotd50_ or rotd100_ of pga, pgv or sa(T) (the others: of the "
                   "motion along the block).")
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
@click.option("--case-vertical", is_flag=True,
              help="When the suite has no vertical records: scale the case's vertical record with each "
                   "horizontal one (by its factor times ground.scale.vertical_factor) instead of leaving "
                   "the vertical out.")
@click.option("--samples", type=click.IntRange(0, 100_000), default=0, show_default=True, metavar="N",
              help="Draw N sets of the block's and contact's parameters per record from the case's uncertain "
                   "section (size, slenderness, friction, restitution) and run each at every level: the curves "
                   "then include the parameter uncertainty (drawn beside the case's own).")
@click.option("--seed", type=click.IntRange(0, 2**62), default=1, show_default=True,
              help="Seed of the parameter samples' Latin hypercube (record r uses seed + r).")
@click.option("--azimuth", "azimuth", default=None, metavar="SPEC",
              help="Orientations of the block (degrees unless a unit is given: START:STOP:STEP or a comma "
                   "list, e.g. 0:180:5) for a suite of two horizontal components: every record at every "
                   "orientation, the fits over them all (the orientation unknown, uniform); one value states "
                   "it (default: the case's block.orientation).")
@click.option("--json", "as_json", is_flag=True, help="Print the fits as one JSON object on stdout.")
@click.option("--export", "export", type=(click.Choice(["pelicun"]), str), default=(None, None),
              metavar="pelicun ID",
              help="Also write the fragility as a row of pelicun's fragility CSV with component ID ID, and its "
                   "JSON metadata: OUT/NAME.fragility.pelicun.csv and .json (docs/floors.md).")
@click.option("--export-family", type=click.Choice(["lognormal", "multilinear_CDF"]), default="lognormal",
              show_default=True, help="The exported limit states: the lognormal fits, or the stripes as "
                                      "pelicun's multilinear_CDF.")
@records_dir_option
@where_options("fragility analysis", "run")
def fragility(case_file, suite_spec, im_text, levels_text, damage_texts, units, resamples, case_vertical, samples,
              seed, azimuth, as_json, export, export_family, records_dir, out_dir, overwrite, no_plot, workers,
              scheduler, tls_ca_file, tls_cert, tls_key, device, chunk_size, no_progress, dpi, size, as_csv, shard,
              wait_workers):
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
        rockslide fragility example/example.yaml --suite example/suite-synthetic.yaml --levels 0.1g:1.5g:0.1g \\
            --export pelicun RS.example
    """
    from ..analyses import fragility as fr
    from ..case import load_case
    from ..engine.execute import check_where, parse_shard
    from ..io import files, records, results
    from ..plots import save_figure

    ctx = click.get_current_context()
    started = time.perf_counter()
    case = load_case(case_file)
    im = fr.parse_im(im_text)
    levels = fr.parse_levels(levels_text, im)
    states = fr.damage_states(damage_texts)
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers,
                            tls=_tls_files(tls_ca_file, tls_cert, tls_key))
    shard = parse_shard(shard)
    suite = fr.suite_at_azimuths(fr.suite_from(suite_spec, units=units), azimuth)
    fplan = fr.plan_fragility(case, suite, im, levels, records_dir=records.records_dir(records_dir),
                              chunk_size=chunk_size, case_vertical=case_vertical, samples=samples, seed=seed)
    h5_path, png_path = _outputs(case, out_dir, ".fragility")
    export_path = None
    if export[0] == "pelicun":
        from ..io import pelicun
        pelicun.check_export(im, export[1])
        export_path = h5_path.with_suffix(".pelicun.csv")
        for path in (export_path, export_path.with_suffix(".json")):
            files.check_destination(path, overwrite=overwrite, example="out/case.fragility.pelicun.csv")
    if _result_set(h5_path, png_path, overwrite=overwrite, no_plot=no_plot, example="out/case.fragility"):
        files.refuse_existing(h5_path, overwrite=False)           # input errors first, then outputs
    if _one_at_a_time(ctx, h5_path, "fragility analysis") and _result_set(
            h5_path, png_path, overwrite=overwrite, no_plot=no_plot, example="out/case.fragility"):
        files.refuse_existing(h5_path, overwrite=False)           # published by the one waited for
    files.remove_stale_temporaries([h5_path, png_path])
    plan = fplan.plan
    if fplan.vertical_note:
        click.echo(f"  note: {fplan.vertical_note}", err=as_json)
    done = _compute(ctx, plan, h5_path, what="fragility", description=fplan.describe(), label=case.name,
                    unit="run", workers=workers, scheduler=scheduler, device=device, no_progress=no_progress,
                    err=as_json, shard=shard, wait_workers=wait_workers)
    analysis = fr.analyse(fplan, done.states, states, resamples=resamples)
    coords, variables, attrs = fr.dataset(fplan, analysis, _command_line(ctx, case_file))
    with files.Staging(overwrite=overwrite) as staging:
        results.write_dataset(h5_path, coords, variables, format=results.FRAGILITY_FORMAT, attrs=attrs,
                              overwrite=overwrite, staging=staging)
        if not no_plot:
            save_figure(fr.figure(fplan, analysis, size=size), png_path, overwrite=overwrite, dpi=dpi, staging=staging)
        if as_csv:
            from ..io.datasets import study_dataset
            per_run = [name for name, _, _ in coords if name not in ("damage_state", "resample")]
            _write_csv(study_dataset(coords, variables), per_run, h5_path.with_suffix(".csv"), overwrite=overwrite,
                       staging=staging)
        if export_path is not None:
            from ..io.datasets import study_dataset
            *_, left_out = pelicun.write_pelicun(study_dataset(coords, variables, attrs), export[1], export_path,
                                                 family=export_family, overwrite=overwrite, staging=staging)
        staging.publish(remove=_stale_figure(h5_path, png_path, staging, no_plot=no_plot,
                                             format=results.FRAGILITY_FORMAT))
    done.store.remove()
    elapsed = time.perf_counter() - started
    if as_json:
        payload = {**fr.json_summary(fplan, analysis),
                   "files": {"hdf5": str(h5_path), "png": None if no_plot else str(png_path)},
                   "elapsed_s": round(elapsed, 3)}
        click.echo(json.dumps(payload, allow_nan=False, default=_json_default))
        return
    outside = int((analysis.variables["status"][0] != 0).sum())
    click.echo(f"  computed {_rate(done, 'runs')}; {outside} of {plan.n_cases} outside the model (left out of "
               "the fits)")
    undecided = int(analysis.variables["undecided"][0].sum())
    if undecided:
        click.echo(f"  {undecided} undecided: still moving at the end with the energy to overturn, counted as "
                   "not overturned (give the case a ground.tail for their free motion)")
    for i, (state, fit) in enumerate(zip(analysis.states, analysis.fits, strict=True)):
        click.echo("  " + fr.describe_fit(state, fit, im))
        for caveat in fr.caveats(fit, im):
            click.echo(f"    warning: {caveat}")
        if analysis.nominal_fits:
            click.echo("    without parameter uncertainty (the case's values): "
                       + fr.describe_fit(state, analysis.nominal_fits[i], im).split(": ", 1)[1])
    if export_path is not None:
        click.echo(f"  pelicun: {export_path} and {export_path.with_suffix('.json').name} ({export_family}, "
                   f"ID {export[1]})" + (f"; not exported: {'; '.join(left_out)}" if left_out else ""))
    _step_note(plan)
    click.echo(f"  wrote {_written(h5_path, png_path, no_plot, as_csv)} in {elapsed:.1f} s")


def _step_note(plan) -> None:
    """The step the study took, and what ``solver.dt: auto`` takes or would take (`step.StudyStep.note`)."""
    if plan.step_study is not None and plan.step_study.note():
        click.echo(f"  {plan.step_study.note()}")


def _stale_figure(h5_path: Path, png_path: Path, staging, *, no_plot: bool, format: str) -> list[Path]:
    """The figure to remove when a study's result is published: with ``--no-plot``, ``NAME.png``
    unless the result it was published with (the ``NAME.h5`` being replaced) holds the same
    results as the new one (`results.same_results`): a figure must not stand beside results it
    does not show, but rerunning the same study for its ``--json`` keeps its figure."""
    from ..io import results

    if not no_plot or not (png_path.exists() or png_path.is_symlink()):
        return [png_path] if no_plot else []
    new = next(tmp for tmp, path in staging.items if Path(path) == Path(h5_path))
    try:
        same = results.same_results(results.read_dataset(h5_path, format=format),
                                    results.read_dataset(new, format=format))
    except OutputError:                 # no result beside it, or another kind: the figure is not its
        same = False
    return [] if same else [png_path]


def _write_csv(dataset, dims, path: Path, *, overwrite: bool, staging) -> None:
    """``io.datasets.tidy_table`` of a study, written with the rest of its set."""
    from ..io.datasets import tidy_table
    from ..io.files import atomic_write

    with atomic_write(path, overwrite=overwrite, mode="w", what="table", staging=staging) as handle:
        handle.write(tidy_table(dataset, dims))


def _one_at_a_time(ctx, h5_path: Path, what: str) -> bool:
    """Hold the lock of ``h5_path``'s study (`files.exclusive` on ``.NAME.h5.lock`` beside it)
    until the command ends, so that two identical sweeps (or fragility analyses) into one folder
    run one after the other instead of sharing, and removing, one chunk folder (issue 28.6: the
    second one said "chunk 0 is missing or damaged" and left chunk files). Returns whether it had
    to wait (the outputs are then checked again)."""
    from ..io import files

    waited = []
    lock = h5_path.with_name(f".{h5_path.name}.lock")
    ctx.with_resource(files.exclusive(lock, waiting_for=f"another {what} writing {h5_path}",
                                      waited=lambda: waited.append(True)))
    return bool(waited)


def _outputs(case, out_dir, suffix: str) -> tuple[Path, Path]:
    """``OUT/NAME<suffix>.h5`` and ``.png``; OUT is ``--out-dir`` or the case's ``output.dir``."""
    from ..io.files import expand_user

    folder = expand_user(out_dir if out_dir is not None else case.output.dir,
                         source="--out-dir" if out_dir is not None else f"{case.source}: output.dir")
    return folder / f"{case.name}{suffix}.h5", folder / f"{case.name}{suffix}.png"


def _written(h5_path: Path, png_path: Path, no_plot: bool, as_csv: bool = False) -> str:
    names = [str(h5_path), *([] if no_plot else [str(png_path)]),
             *([str(h5_path.with_suffix(".csv"))] if as_csv else [])]
    return ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else names[0]


def _rate(done, unit: str) -> str:
    """``1517 cases in 1.2 s (1264 cases/s)``."""
    rate = f" ({done.computed / done.seconds:.0f} {unit}/s)" if done.computed and done.seconds > 0 else ""
    return f"{done.computed} {unit} in {done.seconds:.1f} s{rate}"


def _compute(ctx, plan, h5_path, *, what, description, label, unit, workers, scheduler, no_progress,
             device="cpu", err=False, shard=None, wait_workers=None):
    """`engine.execute.execute` with the chunks kept beside ``h5_path``, its notes on the console
    (stderr with ``err``) and a progress bar on a terminal; after Ctrl-C or SIGTERM, says what is
    kept and exits 130 or 143; with ``shard``, says what this share computed and exits 0."""
    from tqdm import tqdm

    from ..engine.chunks import ChunkStore
    from ..engine.execute import execute

    store = ChunkStore.beside(h5_path, plan.key)

    def report(text: str) -> None:
        click.echo(text, err=err or text.startswith("rockslide:"))

    show_warnings()                     # the input is accepted: its warnings, then the work
    try:
        # disable=None: tqdm draws only on a terminal, so that no frames land in log files
        with tqdm(total=plan.n_cases, unit=unit, file=sys.stderr, disable=True if no_progress else None,
                  dynamic_ncols=True, desc=label, smoothing=0.1) as bar:
            done = execute(plan, store, workers=workers, scheduler=scheduler, device=device, progress=bar.update,
                           report=report, what=what, label=label, description=description, unit=unit,
                           free_space_at=Path(h5_path).parent, shard=shard, wait_workers=wait_workers)
    except interrupts.Interrupted as exc:
        click.echo(f"rockslide: {exc.word}: {store.count()} of {plan.n_chunks} chunks are kept in {store.folder}; "
                   "the same command resumes from them", err=True)
        ctx.exit(exc.exit_code)
    if shard is not None:
        click.echo(f"{what} {label}: shard {shard[0]}/{shard[1]} computed {done.computed} {unit}s in "
                   f"{done.seconds:.1f} s; {store.count()} of {plan.n_chunks} chunks are in {store.folder} (the "
                   "same command without --shard collects them)", err=err)
        ctx.exit(0)
    return done



def _finish_sweep(plan, store, h5_path: Path, png_path: Path, *, no_plot: bool, started: float, dpi=None,
                  size=None) -> None:
    """``NAME.sweep.h5`` exists: if it is this sweep's result (same definition key), draw its
    missing figure and remove its chunks (a run stopped in its final phase); else refuse."""
    from ..analyses.sweep import stored_figure
    from ..io import files, results
    from ..plots import save_figure

    try:
        stored = results.read_sweep(h5_path)
    except OutputError:
        stored = None
    if stored is None or stored.attrs.get("sweep_key") != plan.key:
        files.refuse_existing(h5_path, overwrite=False)
    drawn = ""
    if not no_plot and not (png_path.exists() or png_path.is_symlink()):
        save_figure(stored_figure(stored, size=size), png_path, overwrite=False, dpi=dpi)
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
