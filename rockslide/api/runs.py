"""One case: `run` (its result, files and neighbourhood) and `ensemble` (the neighbourhood alone)."""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from ..case import Case
from ..core.simulate import Result, Summary
from ..errors import CaseError, OutputError
from ._shared import (
    ANALYSIS_MODULES,
    Meanwhile,
    as_case,
    callable_arg,
    check_where,
    importing_meanwhile,
    output_modules,
    path_arg,
    whole,
    with_scale,
)

#: A single run expected to take longer than this [s] says so before it starts (and shows a
#: progress bar on a terminal).
LONG_RUN = 10.0

#: An ensemble of this many members or more says, before it plans them, how long planning and
#: computing them may take (`ensemble_note`): planning takes 40-60 us a member on the 2-core
#: development machine (`PLAN_SECONDS_PER_MEMBER`), a minute for 10^6, which went by without a word.
ENSEMBLE_NOTE_MEMBERS = 20_000
#: [s] Planning one member of an ensemble (its draws, its checks, its kernel row), an upper figure
#: from the 2-core development machine (1.3 s for 20 000 members with both cores busy).
PLAN_SECONDS_PER_MEMBER = 6e-5

#: A run's figure is drawn from its history kept in memory while it has at most this many rows (96
#: MB; reading the file back would take as much); a longer history is read back from the file.
KEEP_HISTORY_ROWS = 2_000_000

