"""Studies of many cases: `sweep` and `fragility`, each conducted once (`sweep_study`,
`fragility_study`) for the Python API and the command line alike: planned (every point checked
first), computed on the engine (threads, a GPU or a dask cluster; resumable from an on-disk
store), then its statistics made and, when asked, written as an output set (`outputs.OutputSet`)."""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import CaseError
from ._shared import (
    ANALYSIS_MODULES,
    as_case,
    axis_text,
    axis_values,
    callable_arg,
    check_where,
    importing_meanwhile,
    output_modules,
    path_arg,
    real,
    whole,
)

if TYPE_CHECKING:
    from ..case import Case


@dataclass
class StudyResult:
    """A study computed (`sweep_study`, `fragility_study`).

    Attributes
    ----------
    kind : {"sweep", "fragility"}
    name : str
        The case's name.
    coords, variables, attrs
        What its file holds (`io.results.write_dataset`): the dimensions ``(name, values,
        attributes)``, the variables ``name: (dims, values, attributes)`` and the root attributes.
    computed : int
        Cases computed now (the others were in the store).
    seconds : float
        [s] Wall time spent computing them.
    lines : list of str
        The printout of ``rockslide sweep`` or ``fragility`` (the files written apart).
    summary : dict
        The JSON summary (``rockslide fragility --json``): its fits; empty for a sweep.
    files : outputs.OutputSet or None
        The files written.
    written : str
        What was written, as the command line says it.
    """

    kind: str
    name: str
    coords: list
    variables: dict
    attrs: dict
    computed: int = 0
    seconds: float = 0.0
    lines: list = field(default_factory=list)
    summary: dict = field(default_factory=dict)
    files: object = None
    written: str = ""
    warnings: list = field(default_factory=list)

    def to_xarray(self):
        """The study as an ``xarray.Dataset`` (`io.datasets`): what `sweep` and `fragility` return."""
        from ..io import datasets

        if self.kind == "sweep":
            return datasets.sweep_dataset(self.coords, self.variables, self.attrs)
        return datasets.study_dataset(self.coords, self.variables, self.attrs)


def _no_bar(description: str, total: int, unit: str, *, transient: bool = False):
    return contextlib.nullcontext(lambda cases: None)


def sweep(case: Case | Mapping | str | Path, *, mu_kinetic_ratio: float | None = None,
          records_dir: str | Path | None = None, device: str = "cpu", workers: int | None = None,
          scheduler=None, wait_workers: float | None = None, chunk_size: int | None = None, store=None,
          progress: Callable[[int], None] | None = None, outputs=None, shard=None, **axes):
    """A grid of cases over some of the case's values, as ``rockslide sweep`` computes it.

    Parameters
    ----------
    case : Case, mapping or path
    **axes : str or sequence
        The axes, in dimension order: ``mu``, ``pga``, ``vertical_factor``, ``restitution``,
        ``height_to_width`` (h/b, the field's slenderness ratio; the height kept), ``gravity``,
        ``floor_period`` (the period of the floor's first horizontal mode, docs/floors.md), ``b1`` and
        ``b2`` (the corners of an asymmetric body, docs/asymmetric.md), and for
        a pulse case
        ``amplitude``, ``period``, ``duration``, and for a case with two horizontal components
        ``azimuth`` (``block.orientation``). Each is ``"start:stop:step"`` or a comma list as
        on the command line (``pga="100gal:1000gal:25gal"``, ``azimuth="0:180:5"`` in degrees), or a
        sequence of values: SI numbers or strings with units (``pga=[1.0, 2.0]`` in m/s^2,
        ``pga=["0.1g", "0.2g"]``, ``azimuth=[0.0, 0.5]`` in rad).
    mu_kinetic_ratio : float, optional
        ``mu_kinetic / mu_static`` with ``mu`` (default: the case's ratio).
    records_dir : str or Path, optional
    device : {"cpu", "gpu", "auto"}
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
        Keep finished chunks there (resumable): ``ChunkStore(folder)`` takes the study's
        definition key; a store made for another study is refused. Default: in memory, or beside
        ``outputs``' result.
    progress : callable, optional
        Called with the number of cases of each finished chunk.
    outputs : outputs.OutputSet, optional
        Also write ``NAME.sweep.h5``, its figure and table there, as the command line does.
    shard : (int, int) or str, optional
        ``(i, n)`` or ``"i/n"``: compute only share i of n of the chunks into the store and return
        None (docs/clusters.md).

    Returns
    -------
    xarray.Dataset
        The variables of the sweep file (``overturned``, ``max_rotation`` [rad], ``status``,
        ``modes``...) on the axes (SI coordinates), with its attributes.
    """
    done = sweep_study(case, list(axes.items()), mu_kinetic_ratio=mu_kinetic_ratio, records_dir=records_dir,
                       device=device, workers=workers, scheduler=scheduler, wait_workers=wait_workers,
                       chunk_size=chunk_size, store=store, progress=progress, outputs=outputs, shard=shard)
    return None if done is None else done.to_xarray()


