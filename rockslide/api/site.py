"""Risk at a site: `risk`, a fragility over hazard curves to annual rates (`analyses.risk`), conducted
once for the Python API and ``rockslide risk``."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import CaseError, RockslideError


def risk(fragility: str | Path | None = None, hazard=None, *, damage: str = "overturn", stripes: bool = False,
         median: str | float | None = None, beta: float | None = None, im: str = "pga",
         life: str | float = 50.0, age: str | float | None = None, confidence: float = 0.95,
         hazard_units: str | None = None, trim_poe: bool = False, drop_zero_poe: bool = False,
         model: str | None = None, fragility_table: str | Path | None = None, outputs=None):
    """The annual rate of a damage state at a site: a fragility integrated over hazard curves, as
    ``rockslide risk`` (`analyses.risk`; docs/risk.md).

    Parameters
    ----------
    fragility : str, Path or xarray.Dataset, optional
        A ``NAME.fragility.h5`` of `fragility`, or the dataset `fragility` returned (its lognormal
        fit, or with ``stripes`` its empirical fractions). Without it, ``median`` and ``beta`` give
        a lognormal.
    hazard : str, Path, sequence of them, or mapping
        Hazard files (OpenQuake's hazard-curve CSV export: one curve per site; or a plain table of
        level and annual rate), or ``{name: (levels, rates)}`` with levels in SI [m/s^2, m/s] and
        annual rates of exceedance [1/yr].
    damage : str
        The fragility file's damage state (``overturn``, ``rotation>0.5alpha``...).
    stripes : bool
        Use the fraction of runs reaching the state at each stripe (linear in ln x between them)
        instead of the lognormal fit.
    median, beta : str or float, float
        A lognormal fragility: its median (``"0.5g"``, or SI) and logarithmic standard deviation.
    im : str
        The intensity measure of ``median`` (``pga``, ``pgv``, ``sa(0.3s)``).
    life : str or float
        Service life [yr] (``50``, ``"50yr"``) of ``probability_in_life``.
    age : str or float, optional
        Age of a precariously balanced rock [yr] (``"24ka"``): adds ``survival`` and ``rejected``.
    confidence : float
        Of the rejection of a hazard curve by a rock's survival (0.95: rejected when the rock would
        have toppled with more than 95 % probability).
    hazard_units : str, optional
        The unit of a plain table's levels when its header does not say (default g, cm/s for PGV).
    trim_poe : bool
        Leave out the levels at the ends of each hazard curve where OpenQuake's PoE has no rate to
        interpolate: those with PoE 1 at its lowest levels (an infinite rate; OpenQuake writes 1
        there for long investigation times) and those with PoE 0 at its highest (below its
        precision); a plain table's rates ``inf`` and 0 likewise. The rate is then a lower bound
        (``rate_missing_max`` says by how much at most). Without it a PoE of 1 or 0 is refused, as
        is one between other values with it.
    drop_zero_poe : bool
        The same as ``trim_poe`` (its former name).
    model : str, optional
        The curve taken from a fragility file (default: the one its analysis chose, its attribute
        ``fragility_model``, else the lognormal): ``"lognormal"`` (its maximum-likelihood fit),
        ``"isotonic"`` (the monotone maximum-likelihood curve of its stripes) or ``"empirical"`` (the
        fractions themselves, as ``stripes``); each linear in ln x between the levels.
    fragility_table : str or Path, optional
        Instead of a fragility file: a CSV of levels and probabilities with the measure and unit in
        its header (``PGA [g], probability``; `io.hazard.read_fragility_table`).

    outputs : outputs.OutputSet, optional
        Also write ``NAME.risk.h5`` and its figure there (`risk_outputs`), as the command line does.

    Returns
    -------
    xarray.Dataset
        Per ``curve``: ``rate`` [1/yr] (a lower bound if the curve is truncated),
        ``rate_missing_max`` [1/yr], ``rate_lower`` / ``rate_upper`` over the fragility's
        uncertainty, ``probability_in_life``, ``return_period`` [yr] (``survival``, ``rejected``
        with ``age``); per curve and ``point`` the hazard curve and the disaggregation
        ``contribution`` [1/yr]; per curve and ``im`` the disaggregation ``density``; the
        fragility on ``im``.
    """
    return risk_study(fragility, hazard, damage=damage, stripes=stripes, median=median, beta=beta, im=im, life=life,
                      age=age, confidence=confidence, hazard_units=hazard_units, trim_poe=trim_poe or drop_zero_poe,
                      model=model, fragility_table=fragility_table, outputs=outputs).to_xarray()


def risk_outputs(fragility, *, out_dir=None, name: str | None = None, overwrite: bool = False, plot: bool = True,
                 dpi=None, size=None, table=None):
    """The output set of `risk`: ``OUT/NAME.risk.h5`` and ``.png``, OUT ``out_dir`` (default: the
    fragility file's folder, else the current one), NAME ``name`` (a name, not a path; default: the
    fragility file's name, else the fragility ``table``'s, else ``lognormal``)."""
    from ..outputs import OutputSet, output_folder

    path = Path(fragility) if isinstance(fragility, (str, Path)) else None
    folder = output_folder(out_dir, default=path.parent if path is not None else Path("."))
    stem = name if name is not None else \
        (path.name.removesuffix(".h5").removesuffix(".fragility") if path is not None else
         Path(table).stem if table is not None else "lognormal")
    return OutputSet(folder, stem, "risk", overwrite=overwrite, plot=plot, dpi=dpi, size=size)


def risk_study(fragility=None, hazard=None, *, outputs=None, command_line: str = "", **options):
    """`risk`, conducted: its analysis, dataset, printout (``lines``, and ``warnings`` for the
    standard error) and JSON summary, written to ``outputs`` when given (`risk_outputs`); the
    other arguments as `risk`'s."""
    from ..analyses import risk as rk
    from ..analyses.measures import parse_im
    from ..io import results
    from .studies import StudyResult

    analysis = risk_analysis(fragility, hazard, **options)
    if outputs is not None:
        if outputs.check():
            outputs.refuse()
        outputs.remove_stale_temporaries()
    result = StudyResult("risk", analysis.fragility.damage_state, *rk.dataset(analysis, command_line),
                         summary=rk.json_summary(analysis))
    show = parse_im(analysis.measure["name"]).show
    result.warnings = [f"rockslide: warning: {line}" for line in rk.warnings_of(analysis, show)]
    result.lines = rk.summary_lines(analysis, show)
    if analysis.fragility.uncertainty:
        result.lines.append(f"  (in parentheses: {analysis.fragility.uncertainty})")
    if outputs is not None:
        with outputs.staging() as staging:
            results.write_dataset(outputs.h5, result.coords, result.variables, format=results.RISK_FORMAT,
                                  attrs=result.attrs, overwrite=outputs.overwrite, staging=staging)
            if outputs.plot:
                outputs.save_figure(rk.figure(analysis, size=outputs.size), staging)
            staging.publish(remove=[] if outputs.plot else [outputs.png])
        result.files, result.written = outputs, f"{outputs.h5}" + (f" and {outputs.png}" if outputs.plot else "")
    return result


