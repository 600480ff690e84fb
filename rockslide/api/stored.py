"""Files rockslide wrote: `read_result`, `plot_results`, `export_pelicun`, and what a file holds
(`describe_file`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from ..analyses.kinds import KINDS, of_format
from ..errors import CaseError, OutputError
from .runs import RunResult


def read_result(path: str | Path):
    """Read any file rockslide writes.

    Returns
    -------
    RunResult
        For a run's result file (``NAME.h5``).
    xarray.Dataset
        For a sweep (``NAME.sweep.h5``), a fragility file (``NAME.fragility.h5``) or a risk file
        (``NAME.risk.h5``): the same dataset `sweep`, `fragility` or `risk` returned.

    Raises
    ------
    OutputError
        The file is missing or is not a rockslide file of a known format and version.
    """
    from ..io import datasets, results
    from ._shared import path_arg

    kind = of_format(results.file_format(path_arg(path, "path", optional=False)))
    if kind.name == "run":
        return _run_result(results.read_result(path), path)
    stored = results.read_dataset(path, format=kind.format)
    return datasets.study_dataset(stored.coords, stored.variables, stored.attrs)


def _read(path):
    """``(kind, what its reader gives)`` of a file rockslide wrote (`analyses.kinds`, `io.results`)."""
    from ..io import results

    kind = of_format(results.file_format(path))
    if kind.name == "run":
        return kind, results.read_result(path)
    if kind.name == "sweep":
        return kind, results.read_sweep(path)
    return kind, results.read_dataset(path, format=kind.format)


def _run_result(stored, path) -> RunResult:
    """A `RunResult` of a result file read back (`io.results.read_result`)."""
    ensemble = None
    if "ensemble" in stored.attrs:
        try:
            ensemble = json.loads(str(stored.attrs["ensemble"]))
        except ValueError:
            raise OutputError("its attribute 'ensemble' is not the JSON rockslide writes", source=str(path)) from None
    floor = None
    if stored.base:                         # a block on a floor: PFA and PFV of what it stood on
        from ..engine.prepare import floor_peaks
        r = stored.result
        floor = floor_peaks(r.ground_time, r.ground_horizontal, stored.base["horizontal"])
    return RunResult(name=stored.name, result=stored.result, ground=stored.ground, records=stored.records,
                     case_text=stored.case_text, attrs=stored.attrs, ensemble=ensemble, floor=floor,
                     base=stored.base)


def plot_results(results: Sequence, *, size=None, names: Sequence[str] | None = None, time_shift: float = 0.0,
                 zoom: tuple | None | str = "auto", crop: tuple | None | str = "auto", path: str | Path | None = None,
                 overwrite: bool = False, dpi: float | None = None):
    """The figure of one result, or several of one kind overlaid, as ``rockslide plot A.h5 B.h5``.

    Parameters
    ----------
    results : sequence of str, Path or RunResult
        Result files (of runs, sweeps, fragility or risk analyses: all of one kind) or runs (`run`).
        One: its own figure (`plots.response_figure`, or the sweep's, fragility or risk analysis's).
        Several runs: liftoff angle, slip and ground motion on shared axes
        (`plots.runs_overlay_figure`); sweeps: their largest rotation side by side on one colour
        scale; fragility analyses: their curves with their confidence bands on one plot.
    size : None, "column", "page", "slide", "WxH" or (width, height)
        The figure's size [in]: a journal column (3.5 in wide), a page (7 in), a 16:9 slide
        (10 x 5.6 in) or the pair given; fonts follow it. Default: the figure's own size.
    names : sequence of str, optional
        The legend's names (default: the cases' names, or the files' names where two cases share
        one).
    time_shift : float
        Added to the time axis of runs [s].
    zoom : "auto", (t0, t1) or None
        The magnified window of a single run (`plots.response_figure`).
    crop : "auto", (t0, t1) or None
        The time range of runs.
    path : str or Path, optional
        Also save the figure there (the format follows the extension), atomically.
    overwrite : bool
        Replace ``path`` if it exists.
    dpi : float, optional
        Resolution of a raster ``path`` (default 150).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    CaseError
        Files of different kinds, sweeps over different axes, fragility analyses over different
        intensity measures, a bad size.
    OutputError
        A file that is not a rockslide file, or ``path`` exists (without ``overwrite``).
    """
    from .. import plots
    from ..units import parse_figure_size

    size = parse_figure_size(size, source="size")
    import os

    if isinstance(results, (str, os.PathLike, RunResult)) and not isinstance(results, bytes):
        items = [results]
    elif hasattr(results, "__iter__") and not isinstance(results, bytes):
        items = list(results)
    else:
        raise CaseError(f"expected result files or runs, got {type(results).__name__}", source="results")
    if not items:
        raise CaseError("no result to draw; give one file or more", source="plot_results")
    kinds, loaded, stems = [], [], []
    for item in items:
        if not isinstance(item, RunResult):
            from ._shared import path_arg
            path_arg(item, "results", optional=False)
        kind, stored = (KINDS["run"], item) if isinstance(item, RunResult) else _read(item)
        if kinds and kind != kinds[0]:
            raise CaseError(f"a {kind.name} file among {kinds[0].name} files ({items[0]}); overlay files of one "
                            "kind", source=str(item))
        kinds.append(kind)
        loaded.append(stored)      # a run's file gives its own caption and ground under a floor
        stems.append(item.name if isinstance(item, RunResult) else Path(item).name.split(".")[0])
    kind = kinds[0]
    names = _names(names, loaded, stems, kind)
    if kind.name != "run":
        if len(loaded) > 1 and not kind.overlays:
            raise CaseError("risk files are drawn one at a time (each is one site's hazard and one fragility)",
                            source=str(items[1]))
        figure = kind.stored_figure(loaded[0], size=size) if len(loaded) == 1 else \
            kind.overlay_figure(loaded, names, size=size)
    elif len(loaded) == 1:
        figure = plots.response_figure(loaded[0], title=names[0], time_shift=time_shift, zoom=zoom, crop=crop,
                                       size=size)
    else:
        caption = "\n".join(f"{name}: {plots.run_caption(run)}" for run, name in zip(loaded, names, strict=True))
        figure = plots.runs_overlay_figure([run.result for run in loaded], names, title=" and ".join(names),
                                           caption=caption, size=size, time_shift=time_shift, crop=crop,
                                           unit=plots.pga_unit(loaded[0].case_text),
                                           floors=[plots.on_a_floor(run.case_text) for run in loaded])
    if path is not None:
        plots.save_figure(figure, path, overwrite=overwrite, dpi=dpi)
    return figure


def _names(names, loaded, stems, kind) -> list[str]:
    """The legend's names: given, else the cases' names, else the files' where two cases share one."""
    if names is None:
        names = [item.name if kind.name == "run" else str(item.attrs.get("name") or stem)
                 for item, stem in zip(loaded, stems, strict=True)]
        if len(set(names)) < len(names):
            names = stems if len(set(stems)) == len(stems) else [f"{n} ({i + 1})" for i, n in enumerate(names)]
    names = [str(n) for n in names]
    if len(names) != len(loaded):
        raise CaseError(f"{len(names)} names for {len(loaded)} results", source="names")
    return names