#: A run's history of at most this many rows (12 MB; the paper's 150 s records with a row every
#: millisecond) is held in memory and its file written after the compute, so that h5py loads while
#: it computes (0.05-0.07 s of a run on the 2-core development machine); a longer one streams into
#: the file as it is computed (bounded memory), the file opened first.
HELD_HISTORY_ROWS = 250_000


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
    ensemble : dict or None
        With ``run(..., ensemble=n)``: the neighbourhood's summary (`analyses.ensemble.summarise`:
        ``p_overturn``, ``interval``, ``flips``, ``robust``...); for a file read back, its stored one.
    floor : dict or None
        For a case on a floor: ``description`` and the peaks of the floor's motion (``pfa``
        [m/s^2], ``pfv`` [m/s], and of the ground under the building).
    planes : dict or None
        With ``block.depth`` or ``block.mesh`` (both planes, model-asymmetric.md section 9): per plane
        (``width``, ``depth``) its ``orientation`` [rad] (None: one component), ``verdict``,
        ``overturned``, ``max_rotation_ratio``; ``worse`` names the plane of the worse verdict, and
        ``screening`` says that the planes are uncoupled. None without a depth.
    integration : dict or None
        The step the run took (``step`` [s], ``mode`` fixed or auto and, with ``solver.dt: auto``,
        its error estimates: `engine.prepare.step_report`), as ``rockslide run --json`` gives it.
    files : outputs.OutputSet or None
        The files written (``run(..., outputs=...)``).
    written : str
        What was written, as the command line says it.
    base : dict or None
        For a file read back of a case on a floor: the ground motion under the building.
    """

    name: str
    result: Result
    ground: dict
    records: list
    case: Case | None = None
    case_text: str = ""
    attrs: dict = field(default_factory=dict)
    ensemble: dict | None = None
    floor: dict | None = None
    planes: dict | None = None
    integration: dict | None = None
    files: object = None
    written: str = ""
    base: dict | None = None

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
        from ..io.datasets import run_dataset

        flat = {**{k: v for k, v in self.ground.items() if k != "components"},
                **(self.ground.get("components") or {})}
        ground = {f"ground_{k}": v for k, v in flat.items() if v is not None}
        return run_dataset(self.result, name=self.name, attrs=ground)


def run(case: Case | Mapping | str | Path, *, records_dir: str | Path | None = None, history: bool = True,
        progress: Callable[[float, float], None] | None = None, outputs=None, ensemble: int | None = None,
        seed: int = 1, device: str = "cpu", workers: int | None = None, report: Callable[[str], None] | None = None,
        pga=None, vertical_factor=None, amplitude=None, bars=None) -> RunResult:
    """Compute one case, as ``rockslide run`` does.

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
    outputs : outputs.OutputSet, optional
        Also write the result file ``NAME.h5`` and its figure ``NAME.png`` (and ``NAME.ensemble.png``)
        there, as the command line does: checked before the work, published together. A complete
        result of the same case (same text, records and ensemble) whose figure is missing gets its
        figure, and is returned as read back.
    ensemble : int, True or str, optional
        Also run this many neighbours of the case (`ensemble`; True: 200; ``"auto"`` or
        ``"precision:W"``: until the 95 % interval of the probability of overturning is narrower
        than 0.1 or W), in memory; their summary is ``RunResult.ensemble`` (and is stored in the
        result file).
    seed : int
        Seed of the ensemble's Latin hypercube.
    device : {"cpu", "gpu", "auto"}
        Where the ensemble computes (the run itself is on the CPU).
    workers : int, optional
        The ensemble's threads (default: all cores).
    report : callable, optional
        Called with each note for the user (a long run, a first compile, a long ensemble).
    bars : callable, optional
        Makes the ensemble's progress bar (as `sweep_study`'s ``bars``).
    pga, vertical_factor, amplitude : str or float, optional
        The case at another intensity, as a sweep's point at these values (``pga="0.6g"`` is the
        case with ``ground.scale.pga_horizontal: 0.6 g``; SI numbers, or strings with units).

    Returns
    -------
    RunResult

    Raises
    ------
    RockslideError
        A bad case, a record that cannot be read or used (one line naming the file and field).
    """
    from ..engine import prepare as engine
    from ..io import records

    case = with_scale(as_case(case), pga=pga, vertical_factor=vertical_factor, amplitude=amplitude)
    if ensemble is not None and ensemble is not False:
        check_where(workers=workers, device=device)     # where the neighbours compute (the engine loads then)
    path_arg(records_dir, "records_dir")
    whole(seed, "seed", 0)
    callable_arg(progress, "progress")
    callable_arg(report, "report")
    members, precision = _members(ensemble)
    say = report if report is not None else (lambda text: None)
    started = time.perf_counter()
    folder = records.records_dir(records_dir)
    prepared = engine.prepare(case, folder, history=history)          # input errors first
    eplan = None
    if members is not None:        # (with a precision: its first round, which says what the ensemble is)
        from ..analyses import ensemble as ens
        if members >= ENSEMBLE_NOTE_MEMBERS:
            say(ensemble_note(prepared, members, workers))
        eplan = ens.plan_ensemble(case, members, seed=seed, records_dir=folder, records=prepared.records)
        eplan.precision = precision
    where = {"device": device, "workers": workers, "say": say, "bars": bars}
    if outputs is not None:
        return _run_into(outputs, prepared, eplan, started, progress=progress, folder=folder, **where)
    result = engine.simulate_prepared(prepared, progress=progress)
    summary = None if eplan is None else _neighbourhood(eplan, result, **where)[0]
    return _run_result(prepared, result, summary, planes=_planes(prepared, result, folder))


def ensemble_note(prepared, members: int, workers: int | None) -> str:
    """What an ensemble of ``members`` of ``prepared``'s case may take, said before it is planned: its
    planning (`PLAN_SECONDS_PER_MEMBER`) and an upper estimate of its compute on ``workers`` threads
    (every member moving to the end, as `engine.prepare.work` estimates a run)."""
    from ..core import local_threads
    from ..engine import prepare as engine

    threads = int(workers) if workers is not None else local_threads()
    computing = members * engine.work(prepared).steps / (engine.STEPS_PER_SECOND * threads)
    return (f"rockslide: note: an ensemble of {members} members: planning them takes about "
            f"{engine.duration_text(members * PLAN_SECONDS_PER_MEMBER)}, computing them up to "
            f"{engine.duration_text(computing)} on {threads} thread{'s' if threads > 1 else ''} (far less for members "
            "at rest or overturned); the progress bar then shows the time left")


def _members(ensemble) -> tuple[int | None, float | None]:
    """``run``'s ``ensemble`` as (members, precision): the members of the first round with a precision."""
    if ensemble is None or ensemble is False:
        return None, None
    from ..analyses import ensemble as ens

    if ensemble is True:
        return ens.DEFAULT_MEMBERS, None
    if isinstance(ensemble, str):
        members, precision = ens.parse_members(ensemble)
        return (ens.PILOT_MEMBERS, precision) if precision is not None else (members, None)
    return whole(ensemble, "ensemble", 1), None