def risk_analysis(fragility=None, hazard=None, *, damage: str = "overturn", stripes: bool = False, median=None,
                  beta=None, im: str = "pga", life=50.0, age=None, confidence: float = 0.95, hazard_units=None,
                  trim_poe: bool = False, model: str | None = None, fragility_table=None):
    """`risk`'s `analyses.risk.Analysis` (for the command's printout and figure); same arguments."""
    from ..analyses import risk as rk

    if model is not None and model not in rk.MODELS:
        raise CaseError(f"unknown model {model!r}; expected {', '.join(rk.MODELS)}", source="model")
    if fragility_table is not None:
        if fragility is not None or median is not None or beta is not None:
            raise CaseError("give a fragility table, a fragility file or median and beta, one of them",
                            source="fragility_table")
        used, measure = _table_fragility(fragility_table, damage)
    else:
        used, measure = _risk_fragility(fragility, damage=damage, stripes=stripes or model == "empirical",
                                        median=median, beta=beta, im=im, model=model)
    curves, about, notes = _hazard_curves(hazard, measure, hazard_units, trim_poe, along_block=used.along_block)
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0.0 < float(confidence) < 1.0:
        raise CaseError(f"must be within 0 and 1 (e.g. 0.95), got {confidence!r}", source="confidence")
    years = rk.parse_years(life, source="life")
    age_years = None if age is None else rk.parse_years(age, source="age")
    about_measure = {key: getattr(measure, key) for key in ("name", "units", "long_name", "label", "display_unit",
                                                            "display_scale")}
    return rk.analyse(used, about_measure, curves, about, life=years, age=age_years, confidence=float(confidence),
                      notes=notes)


def _table_fragility(path, damage):
    """The fragility of `risk --fragility-table` and its intensity measure."""
    from ..analyses import risk as rk
    from ..analyses.measures import parse_im
    from ..io import hazard as hz
    from ..units import unit_factor

    name, unit, levels, p = hz.read_fragility_table(path)
    measure = parse_im(name)
    levels = levels * unit_factor(unit, measure.kind, source=str(path))
    return rk.FragilityUsed(rk.Tabulated(levels, p), damage, str(path), "tabulated (linear in ln x between its "
                            "levels, constant outside)", highest_tested=float(levels[-1])), measure


