"""``rockslide run`` (one case: its result file, figure and printout) and ``rockslide plot``: clients
of `api.run` and `api.redraw` / `api.plot_results`."""

from __future__ import annotations

import time
from pathlib import Path

import click

from .. import api
from ..errors import CaseError
from ..units import parse_quantity
from .app import dpi_option, json_line, main, records_dir_option, size_option
from .console import RunProgress, bars, reporter

#: Largest ``plot --time-shift`` [s]: the bound of a case's start time (``ground.start``).
MAX_TIME_SHIFT = 1e6


def scale_options(command):
    """``--pga``, ``--vertical-factor`` and ``--amplitude``: the case at another intensity, as a
    sweep's point (`api.run`)."""
    for name, what, example in (
            ("amplitude", "Amplitude of the horizontal pulse of a pulse case (ground.horizontal.amplitude)", "0.5g"),
            ("vertical_factor", "Factor on the vertical record (ground.scale.vertical_factor)", "0.5"),
            ("pga", "Peak horizontal ground acceleration (ground.scale.pga_horizontal), with a unit", "0.6g")):
        command = click.option(f"--{name.replace('_', '-')}", name, default=None, metavar="VALUE",
                               help=f"{what}, e.g. {example}: the case at this value, as a sweep's point.")(command)
    return command


@main.command()
@click.argument("case_file", type=click.Path(path_type=Path))
@records_dir_option
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder (default: the case's output.dir).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object on stdout.")
@click.option("--overwrite", is_flag=True, help="Replace existing results of this case.")
@click.option("--no-plot", is_flag=True, help="Do not draw the PNG figure (with --overwrite, an earlier "
              "figure of this case is removed: it showed the result replaced).")
@click.option("--ensemble", "members", default=None, metavar="N|auto|precision:W",
              help="Also run N neighbours of the case, drawn over what is uncertain (the case's uncertain "
                   "section, or intensity +-5 %, restitution +-0.05, friction +-5 %, size and slenderness "
                   "+-2 %), and report the probability of overturning with its 95 % interval; 'auto' (or "
                   "precision:W) adds neighbours until that interval is narrower than 0.1 (or W).")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=1, show_default=True,
              help="Seed of the ensemble's Latin hypercube.")
@click.option("--robustness", is_flag=True,
              help="The verdict's robustness: an ensemble of 200 neighbours (--ensemble 200); robust when "
                   "none of them flips it.")
@click.option("--device", type=click.Choice(["cpu", "gpu", "auto"]), default="cpu", show_default=True,
              help="Where the ensemble's neighbours compute: the CPU's cores or an NVIDIA GPU (docs/guide/gpu.md).")
@scale_options
@dpi_option("PNG figure")
@size_option
def run(case_file, records_dir, out_dir, as_json, overwrite, no_plot, members, seed, robustness, device, pga,
        vertical_factor, amplitude, dpi, size):
    """Compute one case: CASE_FILE (YAML) -> OUT/NAME.h5 and OUT/NAME.png.

    \b
    Example:
        rockslide run example/example.yaml --json
        rockslide run example/example.yaml --pga 0.6g
        rockslide run example/example.yaml --ensemble 200
        rockslide run example/spectrum-one-sine.yaml --size column
    """
    started = time.perf_counter()
    case = api.load_case(case_file)
    outputs = api.OutputSet(api.output_folder(out_dir, case), case.name, overwrite=overwrite, plot=not no_plot,
                            dpi=dpi, size=size)
    with RunProgress(case.name) as progress:
        result = api.run(case, records_dir=records_dir, outputs=outputs, progress=progress, seed=seed, device=device,
                         ensemble=True if robustness and members is None else members, report=reporter(err=as_json),
                         pga=pga, vertical_factor=vertical_factor, amplitude=amplitude, bars=bars())
    elapsed = time.perf_counter() - started
    if as_json:
        click.echo(json_line({**api.run_payload(result), "files": outputs.files(), "elapsed_s": round(elapsed, 3)}))
        return
    click.echo("\n".join(api.run_lines(result, units=case.units)))
    click.echo(f"  wrote {result.written} in {elapsed:.2f} s")


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
    shift = parse_quantity(time_shift, "time", source="--time-shift")
    if not abs(shift) <= MAX_TIME_SHIFT:
        raise CaseError(f"{time_shift!r} is beyond +-{MAX_TIME_SHIFT:g} s, where float64 still resolves "
                        "a record's samples on the time axis", source="--time-shift")
    zoom = _time_range(window, "--window", {"auto": "auto", "none": None})
    span = _time_range(crop, "--crop", {"auto": "auto", "all": None})
    if len(result_files) > 1:
        if zoom != "auto":
            raise CaseError("applies to one result file, not to several overlaid", source="--window")
        stems = [Path(f).name.split(".")[0] for f in result_files]
        own = Path(result_files[0]).parent / ("-vs-".join(stems[:3]) + ("-etc" if len(stems) > 3 else "") + ".png")
        png = output if output is not None else own
        api.plot_results(result_files, size=size, time_shift=shift, crop=span, path=png, dpi=dpi,
                         overwrite=overwrite or png.resolve() == own.resolve())
        click.echo(f"drew {png}")
        return
    own = Path(result_files[0]).with_suffix(".png")
    png = output if output is not None else own
    # the result's own figure is the one redrawn; another file is replaced only when asked to
    api.redraw(result_files[0], png, time_shift=shift, zoom=zoom, crop=span, dpi=dpi, size=size,
               overwrite=overwrite or png.resolve() == own.resolve())
    click.echo(f"redrew {png}")


def _time_range(text: str, option: str, words: dict):
    """``START:END`` (times with units as in case files, bare numbers in s) as a pair of seconds,
    or the value of one of ``words``."""
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