def sweep_study(case, axes: Sequence[tuple], *, mu_kinetic_ratio=None, records_dir=None, device="cpu", workers=None,
                scheduler=None, tls=None, wait_workers=None, chunk_size=None, store=None, progress=None, outputs=None,
                shard=None, report: Callable[[str], None] | None = None, bars=_no_bar,
                command_line: str = "") -> StudyResult | None:
    """`sweep`, conducted: ``axes`` as ``(name, values)`` pairs in dimension order; ``tls`` the TLS
    files (`engine.execute.TLS_OPTIONS`); ``report`` is told each note for the user; ``bars`` makes
    progress bars (called with a description, a total and a unit, and ``transient``; returns a
    context manager that yields the callable to tell of progress); ``command_line`` is stored in the
    file. Returns None for a shard."""
    from ..analyses import sweep as sw
    from ..engine.chunks import ChunkStore
    from ..engine.prepare import duration_text
    from ..io import records

    say = report if report is not None else (lambda text: None)
    started = time.perf_counter()
    case = as_case(case)
    axes = _parse_axes(axes)
    _check_study(records_dir, chunk_size, store, progress)
    real(mu_kinetic_ratio, "mu_kinetic_ratio", optional=True)
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers, tls=tls)
    shard = _shard(shard)
    with contextlib.ExitStack() as held:
        finishing = False
        if outputs is not None:
            leftovers = ChunkStore.beside(outputs.h5, "").root.exists
            finishing = outputs.check(leftovers=leftovers())
            if held.enter_context(outputs.one_at_a_time("sweep", shard=shard is not None)):   # another ran meanwhile
                finishing = outputs.check(leftovers=leftovers())
        n_points = math.prod(len(a) for a in axes) if axes else 0
        if axes and sw.planning_seconds(case, axes) > 10:
            say(f"sweep {case.name}: checking the {n_points} points of the grid first (about "
                f"{duration_text(sw.planning_seconds(case, axes))})")
        checking = bars if n_points >= 10 * sw.PLAN_BATCH else _no_bar
        with checking(f"{case.name}: checking", n_points, "case", transient=True) as update:
            plan = sw.plan_sweep(case, axes, records_dir=records.records_dir(records_dir),
                                 mu_kinetic_ratio=mu_kinetic_ratio, chunk_size=chunk_size, progress=update)
        if finishing:
            return _finish_sweep(plan, outputs, started, say)
        done = _execute(plan, store, outputs, what="sweep", description=plan.describe(), label=case.name, unit="case",
                        workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers, shard=shard,
                        progress=progress, bars=bars, say=say)
        if done is None:
            return None
        variables = sw.sweep_variables(plan, done.states)
        done.states = None                      # 288 bytes a case: not held while the file is written
        result = StudyResult("sweep", case.name, sw.coordinates(plan), variables,
                             sw.root_attributes(plan, command_line), done.computed, done.seconds,
                             lines=_sweep_lines(plan, variables, done) + _step_note(plan))
        if outputs is not None:
            _write(result, outputs, figure=lambda: sw.figure(plan, variables, size=outputs.size),
                   table=lambda: (_datasets().sweep_dataset(sw.table_coordinates(result.coords), variables),
                                  [a.name for a in plan.axes]))
            done.store.remove()
        return result


def retired_axis(name: str) -> str | None:
    """What replaces a sweep axis no longer offered (one line), or None."""
    from ..analyses.sweep import RETIRED_AXES

    return RETIRED_AXES.get(name)


