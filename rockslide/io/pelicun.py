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
  isotonic curve of the stripes (the fragility file's ``isotonic``, the monotone maximum-likelihood
  curve weighted by the runs; a file without it: the fractions pooled with equal weights),
  ``Theta_0 = "x1,...,xn|p1,...,pn"``, written so that pelicun's CDF, linear in x between its
  points, equals rockslide's curve, linear in ln x between the levels (`analyses.risk.Tabulated`,
  what ``rockslide risk --model isotonic`` integrates), within `MULTILINEAR_TOLERANCE`
  (`multilinear_points`: each interval cut at geometric points). pelicun requires the points to
  rise strictly from 0 to 1: only the last level at 0 and the first at 1 are kept, and a level
  where the curve is flat rises by `FLAT_STEP` over the one before. A state whose stripes never
  reach 0 or 1 cannot be written so (one line naming the state and the levels to add).
- **Sequential states.** pelicun takes the limit states as sequential: their capacities perfectly
  correlated, LS2 reached only beyond LS1, so ``P(LS1 | x) >= P(LS2 | x)`` at every demand. Two
  fitted lognormals of different beta always cross somewhere; where the higher state's curve
  exceeds the lower's by more than `SEQUENTIAL_TOLERANCE` at some demand (e.g. two states crossing
  at 0.215 g), the lognormal export is refused, naming the states and the crossing (export
  ``multilinear_CDF`` instead). The multilinear curves are made sequential: each state's curve is
  lowered, level by level, to the one before it where it is above (in the order of their medians;
  for rockslide's states, nested by construction, the stripes never need it), and the metadata says
  at how many levels.
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
           "monotone_stripes", "multilinear_points", "lognormal_crossing"]

FAMILIES = ("lognormal", "multilinear_CDF")
#: Largest difference [-] between pelicun's multilinear CDF and rockslide's curve between its points.
MULTILINEAR_TOLERANCE = 1e-5
#: Rise [-] of a multilinear point over the one before where the curve is flat (pelicun refuses equal
#: values, comparing with numpy's isclose: differences below 1e-8 count as equal).
FLAT_STEP = 1e-6
#: How far [-] a higher limit state's curve may rise above a lower one's before they cross (pelicun's
#: states are sequential).
SEQUENTIAL_TOLERANCE = 1e-3
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


def multilinear_points(levels, probabilities) -> tuple[np.ndarray, np.ndarray]:
    """The points of pelicun's multilinear CDF (linear in x between them) of a non-decreasing curve
    given at ``levels`` and linear in ln x between them (module notes).

    Raises
    ------
    ValueError
        The curve does not reach 0 at its lowest level or 1 at its highest.
    """
    x = np.asarray(levels, dtype=np.float64)
    p = np.asarray(probabilities, dtype=np.float64)
    keep = np.isfinite(p)
    x, p = x[keep], p[keep]
    if p.size == 0 or p[0] != 0.0 or p[-1] != 1.0:
        raise ValueError("the curve does not rise from 0 to 1")
    start, stop = int(np.flatnonzero(p == 0.0)[-1]), int(np.flatnonzero(p == 1.0)[0])
    x, p = x[start:stop + 1], p[start:stop + 1].copy()
    for i in range(1, p.size - 1):                   # flat stretches rise by FLAT_STEP (pelicun's strictness)
        p[i] = max(p[i], p[i - 1] + FLAT_STEP)
    xs, ps = [x[:1]], [p[:1]]
    for (a, b), (pa, pb) in zip(zip(x[:-1], x[1:], strict=True), zip(p[:-1], p[1:], strict=True), strict=True):
        pieces = 1
        while pieces < 4096:
            # the chord (linear in x) against the curve (linear in ln x) on one geometric piece
            ratio = (b / a) ** (1.0 / pieces)
            t = np.linspace(0.0, 1.0, 65)
            gap = np.max(np.abs(np.log1p(t * (ratio - 1.0)) / math.log(ratio) - t)) if ratio > 1 else 0.0
            if (pb - pa) / pieces * gap <= MULTILINEAR_TOLERANCE:
                break
            pieces *= 2
        u = np.linspace(0.0, 1.0, pieces + 1)[1:]
        xs.append(a * (b / a) ** u)
        ps.append(pa + (pb - pa) * u)
    return np.concatenate(xs), np.concatenate(ps)


def lognormal_crossing(median_low: float, beta_low: float, median_high: float, beta_high: float):
    """Where the lognormal of the higher state (larger median) rises above the lower state's:
    ``(x, excess)``, the demand of the crossing [the medians' unit] and the largest ``P_high - P_low``
    over all demands [-] (0 and None when it never does: equal betas)."""
    from ..core.normal import normal_cdf

    if beta_low == beta_high:
        return None, 0.0
    ln_low, ln_high = math.log(median_low), math.log(median_high)
    crossing = math.exp((beta_high * ln_low - beta_low * ln_high) / (beta_high - beta_low))
    spread = 8.0 * max(beta_low, beta_high)
    grid = np.exp(np.linspace(min(ln_low, ln_high) - spread, max(ln_low, ln_high) + spread, 4001))
    excess = normal_cdf(np.log(grid / median_high) / beta_high) - normal_cdf(np.log(grid / median_low) / beta_low)
    return crossing, float(max(excess.max(), 0.0))


