"""The smaller commands: ``info`` (a record), ``table1`` (the paper's Table 1), ``example`` (the
shipped example) and ``criteria`` (mode-initiation maps)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import click

from ..errors import CaseError, OutputError
from .app import _json_default, dpi_option, main, records_dir_option, size_option


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
def info(record, fmt, units, time_column, column, dt, skip_lines, as_json):
    """Describe an accelerogram (format, dt, duration, units and peaks), or what a result, sweep,
    fragility or risk file of rockslide holds (its summary, read back: nothing is computed again).

    \b
    Example:
        rockslide info example/synthetic_kt_h.at2
        rockslide info out/example.h5 --json
    """
    from ..io.records import record_info

    if _is_hdf5(record):
        details = _stored_summary(record)
        if as_json:
            click.echo(json.dumps(details, allow_nan=False, default=_json_default))
        elif details["kind"] == "result":
            click.echo(_stored_run_text(record))
        else:
            lines = [f"{record}", *(f"  {k:<18}{v}" for k, v in details.items() if not isinstance(v, (dict, list)))]
            lines += [f"  {state}: median {fit['median']}, beta {fit['beta']}" for state, fit in
                      details.get("fits", {}).items()]
            lines += [f"  {curve}: " + ", ".join(f"{key} {value:.4g}" for key, value in numbers.items()
                                                 if value is not None)
                      for curve, numbers in details.get("rates", {}).items()]
            click.echo("\n".join(lines))
        return

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
    if details.get("azimuth") is not None:
        click.echo(f"  azimuth   {math.degrees(details['azimuth']):g} deg (from the title line; ground.horizontal_1/2)")
    for key, value in (details.get("cosmos") or {}).items():
        if value not in (None, "") and key != "comments":
            click.echo(f"  {key.replace('_', ' '):<9} {value}")
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
    from ..analyses.table1 import reproduce
    from ..io import records

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
    pulse for overturning spectra; hazard-example-PGA.csv, a made-up hazard curve in OpenQuake's
    layout for 'rockslide risk'. The examples of every command's --help work anywhere after it.

    \b
    Example:
        rockslide example
        rockslide run example/example.yaml
    """
    from ..io.example import write_example

    paths = write_example(folder, overwrite=overwrite)
    click.echo(f"wrote {', '.join(str(p) for p in paths)}")
    click.echo(f"next: rockslide run {paths[0]}")


#: Panels of the criteria map (one per --av value): more are unreadable, and each takes a while.
MAX_CRITERIA_PANELS = 12


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path), required=False)
@click.option("--height", type=str, default=None, help="Block height (default: the case's, else 0.2 m).")
@click.option("--width", type=str, default=None, help="Block width (default: the case's, else 0.1 m).")
@click.option("--av", "vertical", type=str, default="-0.5g,0g,0.5g", show_default=True,
              help="Vertical accelerations with units (g, gal, m/s^2), comma separated (one panel each).")
@click.option("--ah-max", type=str, default="1.5g", show_default=True,
              help="Largest |A_h| on the map, with a unit (g, gal, m/s^2).")
