"""The smaller tools: a record described, the paper's Table 1 reproduced, a block's mode-initiation
map, the shipped example written."""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import CaseError, OutputError

#: Panels of the criteria map (one per vertical acceleration): more are unreadable, and each takes a while.
MAX_CRITERIA_PANELS = 12


def describe_record(path: str | Path, *, format: str | None = None, units: str | None = None, time_column=None,
                    column=None, dt: float | None = None, skip_lines: int = 0) -> dict:
    """An accelerogram's format, step, duration, units and peaks (`io.records.record_info`);
    ``time_column`` and ``column`` are 1-based numbers or header names."""
    from ..io.records import record_info

    def column_of(value):
        if value is None:
            return None
        return int(value) if str(value).isdigit() else value

    return record_info(path, format=format, units=units, time_column=column_of(time_column), column=column_of(column),
                       dt=dt, skip_lines=skip_lines)


def is_result_file(path: str | Path) -> bool:
    """Whether ``path`` starts with HDF5's signature (a file rockslide wrote; a record never does)."""
    from ..errors import RockslideError
    from ..inputs import open_regular

    try:
        with open_regular(path, what="file", error=RockslideError) as handle:   # a FIFO: not opened
            return handle.read(8) == b"\x89HDF\r\n\x1a\n"
    except (OSError, RockslideError):
        return False


def table1(configs: str | Path, records_dir: str | Path | None, out: str | Path) -> dict:
    """The paper's Table 1 and Figures 5-10 (`analyses.table1.reproduce`) from the case files in
    ``configs`` into ``out``. Returns its report: ``summary`` per gravity (verdicts and descriptions
    that match the paper), ``files``, ``figures``, ``elapsed`` [s]."""
    from ..analyses.table1 import reproduce
    from ..io import records

    configs = Path(configs)
    if not configs.is_dir():
        raise CaseError(f"{configs}: folder not found; expected the folder of the Table 1 case files "
                        "(configs/table1 in the repository)", source="configs")
    return reproduce(configs, records.records_dir(records_dir), Path(out))