def _number(value: float) -> str:
    """Shortest text that reads back to the same float (Python's repr)."""
    return repr(float(value))


def _limit_states(fragility, family: str, scale: float, unit: str = "g"):
    """``[(state name, definition, family, theta_0, theta_1)]`` in the order of their medians, and
    the states left out with why."""
    names = [str(s) for s in fragility["damage_state"].values]
    definitions = [str(s) for s in fragility["definition"].values]
    medians = np.asarray(fragility["median"].values, dtype=np.float64)
    betas = np.asarray(fragility["beta"].values, dtype=np.float64)
    levels = np.asarray(fragility["level"].values, dtype=np.float64) / scale
    fractions = np.asarray(fragility["fraction_exceeded"].transpose("damage_state", "level").values)
    states, left_out = [], []
    if family == "lognormal":
        for i, name in enumerate(names):
            if not (math.isfinite(medians[i]) and math.isfinite(betas[i])):
                note = str(fragility["fit_note"].values[i]) if "fit_note" in fragility else ""
                left_out.append(f"{name}: {note or 'no fit'}")
                continue
            states.append((medians[i], name, definitions[i], family, _number(medians[i] / scale),
                           _number(betas[i])))
        states.sort(key=lambda s: s[0])
        _refuse_crossing(states, unit)
        return [s[1:] for s in states], left_out
    if "isotonic" in fragility:
        curves = np.asarray(fragility["isotonic"].transpose("damage_state", "level").values, dtype=np.float64)
    else:
        curves = np.full(fractions.shape, np.nan)
        for i in range(len(names)):
            known = np.isfinite(fractions[i])
            if known.any():
                curves[i, known] = _pooled(fractions[i][known])
    order = sorted(range(len(names)), key=lambda i: _middle(levels, curves[i], medians[i] / scale))
    lowered, previous = {}, None
    for i in order:
        if previous is not None:
            above = np.isfinite(curves[i]) & np.isfinite(previous) & (curves[i] > previous)
            if above.any():
                curves[i] = np.where(above, previous, curves[i])
                lowered[names[i]] = int(above.sum())
        if np.isfinite(curves[i]).any():
            previous = curves[i]
    for i in order:
        name = names[i]
        try:
            x, p = multilinear_points(levels, curves[i])
        except ValueError:
            left_out.append(f"{name}: its stripes do not rise from 0 to 1 (add levels below the first "
                            "exceedance and above the last survival)")
            continue
        theta = ",".join(_number(v) for v in x) + "|" + ",".join(_number(v) for v in p)
        states.append((0.0, name, definitions[i], family, theta, ""))
    for name, count in lowered.items():
        left_out.append(f"{name}: exported lowered to the state before it at {count} level(s) (pelicun's states "
                        "are sequential)")
    return [s[1:] for s in states], left_out


def _pooled(fractions) -> np.ndarray:
    """Pool adjacent violators with equal weights (`monotone_stripes`' pooling, all levels kept)."""
    blocks: list[list[float]] = []
    for value in fractions:
        blocks.append([value, 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            total, count = blocks.pop()
            blocks[-1][0] += total
            blocks[-1][1] += count
    return np.concatenate([np.full(int(count), total / count) for total, count in blocks])


def _middle(levels, curve, median) -> float:
    """Where a curve is 0.5 (its median if it has one, else interpolated), to order the states."""
    if math.isfinite(median):
        return float(median)
    known = np.isfinite(curve)
    if not known.any():
        return math.inf
    return float(np.interp(0.5, np.maximum.accumulate(curve[known]), levels[known]))


def _refuse_crossing(states, unit: str) -> None:
    """Refuse lognormal limit states (in the order of their medians) of which a higher one rises
    above a lower one by more than `SEQUENTIAL_TOLERANCE` (module notes)."""
    for low, high in zip(states[:-1], states[1:], strict=True):
        at, excess = lognormal_crossing(float(low[4]), float(low[5]), float(high[4]), float(high[5]))
        if excess > SEQUENTIAL_TOLERANCE:
            raise CaseError(f"the lognormal fits of {low[1]} and {high[1]} cross at {at:.4g} {unit} ("
                            f"{high[1]} up to {excess:.3g} more likely than {low[1]}); pelicun's limit states are "
                            "sequential: export --export-family multilinear_CDF (made sequential)",
                            source="export")


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
    states, left_out = _limit_states(fragility, family, scale, unit)
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
    states, left_out = _limit_states(fragility, family, scale, unit)
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
