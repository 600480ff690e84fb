"""``rockslide sweep`` and ``rockslide fragility``: clients of `api.sweep_study` and
`api.fragility_study`, which plan, compute (resumable from the chunks kept beside the result) and
write the output set; the commands parse their options, call them and print."""

from __future__ import annotations

import time
from pathlib import Path

import click

from .. import api
from ..errors import CaseError
from .app import dpi_option, json_line, main, records_dir_option, size_option
from .console import bars, command_line, reporter


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
            if name.startswith("--") and name not in known:      # (the API only then: --help stays light)
                replaced = api.retired_axis(name[2:].replace("-", "_"))
                if replaced:
                    raise CaseError(replaced, source=name)
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
                     help=f"{unit.capitalize()}s per chunk (default: about 1/100 of them, 4 to 256; on the GPU a "
                          f"launch's, up to 262144). Part of the {what}'s definition: a different size does not "
                          "resume an interrupted run."),
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
@_axis_option("b1", "length", "Distance b1 of the base corner a positive ground acceleration tips the body over "
              "(block.half_widths[0]; a rectangle becomes the body of its half height and b2 = width/2: "
              "docs/asymmetric.md)", "20mm:100mm:5mm")
@_axis_option("b2", "length", "Distance b2 of the other base corner (block.half_widths[1])", "50mm:150mm:10mm")
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
    ctx = click.get_current_context()
    started = time.perf_counter()
    case = api.load_case(case_file)
    axes = ctx.meta.get("rockslide.sweep.axes", [])   # in the order given (dimension order); **_axes is unordered
    outputs = api.OutputSet(api.output_folder(out_dir, case), case.name, "sweep", overwrite=overwrite,
                            plot=not no_plot, csv=as_csv, dpi=dpi, size=size)
    result = api.sweep_study(case, axes, mu_kinetic_ratio=mu_kinetic_ratio, records_dir=records_dir, device=device,
                             workers=workers, scheduler=scheduler, tls=_tls_files(tls_ca_file, tls_cert, tls_key),
                             wait_workers=wait_workers, chunk_size=chunk_size, outputs=outputs, shard=shard,
                             report=reporter(), bars=bars(no_progress=no_progress),
                             command_line=command_line(ctx, case_file, axes))
    if result is not None:
        _print(result, started)


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
@click.option("--model", type=click.Choice(["lognormal", "isotonic", "empirical"]), default="lognormal",
              show_default=True, help="The curve offered to 'rockslide risk' and the pelicun export: the lognormal "
              "fit, the isotonic (monotone maximum-likelihood) curve, or the per-level fractions.")
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
              seed, azimuth, model, as_json, export, export_family, records_dir, out_dir, overwrite, no_plot, workers,
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
    ctx = click.get_current_context()
    started = time.perf_counter()
    case = api.load_case(case_file)
    outputs = api.OutputSet(api.output_folder(out_dir, case), case.name, "fragility", overwrite=overwrite,
                            plot=not no_plot, csv=as_csv, dpi=dpi, size=size)
    result = api.fragility_study(
        case, suite_spec, im=im_text, levels=levels_text, damage=damage_texts, units=units, resamples=resamples,
        case_vertical=case_vertical, samples=samples, seed=seed, azimuth=azimuth, records_dir=records_dir,
        device=device, workers=workers, scheduler=scheduler, tls=_tls_files(tls_ca_file, tls_cert, tls_key),
        wait_workers=wait_workers, chunk_size=chunk_size, outputs=outputs, shard=shard,
        export=export if export[0] else None, export_family=export_family, model=model, report=reporter(err=as_json),
        bars=bars(no_progress=no_progress), command_line=command_line(ctx, case_file))
    if result is None:
        return
    if as_json:
        click.echo(json_line({**result.summary, "files": outputs.files(),
                              "elapsed_s": round(time.perf_counter() - started, 3)}))
        return
    _print(result, started)


def _print(result, started: float) -> None:
    """A study's printout, then what it wrote and how long it took."""
    for line in result.lines:
        click.echo(line)
    if result.written:
        click.echo(f"  wrote {result.written} in {time.perf_counter() - started:.1f} s")