@click.option("--mu-max", type=float, default=1.2, show_default=True, help="Largest mu on the map.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=Path("criteria.png"),
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
    import numpy as np

    from .._version import __version__
    from ..core import criteria as crit
    from ..plots import criteria_figure, save_figure
    from ..units import STANDARD_GRAVITY, parse_quantity

    block = None
    if case_file is not None:
        from ..case import load_case
        block = load_case(case_file).block
    h = block.height if block is not None and height is None else \
        parse_quantity(height or "0.2 m", "length", source="--height")
    w = block.width if block is not None and width is None else \
        parse_quantity(width or "0.1 m", "length", source="--width")
    if h <= 0 or w <= 0:
        raise CaseError("height and width must be positive lengths", source="--height/--width")
    avs = [parse_quantity(v, "acceleration", source="--av") / STANDARD_GRAVITY
           for v in vertical.split(",") if v.strip()]
    ah_max = parse_quantity(ah_max, "acceleration", source="--ah-max") / STANDARD_GRAVITY
    for option, value in (("--ah-max", ah_max), ("--mu-max", mu_max)):
        if not (math.isfinite(value) and value > 0):
            raise CaseError(f"expected a positive finite value, got {value:g}", source=option)
    if len(avs) > MAX_CRITERIA_PANELS:
        raise CaseError(f"{len(avs)} vertical accelerations give as many panels; expected at most "
                        f"{MAX_CRITERIA_PANELS}", source="--av")
    if not avs or any(not -1.0 < a for a in avs):
        raise CaseError("each vertical acceleration must be above -1 g (the block would fly)", source="--av")
    if not overwrite and (output.exists() or output.is_symlink()):
        raise OutputError(f"{output} exists (use --overwrite to replace it)")
    ah = np.linspace(0.0, ah_max, 301)
    mu = np.linspace(0.0, mu_max, 241)
    maps = [(f"A_v = {a:+.2f} g", crit.mode_map(ah, mu, a, w / 2, h / 2), crit.mode_boundaries(ah, a, w / 2, h / 2))
            for a in avs]
    caption = (f"block width × height {w:.4g} × {h:.4g} m, α = {math.atan2(w, h):.4g} rad; from rest under "
               f"constant accelerations (eqs. 6, 11, 26: no record, no time step; μ across the map, e plays no "
               f"part); rockslide {__version__}")
    figure = criteria_figure(ah, mu, maps, title=f"modes initiated from rest: {w:g} m wide, {h:g} m high",
                             size=size, caption=caption)
    save_figure(figure, output, overwrite=overwrite, dpi=dpi)
    click.echo(f"wrote {output}")


def _column(value):
    if value is None:
        return None
    return int(value) if str(value).isdigit() else value


def _is_hdf5(path: Path) -> bool:
    """Whether ``path`` starts with HDF5's signature (a result file; a record never does)."""
    from ..errors import RockslideError
    from ..inputs import open_regular

    try:
        with open_regular(path, what="file", error=RockslideError) as handle:   # a FIFO: not opened
            return handle.read(8) == b"\x89HDF\r\n\x1a\n"
    except (OSError, RockslideError):
        return False


def _stored_summary(path: Path) -> dict:
    """What a rockslide file holds, from its stored values: a run's summary (as ``run --json`` gives
    it, and its ensemble), a sweep's counts, a fragility analysis's fits."""
    import numpy as np

    from ..io import results

    kind = results.file_format(path)
    if kind == results.RISK_FORMAT:
        stored = results.read_dataset(path, format=kind)
        v, attrs = stored.variables, stored.attrs
        curves = [str(c) for c in dict((n, vals) for n, vals, _ in stored.coords)["curve"]]
        shown = [key for key in ("rate", "rate_missing_max", "return_period", "probability_in_life", "survival",
                                 "rejected") if key in v]
        return {"file": str(path), "kind": "risk", "damage_state": attrs.get("damage_state"),
                "fragility": attrs.get("fragility_source"), "intensity_measure": attrs.get("intensity_measure"),
                "command_line": attrs.get("command_line"),
                "rates": {curve: {key: _number(np.asarray(v[key][1])[i]) for key in shown}
                          for i, curve in enumerate(curves)},
                "rockslide_version": attrs.get("rockslide_version")}
    if kind in (results.SWEEP_FORMAT, results.FRAGILITY_FORMAT):
        stored = results.read_dataset(path, format=kind)
        v, attrs = stored.variables, stored.attrs
        out = {"file": str(path), "kind": "sweep" if kind == results.SWEEP_FORMAT else "fragility",
               "name": attrs.get("name"), "command_line": attrs.get("command_line"),
               "dimensions": {name: int(np.size(values)) for name, values, _ in stored.coords}}
        status = np.asarray(v["status"][1])
        out.update(n_cases=int(status.size), n_overturned=int(np.asarray(v["overturned"][1]).sum()),
                   n_outside_model=int((status != 0).sum()), n_undecided=int(np.asarray(v["undecided"][1]).sum()))
        if kind == results.FRAGILITY_FORMAT:
            states = [str(s) for s in dict((n, vals) for n, vals, _ in stored.coords)["damage_state"]]
            out["fits"] = {state: {key: _number(np.asarray(v[key][1])[i])
                                   for key in ("median", "median_lower", "median_upper", "beta", "beta_lower",
                                               "beta_upper")}
                           for i, state in enumerate(states)}
            out["intensity_measure"] = attrs.get("intensity_measure")
        out["rockslide_version"] = attrs.get("rockslide_version")
        return out
    stored = results.read_result(path)
    out = {"file": str(path), "kind": "result", "name": stored.name,
           **results.summary_to_json_dict(stored.result.summary, stored.result.events),
           "ground": stored.ground, "rockslide_version": stored.attrs.get("rockslide_version")}
    if "ensemble" in stored.attrs:
        out["ensemble"] = results.json_ready(json.loads(stored.attrs["ensemble"]))
    return out


def _number(value):
    value = float(value)
    return None if math.isnan(value) else value


def _stored_run_text(path: Path) -> str:
    """A result file's summary as ``rockslide run`` printed it (and its ensemble's lines)."""
    from ..io import results
    from .run import run_text

    stored = results.read_result(path)
    neighbourhood = json.loads(stored.attrs["ensemble"]) if "ensemble" in stored.attrs else None
    text = run_text(stored.name, stored.result.summary, neighbourhood, ground=stored.ground or None)
    if stored.base:                          # a block on a floor: PFA and PFV of what it stood on
        from ..engine.prepare import floor_peaks, floor_peaks_text
        r = stored.result
        text += f"\n  {floor_peaks_text(floor_peaks(r.ground_time, r.ground_horizontal, stored.base['horizontal']))}"
    return f"{text}\n  (read from {path}; rockslide {stored.attrs.get('rockslide_version', '?')})"
