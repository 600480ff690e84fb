"""A fragility as pelicun reads it: a row of its fragility CSV and its JSON metadata entry.

pelicun (the open implementation of FEMA P-58; SimCenter's damage and loss model library,
``seismic/building/component/FEMA P-58 2nd Edition/fragility.csv`` and ``.json``) describes a
component's damage by limit states ``LS1, LS2, ...``, each a distribution of the demand at which it
is reached. The CSV's columns are::

    ID, Incomplete, Demand-Type, Demand-Unit, Demand-Offset, Demand-Directional,
    LS1-Family, LS1-Theta_0, LS1-Theta_1, LS1-DamageStateWeights, LS2-Family, ...

and the JSON maps the ID to its description and the words of each damage state
(``LimitStates: {LS1: {DS1: {Description: ...}}}``). pelicun reads the limit states in order and
assigns the highest one reached, so the states are written in the order of their medians.

- **Demand.** ``pfa`` -> ``Peak Floor Acceleration`` [g], ``pfv`` -> ``Peak Floor Velocity``
  [cmps], ``pga`` -> ``Peak Ground Acceleration`` [g], ``pgv`` -> ``Peak Ground Velocity`` [cmps],
  ``sa(T)`` -> ``Spectral Acceleration|T`` [g] (pelicun's ``SA_T`` demand). The offset is 0:
  pelicun's default configuration takes a component's PFA and PFV one location below its own
  (``DemandOffset: {PFA: -1, PFV: -1}``), the floor slab it stands on, as for P-58's contents.
  Directional is 1: a rockslide block is fitted to the motion along one axis (its weak, rocking
  axis), so the demand is the floor motion along that axis, not the larger of two directions
  times pelicun's non-directional multiplier.
- **Families.** ``lognormal``: ``Theta_0`` the median (in the demand unit), ``Theta_1`` the
  logarithmic standard deviation beta, from the maximum-likelihood fit. ``multilinear_CDF``: the
  empirical stripes themselves, ``Theta_0 = "x1,...,xn|p1,...,pn"``, which pelicun requires to
  rise strictly from 0 to 1: the fractions are made non-decreasing by pooling adjacent violators
  (the least-squares monotone fit), then only the last level at 0, the first level at each
  higher value and the first level at 1 are kept. A state whose stripes never reach 0 or 1
  cannot be written so (one line naming the state and the levels to add).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..units import STANDARD_GRAVITY
from .files import atomic_write, check_destination

__all__ = ["FAMILIES", "COLUMNS", "check_export", "pelicun_row", "pelicun_metadata", "write_pelicun",
           "monotone_stripes"]

FAMILIES = ("lognormal", "multilinear_CDF")
#: The fixed columns of pelicun's fragility CSV, before the limit states' four columns each.
COLUMNS = ("ID", "Incomplete", "Demand-Type", "Demand-Unit", "Demand-Offset", "Demand-Directional")
_LS_COLUMNS = ("Family", "Theta_0", "Theta_1", "DamageStateWeights")
#: pelicun's demand type and unit of each intensity measure, and the size of that unit [SI].
_DEMANDS = {"pfa": ("Peak Floor Acceleration", "g", STANDARD_GRAVITY),
            "pfv": ("Peak Floor Velocity", "cmps", 0.01),
            "pga": ("Peak Ground Acceleration", "g", STANDARD_GRAVITY),
            "pgv": ("Peak Ground Velocity", "cmps", 0.01)}
_SA = re.compile(r"^sa\((?P<period>[0-9.eE+-]+) s\)$")
#: What pelicun accepts in an ID: P-58's ``E.20.22.001`` and anything of the same characters.
_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


def _demand(im_name: str) -> tuple[str, str, float]:
    if im_name in _DEMANDS:
        return _DEMANDS[im_name]
    match = _SA.match(im_name)
    if match:
        return f"Spectral Acceleration|{float(match.group('period')):g}", "g", STANDARD_GRAVITY
    raise CaseError(f"a fragility in {im_name} has no pelicun demand type; fit it in pfa, pfv, pga, pgv or "
                    "sa(T) (--im) to export it", source="export")


def _check_id(component_id: str) -> str:
    if not isinstance(component_id, str) or not _ID.match(component_id):
        raise CaseError(f"expected a component ID of letters, digits, '.', '_' and '-' (as P-58's "
                        f"E.20.22.001), got {component_id!r}", source="export")
    return component_id


def check_export(im, component_id: str) -> None:
    """Refuse, before any run, an export that cannot be written: an ID pelicun cannot hold, or an
    intensity measure (`analyses.fragility.IntensityMeasure`) without a pelicun demand type."""
    _check_id(component_id)
    _demand(im.name)


def monotone_stripes(levels, fractions) -> tuple[np.ndarray, np.ndarray]:
    """The empirical stripes as a CDF pelicun accepts (module notes): ``x`` strictly rising, ``p``
    strictly rising from 0 to 1.

    Parameters
    ----------
    levels : array_like
        The stripes' levels, rising (any unit).
    fractions : array_like
        The fraction of runs reaching the state at each level [-]; NaN (no run inside the model)
        is left out.

    Returns
    -------
    x, p : numpy.ndarray

    Raises
    ------
    ValueError
        The monotone fit does not reach 0 at its lowest level or 1 at its highest.
    """
    x = np.asarray(levels, dtype=np.float64)
    p = np.asarray(fractions, dtype=np.float64)
    keep = ~np.isnan(p)
    x, p = x[keep], p[keep]
    # pool adjacent violators: blocks of (sum, count), merged while a block's mean falls
    blocks: list[list[float]] = []
    for value in p:
        blocks.append([value, 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            total, count = blocks.pop()
            blocks[-1][0] += total
            blocks[-1][1] += count
    fitted = np.concatenate([np.full(int(count), total / count) for total, count in blocks]) if blocks else p
    if fitted.size == 0 or fitted[0] != 0.0 or fitted[-1] != 1.0:
        raise ValueError("the stripes do not rise from 0 to 1")
    last_zero = int(np.flatnonzero(fitted == 0.0)[-1])
    first_one = int(np.flatnonzero(fitted == 1.0)[0])
    chosen = [last_zero] + [i for i in range(last_zero + 1, first_one + 1) if fitted[i] > fitted[i - 1]]
    return x[chosen], fitted[chosen]


def _number(value: float) -> str:
    """Shortest text that reads back to the same float (Python's repr)."""
    return repr(float(value))


def _limit_states(fragility, family: str, scale: float):
    """``[(state name, definition, family, theta_0, theta_1)]`` in the order of their medians, and
    the states left out with why."""
    names = [str(s) for s in fragility["damage_state"].values]
    definitions = [str(s) for s in fragility["definition"].values]
    medians = np.asarray(fragility["median"].values, dtype=np.float64)
    betas = np.asarray(fragility["beta"].values, dtype=np.float64)
    levels = np.asarray(fragility["level"].values, dtype=np.float64) / scale
    fractions = np.asarray(fragility["fraction_exceeded"].transpose("damage_state", "level").values)
    states, left_out = [], []
    for i, name in enumerate(names):
        if family == "lognormal":
            if not (math.isfinite(medians[i]) and math.isfinite(betas[i])):
                note = str(fragility["fit_note"].values[i]) if "fit_note" in fragility else ""
                left_out.append(f"{name}: {note or 'no fit'}")
                continue
            states.append((medians[i], name, definitions[i], family, _number(medians[i] / scale),
                           _number(betas[i])))
        else:
            try:
                x, p = monotone_stripes(levels, fractions[i])
            except ValueError:
                left_out.append(f"{name}: its stripes do not rise from 0 to 1 (add levels below the first "
                                "exceedance and above the last survival)")
                continue
            theta = ",".join(_number(v) for v in x) + "|" + ",".join(_number(v) for v in p)
            median = medians[i] if math.isfinite(medians[i]) else float(np.interp(0.5, p, x)) * scale
            states.append((median, name, definitions[i], family, theta, ""))
    states.sort(key=lambda s: s[0])
    return [s[1:] for s in states], left_out


def pelicun_row(fragility, component_id: str, *, family: str = "lognormal") -> tuple[dict, list[str]]:
    """The fragility as one row of pelicun's fragility CSV.

    Parameters
    ----------
    fragility : xarray.Dataset
        A fragility (`rockslide.fragility`, or a ``NAME.fragility.h5`` read with
        `rockslide.read_result`).
    component_id : str
        The row's ID (letters, digits, ``.``, ``_``, ``-``), e.g. ``"RS.cabinet.5F"``.
    family : str
        ``"lognormal"`` (the maximum-likelihood fits) or ``"multilinear_CDF"`` (the stripes).

    Returns
    -------
    row : dict
        Column name -> text, in the CSV's order (`COLUMNS`, then ``LSi-...`` for each state).
    left_out : list of str
        The damage states not written, each with why.

    Raises
    ------
    CaseError
        An ID pelicun cannot hold, an unknown family, a measure without a pelicun demand type
        (``pga_rocking``), or no damage state that can be written.
    """
    _check_id(component_id)
    if family not in FAMILIES:
        raise CaseError(f"unknown family {family!r}; expected {' or '.join(FAMILIES)}", source="export_family")
    demand_type, unit, scale = _demand(str(fragility.attrs["intensity_measure"]))
    states, left_out = _limit_states(fragility, family, scale)
    if not states:
        raise CaseError("no damage state can be exported: " + "; ".join(left_out), source="export")
    row = {"ID": component_id, "Incomplete": "0", "Demand-Type": demand_type, "Demand-Unit": unit,
           "Demand-Offset": "0", "Demand-Directional": "1"}
    for k, (_, _, fam, theta_0, theta_1) in enumerate(states, start=1):
        row.update({f"LS{k}-Family": fam, f"LS{k}-Theta_0": theta_0, f"LS{k}-Theta_1": theta_1,
                    f"LS{k}-DamageStateWeights": ""})
    return row, left_out


def pelicun_metadata(fragility, component_id: str, *, family: str = "lognormal", description: str = "") -> dict:
    """The JSON metadata entry of the row (`pelicun_row`): ``{ID: {Description, Comments,
    SuggestedComponentBlockSize, RoundUpToIntegerQuantity, LimitStates}}``."""
    _check_id(component_id)
    demand_type, unit, scale = _demand(str(fragility.attrs["intensity_measure"]))
    states, left_out = _limit_states(fragility, family, scale)
    source = fragility.attrs.get("title", "rockslide fragility")
    comments = (f"Computed by rockslide ({source}); fit: {fragility.attrs.get('fit_method', '')}. "
                f"Demand: {demand_type} [{unit}] along the block's rocking axis (directional). "
                f"Intensity measure: {fragility.attrs.get('intensity_measure_long_name', '')}.")
    if left_out:
        comments += " Not exported: " + "; ".join(left_out) + "."
    return {component_id: {
        "Description": description or f"Free-standing rigid block ({source})",
        "Comments": comments,
        "SuggestedComponentBlockSize": "1 EA",
        "RoundUpToIntegerQuantity": "True",
        "LimitStates": {f"LS{k}": {f"DS{k}": {"Description": f"{name}: {definition}"}}
                        for k, (name, definition, *_) in enumerate(states, start=1)},
    }}


def write_pelicun(fragility, component_id: str, path, *, family: str = "lognormal", description: str = "",
                  overwrite: bool = False, staging=None) -> tuple[Path, Path, list[str]]:
    """Write ``path`` (``.csv``: the header and the row) and the same name with ``.json`` (the
    metadata), each atomically (or with ``staging``'s set).

    Returns
    -------
    csv, json : Path
    left_out : list of str
        The damage states not written, each with why (`pelicun_row`).
    """
    row, left_out = pelicun_row(fragility, component_id, family=family)
    metadata = pelicun_metadata(fragility, component_id, family=family, description=description)
    csv_path = Path(path).with_suffix(".csv")
    json_path = csv_path.with_suffix(".json")
    for target in (csv_path, json_path):         # both refused before either is written
        check_destination(target, overwrite=overwrite, example="out/cabinet.pelicun.csv")
    states = (len(row) - len(COLUMNS)) // len(_LS_COLUMNS)
    header = list(COLUMNS) + [f"LS{k}-{c}" for k in range(1, states + 1) for c in _LS_COLUMNS]
    with atomic_write(csv_path, overwrite=overwrite, mode="w", what="pelicun fragility", staging=staging) as f:
        f.write(",".join(header) + "\n")
        f.write(",".join(_csv_field(row[c]) for c in header) + "\n")
    with atomic_write(json_path, overwrite=overwrite, mode="w", what="pelicun metadata", staging=staging) as f:
        f.write(json.dumps(metadata, indent=2) + "\n")
    return csv_path, json_path, left_out


def _csv_field(text: str) -> str:
    return f'"{text}"' if "," in text or '"' in text else text
