"""The smaller commands: ``info`` (a record, or a file rockslide wrote), ``table1`` (the paper's
Table 1), ``example`` (the shipped example) and ``criteria`` (mode-initiation maps): clients of
`api.tools` and `api.stored`."""

from __future__ import annotations

from pathlib import Path

import click

from .. import api
from ..errors import CaseError
from .app import dpi_option, json_line, main, records_dir_option, size_option


@main.command()
@click.argument("record", type=click.Path(path_type=Path))
@click.option("--format", "fmt", default=None,
              help="File format (default: detected): at2, knet, cosmos, column, values, or an obspy format.")
@click.option("--units", default=None,
              help="Acceleration unit of the values (g, gal, m/s^2); default: what the file states (AT2, K-NET, "
                   "a column header such as 'Acceleration (g)').")
@click.option("--time-column", default=None,
              help="Column text: 1-based number or header name of the time column.")
@click.option("--column", default=None,
              help="Column text: 1-based number or header name of the acceleration column.")
@click.option("--dt", type=float, default=None,
              help="Sampling step [s]: for values, or to read one column without its time column.")
@click.option("--skip-lines", type=int, default=0,
              help="Lines to skip before the data (header lines of names are recognised without it).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
@click.option("--azimuth", default=None, metavar="ANGLE",
              help="A mesh (OBJ, STL, PLY): the shaking direction, clockwise from north (default 90 deg, its x axis).")
@click.option("--density", default=None, metavar="DENSITY", help="A mesh: its density (2650 kg/m^3), for its mass.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="A mesh: also draw its planar bodies (outline, support, centre of mass, tipping angles) there.")
def info(record, fmt, units, time_column, column, dt, skip_lines, as_json, azimuth, density, output):
    """Describe an accelerogram (format, dt, duration, units and peaks), what a result, sweep,
    fragility or risk file of rockslide holds (its summary, read back: nothing is computed again), or
    the planar bodies of a scanned object's mesh (OBJ, STL, PLY; --units gives its length unit) with
    the case-file keys of each (docs/meshes.md).

    \b
    Example:
        rockslide info example/synthetic_kt_h.at2
        rockslide info out/example.h5 --json
        rockslide info example/rock.obj --units m --density 2650kg/m^3
    """
    if api.is_mesh_file(record):
        details = api.describe_mesh(record, units=units, azimuth=azimuth, density=density, figure=output,
                                    overwrite=True)
        lines = details["lines"]
    elif api.is_result_file(record):
        details = api.describe_file(record)
        lines = api.stored_lines(record, details)
    else:
        details = api.describe_record(record, format=fmt, units=units, time_column=time_column, column=column, dt=dt,
                                      skip_lines=skip_lines)
        lines = api.record_lines(record, details)
    click.echo(json_line(details) if as_json else "\n".join(lines))


@main.command()
@records_dir_option
@click.option("--configs", type=click.Path(file_okay=False, path_type=Path), default="configs/table1",
              show_default=True, help="Folder of the Table 1 case files.")
@click.option("--out-dir", "out", type=click.Path(file_okay=False, path_type=Path),
              default="results", show_default=True,
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
    if old_out is not None:
        from click.core import ParameterSource

        if click.get_current_context().get_parameter_source("out") is ParameterSource.COMMANDLINE:
            raise CaseError("--out is the former name of --out-dir: give one of them", source="--out")
        out = old_out
    report = api.table1(configs, records_dir, out)
    for gravity, s in report["summary"].items():
        click.echo(f"g = {gravity}: {s['verdicts']}/{s['rows']} verdicts match the paper, "
                   f"{s['all']}/{s['rows']} verdicts and descriptions")
    click.echo(f"wrote {', '.join(str(p) for p in report['files'])} and {len(report['figures'])} figures "
               f"in {report['elapsed']:.1f} s")


@main.command()
@click.argument("folder", type=click.Path(file_okay=False, path_type=Path), default="example",
                required=False)
@click.option("--overwrite", is_flag=True, help="Replace the files if they exist.")
def example(folder, overwrite):
    """Write the shipped example into FOLDER (default: ./example): example.yaml, the paper's block on
    the project's own synthetic records, and those two records (synthetic_kt_h.at2,
    synthetic_kt_v.at2); suite-synthetic.yaml, a suite of six synthetic record pairs (in
    suite-synthetic/) for 'rockslide fragility'; spectrum-one-sine.yaml, a block under a one-sine
    pulse for overturning spectra; hazard-example-PGA.csv, a made-up hazard curve in OpenQuake's
    layout for 'rockslide risk'. The examples of every command's --help work anywhere after it.

    \b
    Example:
        rockslide example
        rockslide run example/example.yaml
    """
    paths = api.write_example(folder, overwrite=overwrite)
    click.echo(f"wrote {', '.join(str(p) for p in paths)}")
    click.echo(f"next: rockslide run {paths[0]}")


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path), required=False)
@click.option("--height", type=str, default=None, help="Block height (default: the case's, else 0.2 m).")
@click.option("--width", type=str, default=None, help="Block width (default: the case's, else 0.1 m).")
@click.option("--av", "vertical", type=str, default="-0.5g,0g,0.5g", show_default=True,
              help="Vertical accelerations with units (g, gal, m/s^2), comma separated (one panel each).")
@click.option("--ah-max", type=str, default="1.5g", show_default=True,
              help="Largest |A_h| on the map, with a unit (g, gal, m/s^2).")
@click.option("--mu-max", type=float, default=1.2, show_default=True, help="Largest mu on the map.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default="criteria.png",
              show_default=True, help="PNG to write.")
@click.option("--overwrite", is_flag=True, help="Replace an existing PNG.")
@dpi_option("PNG")
@size_option
def criteria(case_file, height, width, vertical, ah_max, mu_max, output, overwrite, dpi, size):
    """Draw the mode-initiation map (rest / slip / liftoff / liftoff-slip) of a block, from eqs. 6, 11, 26:
    of CASE_FILE's block if given, else of --height and --width.

    \b
    Example:
        rockslide criteria --height 0.2m --width 0.1m --av=-0.5g,0g,0.5g -o criteria.png
        rockslide criteria example/example.yaml -o criteria.png
    """
    path = api.criteria_map(case_file, height=height, width=width, vertical=vertical, ah_max=ah_max, mu_max=mu_max,
                            path=output, overwrite=overwrite, dpi=dpi, size=size)
    click.echo(f"wrote {path}")
