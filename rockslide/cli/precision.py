"""``rockslide work-precision``: speed against error on the user's own case (a thin client of
`rockslide.work_precision`)."""

from __future__ import annotations

from pathlib import Path

import click

from .. import api
from .app import dpi_option, json_line, main, records_dir_option, show_warnings, size_option


@main.command("work-precision")
@click.argument("case_file", type=click.Path(path_type=Path))
@records_dir_option
@click.option("--reference", type=click.Choice(["auto", "solver", "finest"]), default="auto", show_default=True,
              help="What errors are measured against: the reference solver (DOP853), the kernel at the finest "
                   "step halved, or auto (the solver for short cases).")
@click.option("--step-end", is_flag=True, help="Also step-end switching (first order) besides located events.")
@click.option("--out", "png_path", type=click.Path(path_type=Path), default=None,
              help="The figure (default: OUT_DIR/NAME.work-precision.png).")
@click.option("--no-plot", is_flag=True, help="Print the table only.")
@click.option("--json", "as_json", is_flag=True, help="Print the table as one JSON object.")
@dpi_option("figure (PNG)")
@size_option
def work_precision(case_file, records_dir, reference, step_end, png_path, no_plot, as_json, dpi, size):
    """Error against CPU time on CASE_FILE at a few steps (whole divisors of its record's step):
    event times, largest rotation and verdict, against the reference solver or the finest step.

    \b
    Example:
        rockslide work-precision example/example.yaml
    """
    table = api.work_precision(case_file, records_dir=records_dir, reference=reference,
                               modes=("located", "step-end") if step_end else ("located",),
                               path=None if no_plot else (png_path or "default"), dpi=dpi, size=size)
    show_warnings()
    if as_json:
        click.echo(json_line(api.json_ready({"name": table.name, "reference": table.reference, "rows": table.rows,
                                             "reference_values": table.reference_values})))
    else:
        click.echo(table.text())
    if table.figure_path is not None:
        click.echo(f"  wrote {table.figure_path}", err=as_json)