#: What every printout of a box in both planes says of it (model-asymmetric.md section 9).
SCREENING = ("an uncoupled screening: each plane is the planar model under the component along it; a body "
             "rocking about a corner is not modelled")


def _planes(prepared, result, folder) -> dict | None:
    """A box's or a mesh's screening in both planes (`case.Block.both_planes`): the run just made is
    the width plane; the depth plane is `case.other_plane` across it, under the component across the
    block (with one horizontal component it sees none: no run). None for a body in one plane."""
    from ..case import other_plane
    from ..engine import prepare as engine

    case = prepared.case
    if not case.block.both_planes:
        return None
    width = {"orientation": None if prepared.components is None else prepared.components.orientation,
             **_plane_of(result.summary)}
    across = _facing(prepared) + 0.5 * math.pi
    across -= 2.0 * math.pi if across > 2.0 * math.pi else 0.0
    other = other_plane(case, across) if prepared.components is not None or case.block.mesh is not None else None
    if prepared.components is None:
        depth = {"orientation": None, "verdict": "standing", "overturned": False, "max_rotation_ratio": 0.0,
                 "note": "one horizontal component: the depth plane sees no horizontal motion"}
    else:
        depth = {"orientation": across,
                 **_plane_of(engine.simulate_prepared(engine.prepare(other, folder, history=False)).summary)}
    if case.block.mesh is not None:         # a mesh's planes are bodies of their own: say which
        width["body"], depth["body"] = case.block.describe(), other.block.describe()
    worse = "depth" if (depth["overturned"], depth["max_rotation_ratio"]) > (width["overturned"],
                                                                            width["max_rotation_ratio"]) else "width"
    return {"width": width, "depth": depth, "worse": worse, "screening": SCREENING}


def _facing(prepared) -> float:
    """[rad] The azimuth a run's (width) plane is taken along: its components' orientation (the
    block's, or the first component's), else ``block.orientation`` (a mesh's direction under one
    component), else 90 deg (a mesh's x axis)."""
    if prepared.components is not None:
        return prepared.components.orientation
    orientation = prepared.case.block.orientation
    return orientation if orientation is not None else 0.5 * math.pi


def _block_bodies(case, prepared) -> tuple:
    """The planar bodies a run's figure ``NAME.body.png`` draws (`plots.body_figure`): a mesh's
    silhouette along the block's direction and across it, a box's two planes, an asymmetric body's
    outline; none for a plain rectangle (the paper's block)."""
    from .. import mesh

    block, facing = case.block, _facing(prepared)
    if block.mesh is not None:
        return tuple(mesh.body_of_file(block.mesh, units=block.mesh_units, azimuth=az, density=block.density,
                                       mass=None if block.density is not None else block.mass)
                     for az in (facing, facing + 0.5 * math.pi))
    if block.depth is not None:
        return mesh.box_bodies(block.width, block.depth, block.height, block.mass, facing)
    if not block.asymmetric:
        return ()
    (b1, b2), h = block.corners, block.half_height
    k2 = block.radius_of_gyration ** 2 if block.radius_of_gyration is not None else mesh.rectangle_k2(b1, b2, h)
    return (mesh.PlanarBody(azimuth=facing, b1=b1, b2=b2, h=h, k2=k2, mass=block.mass, volume=math.nan,
                            centre_of_mass=(0.0, 0.0, h), support=((-b1, 0.0), (b2, 0.0)),
                            plane="width" if prepared.components is not None else "shaking"),)


def _plane_of(summary) -> dict:
    return {"verdict": summary.verdict, "overturned": bool(summary.overturned),
            "max_rotation_ratio": math.inf if summary.overturned else float(summary.max_rotation_ratio)}


def _run_result(prepared, result, summary, **more) -> RunResult:
    from ..engine import prepare as engine

    case = prepared.case
    floor = None
    if prepared.base is not None:
        floor = {"description": engine.floor_text(case),
                 **engine.floor_peaks(result.ground_time, result.ground_horizontal, prepared.base.horizontal)}
    return RunResult(name=case.name, result=result, ground=engine.applied_ground(prepared),
                     records=engine.record_entries(prepared), case=case, case_text=case.text, ensemble=summary,
                     floor=floor, integration=engine.step_report(prepared, result.step), **more)