def export_pelicun(fragility, component_id: str, path: str | Path, *, family: str = "lognormal",
                   description: str = "", overwrite: bool = False) -> tuple[Path, Path]:
    """Write a fragility as a row of pelicun's fragility CSV and its JSON metadata entry, as
    ``rockslide fragility ... --export pelicun ID`` does (`io.pelicun`; docs/floors.md).

    Parameters
    ----------
    fragility : xarray.Dataset or str or Path
        The dataset `fragility` returned, or a ``NAME.fragility.h5`` file.
    component_id : str
        The row's ID, e.g. ``"RS.cabinet.5F"``.
    path : str or Path
        The CSV file; the JSON is written beside it with the suffix ``.json``.
    family : str
        ``"lognormal"`` (the maximum-likelihood fits; demand unit g or cm/s) or ``"multilinear_CDF"``
        (the stripes, made monotone).
    description : str
        The component's description in the JSON.
    overwrite : bool
        Replace existing files.

    Returns
    -------
    csv, json : Path
    """
    import os

    from ..io import pelicun

    source = str(fragility) if isinstance(fragility, (str, os.PathLike)) else "fragility"
    if isinstance(fragility, (str, os.PathLike)):
        fragility = read_result(fragility)
    if not hasattr(fragility, "coords") or "damage_state" not in fragility.coords:
        raise CaseError("not a fragility analysis (the dataset of rockslide.fragility, or its NAME.fragility.h5)",
                        source=source)
    csv_path, json_path, _ = pelicun.write_pelicun(fragility, component_id, path, family=family,
                                                   description=description, overwrite=overwrite)
    return csv_path, json_path