def _parse_axes(axes):
    """`analyses.sweep.Axis` es of ``(name, values)`` pairs; an axis no longer offered, or unknown,
    is one line naming it."""
    from ..analyses import sweep as sw

    parsed = []
    for name, values in axes:
        if name in sw.RETIRED_AXES:
            raise CaseError(sw.RETIRED_AXES[name], source=name)
        if name not in sw.AXES:
            raise CaseError(f"unknown axis {name!r}; expected one of {', '.join(sw.AXES)}", source="axes")
        if values is not None:
            parsed.append(sw.parse_axis(name, axis_text(axis_values(values, name), sw.AXES[name].kind)))
    return parsed


def _check_study(records_dir, chunk_size, store, progress) -> None:
    """The arguments every study takes, checked before any work."""
    path_arg(records_dir, "records_dir")
    whole(chunk_size, "chunk_size", 1, optional=True)
    callable_arg(progress, "progress")
    if store is not None and not hasattr(store, "for_plan"):
        raise CaseError(f"expected an engine.chunks.ChunkStore or MemoryStore, got {type(store).__name__}",
                        source="store")


def _shard(shard):
    from ..engine.execute import parse_shard

    if shard is None or isinstance(shard, str):
        return parse_shard(shard)
    return parse_shard(f"{shard[0]}/{shard[1]}")


def _execute(plan, store, outputs, *, what, description, label, unit, workers, scheduler, device, wait_workers,
             shard, progress, bars, say):
    """`engine.execute.execute` with the chunks beside ``outputs``' result (or in ``store``), its
    notes told to ``say`` and its progress to ``progress`` and a bar; after Ctrl-C the exception
    says what is kept (``kept``); with ``shard``, says what this share computed and returns None."""
    from .. import interrupts
    from ..engine.chunks import ChunkStore
    from ..engine.execute import execute

    if store is None and outputs is not None:
        store = ChunkStore.beside(outputs.h5, plan.key)
    if outputs is not None:
        outputs.remove_stale_temporaries()
    held = store if store is not None else None
    with bars(label, plan.n_cases, unit) as update:
        def tell(cases: int) -> None:
            update(cases)
            if progress is not None:
                progress(cases)

        try:
            analysis = () if shard is not None else ANALYSIS_MODULES.get(what, ())
            with importing_meanwhile(output_modules(None if shard is not None else outputs, device=device,
                                                    scheduler=scheduler, analysis=analysis)):
                done = execute(plan, held, workers=workers, scheduler=scheduler, device=device, progress=tell,
                               report=say, what=what, label=label, description=description, unit=unit,
                               free_space_at=None if outputs is None else outputs.folder, shard=shard,
                               wait_workers=wait_workers)
        except interrupts.Interrupted as exc:
            if isinstance(held, ChunkStore):
                kept = getattr(exc, "store", None)         # where the compute kept them (the GPU's own)
                kept = held.for_plan(plan.key) if kept is None else kept
                exc.kept = (f"{kept.count()} of {getattr(exc, 'chunks', plan.n_chunks)} chunks are kept in "
                            f"{kept.folder}; the same command resumes from them")
            raise
    if shard is not None:
        say(f"{what} {label}: shard {shard[0]}/{shard[1]} computed {done.computed} {unit}s in {done.seconds:.1f} s; "
            f"{done.store.count()} of {done.chunks} chunks are in {done.store.folder} (the same command without "
            "--shard collects them)")
        return None
    return done


def _datasets():
    """`io.datasets`, loaded where a table is written (it loads h5py, which a study loads while it
    computes: `importing_meanwhile`)."""
    from ..io import datasets

    return datasets


def _write(result: StudyResult, outputs, *, figure, table, more=None) -> None:
    """Write a study's output set: its file, figure, table and ``more`` (a callable given the staging)."""
    from ..io import results

    sweep = result.kind == "sweep"
    fmt = results.SWEEP_FORMAT if sweep else results.FRAGILITY_FORMAT
    with outputs.staging() as staging:
        write = results.write_sweep if sweep else partial(results.write_dataset, format=fmt)
        write(outputs.h5, result.coords, result.variables, attrs=result.attrs, overwrite=outputs.overwrite,
              staging=staging)
        if outputs.plot:
            outputs.save_figure(figure(), staging)
        if outputs.csv:
            outputs.write_csv(*table(), staging)
        if more is not None:
            more(staging)
        staging.publish(remove=outputs.stale(staging, format=fmt))
    result.files = outputs
    result.written = outputs.written()