def _risk_fragility(path, *, damage, stripes, median, beta, im, model=None):
    """The fragility of `risk` and its intensity measure."""
    from ..analyses import risk as rk
    from ..analyses.measures import parse_im
    from ..units import parse_quantity

    if path is None:
        if median is None or beta is None:
            raise CaseError("give a fragility file, or a lognormal with both median and beta "
                            "(e.g. median 0.5g, beta 0.4)", source="fragility")
        measure = parse_im(im)
        theta = parse_quantity(median, measure.kind, source="median")
        if not theta > 0:
            raise CaseError(f"the lognormal needs a positive median, got {median!r}", source="median")
        if rk.beta_problem(beta):
            raise CaseError(rk.beta_problem(beta), source="beta")
        b = float(beta)
        return rk.FragilityUsed(rk.Lognormal(theta, b), damage, "--median/--beta", "lognormal given", theta, b,
                                [], ""), measure
    if median is not None or beta is not None:
        raise CaseError("give either a fragility file or median and beta, not both", source="median/beta")
    from .runs import RunResult
    from .stored import read_result

    given = hasattr(path, "data_vars")
    ds = path if given else read_result(path)
    path = "the fragility dataset given" if given else str(path)
    if isinstance(ds, RunResult) or "damage_state" not in ds.coords:
        raise CaseError("not a fragility file (NAME.fragility.h5 of 'rockslide fragility')", source=path)
    measure = parse_im(ds.attrs["intensity_measure"])
    along = measure.rotd is None and _two_components(ds.attrs)
    states = [str(s) for s in ds["damage_state"].values]
    if damage not in states:
        raise CaseError(f"no damage state {damage!r} in the file; it has {', '.join(states)}", source="damage")
    at = ds.sel(damage_state=damage)
    model = model or str(ds.attrs.get("fragility_model", "lognormal"))
    stripes = stripes or model == "empirical"
    fraction = np.asarray(at["fraction_exceeded"].values, dtype=np.float64)
    levels = np.asarray(ds["level"].values, dtype=np.float64)
    known = {**rk.evidence(levels, fraction, at["isotonic"].values if "isotonic" in at else None),
             "vertical_note": str(ds.attrs.get("vertical_note", ""))}
    if stripes or model == "isotonic":
        if not np.isfinite(fraction).any():
            raise CaseError(f"no stripe has a run inside the model for {damage!r}", source=str(path))
        if model == "isotonic":
            return rk.FragilityUsed(known["stripes"], damage, str(path), "isotonic curve of the stripes (monotone "
                                    "maximum likelihood, linear in ln x between them, constant outside)",
                                    along_block=along, **known), measure
        kept = np.isfinite(fraction)
        return rk.FragilityUsed(rk.Tabulated(levels[kept], fraction[kept]), damage, str(path),
                                "empirical stripes (linear in ln x between them, constant outside)",
                                variants=[], along_block=along, **known), measure
    if "gof_rejected" in at and int(at["gof_rejected"]) == 1:
        known["rejection"] = (f"lognormal is REJECTED by its per-level fractions (deviance "
                              f"{float(at['gof_deviance']):.3g} on {int(at['gof_dof'])} degrees of freedom, "
                              f"p = {float(at['gof_p_value']):.2g})")
    theta, b = float(at["median"]), float(at["beta"])
    note = str(at["fit_note"].values)
    if not math.isfinite(theta) or (not math.isfinite(b) and note):
        raise CaseError(f"no lognormal fit for {damage!r} ({note}); use its empirical fractions instead "
                        "(stripes)", source=str(path))
    bounds = [float(at[f"{name}_{side}"]) for name in ("median", "beta") for side in ("lower", "upper")]
    for what, value in (("beta", b), ("beta_lower", bounds[2]), ("beta_upper", bounds[3])):
        if (what == "beta" or math.isfinite(value)) and rk.beta_problem(value):
            raise CaseError(f"{what} of {damage!r}: {rk.beta_problem(value)}", source=str(path))
    variants, uncertainty, level = [], "", float(ds.attrs.get("confidence_level", 0.95))
    if "bootstrap_median" in at:
        pairs = np.column_stack([at["bootstrap_median"].values, at["bootstrap_beta"].values]).astype(np.float64)
        pairs = pairs[np.isfinite(pairs).all(axis=1)]             # NaN: a resample without a fit
        low, high = rk.BETA_RANGE
        inside = (pairs[:, 1] >= low) & (pairs[:, 1] <= high)
        left_out = (f"; {np.count_nonzero(~inside)} with beta outside {low:g} ... {high:g} left out"
                    if not inside.all() else "")
        pairs = pairs[inside]
        if len(pairs) >= 2:
            uncertainty = (f"the {level:.0%} percentile interval of the rate over the fits of the {len(pairs)} "
                           f"bootstrap resamples of the records{left_out}")
            return rk.FragilityUsed(rk.Lognormal(theta, b), damage, path, "lognormal fit", theta, b,
                                    [rk.Lognormal(m, s) for m, s in pairs], uncertainty, level, along,
                                    **known), measure
    if all(math.isfinite(v) for v in bounds):
        variants = rk.lognormal_box(bounds[:2], bounds[2:])
        uncertainty = (f"the range of the rate over the {level:.0%} bootstrap intervals of the median "
                       f"({measure.show(bounds[0])} ... {measure.show(bounds[1])}) and of beta ({bounds[2]:.3g} ... "
                       f"{bounds[3]:.3g}), on a grid over their rectangle (marginal intervals: a wide range)")
    return rk.FragilityUsed(rk.Lognormal(theta, b), damage, str(path), "lognormal fit", theta, b, variants,
                            uncertainty, along_block=along, **known), measure