def criteria_map(case=None, *, height=None, width=None, vertical="-0.5g,0g,0.5g", ah_max="1.5g", mu_max: float = 1.2,
                 path: str | Path = "criteria.png", overwrite: bool = False, dpi=None, size=None) -> Path:
    """Draw the mode-initiation map (rest / slip / liftoff / liftoff-slip) of a block from eqs. 6, 11
    and 26, of ``case``'s block or of ``height`` and ``width`` (default 0.2 m x 0.1 m): one panel
    per vertical acceleration of the comma list ``vertical``, up to ``ah_max`` and ``mu_max``."""
    import numpy as np

    from .._version import __version__
    from ..core import criteria as crit
    from ..plots import criteria_figure, save_figure
    from ..units import STANDARD_GRAVITY, parse_quantity
    from ._shared import as_case

    block = None if case is None else as_case(case).block
    h = block.height if block is not None and height is None else \
        parse_quantity(height or "0.2 m", "length", source="height")
    w = block.width if block is not None and width is None else \
        parse_quantity(width or "0.1 m", "length", source="width")
    if h <= 0 or w <= 0:
        raise CaseError("height and width must be positive lengths", source="height/width")
    avs = [parse_quantity(v, "acceleration", source="vertical") / STANDARD_GRAVITY
           for v in str(vertical).split(",") if v.strip()]
    ah_max = parse_quantity(ah_max, "acceleration", source="ah_max") / STANDARD_GRAVITY
    for name, value in (("ah_max", ah_max), ("mu_max", mu_max)):
        if not (math.isfinite(value) and value > 0):
            raise CaseError(f"expected a positive finite value, got {value:g}", source=name)
    if len(avs) > MAX_CRITERIA_PANELS:
        raise CaseError(f"{len(avs)} vertical accelerations give as many panels; expected at most "
                        f"{MAX_CRITERIA_PANELS}", source="vertical")
    if not avs or any(not -1.0 < a for a in avs):
        raise CaseError("each vertical acceleration must be above -1 g (the block would fly)", source="vertical")
    path = Path(path)
    if not overwrite and (path.exists() or path.is_symlink()):
        raise OutputError(f"{path} exists (use --overwrite to replace it)")
    mu = np.linspace(0.0, mu_max, 241)
    about = "from rest under constant accelerations (eqs. 6, 11, 26: no record, no time step; μ across the map, " \
            f"e plays no part); rockslide {__version__}"
    if block is not None and block.asymmetric and height is None and width is None:
        # a body tips over corner 1 under A_h > 0 and corner 2 under A_h < 0: both sides drawn
        (b1, b2), k = block.corners, block.radius_of_gyration
        body = {"half_width_2": b2, "radius_of_gyration": k}
        ah = np.linspace(-ah_max, ah_max, 601)
        maps = [(f"A_v = {a:+.2f} g", crit.mode_map(ah, mu, a, b1, h / 2, **body),
                 crit.mode_boundaries(ah, a, b1, h / 2, **body)) for a in avs]
        caption = f"{block.describe()}; A_h > 0 turns it about corner 1 (b1), A_h < 0 about corner 2 (b2); {about}"
        title = (f"modes initiated from rest: a body with corners {b1:.4g} m and {b2:.4g} m, centre of mass "
                 f"{h / 2:.4g} m high")
        figure = criteria_figure(ah, mu, maps, title=title, size=size, caption=caption,
                                 xlabel="horizontal acceleration A_h [g]")
    else:
        ah = np.linspace(0.0, ah_max, 301)
        maps = [(f"A_v = {a:+.2f} g", crit.mode_map(ah, mu, a, w / 2, h / 2), crit.mode_boundaries(ah, a, w / 2, h / 2))
                for a in avs]
        caption = f"block width × height {w:.4g} × {h:.4g} m, α = {math.atan2(w, h):.4g} rad; {about}"
        figure = criteria_figure(ah, mu, maps, title=f"modes initiated from rest: {w:g} m wide, {h:g} m high",
                                 size=size, caption=caption)
    save_figure(figure, path, overwrite=overwrite, dpi=dpi)
    return path


def write_example(folder: str | Path = "example", *, overwrite: bool = False) -> list[Path]:
    """Write the shipped example into ``folder`` (`io.example.write_example`): its case files, records,
    suite and hazard curve; returns the files written, the case file first."""
    from ..io.example import write_example as write

    return write(folder, overwrite=overwrite)


def work_precision(case, *, records_dir=None, reference: str = "auto", modes=("located",), path=None,
                   overwrite: bool = True, dpi=None, size=None):
    """Error against CPU time on one case, at a few steps (`analyses.precision.work_precision`), as
    ``rockslide work-precision``.

    Parameters
    ----------
    case : Case, mapping or path
    records_dir : str or Path, optional
    reference : {"auto", "solver", "finest"}
        Errors against the reference solver (DOP853), the kernel's finest step halved, or the
        solver when the case is short.
    modes : sequence of str
        Event schemes: ``located`` and/or ``step-end``.
    path : str or Path, optional
        Also draw the figure there (``"default"``: ``OUT/NAME.work-precision.png``, OUT the case's
        ``output.dir``).
    overwrite, dpi, size
        Of the figure.

    Returns
    -------
    analyses.precision.PrecisionTable
        ``rows`` (step [s], CPU [s], errors of the event times [s] and the largest rotation [rad],
        verdict), ``text()`` the printout, ``figure_path`` the figure written (or None).
    """
    from ..analyses import precision
    from ..engine import prepare as engine
    from ..io import records
    from ._shared import as_case

    case = as_case(case)
    if reference not in ("auto", "solver", "finest"):
        raise CaseError(f"expected auto, solver or finest, got {reference!r}", source="reference")
    prepared = engine.prepare(case, records.records_dir(records_dir), history=False)
    table = precision.work_precision(prepared, reference=reference, modes=tuple(modes))
    if path is not None:
        from ..outputs import output_folder
        from ..plots import save_figure

        if str(path) == "default":
            path = output_folder(None, case) / f"{case.name}.work-precision.png"
        save_figure(precision.figure(table, size=size), path, overwrite=overwrite, dpi=dpi)
        table.figure_path = Path(path)
    return table