def _rate(done, unit: str) -> str:
    """``1517 cases in 1.2 s (1264 cases/s)`` (``unit`` plural; ``1 case``)."""
    rate = f" ({done.computed / done.seconds:.0f} {unit}/s)" if done.computed and done.seconds > 0 else ""
    return f"{done.computed} {unit if done.computed != 1 else unit[:-1]} in {done.seconds:.1f} s{rate}"


def _step_note(plan) -> list[str]:
    """The step the study took, and what ``solver.dt: auto`` takes or would take (`step.StudyStep.note`)."""
    note = plan.step_study.note() if plan.step_study is not None else ""
    return [f"  {note}"] if note else []


def _sweep_lines(plan, variables, done) -> list[str]:
    from ..analyses import sweep as sw

    over = int(variables["overturned"][0].sum())
    outside = int((variables["status"][0] != 0).sum())
    undecided = int(variables["undecided"][0].sum())
    lines = [f"  {over} of {plan.n_cases} overturned, {outside} outside the model; computed {_rate(done, 'cases')}"]
    worst = sw.worst_azimuth(plan, variables)
    if worst is not None:
        lines.append(f"  {worst['text']}")
    if undecided:
        lines.append(f"  {undecided} undecided: still moving at the end with the energy to overturn "
                     "(give the case a ground.tail for their free motion)")
    return lines


def _finish_sweep(plan, outputs, started: float, say) -> StudyResult:
    """``NAME.sweep.h5`` exists: if it is this sweep's result (same definition key), draw its
    missing figure and remove its chunks (a run stopped in its final phase); else refuse."""
    from ..analyses.sweep import stored_figure
    from ..engine.chunks import ChunkStore
    from ..errors import OutputError
    from ..io import results

    try:
        stored = results.read_sweep(outputs.h5)
    except OutputError:
        stored = None
    if stored is None or stored.attrs.get("sweep_key") != plan.key:
        outputs.refuse()
    drawn = ""
    if outputs.plot and not (outputs.png.exists() or outputs.png.is_symlink()):
        from ..plots import save_figure
        save_figure(stored_figure(stored, size=outputs.size), outputs.png, overwrite=False, dpi=outputs.dpi)
        drawn = f"; drew its missing figure {outputs.png}"
    ChunkStore.beside(outputs.h5, plan.key).remove()
    line = (f"sweep {plan.case.name}: {outputs.h5} is this sweep's complete result{drawn}; removed its "
            f"chunks ({time.perf_counter() - started:.1f} s)")
    return StudyResult("sweep", plan.case.name, stored.coords, stored.variables, stored.attrs, lines=[line],
                       files=outputs)