def _neighbourhood(eplan, result, *, device="cpu", workers=None, say=None, bars=None):
    """The ensemble of a run just computed: its summary, dimension and member variables; a long one
    says how long it may take (``say``) and shows its progress (``bars``)."""
    from .. import interrupts
    from ..analyses import ensemble as ens
    from .studies import _no_bar

    where = dict(device=device, workers=workers, report=say, what="ensemble", label=eplan.plan.case.name,
                 unit="member")
    if eplan.precision is not None:           # rounds until the interval is narrow enough
        _, summary, members, variables = ens.to_precision(eplan.plan.case, eplan.precision, result.summary.overturned,
                                                          seed=eplan.seed, records=eplan.records,
                                                          progress=lambda cases: interrupts.check(), **where)
        return summary, members, variables
    with (bars or _no_bar)(f"{eplan.plan.case.name}: neighbours", eplan.plan.n_cases,
                           "plane" if eplan.planes else "member") as update:
        def tell(members: int) -> None:
            interrupts.check()
            update(members)

        return ens.compute(eplan, result.summary.overturned, progress=tell, **where)


def _run_into(outputs, prepared, eplan, started, *, say, progress, device, workers, bars, folder) -> RunResult:
    """`run` with its files (``outputs``): the command line's run.

    A history of at most `HELD_HISTORY_ROWS` rows is held in memory and the file written after the
    compute, so that the file's modules (h5py) load while it computes (`importing_meanwhile`); a
    longer one streams into the file as it is computed (bounded memory). With an ensemble, the
    run's history is written and compressed on a thread of its own while the neighbours compute
    (`Meanwhile`, where `output_modules` allows it), the rest of the file after them."""
    from ..engine import prepare as engine
    from ..io import files

    case = prepared.case
    if outputs.check():
        return _finish_run(outputs, prepared, eplan, started)
    outputs.remove_stale_temporaries()
    work = engine.work(prepared)
    if work.seconds > LONG_RUN:
        say(f"rockslide: note: {work.describe()}")
    files.warn_free_space(outputs.folder, work.rows * files.BYTES_PER_ROW)
    _compile_note(say)
    ensemble_png = outputs.folder / f"{case.name}.ensemble.png"
    body_png = outputs.folder / f"{case.name}.body.png"
    bodies = _block_bodies(case, prepared)
    summary = group = None
    streamed = case.solver.method == "kernel" and work.rows > HELD_HISTORY_ROWS
    with outputs.staging() as staging, contextlib.ExitStack() as opened:
        def new_writer():
            from ..io import results

            keep = KEEP_HISTORY_ROWS if outputs.plot else 0
            return results.ResultWriter(outputs.h5, overwrite=outputs.overwrite, staging=staging, keep_rows=keep)

        def writer_with_history(history):
            made = new_writer()
            try:
                made.write_history(history)
            except BaseException:
                made.discard()
                raise
            return made

        if streamed:
            writer = opened.enter_context(new_writer())
        else:                   # the file is written after the compute: its folder is tried before
            files.check_writable(outputs.h5)
            writer = None
        analysis = ANALYSIS_MODULES["ensemble"] if eplan is not None else ()
        meanwhile = output_modules(outputs, device=device, analysis=analysis)
        with importing_meanwhile(meanwhile):
            result = engine.simulate_prepared(prepared, on_chunk=writer.append_history if streamed else None,
                                              progress=progress)
            if eplan is not None:
                # the run's history is written (and compressed) while its neighbours compute
                early = Meanwhile(lambda: writer_with_history(result.history)) if writer is None and meanwhile else None
                try:
                    summary, dimension, group = _neighbourhood(eplan, result, device=device, workers=workers, say=say,
                                                               bars=bars)
                except BaseException:
                    _discard_meanwhile(early)
                    raise
                if early is not None:
                    writer = opened.enter_context(early.result())
        if writer is None:
            writer = opened.enter_context(new_writer())
        planes = _planes(prepared, result, folder)
        stored = _stored_run(case, prepared, summary, None if group is None else (dimension, group))
        if planes is not None:
            stored["extra_attrs"] = {**stored["extra_attrs"], "planes": json.dumps(planes, allow_nan=True)}
        writer.finish(result, **stored)
        if outputs.plot:
            from ..io import results
            from ..plots import response_figure
            kept = writer.written_result()
            drawn = kept if kept is not None else results.read_result(writer.tmp).result
            outputs.save_figure(response_figure(drawn, title=case.name, size=outputs.size, **_run_about(prepared,
                                                                                                       result.step)),
                                staging)
            if summary is not None:
                outputs.save_figure(_ensemble_figure(summary, group, result.summary, case.name, prepared, result.step,
                                                     size=outputs.size), staging, ensemble_png)
            if bodies:
                from ..plots import body_figure
                outputs.save_figure(body_figure(bodies, title=f"{case.name}: the body's planes", size=outputs.size),
                                    staging, body_png)
        stale = [] if outputs.plot else [outputs.png]
        if outputs.overwrite and (not outputs.plot or summary is None):
            stale.append(ensemble_png)          # it showed the neighbourhood of the result replaced
        if outputs.overwrite and (not outputs.plot or not bodies):
            stale.append(body_png)
        staging.publish(remove=stale)
    written = outputs.written() + (f" and {ensemble_png}" if summary is not None and outputs.plot else "") \
        + (f" and {body_png}" if bodies and outputs.plot else "")
    return _run_result(prepared, result, summary, files=outputs, written=written, planes=planes)


