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

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from .case import Case, case_with, load_case
from .core.simulate import Result, Summary
from .errors import CaseError

__all__ = ["load_case", "case_with", "run", "sweep", "fragility", "ensemble", "read_result", "RunResult",
           "Case", "Summary"]


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
        factors ``scale_horizontal``, ``scale_vertical`` (None where there is no record).
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
        """What happened (`core.simulate.Summary`): ``overturned``, ``max_rotation`` [rad],
        ``max_rotation_ratio`` (of alpha), ``max_slip`` [m], ``impacts``, ``status``, ``verdict``..."""
        return self.result.summary

    @property
    def history(self) -> dict:
        """The time histories by column (numpy arrays; SI)."""
        return self.result.history

    @property
    def events(self):
        """The event log (a numpy structured array: time [s], from, to, cause, edge, ...)."""
        return self.result.events

    def to_xarray(self):
        """The run as an ``xarray.Dataset`` (`io.datasets.run_dataset`): histories on ``time``, the
        ground motion on ``ground_time``, the event log on ``event``, the summary as attributes."""
        from .io.datasets import run_dataset

        ground = {f"ground_{k}": v for k, v in self.ground.items() if v is not None}
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
    return RunResult(name=case.name, result=result, ground=prepared.ground.as_applied(),
                     records=engine.record_entries(prepared), case=case, case_text=case.text)


def sweep(case: Case | Mapping | str | Path, *, mu_kinetic_ratio: float | None = None,
          records_dir: str | Path | None = None, device: str = "cpu", workers: int | None = None,
          scheduler: str | None = None, chunk_size: int | None = None, store=None,
          progress: Callable[[int], None] | None = None, **axes):
    """A grid of cases over some of the case's values, as ``rockslide sweep`` computes it.

    Parameters
    ----------
    case : Case, mapping or path
    **axes : str or sequence
        The axes, in dimension order: ``mu``, ``pga``, ``vertical_factor``, ``restitution``,
        ``height_to_width`` (h/b, the field's slenderness ratio; the height kept), ``gravity``, and for a pulse case
        ``amplitude``, ``period``, ``duration``. Each is ``"start:stop:step"`` or a comma list as
        on the command line (``pga="100gal:1000gal:25gal"``), or a sequence of values: SI numbers
        or strings with units (``pga=[1.0, 2.0]`` in m/s^2, ``pga=["0.1g", "0.2g"]``).
    mu_kinetic_ratio : float, optional
        ``mu_kinetic / mu_static`` with ``mu`` (default: the case's ratio).
    records_dir : str or Path, optional
    device : {"cpu", "gpu"}
    workers : int, optional
        Threads (default: all cores).
    scheduler : str, optional
        A dask.distributed scheduler's address: compute there.
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
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device)
    plan = sw.plan_sweep(case, parsed, records_dir=records.records_dir(records_dir),
                         mu_kinetic_ratio=mu_kinetic_ratio, chunk_size=chunk_size)
    done = execute(plan, store, workers=workers, scheduler=scheduler, device=device, progress=progress)
    return datasets.sweep_dataset(sw.coordinates(plan), sw.sweep_variables(plan, done.states),
                                  sw.root_attributes(plan, ""))


def fragility(case: Case | Mapping | str | Path, suite: str | Path, *, im: str = "pga",
              levels: str | Sequence, damage: Sequence[str] = (), units: str | None = None,
              resamples: int = 1000, case_vertical: bool = False, samples: int = 0, seed: int = 1,
              records_dir: str | Path | None = None,
              device: str = "cpu", workers: int | None = None, scheduler: str | None = None,
              chunk_size: int | None = None, store=None, progress: Callable[[int], None] | None = None):
    """Fragility curves of the case's block over a record suite, as ``rockslide fragility``.

    Parameters
    ----------
    case : Case, mapping or path
        The block, contact, solver and ``ground.tail`` (its records are replaced by the suite's).
    suite : str or Path
        A suite file (YAML), a folder of horizontal records, or a glob of them.
    im : str
        The intensity measure: ``pga``, ``pgv``, ``pga_rocking`` or ``sa(T)`` (e.g. ``"sa(0.5s)"``).
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
    records_dir, device, workers, scheduler, chunk_size, store, progress
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
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device)
    fplan = fr.plan_fragility(case, fr.suite_from(str(suite), units=units), measure, parsed,
                              records_dir=records.records_dir(records_dir), chunk_size=chunk_size,
                              case_vertical=case_vertical, samples=samples, seed=seed)
    done = execute(fplan.plan, store, workers=workers, scheduler=scheduler, device=device, progress=progress)
    analysis = fr.analyse(fplan, done.states, states, resamples=resamples)
    return datasets.study_dataset(*fr.dataset(fplan, analysis))


def ensemble(case: Case | Mapping | str | Path, n: int = 200, *, seed: int = 1,
             records_dir: str | Path | None = None, device: str = "cpu", workers: int | None = None,
             scheduler: str | None = None, store=None, progress: Callable[[int], None] | None = None):
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
    records_dir, device, workers, scheduler, store, progress
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
    nominal = run(case, records_dir=records_dir, history=False)
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device)
    eplan = ens.plan_ensemble(case, n, seed=seed, records_dir=records.records_dir(records_dir))
    summary, members, variables = ens.compute(eplan, nominal.summary.overturned, store=store, workers=workers,
                                              scheduler=scheduler, device=device, progress=progress)
    attrs = {"name": case.name, "nominal_verdict": nominal.summary.verdict, "p_overturn": summary["p_overturn"],
             "interval_low": summary["interval"][0], "interval_high": summary["interval"][1],
             "flips": summary["flips"], "robust": int(summary["robust"]), "seed": seed,
             "ensemble": json.dumps(summary)}
    return datasets.study_dataset([members], variables, attrs)


def read_result(path: str | Path):
    """Read any file rockslide writes.

    Returns
    -------
    RunResult
        For a run's result file (``NAME.h5``).
    xarray.Dataset
        For a sweep (``NAME.sweep.h5``) or a fragility file (``NAME.fragility.h5``): the same
        dataset `sweep` or `fragility` returned.

    Raises
    ------
    OutputError
        The file is missing or is not a rockslide file of a known format and version.
    """
    from .io import datasets, results

    kind = results.file_format(path)
    if kind in (results.SWEEP_FORMAT, results.FRAGILITY_FORMAT):
        stored = results.read_dataset(path, format=kind)
        return datasets.study_dataset(stored.coords, stored.variables, stored.attrs)
    stored = results.read_result(path)
    return RunResult(name=stored.name, result=stored.result, ground=stored.ground, records=stored.records,
                     case_text=stored.case_text, attrs=stored.attrs)


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