def fragility(case: Case | Mapping | str | Path, suite: str | Path, *, im: str = "pga",
              levels: str | Sequence, damage: Sequence[str] = (), units: str | None = None,
              resamples: int = 1000, case_vertical: bool = False, samples: int = 0, seed: int = 1,
              azimuth: str | None = None, records_dir: str | Path | None = None,
              device: str = "cpu", workers: int | None = None, scheduler=None, wait_workers: float | None = None,
              chunk_size: int | None = None, store=None, progress: Callable[[int], None] | None = None,
              outputs=None, shard=None, export: tuple | None = None, export_family: str = "lognormal",
              model: str = "lognormal"):
    """Fragility curves of the case's block over a record suite, as ``rockslide fragility``.

    Parameters
    ----------
    case : Case, mapping or path
        The block, contact, solver and ``ground.tail`` (its records are replaced by the suite's).
    suite : str or Path
        A suite file (YAML), a folder of horizontal records, or a glob of them.
    im : str
        The intensity measure the records are scaled to: ``pga``, ``pgv``, ``pga_rocking`` or ``sa(T)``
        (e.g. ``"sa(0.5s)"``); with a second one (``"pga,pgv"``, ``"pga,pgv/pga"``) a surface too;
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
    records_dir, device, workers, scheduler, wait_workers, chunk_size, store, progress, outputs, shard
        As in `sweep`.
    export : (str, str), optional
        With ``outputs``: ``("pelicun", ID)`` also writes the fragility as a row of pelicun's
        fragility CSV and its JSON (`export_pelicun`), of ``export_family`` (the multilinear CDF of
        the curve chosen when ``model`` is not the lognormal).
    model : str
        The curve offered to `risk` (its default) and `export_pelicun`: ``"lognormal"``,
        ``"isotonic"`` or ``"empirical"`` (attribute ``fragility_model``). Every curve is in the
        dataset whichever is chosen, with the goodness of fit (``gof_*``). With two measures
        (``im="pga,pgv"`` or ``"pga,pgv/pga"``: scaled on the first), the probit surface
        ``P = Phi(a + b ln IM1 + c ln IM2)`` is fitted too (the attribute ``surface``, JSON).

    Returns
    -------
    xarray.Dataset
        The variables of the fragility file: per record and level (``overturned``, ``status``,
        ``max_rotation``...), per damage state (``median`` [SI of the measure], ``beta``, their
        intervals, counts), per record (its measures), with its attributes.
    """
    done = fragility_study(case, suite, im=im, levels=levels, damage=damage, units=units, resamples=resamples,
                           case_vertical=case_vertical, samples=samples, seed=seed, azimuth=azimuth,
                           records_dir=records_dir, device=device, workers=workers, scheduler=scheduler,
                           wait_workers=wait_workers, chunk_size=chunk_size, store=store, progress=progress,
                           outputs=outputs, shard=shard, export=export, export_family=export_family, model=model)
    return None if done is None else done.to_xarray()


def fragility_study(case, suite, *, im="pga", levels, damage=(), units=None, resamples=1000, case_vertical=False,
                    samples=0, seed=1, azimuth=None, records_dir=None, device="cpu", workers=None, scheduler=None,
                    tls=None, wait_workers=None, chunk_size=None, store=None, progress=None, outputs=None, shard=None,
                    export=None, export_family="lognormal", model="lognormal", report=None, bars=_no_bar,
                    command_line: str = "") -> StudyResult | None:
    """`fragility`, conducted (the arguments as in `sweep_study`). Returns None for a shard."""
    from ..analyses import fragility as fr
    from ..io import records

    say = report if report is not None else (lambda text: None)
    case = as_case(case)
    _check_study(records_dir, chunk_size, store, progress)
    path_arg(suite, "suite", optional=False)
    for name, value in (("im", im), ("units", units), ("azimuth", azimuth)):
        if value is not None and not isinstance(value, str):
            raise CaseError(f"expected text, got {type(value).__name__}", source=name)
    whole(resamples, "resamples", 0, 100_000)
    whole(samples, "samples", 0, 100_000)
    whole(seed, "seed", 0)
    im, second = fr.split_measures(im)       # "pga,pgv": scaled on pga, fitted on both
    measure = fr.parse_im(im)
    parsed = fr.parse_levels(axis_text(axis_values(levels, "levels"), measure.kind), measure)
    states = fr.damage_states([damage] if isinstance(damage, str) else _texts(damage, "damage"))
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers, tls=tls)
    shard = _shard(shard)
    fplan = fr.plan_fragility(case, fr.suite_at_azimuths(fr.suite_from(str(suite), units=units), azimuth), measure,
                              parsed, records_dir=records.records_dir(records_dir), chunk_size=chunk_size,
                              case_vertical=case_vertical, samples=samples, seed=seed)
    with contextlib.ExitStack() as held:
        export_path = _check_outputs(outputs, held, measure, export, shard is not None)
        if fplan.vertical_note:
            say(f"  note: {fplan.vertical_note}")
        done = _execute(fplan.plan, store, outputs, what="fragility", description=fplan.describe(), label=case.name,
                        unit="run", workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers,
                        shard=shard, progress=progress, bars=bars, say=say)
        if done is None:
            return None
        analysis = fr.analyse(fplan, done.states, states, resamples=resamples, model=model)
        if model != "lognormal" and export_family == "lognormal":
            export_family = "multilinear_CDF"           # the curve chosen, not the fit
        result = StudyResult("fragility", case.name, *fr.dataset(fplan, analysis, command_line), done.computed,
                             done.seconds, summary=fr.json_summary(fplan, analysis))
        surfaces = None if second is None else fr.fit_surface(fplan, analysis, second, resamples=min(resamples, 200))
        if surfaces is not None:
            result.summary["surface"] = fr.surface_json(surfaces, second)
            result.attrs["surface"] = json.dumps(result.summary["surface"])
        left_out = []
        if outputs is not None:
            def more(staging):
                if surfaces is not None and outputs.plot:
                    outputs.save_figure(fr.surface_figure(fplan, surfaces, second, size=outputs.size), staging,
                                        outputs.png.with_suffix(".surface.png"))
                if export_path is not None:
                    from ..io import pelicun
                    dataset = _datasets().study_dataset(result.coords, result.variables, result.attrs)
                    left_out.extend(pelicun.write_pelicun(dataset, export[1], export_path, family=export_family,
                                                          overwrite=outputs.overwrite, staging=staging)[2])

            per_run = [name for name, _, _ in result.coords if name not in ("damage_state", "resample")]
            _write(result, outputs, figure=lambda: fr.figure(fplan, analysis, size=outputs.size),
                   table=lambda: (_datasets().study_dataset(result.coords, result.variables), per_run), more=more)
            done.store.remove()
        result.lines = _fragility_lines(fplan, analysis, done, measure, export, export_path, export_family, left_out,
                                        model, surfaces, second) + _step_note(fplan.plan)
        return result