def _discard_meanwhile(early) -> None:
    """After the compute failed or was interrupted: wait for the writer that `_run_into` made
    meanwhile (if any) and discard it; its own failure, if any, is not the one to report."""
    if early is None:
        return
    try:
        early.result().discard()
    except BaseException:  # noqa: BLE001, S110 - the compute's exception is the one raised
        pass


def _stored_run(case, prepared, summary, group) -> dict:
    """What `results.ResultWriter.finish` stores beside the histories (``group``: the ensemble's
    dimension and member variables)."""
    from ..case import case_to_dict
    from ..engine import prepare as engine
    from ..engine.step import choice_attributes

    attrs = dict(choice_attributes(prepared.step_choice))
    if summary is not None:
        from ..analyses import ensemble as ens
        attrs = {**ens.attributes(summary), **attrs}
    return dict(name=case.name, case_text=case.text, case=case_to_dict(case, case_file=False),
                records=engine.record_entries(prepared), ground=engine.applied_ground(prepared), extra_attrs=attrs,
                extra_groups={**(engine.base_motion(prepared) or {}),
                              **({} if group is None else {"ensemble": group})} or None)


def _finish_run(outputs, prepared, eplan, started) -> RunResult:
    """The complete result of this case exists without its figure: draw it (else refuse)."""
    from ..engine import prepare as engine
    from ..io import results
    from ..plots import response_figure

    try:
        stored = results.read_result(outputs.h5)
    except OutputError:
        stored = None
    case = prepared.case
    same = (stored is not None and stored.case_text == case.text
            and [r.get("sha256") for r in stored.records]
            == [r.get("sha256") for r in engine.record_entries(prepared)]
            and (eplan is None or _same_ensemble(stored.attrs.get("ensemble"), eplan)))
    if not same:
        outputs.refuse()
    with outputs.staging() as staging:
        outputs.save_figure(response_figure(stored, title=stored.name, size=outputs.size), staging)
        staging.publish()
    summary = None if eplan is None else json.loads(stored.attrs["ensemble"])
    return _run_result(prepared, stored.result, summary, files=outputs,
                       written=f"{outputs.png} (the missing figure of the complete {outputs.h5})")


def _same_ensemble(text, eplan) -> bool:
    """Whether a result file's ``ensemble`` attribute is the ensemble ``eplan`` would compute."""
    try:
        stored = json.loads(text)
    except (TypeError, ValueError):
        return False
    quantities = {name: d.spec() for name, d in eplan.distributions.items()}
    precision = eplan.precision
    same_n = stored.get("precision") == precision if precision is not None else stored.get("n") == eplan.n
    return same_n and stored.get("seed") == eplan.seed and stored.get("quantities") == quantities


def _compile_note(say) -> None:
    """Say that the kernel compiles first, when the build left no machine code for a run."""
    from ..core import native

    if native.ahead_of_time() is None:      # no machine code from the build: numba's JIT
        from ..core import kernel
        from ..engine.execute import first_compile_note
        note = first_compile_note(kernel.run)
        if note:
            say(note)