#: The file endings read as meshes (`rockslide.mesh`) by `describe_mesh` and ``rockslide info``.
MESH_ENDINGS = (".obj", ".stl", ".ply")


def is_mesh_file(path) -> bool:
    """Whether ``path`` names a mesh (OBJ, STL, PLY) by its ending."""
    return str(path).lower().endswith(MESH_ENDINGS)


def describe_mesh(path: str | Path, *, units: str | None, azimuth=None, density=None, mass=None,
                  figure: str | Path | None = None, overwrite: bool = False, dpi=None, size=None) -> dict:
    """A scanned object's planar bodies along ``azimuth`` and across it (`mesh.planar_bodies`;
    docs/meshes.md), as ``rockslide info rock.obj`` prints them, with the case-file keys of each.

    Parameters
    ----------
    path : str or Path
        A closed triangle mesh (OBJ, STL, PLY).
    units : str
        Its length unit (``m``, ``cm``, ``mm``, ``in``, ``ft``): a mesh file does not say.
    azimuth : str or float, optional
        The shaking direction, clockwise from north (``"30 deg"``; SI numbers in rad); default 90
        deg, along the mesh's x axis (east).
    density, mass : str or float, optional
        ``"2650 kg/m^3"`` (or SI), or the mass [kg]: the body's mass.
    figure : str or Path, optional
        Also draw its outline, support, centre of mass and tipping angles there (`plots.body_figure`).

    Returns
    -------
    dict
        ``lines`` (the printout), ``bodies`` (per plane: ``b1``, ``b2``, ``h`` [m], ``k2`` [m^2],
        ``mass`` [kg], ``azimuth`` [rad], and ``block``, the case file's keys of that body).
    """
    from .. import mesh
    from ..units import parse_quantity

    if units is None:
        raise CaseError("give the mesh's length unit (m, cm, mm, in or ft): a mesh file does not state it",
                        source="units")
    az = math.pi / 2 if azimuth is None else parse_quantity(azimuth, "angle", source="azimuth", si_numbers=True)
    rho = None
    if density is not None:
        rho = parse_quantity(density, "density", source="density", si_numbers=True)
        if not (math.isfinite(rho) and rho > 0.0):
            raise CaseError(f"expected a positive density such as '2650 kg/m^3', got {density!r}", source="density")
    kg = None if mass is None else parse_quantity(mass, "mass", source="mass")
    bodies = mesh.planar_bodies(mesh.read_mesh(path, units=units), azimuth=az, density=rho, mass=kg)
    out = {"file": str(path), "lines": mesh.describe(bodies), "bodies": []}
    for body in bodies:
        block = {"centre_of_mass_height": f"{body.h:.6g} m",
                 "half_widths": [f"{body.b1:.6g} m", f"{body.b2:.6g} m"],
                 "radius_of_gyration": f"{body.radius_of_gyration:.6g} m"}
        if body.mass is not None:
            block["mass"] = f"{body.mass:.6g} kg"
        out["bodies"].append({"plane": body.plane, "azimuth": body.azimuth, "b1": body.b1, "b2": body.b2,
                              "h": body.h, "k2": body.k2, "mass": body.mass, "block": block})
        out["lines"].append(f"case file, along {math.degrees(body.azimuth) % 360:g} deg: block: "
                            "{" + ", ".join(f"{k}: {v}" if not isinstance(v, list) else f"{k}: [{v[0]}, {v[1]}]"
                                            for k, v in block.items()) + "}")
    if figure is not None:
        from ..plots import body_figure, save_figure
        save_figure(body_figure(bodies, title=Path(path).name, size=size), figure, overwrite=overwrite, dpi=dpi)
        out["figure"] = str(figure)
    return out