def _texts(values, name: str) -> list[str]:
    """A sequence of strings, or a `CaseError` naming the argument."""
    if not hasattr(values, "__iter__") or not all(isinstance(v, str) for v in values):
        raise CaseError("expected a sequence of strings", source=name)
    return list(values)


def _check_outputs(outputs, held, measure, export, shard: bool):
    """The fragility's outputs checked before the work (input errors first), its lock held; the
    pelicun export's path (or None)."""
    if outputs is None:
        return None
    export_path = None
    if export is not None and export[0] == "pelicun":
        from ..io import pelicun
        pelicun.check_export(measure, export[1])
        export_path = outputs.h5.with_suffix(".pelicun.csv")
        for path in (export_path, export_path.with_suffix(".json")):
            outputs.check_extra(path, "out/case.fragility.pelicun.csv")
    if outputs.check():
        outputs.refuse()
    if held.enter_context(outputs.one_at_a_time("fragility analysis", shard=shard)) and outputs.check():
        outputs.refuse()                                # published by the one waited for
    return export_path


def _fragility_lines(fplan, analysis, done, measure, export, export_path, family, left_out, model, surfaces,
                     second) -> list[str]:
    from ..analyses import fragility as fr

    outside = int((analysis.variables["status"][0] != 0).sum())
    lines = [f"  computed {_rate(done, 'runs')}; {outside} of {fplan.plan.n_cases} outside the model (left out of "
             "the fits)"]
    undecided = int(analysis.variables["undecided"][0].sum())
    if undecided:
        lines.append(f"  {undecided} undecided: still moving at the end with the energy to overturn, counted as "
                     "not overturned (give the case a ground.tail for their free motion)")
    for i, (state, fit) in enumerate(zip(analysis.states, analysis.fits, strict=True)):
        lines.append("  " + fr.describe_fit(state, fit, measure))
        lines += [f"    {line}" for line in fr.goodness_lines(fit)]
        if model != "lognormal":
            lines.append(f"    {fr.isotonic_line(fit, fplan.levels.values, measure)}")
        lines += [f"    warning: {caveat}" for caveat in fr.caveats(fit, measure)]
        if analysis.nominal_fits:
            lines.append("    without parameter uncertainty (the case's values): "
                         + fr.describe_fit(state, analysis.nominal_fits[i], measure).split(": ", 1)[1])
    lines += [f"  {line}" for line in ([] if surfaces is None else fr.surface_lines(surfaces, second))]
    if export_path is not None:
        lines.append(f"  pelicun: {export_path} and {export_path.with_suffix('.json').name} ({family}, "
                     f"ID {export[1]})" + (f"; not exported: {'; '.join(left_out)}" if left_out else ""))
    return lines