def _run_about(prepared, step: float) -> dict:
    """`plots.response_figure`'s caption, unit, direction and ground under the building of a run."""
    from .._version import __version__
    from ..engine import prepare as engine
    from ..plots import along_the_block, case_caption, pga_unit

    text = prepared.case.text
    components = prepared.components
    azimuths = None if components is None else (components.azimuth_1, components.azimuth_2)
    base = engine.base_motion(prepared)
    if base is not None:
        (_, times, _), variables = base["base"]
        base = {"time": times, **{role: values for role, (_, values, _) in variables.items()}}
    return {"caption": case_caption(text, records=engine.record_entries(prepared), step=step, version=__version__,
                                    azimuths=azimuths),
            "unit": pga_unit(text), "horizontal": along_the_block(text), "base": base}


def _ensemble_figure(summary: dict, variables: dict, nominal, name: str, prepared, step: float, *, size=None):
    """The neighbourhood's figure (`plots.ensemble_figure`): its members' largest rotations."""
    from ..analyses import ensemble as ens
    from ..plots import ensemble_figure

    ok = variables["status"][1] == 0
    ratio = variables["max_rotation_ratio"][1][ok]
    over = variables["overturned"][1][ok].astype(bool)
    headline = ens.describe(summary, nominal.verdict)[0]
    return ensemble_figure(ratio, over, math.inf if nominal.overturned else nominal.max_rotation_ratio,
                           summary_text=headline.split("; ", 1)[-1],
                           title=f"{name}: {summary['n']} neighbours (seed {summary['seed']})"
                                 + (", each the worse of its two planes" if summary.get("planes") else ""), size=size,
                           caption=_run_about(prepared, step)["caption"])


def ensemble(case: Case | Mapping | str | Path, n: int | str = 200, *, seed: int = 1,
             records_dir: str | Path | None = None, device: str = "cpu", workers: int | None = None,
             scheduler=None, wait_workers: float | None = None, store=None,
             progress: Callable[[int], None] | None = None, precision: float | None = None):
    """A verdict's neighbourhood: ``n`` cases drawn around ``case`` over what is uncertain, as
    ``rockslide run --ensemble n`` computes them (`analyses.ensemble`).

    Parameters
    ----------
    case : Case, mapping or path
        Its ``uncertain`` section says what varies (intensity, restitution, friction, size,
        slenderness); without one, the stated defaults (`analyses.ensemble.DEFAULTS`).
    n : int or str
        Members; or ``"auto"`` / ``"precision:W"`` as ``precision`` (0.1 / W).
    seed : int
        Seed of the Latin hypercube (the same seed gives the same members).
    precision : float, optional
        Add members until the 95 % interval of the probability of overturning is at most this wide
        (`analyses.ensemble.to_precision`); the summary's ``n`` says how many it took and ``rounds``
        the members of each round.
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
    from ..analyses import ensemble as ens
    from ..engine import prepare as engine
    from ..io import datasets, records

    case = as_case(case)
    whole(seed, "seed", 0)
    callable_arg(progress, "progress")
    scheduler = check_where(workers=workers, scheduler=scheduler, device=device, wait_workers=wait_workers)
    folder = records.records_dir(path_arg(records_dir, "records_dir"))
    if isinstance(n, str):
        n, precision = ens.parse_members(n) if precision is None else (None, precision)
    prepared = engine.prepare(case, folder, history=False)
    nominal = engine.simulate_prepared(prepared)
    where = {"store": store, "workers": workers, "scheduler": scheduler, "device": device, "progress": progress,
             "wait_workers": wait_workers}
    if precision is not None:
        if isinstance(precision, bool) or not isinstance(precision, (int, float)) or not 0.0 < precision < 1.0:
            raise CaseError(f"expected a width within 0 and 1, got {precision!r}", source="precision")
        _, summary, members, variables = ens.to_precision(case, float(precision), nominal.summary.overturned,
                                                          seed=seed, records_dir=folder, records=prepared.records,
                                                          **where)
    else:
        eplan = ens.plan_ensemble(case, n, seed=seed, records_dir=folder, records=prepared.records)
        summary, members, variables = ens.compute(eplan, nominal.summary.overturned, **where)
    attrs = {"name": case.name, "nominal_verdict": nominal.summary.verdict, "p_overturn": summary["p_overturn"],
             "interval_low": summary["interval"][0], "interval_high": summary["interval"][1],
             "flips": summary["flips"], "robust": int(summary["robust"]), "seed": seed,
             "ensemble": json.dumps(summary)}
    return datasets.study_dataset([members], variables, attrs)
