"""The Python API: cases, runs and studies from a notebook or a script.

Everything here is what the command line does, without the console and, unless asked, without
files: ``rockslide run``, ``sweep`` and ``fragility`` are clients of the same engine
(`engine.prepare`, `engine.plan`, `engine.execute`) and give the same numbers, bit for bit.

>>> import rockslide
>>> case = rockslide.load_case("configs/example.yaml")                     # doctest: +SKIP
>>> result = rockslide.run(case)                                            # doctest: +SKIP
>>> result.summary.verdict                                                  # doctest: +SKIP
'standing'
>>> grid = rockslide.sweep(case, mu="0.3:0.7:0.1", pga="200gal:800gal:200gal")   # doctest: +SKIP
>>> grid.overturned.sum().item()                                            # doctest: +SKIP

Units: every number given is SI (m, kg, s, m/s^2, rad) unless it is a string with its unit, as in
case files (``"0.3 g"``, ``"50 mm"``); every number returned is SI, and datasets say their units in
each variable's ``units`` attribute.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .case import Case, case_with, load_case
from .core.simulate import Result, Summary
from .errors import CaseError, RockslideError

__all__ = ["load_case", "case_with", "run", "sweep", "fragility", "ensemble", "risk", "read_result", "plot_results",
           "export_pelicun",
           "RunResult", "Case", "Summary"]


@dataclass
class RunResult:
    """One run of a case (`run`), or a result file read back (`read_result`).

    Attributes
    ----------
    name : str
        The case's name.
    result : core.simulate.Result
        Time histories (``history``: time [s], rotation [rad], rotation_rate [rad/s], slip [m],
        slip_rate [m/s], state), the event log (``events``), the summary, the integration step [s]
        and the ground motion as applied [m/s^2].
    ground : dict
        The ground motion as applied: ``pga_horizontal``, ``pga_vertical`` [m/s^2], the scale
        factors ``scale_horizontal``, ``scale_vertical`` (None where there is no record); with two
        horizontal components also ``components`` (`engine.prepare.Components`: azimuths,
        orientation, peaks along and across the block, the share the planar model ignores).
    records : list of dict
        The record files (name, SHA-256, format, scale factor).
    case : Case or None
        The case that was run (None for a file read back: its text is ``case_text``).
    case_text : str
        The case file's text.
    attrs : dict
        For a file read back: all its root attributes (provenance, versions).
    """

    name: str
    result: Result
    ground: dict
    records: list
    case: Case | None = None
    case_text: str = ""
    attrs: dict = field(default_factory=dict)

    @property
    def summary(self) -> Summary:
        """What happened, a `Summary`, with ``overturned``, ``max_rotation`` [rad], ``max_rotation_ratio``
        (of alpha), ``max_slip`` [m], ``impacts``, ``status``, ``verdict`` and more."""
        return self.result.summary

    @property
    def history(self) -> dict:
        """The time histories by column (numpy arrays; SI)."""
        return self.result.history

    @property
    def events(self):
        """The event log, a numpy structured array with the fields time [s], from, to, cause, edge..."""
        return self.result.events

    def to_xarray(self):
        """The run as an ``xarray.Dataset`` (`io.datasets.run_dataset`): histories on ``time``, the
        ground motion on ``ground_time``, the event log on ``event``, the summary as attributes."""
        from .io.datasets import run_dataset

        flat = {**{k: v for k, v in self.ground.items() if k != "components"},
                **(self.ground.get("components") or {})}
        ground = {f"ground_{k}": v for k, v in flat.items() if v is not None}
        return run_dataset(self.result, name=self.name, attrs=ground)


def run(case: Case | Mapping | str | Path, *, records_dir: str | Path | None = None, history: bool = True,
        progress: Callable[[float, float], None] | None = None) -> RunResult:
    """Compute one case, as ``rockslide run`` does (without its files).

    Parameters
    ----------
    case : Case, mapping or path
        A case (`load_case`), or what `load_case` reads.
    records_dir : str or Path, optional
        Where record files are looked for after the case's folder (default: ``$ROCKSLIDE_RECORDS``,
        else ``./records``).
    history : bool
        Keep the time histories (at ``output.interval``); False keeps the summary and events only.
    progress : callable, optional
        Called with (time reached, end time) [s] between kernel chunks.

    Returns
    -------
    RunResult

    Raises
    ------
    RockslideError
        A bad case, a record that cannot be read or used (one line naming the file and field).
    """
    from .engine import prepare as engine
    from .io import records

    case = _case(case)
    prepared = engine.prepare(case, records.records_dir(records_dir), history=history)
    result = engine.simulate_prepared(prepared, progress=progress)
    return RunResult(name=case.name, result=result, ground=engine.applied_ground(prepared),
                     records=engine.record_entries(prepared), case=case, case_text=case.text)


def work_precision(case: Case | Mapping | str | Path, *, records_dir: str | Path | None = None,
                   reference: str = "auto", modes=("located",)):
    """Error against CPU time on one case, at a few steps (`analyses.precision.work_precision`).

    Parameters
    ----------
    case : Case, mapping or path
    records_dir : str or Path, optional
    reference : {"auto", "solver", "finest"}
        Errors against the reference solver (DOP853), the kernel's finest step halved, or the
        solver when the case is short.
    modes : sequence of str
        Event schemes: ``located`` and/or ``step-end``.

    Returns
    -------
    analyses.precision.PrecisionTable
        ``rows`` (step [s], CPU [s], errors of the event times [s] and the largest rotation [rad],
        verdict), ``text()`` the printout.
    """
    from .analyses import precision
    from .engine import prepare as engine
    from .io import records

    prepared = engine.prepare(_case(case), records.records_dir(records_dir), history=False)
    return precision.work_precision(prepared, reference=reference, modes=tuple(modes))


def sweep(case: Case | Mapping | str | Path, *, mu_kinetic_ratio: float | None = None,
          records_dir: str | Path | None = None, device: str = "cpu", workers: int | None = None,
          scheduler=None, wait_workers: float | None = None, chunk_size: int | None = None, store=None,
          progress: Callable[[int], None] | None = None, **axes):
    """A grid of cases over some of the case's values, as ``rockslide sweep`` computes it.

    Parameters
    ----------
    case : Case, mapping or path
    **axes : str or sequence
        The axes, in dimension order: ``mu``, ``pga``, ``vertical_factor``, ``restitution``,
        ``height_to_width`` (h/b, the field's slenderness ratio; the height kept), ``gravity``,
        ``floor_period`` (the period of the floor's first horizontal mode, docs/floors.md), and for
        a pulse case
        ``amplitude``, ``period``, ``duration``, and for a case with two horizontal components
        ``azimuth`` (``block.orientation``). Each is ``"start:stop:step"`` or a comma list as
        on the command line (``pga="100gal:1000gal:25gal"``, ``azimuth="0:180:5"`` in degrees), or a
        sequence of values: SI numbers or strings with units (``pga=[1.0, 2.0]`` in m/s^2,
        ``pga=["0.1g", "0.2g"]``, ``azimuth=[0.0, 0.5]`` in rad).
    mu_kinetic_ratio : float, optional
        ``mu_kinetic / mu_static`` with ``mu`` (default: the case's ratio).
    records_dir : str or Path, optional
    device : {"cpu", "gpu"}
    workers : int, optional
        Threads (default: all cores).
    scheduler : str, distributed.Client or cluster object, optional
        Compute on a dask.distributed cluster (docs/clusters.md): its scheduler's address
        (``"tcp://host:8786"``; ``"tls://host:8786"`` with the certificates of dask's
        configuration), a connected ``distributed.Client`` (used as is and left open), or a
        cluster object with ``scheduler_address`` and optionally ``security``, reached with that
        security (dask-jobqueue's ``SLURMCluster``, dask-gateway's ``GatewayCluster``,
        ``distributed.LocalCluster``). The scheduler is asked who it is before any planning, the
        workers' rockslide is checked against this one's, and the results equal a local run's.
    wait_workers : float, optional
        [s] With ``scheduler``: how long to wait for a first worker to join (default 120 s; the
        jobs of dask-jobqueue start when the queue lets them).
    chunk_size : int, optional
        Cases per chunk (default about 1/100 of the grid, 4 to 256).
    store : engine.chunks.ChunkStore, optional
        Keep finished chunks there (resumable); default: in memory.
    progress : callable, optional
        Called with the number of cases of each finished chunk.

    Returns
    -------
    xarray.Dataset
        The variables of the sweep file (``overturned``, ``max_rotation`` [rad], ``status``,
        ``modes``...) on the axes (SI coordinates), with its attributes.
    """
    from .analyses import sweep as sw
    from .engine.execute import check_where, execute
    from .io import datasets, records

    case = _case(case)
    retired = [name for name in axes if name in sw.RETIRED_AXES]
    if retired:
        raise CaseError(sw.RETIRED_AXES[retired[0]], source=retired[0])
    unknown = [name for name in axes if name not in sw.AXES]
    if unknown:
        raise CaseError(f"unknown axis {unknown[0]!r}; expected one of {', '.join(sw.AXES)}",
                        source="rockslide.sweep")
    parsed = [sw.parse_axis(name, _axis_text(values, sw.AXES[name].kind)) for name, values in axes.items()
              if values is not None]
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers)
    plan = sw.plan_sweep(case, parsed, records_dir=records.records_dir(records_dir),
                         mu_kinetic_ratio=mu_kinetic_ratio, chunk_size=chunk_size)
    done = execute(plan, store, workers=workers, scheduler=scheduler, device=device, progress=progress,
                   wait_workers=wait_workers)
    return datasets.sweep_dataset(sw.coordinates(plan), sw.sweep_variables(plan, done.states),
                                  sw.root_attributes(plan, ""))


def fragility(case: Case | Mapping | str | Path, suite: str | Path, *, im: str = "pga",
              levels: str | Sequence, damage: Sequence[str] = (), units: str | None = None,
              resamples: int = 1000, case_vertical: bool = False, samples: int = 0, seed: int = 1,
              azimuth: str | None = None, records_dir: str | Path | None = None,
              device: str = "cpu", workers: int | None = None, scheduler=None, wait_workers: float | None = None,
              chunk_size: int | None = None, store=None, progress: Callable[[int], None] | None = None):
    """Fragility curves of the case's block over a record suite, as ``rockslide fragility``.

    Parameters
    ----------
    case : Case, mapping or path
        The block, contact, solver and ``ground.tail`` (its records are replaced by the suite's).
    suite : str or Path
        A suite file (YAML), a folder of horizontal records, or a glob of them.
    im : str
        The intensity measure: ``pga``, ``pgv``, ``pga_rocking`` or ``sa(T)`` (e.g. ``"sa(0.5s)"``);
        for a suite of two horizontal components also ``rotd50_`` or ``rotd100_`` of ``pga``, ``pgv``
        or ``sa(T)`` (``"rotd50_sa(1s)"``; the others are then of the motion along the block); or
        ``pfa``, ``pfv`` of the motion the block stands on (the floor's, with the case's
        ``ground.floor``; else the records', floor records).
    levels : str or sequence
        ``"0.1g:1.5g:0.1g"`` or a comma list as on the command line, or a sequence of values (SI
        numbers of the measure, or strings with units).
    damage : sequence of str
        Damage states besides overturning: ``"rotation>0.5alpha"``, ``"slip>50mm"``...
    units : str, optional
        The acceleration unit of a folder's or glob's records that do not state theirs.
    resamples : int
        Bootstrap resamples of the records for the confidence intervals (0: none).
    case_vertical : bool
        When the suite has no vertical records, scale the case's vertical record with each
        horizontal one (default: horizontal only; the dataset's ``vertical_note`` says so).
    samples : int
        Parameter sets drawn per record from the case's ``uncertain`` section (size, slenderness,
        friction, restitution), each run at every level: the fits then include the parameter
        uncertainty; ``median_without_samples`` and ``beta_without_samples`` are the case's own.
    seed : int
        Seed of their Latin hypercube.
    azimuth : str, optional
        The block's orientations for a suite of two horizontal components (``"0:180:5"``, degrees
        unless a unit is given): every record at every orientation, the fits over all of them (the
        orientation unknown, uniform); one value states it. Default: the case's ``block.orientation``.
    records_dir, device, workers, scheduler, wait_workers, chunk_size, store, progress
        As in `sweep`.

    Returns
    -------
    xarray.Dataset
        The variables of the fragility file: per record and level (``overturned``, ``status``,
        ``max_rotation``...), per damage state (``median`` [SI of the measure], ``beta``, their
        intervals, counts), per record (its measures), with its attributes.
    """
    from .analyses import fragility as fr
    from .engine.execute import check_where, execute
    from .io import datasets, records

    case = _case(case)
    measure = fr.parse_im(im)
    parsed = fr.parse_levels(_axis_text(levels, measure.kind), measure)
    states = fr.damage_states(damage)
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers)
    fplan = fr.plan_fragility(case, fr.suite_at_azimuths(fr.suite_from(str(suite), units=units), azimuth),
                              measure, parsed,
                              records_dir=records.records_dir(records_dir), chunk_size=chunk_size,
                              case_vertical=case_vertical, samples=samples, seed=seed)
    done = execute(fplan.plan, store, workers=workers, scheduler=scheduler, device=device, progress=progress,
                   wait_workers=wait_workers)
    analysis = fr.analyse(fplan, done.states, states, resamples=resamples)
    return datasets.study_dataset(*fr.dataset(fplan, analysis))


def ensemble(case: Case | Mapping | str | Path, n: int = 200, *, seed: int = 1,
             records_dir: str | Path | None = None, device: str = "cpu", workers: int | None = None,
             scheduler=None, wait_workers: float | None = None, store=None,
             progress: Callable[[int], None] | None = None):
    """A verdict's neighbourhood: ``n`` cases drawn around ``case`` over what is uncertain, as
    ``rockslide run --ensemble n`` computes them (`analyses.ensemble`).

    Parameters
    ----------
    case : Case, mapping or path
        Its ``uncertain`` section says what varies (intensity, restitution, friction, size,
        slenderness); without one, the stated defaults (`analyses.ensemble.DEFAULTS`).
    n : int
        Members.
    seed : int
        Seed of the Latin hypercube (the same seed gives the same members).
    records_dir, device, workers, scheduler, wait_workers, store, progress
        As in `sweep`.

    Returns
    -------
    xarray.Dataset
        Per member (dimension ``member``): the sampled quantities (``sample_intensity``...), and
        ``overturned``, ``max_rotation`` [rad], ``max_rotation_ratio``, ``status``, ...; the
        summary as attributes: ``p_overturn``, ``interval_low``, ``interval_high`` (95 % Wilson),
        ``flips`` (members whose verdict differs from the nominal run's), ``robust``, and the whole
        summary as JSON in ``ensemble``.
    """
    import json

    from .analyses import ensemble as ens
    from .engine.execute import check_where
    from .io import datasets, records

    case = _case(case)
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers)
    nominal = run(case, records_dir=records_dir, history=False)
    eplan = ens.plan_ensemble(case, n, seed=seed, records_dir=records.records_dir(records_dir))
    summary, members, variables = ens.compute(eplan, nominal.summary.overturned, store=store, workers=workers,
                                              scheduler=scheduler, device=device, progress=progress,
                                              wait_workers=wait_workers)
    attrs = {"name": case.name, "nominal_verdict": nominal.summary.verdict, "p_overturn": summary["p_overturn"],
             "interval_low": summary["interval"][0], "interval_high": summary["interval"][1],
             "flips": summary["flips"], "robust": int(summary["robust"]), "seed": seed,
             "ensemble": json.dumps(summary)}
    return datasets.study_dataset([members], variables, attrs)


def risk(fragility: str | Path | None = None, hazard=None, *, damage: str = "overturn", stripes: bool = False,
         median: str | float | None = None, beta: float | None = None, im: str = "pga",
         life: str | float = 50.0, age: str | float | None = None, confidence: float = 0.95,
         hazard_units: str | None = None, trim_poe: bool = False, drop_zero_poe: bool = False):
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
    from .analyses import risk as rk
    from .io import datasets

    analysis = risk_analysis(fragility, hazard, damage=damage, stripes=stripes, median=median, beta=beta, im=im,
                             life=life, age=age, confidence=confidence, hazard_units=hazard_units,
                             trim_poe=trim_poe or drop_zero_poe)
    return datasets.study_dataset(*rk.dataset(analysis))


def risk_analysis(fragility=None, hazard=None, *, damage: str = "overturn", stripes: bool = False, median=None,
                  beta=None, im: str = "pga", life=50.0, age=None, confidence: float = 0.95, hazard_units=None,
                  trim_poe: bool = False):
    """`risk`'s `analyses.risk.Analysis` (for the command's printout and figure); same arguments."""
    from .analyses import risk as rk

    used, measure = _risk_fragility(fragility, damage=damage, stripes=stripes, median=median, beta=beta, im=im)
    curves, about, notes = _hazard_curves(hazard, measure, hazard_units, trim_poe, along_block=used.along_block)
    if not 0.0 < float(confidence) < 1.0:
        raise CaseError(f"must be within 0 and 1 (e.g. 0.95), got {confidence!r}", source="--confidence")
    years = rk.parse_years(life, source="--life")
    age_years = None if age is None else rk.parse_years(age, source="--age")
    about_measure = {key: getattr(measure, key) for key in ("name", "units", "long_name", "label", "display_unit",
                                                            "display_scale")}
    return rk.analyse(used, about_measure, curves, about, life=years, age=age_years, confidence=float(confidence),
                      notes=notes)


def _risk_fragility(path, *, damage, stripes, median, beta, im):
    """The fragility of `risk` and its intensity measure."""
    from .analyses import fragility as fr
    from .analyses import risk as rk
    from .units import parse_quantity

    if path is None:
        if median is None or beta is None:
            raise CaseError("give a fragility file, or a lognormal with both --median and --beta "
                            "(e.g. --median 0.5g --beta 0.4)", source="FRAGILITY")
        measure = fr.parse_im(im)
        theta = parse_quantity(median, measure.kind, source="--median")
        if not theta > 0:
            raise CaseError(f"the lognormal needs a positive median, got {median!r}", source="--median")
        if rk.beta_problem(beta):
            raise CaseError(rk.beta_problem(beta), source="--beta")
        b = float(beta)
        return rk.FragilityUsed(rk.Lognormal(theta, b), damage, "--median/--beta", "lognormal given", theta, b,
                                [], ""), measure
    if median is not None or beta is not None:
        raise CaseError("give either a fragility file or --median/--beta, not both", source="--median/--beta")
    given = hasattr(path, "data_vars")
    ds = path if given else read_result(path)
    path = "the fragility dataset given" if given else str(path)
    if isinstance(ds, RunResult) or "damage_state" not in ds.coords:
        raise CaseError("not a fragility file (NAME.fragility.h5 of 'rockslide fragility')", source=path)
    measure = fr.parse_im(ds.attrs["intensity_measure"])
    along = measure.rotd is None and _two_components(ds.attrs)
    states = [str(s) for s in ds["damage_state"].values]
    if damage not in states:
        raise CaseError(f"no damage state {damage!r} in the file; it has {', '.join(states)}", source="--damage")
    at = ds.sel(damage_state=damage)
    if stripes:
        fraction = np.asarray(at["fraction_exceeded"].values, dtype=np.float64)
        levels = np.asarray(ds["level"].values, dtype=np.float64)
        known = np.isfinite(fraction)
        if not known.any():
            raise CaseError(f"no stripe has a run inside the model for {damage!r}", source=str(path))
        return rk.FragilityUsed(rk.Tabulated(levels[known], fraction[known]), damage, str(path),
                                "empirical stripes (linear in ln x between them, constant outside)",
                                variants=[], along_block=along), measure
    theta, b = float(at["median"]), float(at["beta"])
    note = str(at["fit_note"].values)
    if not math.isfinite(theta) or (not math.isfinite(b) and note):
        raise CaseError(f"no lognormal fit for {damage!r} ({note}); use --stripes for its "
                        "empirical fractions", source=str(path))
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
                                    [rk.Lognormal(m, s) for m, s in pairs], uncertainty, level, along), measure
    if all(math.isfinite(v) for v in bounds):
        variants = rk.lognormal_box(bounds[:2], bounds[2:])
        uncertainty = (f"the range of the rate over the {level:.0%} bootstrap intervals of the median "
                       f"({measure.show(bounds[0])} ... {measure.show(bounds[1])}) and of beta ({bounds[2]:.3g} ... "
                       f"{bounds[3]:.3g}), on a grid over their rectangle (marginal intervals: a wide range)")
    return rk.FragilityUsed(rk.Lognormal(theta, b), damage, str(path), "lognormal fit", theta, b, variants,
                            uncertainty, along_block=along), measure


def _two_components(attrs) -> bool:
    """Whether a fragility file's suite (its ``suite_text``) has records of two horizontal
    components: its measure, unless RotD, is then of the motion along the block. False when the
    file does not say (no suite, or one that does not parse)."""
    from .case import parse_suite

    try:
        suite = parse_suite(str(attrs.get("suite_text", "")))
    except RockslideError:
        return False
    return any(entry.horizontal_2 is not None for entry in suite.entries)


def _hazard_curves(hazard, measure, units, trim: bool, *, along_block: bool = False):
    """`analyses.risk.HazardCurve` s from `risk`'s ``hazard`` (files or arrays), checked against the
    fragility's ``measure`` (``along_block``: of the motion along the block); what is known of each
    (file, kind, site); and the notes on their components (`io.hazard.component_note`)."""
    from .analyses import risk as rk
    from .io import hazard as hz

    if hazard is None or (not isinstance(hazard, (str, Path, Mapping)) and len(hazard) == 0):
        raise CaseError("give one or more hazard curves (OpenQuake's hazard-curve CSV, or a CSV of level and annual "
                        "rate)", source="--hazard")
    tables, named = [], False
    if isinstance(hazard, Mapping):
        for name, (levels, rates) in hazard.items():
            problem = hz.curve_problem(levels, rates)
            if problem:
                raise CaseError(problem, source=f"hazard[{name!r}]")
            tables.append(hz.HazardTable(str(name), None, np.asarray(levels, dtype=np.float64),
                                         np.asarray(rates, dtype=np.float64), "", level_units=None))
    else:
        for path in [hazard] if isinstance(hazard, (str, Path)) else hazard:
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
    from .io import datasets, results

    kind = results.file_format(path)
    if kind in (results.SWEEP_FORMAT, results.FRAGILITY_FORMAT, results.RISK_FORMAT):
        stored = results.read_dataset(path, format=kind)
        return datasets.study_dataset(stored.coords, stored.variables, stored.attrs)
    stored = results.read_result(path)
    return RunResult(name=stored.name, result=stored.result, ground=stored.ground, records=stored.records,
                     case_text=stored.case_text, attrs=stored.attrs)


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
    from . import plots
    from .io import results as stored_files
    from .units import parse_figure_size

    size = parse_figure_size(size, source="size")
    items = list(results) if not isinstance(results, (str, Path, RunResult)) else [results]
    if not items:
        raise CaseError("no result to draw; give one file or more", source="plot_results")
    kinds, loaded, stems = [], [], []
    for item in items:
        if isinstance(item, RunResult):
            kinds.append("result")
            loaded.append(item)
            stems.append(item.name)
            continue
        kind = stored_files.file_format(item)
        kind = {stored_files.SWEEP_FORMAT: "sweep", stored_files.FRAGILITY_FORMAT: "fragility",
                stored_files.RISK_FORMAT: "risk"}.get(kind, "result")
        if kinds and kind != kinds[0]:
            raise CaseError(f"a {kind} file among {kinds[0]} files ({items[0]}); overlay files of one kind",
                            source=str(item))
        kinds.append(kind)
        stems.append(Path(item).name.split(".")[0])
        if kind == "sweep":
            loaded.append(stored_files.read_sweep(item))
        elif kind in ("fragility", "risk"):
            loaded.append(stored_files.read_dataset(item, format=stored_files.file_format(item)))
        else:
            loaded.append(stored_files.read_result(item))   # it gives its own caption and ground under a floor
    kind = kinds[0]
    if names is None:
        names = [item.name if kind == "result" else str(item.attrs.get("name") or stem)
                 for item, stem in zip(loaded, stems, strict=True)]
        if len(set(names)) < len(names):
            names = stems if len(set(stems)) == len(stems) else [f"{n} ({i + 1})" for i, n in enumerate(names)]
    names = [str(n) for n in names]
    if len(names) != len(loaded):
        raise CaseError(f"{len(names)} names for {len(loaded)} results", source="names")
    if len(loaded) == 1:
        if kind == "sweep":
            from .analyses.sweep import stored_figure
            figure = stored_figure(loaded[0], size=size)
        elif kind == "fragility":
            from .analyses.fragility import stored_figure
            figure = stored_figure(loaded[0], size=size)
        elif kind == "risk":
            from .analyses.risk import stored_figure
            figure = stored_figure(loaded[0].coords, loaded[0].variables, loaded[0].attrs, size=size)
        else:
            figure = plots.response_figure(loaded[0], title=names[0], time_shift=time_shift, zoom=zoom, crop=crop,
                                           size=size)
    elif kind == "sweep":
        from .analyses.sweep import overlay_figure
        figure = overlay_figure(loaded, names, size=size)
    elif kind == "fragility":
        from .analyses.fragility import overlay_figure
        figure = overlay_figure(loaded, names, size=size)
    elif kind == "risk":
        raise CaseError("risk files are drawn one at a time (each is one site's hazard and one fragility)",
                        source=str(items[1]))
    else:
        caption = "\n".join(f"{name}: {plots.run_caption(run)}" for run, name in zip(loaded, names, strict=True))
        figure = plots.runs_overlay_figure([run.result for run in loaded], names, title=" and ".join(names),
                                           caption=caption, size=size, time_shift=time_shift, crop=crop,
                                           unit=plots.pga_unit(loaded[0].case_text),
                                           floors=[plots.on_a_floor(run.case_text) for run in loaded])
    if path is not None:
        plots.save_figure(figure, path, overwrite=overwrite, dpi=dpi)
    return figure


def _case(case) -> Case:
    """A Case from a Case, a mapping or a path (`load_case`)."""
    return case if isinstance(case, Case) else load_case(case)


def _axis_text(values, kind: str) -> str:
    """An axis given as text (as on the command line) or as values of the unit kind ``kind``: a
    comma list, numbers in SI."""
    if isinstance(values, str):
        return values
    from .units import SI_UNITS

    unit = SI_UNITS.get(kind, "") if kind != "dimensionless" else ""
    return ",".join(value if isinstance(value, str) else f"{float(value)!r}{unit}" for value in values)


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
    from .io import pelicun

    if isinstance(fragility, (str, Path)):
        fragility = read_result(fragility)
    csv_path, json_path, _ = pelicun.write_pelicun(fragility, component_id, path, family=family,
                                                   description=description, overwrite=overwrite)
    return csv_path, json_path