def redraw(result_file: str | Path, png: str | Path, *, time_shift: float = 0.0, zoom="auto", crop="auto",
           dpi: float | None = None, overwrite: bool = False, size=None) -> Path:
    """Draw a file rockslide wrote into ``png`` (any format by its extension), as ``rockslide plot``:
    published only if the file read is still the one drawn (a run replacing it meanwhile leaves
    nothing written). ``time_shift``, ``zoom`` and ``crop`` apply to a run's file only, and must
    fall inside it.

    Raises
    ------
    CaseError
        ``time_shift``, ``zoom`` or ``crop`` given for a study's file, or outside the run.
    OutputError
        Not a rockslide file; ``png`` exists (without ``overwrite``); the file was replaced meanwhile.
    """
    from ..io import files
    from ..plots import save_figure

    read = files.Unchanged(result_file)        # a figure of what was read, or nothing (issue 28.6)
    kind, stored = _read(result_file)
    if kind.name != "run":
        given = [name for name, value, default in (("time_shift", time_shift, 0.0), ("zoom", zoom, "auto"),
                                                   ("crop", crop, "auto")) if value != default]
        if given:
            raise CaseError(f"applies to result files, not to {kind.name} files", source=given[0])
        figure = kind.stored_figure(stored, size=size)
    else:
        _check_window(stored.result.ground_time, time_shift, {"zoom": zoom, "crop": crop})
        from ..plots import response_figure
        figure = response_figure(stored, title=stored.name, time_shift=time_shift, zoom=zoom, crop=crop, size=size)
    with files.Staging(overwrite=overwrite) as staging:
        save_figure(figure, png, overwrite=overwrite, dpi=dpi, staging=staging)
        staging.publish(verify=read)
    return Path(png)


def _check_window(times, shift: float, windows: dict) -> None:
    """Refuse a window (``(start, end)`` [s], in the figure's time) outside a run's ground motion."""
    if not times.size:
        return
    first, last = float(times[0]) + shift, float(times[-1]) + shift
    for name, pair in windows.items():
        if isinstance(pair, tuple) and (pair[1] <= first or pair[0] >= last):
            raise CaseError(f"{pair[0]:g} to {pair[1]:g} s is outside the result, which runs from "
                            f"{first:g} to {last:g} s (in the figure's time)", source=name)


def describe_file(path: str | Path) -> dict:
    """What a file rockslide wrote holds, from its stored values (nothing computed again): a run's
    summary (as ``run --json`` gives it, and its ensemble), a sweep's counts, a fragility
    analysis's fits, a risk analysis's rates."""
    import math

    import numpy as np

    from ..io import results

    def number(value):
        value = float(value)
        return None if math.isnan(value) else value

    kind, stored = _read(path)
    if kind.name == "run":
        out = {"file": str(path), "kind": "result", "name": stored.name,
               **results.summary_to_json_dict(stored.result.summary, stored.result.events),
               "ground": stored.ground, "rockslide_version": stored.attrs.get("rockslide_version")}
        ensemble = _run_result(stored, path).ensemble
        if ensemble is not None:
            out["ensemble"] = results.json_ready(ensemble)
        return out
    v, attrs = stored.variables, stored.attrs
    coords = {name: values for name, values, _ in stored.coords}
    if kind.name == "risk":
        shown = [key for key in ("rate", "rate_missing_max", "return_period", "probability_in_life", "survival",
                                 "rejected") if key in v]
        return {"file": str(path), "kind": "risk", "damage_state": attrs.get("damage_state"),
                "fragility": attrs.get("fragility_source"), "intensity_measure": attrs.get("intensity_measure"),
                "command_line": attrs.get("command_line"),
                "rates": {str(curve): {key: number(np.asarray(v[key][1])[i]) for key in shown}
                          for i, curve in enumerate(coords["curve"])},
                "rockslide_version": attrs.get("rockslide_version")}
    value = {name: np.asarray(item[-2]) for name, item in v.items()}
    out = {"file": str(path), "kind": kind.name, "name": attrs.get("name"), "command_line": attrs.get("command_line"),
           "dimensions": {name: int(np.size(values)) for name, values in coords.items()}}
    out.update(n_cases=int(value["status"].size), n_overturned=int(value["overturned"].sum()),
               n_outside_model=int((value["status"] != 0).sum()), n_undecided=int(value["undecided"].sum()))
    if kind.name == "fragility":
        out["fits"] = {str(state): {key: number(value[key][i]) for key in ("median", "median_lower", "median_upper",
                                                                         "beta", "beta_lower", "beta_upper")}
                       for i, state in enumerate(coords["damage_state"])}
        out["intensity_measure"] = attrs.get("intensity_measure")
    out["rockslide_version"] = attrs.get("rockslide_version")
    return out