def _two_components(attrs) -> bool:
    """Whether a fragility file's suite (its ``suite_text``) has records of two horizontal
    components: its measure, unless RotD, is then of the motion along the block. False when the
    file does not say (no suite, or one that does not parse)."""
    from ..case import parse_suite

    try:
        suite = parse_suite(str(attrs.get("suite_text", "")))
    except RockslideError:
        return False
    return any(entry.horizontal_2 is not None for entry in suite.entries)


#: Most hazard files of one analysis.
MAX_HAZARD_FILES = 10_000


def _hazard_arg(hazard):
    """``risk``'s ``hazard`` as a mapping or a list of paths (a generator read once, bounded), or a
    `CaseError` naming it."""
    import itertools
    import os

    message = ("give one or more hazard curves (OpenQuake's hazard-curve CSV, or a CSV of level and annual rate; "
               "from Python also a mapping of name to (levels, rates))")
    if isinstance(hazard, Mapping):
        if not hazard:
            raise CaseError(message, source="hazard")
        return hazard
    if isinstance(hazard, (str, os.PathLike)) and not isinstance(hazard, bytes):
        return [hazard]
    if hazard is None or isinstance(hazard, bytes) or not hasattr(hazard, "__iter__"):
        raise CaseError(message, source="hazard")
    files = list(itertools.islice(hazard, MAX_HAZARD_FILES + 1))
    if not files or len(files) > MAX_HAZARD_FILES:
        raise CaseError(message if not files else f"more than {MAX_HAZARD_FILES} hazard files", source="hazard")
    for item in files:
        if not isinstance(item, (str, os.PathLike)) or isinstance(item, bytes):
            raise CaseError(f"expected paths of hazard files, got {type(item).__name__}", source="hazard")
    return files


def _hazard_curves(hazard, measure, units, trim: bool, *, along_block: bool = False):
    """`analyses.risk.HazardCurve` s from `risk`'s ``hazard`` (files or arrays), checked against the
    fragility's ``measure`` (``along_block``: of the motion along the block); what is known of each
    (file, kind, site); and the notes on their components (`io.hazard.component_note`)."""
    from ..analyses import risk as rk
    from ..io import hazard as hz

    hazard = _hazard_arg(hazard)
    tables, named = [], False
    if isinstance(hazard, Mapping):
        for name, pair in hazard.items():
            if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2:
                raise CaseError("expected a pair (levels, annual rates)", source=f"hazard[{name!r}]")
            levels, rates = pair
            problem = hz.curve_problem(levels, rates)
            if problem:
                raise CaseError(problem, source=f"hazard[{name!r}]")
            tables.append(hz.HazardTable(str(name), None, np.asarray(levels, dtype=np.float64),
                                         np.asarray(rates, dtype=np.float64), "", level_units=None))
    else:
        for path in hazard:
            read = hz.read_hazard(path, units=units, trim=trim)
            named = named or any(t.measure is not None for t in read)     # says which measure it is of
            tables += [hz.matching(t, measure.name, measure.period, measure.kind, measure.label, rotd=measure.rotd)
                       for t in read]
    names = [t.name for t in tables]
    curves, about = [], []
    for t in tables:
        name = t.name if names.count(t.name) == 1 else f"{Path(t.source).name}: {t.name}"
        curves.append(rk.HazardCurve(name, t.levels, t.rates))
        about.append({"source": t.source, "kind": t.kind, "lon": t.site[0], "lat": t.site[1],
                      "investigation_time": t.investigation_time, "dropped_low": t.dropped_low,
                      "dropped_high": t.dropped_high})
    note = hz.component_note(measure.label, rotd=measure.rotd, along_block=along_block) if named else ""
    return curves, about, [note] if note else []

