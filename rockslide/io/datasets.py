"""Results as labelled data: xarray Datasets of a run, a sweep or a fragility analysis.

The same names, dimensions, values and attributes as the files (`results.write_dataset` writes a
study in the netCDF-4 data model, which ``xarray.open_dataset(path, engine="h5netcdf")`` reads
back as these datasets). xarray is imported here only, when a dataset is asked for.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.layout import HISTORY_COLUMNS
from .results import GROUND_UNITS, HISTORY_UNITS, STATE_CODES, summary_attributes


def study_dataset(coords, variables, attrs: dict | None = None):
    """An ``xarray.Dataset`` from a study's dimensions and variables, as `results.write_dataset`
    takes them.

    Parameters
    ----------
    coords : sequence of (str, array_like, dict)
        The dimensions in order: name, coordinate values, attributes.
    variables : mapping of str to (tuple of str, array_like, dict)
        Each variable's dimension names, values and attributes.
    attrs : dict, optional
        The dataset's attributes.
    """
    import xarray as xr

    return xr.Dataset(
        {name: (dims, np.asarray(values), dict(a)) for name, (dims, values, a) in variables.items()},
        coords={name: (name, np.asarray(values), dict(a)) for name, values, a in coords},
        attrs=dict(attrs or {}))


def sweep_dataset(coords, variables, attrs: dict | None = None):
    """`study_dataset` of a sweep: every variable on every axis (`results.write_sweep`)."""
    dims = tuple(str(name) for name, _, _ in coords)
    return study_dataset(coords, {name: (dims, values, a) for name, (values, a) in variables.items()}, attrs)


def run_dataset(result, *, name: str = "", attrs: dict | None = None):
    """One run as an ``xarray.Dataset``.

    Variables ``rotation`` [rad], ``rotation_rate`` [rad/s], ``slip`` [m], ``slip_rate`` [m/s],
    ``state`` (codes in its ``codes`` attribute) on the dimension ``time`` [s]; the ground motion as
    applied, ``ground_horizontal`` and ``ground_vertical`` [m/s^2], on ``ground_time`` [s]; the event
    log as one variable per field on ``event``; the summary (`results` names and units: the root
    attributes of the result file) as attributes.
    """
    import xarray as xr

    history = result.history or {}
    time = np.asarray(history.get("time", np.empty(0)), dtype=np.float64)
    data = {}
    for column in HISTORY_COLUMNS[1:]:
        values = np.asarray(history.get(column, np.empty(0)))
        a = {"units": HISTORY_UNITS[column]}
        if column == "state":
            a["codes"] = STATE_CODES
        data[column] = ("time", values, a)
    for role in ("horizontal", "vertical"):
        data[f"ground_{role}"] = ("ground_time", np.asarray(getattr(result, f"ground_{role}")),
                                  {"units": GROUND_UNITS[role], "long_name": f"{role} ground acceleration as applied"})
    events = np.asarray(result.events)
    for field in events.dtype.names or ():
        values = events[field]
        if values.dtype.kind == "S":
            values = values.astype(str)
        data[f"event_{field}"] = ("event", values, {"units": {"time": "s", "energy_loss": "J"}.get(field, "1")})
    attrs = {**{k: _attribute(v) for k, v in summary_attributes(result.summary).items()},
             "verdict": result.summary.verdict, "name": name, "integration_step": float(result.step),
             **(attrs or {})}
    return xr.Dataset(data, coords={"time": ("time", time, {"units": "s"}),
                                    "ground_time": ("ground_time", np.asarray(result.ground_time), {"units": "s"}),
                                    "event": ("event", np.arange(events.shape[0]))}, attrs=attrs)


def _attribute(value):
    """A summary value as an attribute (None as NaN, as in the file)."""
    if value is None:
        return math.nan
    return value


def tidy_table(dataset, dims) -> str:
    """The variables of ``dataset`` on the dimensions ``dims`` as a tidy CSV table: one row per
    point of those dimensions (a sweep's case; a fragility analysis's record and level), a column
    per coordinate and per variable (variables on other dimensions are left out). Numbers are
    written with every digit (Python's shortest exact form), so the table reads back to the file's
    values exactly; each column's unit is in its header (``max_rotation [rad]``)."""
    import io

    names = [name for name, var in dataset.data_vars.items() if tuple(var.dims) == tuple(dims)]
    frame = dataset[names].to_dataframe().reset_index()
    frame = frame[[*dims, *names]]

    def header(name):
        unit = (dataset[name].attrs.get("units") if name in dataset.variables else None) or ""
        return f"{name} [{unit}]" if unit and unit != "1" else name

    frame.columns = [header(name) for name in frame.columns]
    out = io.StringIO()
    frame.to_csv(out, index=False, lineterminator="\n", float_format=None)
    return out.getvalue()
