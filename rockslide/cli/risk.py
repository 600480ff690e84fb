"""``rockslide risk``: a fragility curve over a site's hazard curves, to an annual rate of reaching
a damage state: a client of `api.risk_study`."""

from __future__ import annotations

from pathlib import Path

import click

from .. import api
from ..errors import CaseError
from .app import dpi_option, json_line, main, show_warnings, size_option
from .console import command_line


@main.command()
@click.argument("fragility_file", required=False, type=click.Path(path_type=Path))
@click.option("--hazard", "hazard_files", multiple=True, required=True, type=click.Path(path_type=Path),
              metavar="FILE", help="Hazard curves: OpenQuake's hazard-curve CSV export (one curve per site; give "
              "several files for branches or quantiles), or a CSV of IM level and annual rate of exceedance. "
              "Repeat for more files.")
@click.option("--damage", default="overturn", show_default=True, metavar="STATE",
              help="The fragility file's damage state (e.g. 'rotation>0.5alpha').")
@click.option("--stripes", is_flag=True, help="Use the fragility file's empirical fractions per stripe (linear "
              "in ln x between them) instead of its lognormal fit.")
@click.option("--model", type=click.Choice(["lognormal", "isotonic", "empirical"]), default=None,
              help="The fragility file's curve (default: the one 'rockslide fragility --model' chose, else the "
              "lognormal): its lognormal fit, the isotonic (monotone maximum-likelihood) curve of its stripes, or "
              "the stripes' fractions (= --stripes).")
@click.option("--fragility-table", type=click.Path(path_type=Path), default=None, metavar="FILE",
              help="Instead of a fragility file: a CSV of levels and probabilities, its header naming the measure "
              "and unit ('PGA [g], probability').")
@click.option("--median", default=None, metavar="LEVEL", help="Without a fragility file: the median of a "
              "lognormal fragility, with its unit (0.5g).")
@click.option("--beta", type=float, default=None, help="Without a fragility file: its logarithmic standard "
              "deviation.")
@click.option("--im", "im_text", default="pga", show_default=True, metavar="IM",
              help="Intensity measure of --median: pga, pgv or sa(T), e.g. 'sa(0.3s)'.")
@click.option("--life", default="50yr", show_default=True, metavar="YEARS",
              help="Service life for the probability of the damage state (50yr, 100).")
@click.option("--age", default=None, metavar="YEARS", help="Age of a precariously balanced rock (24ka): its "
              "survival probability under each hazard curve, and the curves it rejects.")
@click.option("--confidence", type=float, default=0.95, show_default=True,
              help="A curve is rejected when the rock would have toppled with more than this probability.")
@click.option("--hazard-units", default=None, metavar="UNIT", help="Unit of a plain table's levels when its "
              "header does not say (default: OpenQuake's, g; cm/s for PGV).")
@click.option("--trim-poe", "--drop-zero-poe", "trim_poe", is_flag=True, help="Leave out the levels at the ends of "
              "each hazard curve where the PoE has no rate: 1 at the lowest levels (OpenQuake writes it for long "
              "investigation times), 0 at the highest (below its precision). The rate is then a lower bound, and "
              "says by how much at most; the printout names the levels left out. Without it a PoE of 1 or 0 is "
              "refused. (--drop-zero-poe: its former name.)")
@click.option("--out-dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder (default: the fragility file's folder, else the current one).")
@click.option("--name", default=None, help="Name of the outputs OUT/NAME.risk.h5 and .png (default: the "
              "fragility file's name, else 'lognormal').")
@click.option("--overwrite", is_flag=True, help="Replace an existing result.")
@click.option("--no-plot", is_flag=True, help="Do not draw the PNG figure.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as one JSON object on stdout.")
@dpi_option("PNG figure")
@size_option
def risk(fragility_file, hazard_files, damage, stripes, model, fragility_table, median, beta, im_text, life, age,
         confidence, hazard_units, trim_poe, out_dir, name, overwrite, no_plot, as_json, dpi, size):
    """Annual rate of a damage state at a site: a fragility integrated over hazard curves,
    FRAGILITY_FILE (NAME.fragility.h5) or --median/--beta -> OUT/NAME.risk.h5 and OUT/NAME.risk.png.

    lambda_F = integral of P(F|x) |d lambda(x)|, the hazard curve log-log interpolated between its
    levels (a power law on each interval) and integrated exactly. Prints per hazard curve the rate,
    the return period, the probability in --life years, the intensities that contribute most, and
    with --age a rock's survival probability and whether it rejects the curve. A hazard curve that
    ends where the fragility still rises gives a lower bound, and says by how much at most.

    With a fragility file of 'rockslide fragility' (its --im pga):
    rockslide risk out/example.fragility.h5 --hazard example/hazard-example-PGA.csv

    \b
    Example:
        rockslide risk --median 0.5g --beta 0.4 --hazard example/hazard-example-PGA.csv --age 24ka
        rockslide risk --median 0.5g --beta 0.4 --hazard example/hazard-example-PGA.csv --name site --json
    """
    if fragility_file is None and fragility_table is None and (median is None or beta is None):
        raise CaseError("give a fragility file, or a lognormal with both --median and --beta (e.g. --median 0.5g "
                        "--beta 0.4)", source="FRAGILITY")
    ctx = click.get_current_context()
    outputs = api.risk_outputs(fragility_file, out_dir=out_dir, name=name, overwrite=overwrite, plot=not no_plot,
                               dpi=dpi, size=size, table=fragility_table)
    result = api.risk_study(fragility_file, list(hazard_files), damage=damage, stripes=stripes, median=median,
                            beta=beta, im=im_text, life=life, age=age, confidence=confidence,
                            hazard_units=hazard_units, trim_poe=trim_poe, model=model, fragility_table=fragility_table,
                            outputs=outputs,
                            command_line=command_line(ctx, fragility_file if fragility_file is not None else "")
                            .replace(" '' ", " ", 1))
    show_warnings()
    for line in result.warnings:
        click.echo(line, err=True)
    if as_json:
        click.echo(json_line({**result.summary, "files": outputs.files()}))
        return
    click.echo("\n".join(result.lines))
    click.echo(f"  wrote {result.written}")
