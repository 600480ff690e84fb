"""Record suites, intensity measures and fragility curves (``rockslide fragility``).

A fragility analysis runs one block (a case file) under every record of a suite, each scaled so
that its intensity measure (IM) equals each of a list of levels (multiple stripe analysis), and
fits lognormal fragility curves ``P(damage | IM = x) = Phi(ln(x / median) / beta)`` to the
fraction of runs that reach each damage state.

- **A sweep with a record axis.** The runs form a grid ``record x level`` computed exactly as
  ``rockslide sweep`` computes its grids (`sweep.Plan`: one batch of the compiled kernel, chunks
  kept for resuming, local threads or a dask cluster). Each run is the case file with its records
  replaced by the suite's and scaled by one factor ``k = level / IM(record)`` for horizontal and
  vertical alike (the paper's Table 1 convention; the case's ``ground.scale.vertical_factor``
  still multiplies the vertical), validated like a case file; `point_case` gives it, and
  ``rockslide run`` of that case gives identical numbers.
- **Intensity measures** (:data:`INTENSITY_MEASURES`, `core.intensity`): ``pga``, ``pgv``
  (baseline-corrected, see `core.intensity`), ``pga_rocking`` = PGA / (g tan alpha) with the
  case's block and gravity (an asymmetric body: the weaker corner's ``min(b1, b2) / h``, the
  smaller static tipping acceleration), and ``sa(T)``, the 5 %-damped pseudo-spectral acceleration at period
  ``T``, all of the horizontal record as read; ``pfa`` and ``pfv``, the same peaks of the motion the
  block stands on: the floor's when the case gives ``ground.floor`` (each record is the ground under
  the building, filtered by its modes, `engine.prepare.floor_ground`), else the record's (a floor
  record, such as a COSMOS file of a building's floor). PGV/PGA is reported for each record but cannot be a
  stripe IM: scaling a record does not change it.
- **Damage states** (`parse_damage`): overturning always, and ``rotation>0.5alpha`` (max |rotation|
  over alpha; or ``rotation>10deg``), ``slip>50mm`` (max |slip|), ``residual>10mm`` (|residual
  slip|). An overturned block exceeds every state. A run that leaves the model (status flight or
  painleve) is counted, reported, and left out of every fit: never a survival.
- **Fits** (`fit_state`). The maximum-likelihood lognormal fit over the stripes (Baker 2015,
  Earthquake Spectra 31(1): the binomial likelihood of multiple stripes), solved as a probit
  regression on ln(x) by Newton's method with step halving (the log-likelihood is concave); 95 %
  confidence intervals by the percentile bootstrap over records (`BOOTSTRAP_RESAMPLES` resamples
  of the suite's records with replacement, seed `BOOTSTRAP_SEED`; none for a single record); and
  the method of moments (Baker 2015, as for incremental dynamic analysis: the mean and the standard
  deviation (n - 1) of the logarithms of the records' capacities) as a second estimate, each
  capacity taken at the geometric midpoint of the two levels that bracket the record's first
  exceedance, with the same resamples for its intervals. A fit is refused, with the reason, where
  the data cannot support one: no run or every run exceeds, or the runs separate (every run at or
  below some level stays below the state and every run above it exceeds: the likelihood grows
  without bound as beta goes to 0), or the fitted probability falls as the IM rises (every run up
  to some level exceeds and none above it). Bootstrap resamples that cannot support a fit are left
  out of the intervals; how many were used is reported. The moments need every record's
  capacity bracketed: a record that never exceeds up to the highest level, or exceeds already at
  the lowest, leaves them undefined (censored).
"""

from __future__ import annotations

import glob
import json
import math
import os
import re
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..case import Case, RecordSpec, Suite, SuiteEntry, case_with, load_suite, with_orientations
from ..core import layout as L
from ..core.normal import log_normal_cdf_pair, normal_cdf, normal_quantile
from ..core.simulate import ground_array
from ..engine.plan import MAX_POINTS, Plan, assemble, case_inputs, default_chunk_size
from ..engine.prepare import (
    ABSURD_ACCELERATION_IN_G,
    MAX_GROUND_SAMPLES,
    RunWarning,
    absurd_acceleration,
    check_against_ground,
    check_parameters,
    check_size,
    check_step,
    coarse_step_warning,
    flight_warning,
    floor_ground,
    ground_along,
    settings_for,
    still_step,
    study_step,
)
from ..engine.step import keep_resolved
from ..errors import CaseError, RecordError
from ..io import records as rec
from ..units import STANDARD_GRAVITY, parse_quantity, unit_factor
from . import goodness as gf
from . import sweep as sw
from .measures import INTENSITY_MEASURES, SA_PERIODS, IntensityMeasure, parse_im  # noqa: F401 (re-exported)

__all__ = ["IntensityMeasure", "INTENSITY_MEASURES", "parse_im", "parse_levels", "DamageState",
           "parse_damage", "damage_states", "suite_from", "suite_at_azimuths", "FragilityPlan", "plan_fragility",
           "point_case", "StateFit", "fit_state", "probit_mle", "stripe_counts", "exceedances",
           "analyse", "Analysis", "dataset", "json_summary", "caveats", "figure", "stored_figure",
           "BOOTSTRAP_RESAMPLES", "BOOTSTRAP_SEED", "CONFIDENCE"]

#: Bootstrap resamples of the records for the confidence intervals (the default of ``--bootstrap``).
BOOTSTRAP_RESAMPLES = 1000
#: Seed of the resampling (numpy's default generator): the same data give the same intervals.
BOOTSTRAP_SEED = 2015
#: Confidence level of the intervals (percentiles 2.5 and 97.5 of the resamples).
CONFIDENCE = 0.95
#: Fewer records than this make the percentile bootstrap's intervals untrustworthy, and the printout
#: says so: R records give at most C(2R-1, R) distinct resamples (35 for 4 records, 10 for 3), so
#: the 2.5 and 97.5 percentiles are a handful of values and the intervals cover far less than 95 %.
MIN_BOOTSTRAP_RECORDS = 5
#: A median or bound further than this (relative) beyond the levels run is flagged as extrapolated:
#: within it, it rests on the runs of the nearest level (and prints as that level).
EXTRAPOLATION_MARGIN = 0.01
#: Newton iterations of the maximum-likelihood fit at most; it stops when a step moves the
#: parameters by less than `FIT_TOLERANCE` (relative).
FIT_ITERATIONS = 100
FIT_TOLERANCE = 1e-12
#: Files of a folder suite that are not records: hidden files and these endings.
NOT_RECORDS = (".md", ".rst", ".pdf", ".html", ".yaml", ".yml", ".json", ".py", ".zip", ".gz")



#: Points of the oscillator's response on one record, at most (16 bytes each: 0.8 GB).
MAX_OSCILLATOR_POINTS = 5 * 10**7
#: Most ground samples (records and tails) of a suite together, as of one run's ground
#: (`MAX_GROUND_SAMPLES`): every record's samples are held at once (1.6 GB at the bound). Checked
#: as the records are read, before any run; a record listed twice is read once.
MAX_SUITE_SAMPLES = MAX_GROUND_SAMPLES


def parse_levels(text: str, im: IntensityMeasure) -> sw.Axis:
    """Read ``--levels`` like a sweep axis (``0.1g:1.5g:0.1g`` or a comma list, units as in case
    files, decimal ranges), in the unit kind of ``im``; positive and increasing.

    Raises
    ------
    CaseError
        Naming ``--levels``.
    """
    kind = sw.AxisKind("level", "level", im.kind, "", f"intensity level: {im.long_name}", im.units,
                       im.axis_label(), im.display_scale)
    axis = sw.parse_axis("level", text, kind=kind)
    values = np.asarray(axis.values)
    if not (values > 0).all():
        raise CaseError(f"the levels must be positive, got {text!r}", source="levels")
    if not (np.diff(values) > 0).all():
        raise CaseError(f"give the levels in increasing order, got {text!r}", source="levels")
    return axis


# --------------------------------------------------------------------------------------------------
# Damage states
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DamageState:
    """A damage state: a response quantity above a threshold (or overturning).

    Attributes
    ----------
    name : str
        As given, without spaces (``overturn``, ``rotation>0.5alpha``, ``slip>50mm``).
    quantity : str
        The result variable compared: ``overturned``, ``max_rotation_ratio`` (max |rotation| /
        alpha), ``max_rotation``, ``max_slip`` or ``residual_slip`` (its absolute value).
    threshold : float
        [SI, or a fraction of alpha] exceeded when the quantity is above it.
    long_name : str
        In words.
    """

    name: str
    quantity: str
    threshold: float
    long_name: str


OVERTURN = DamageState("overturn", "overturned", 0.5, "overturning")
_DAMAGE = re.compile(r"^(?P<what>rotation|slip|residual)>(?P<value>.+)$")
_DAMAGE_EXAMPLES = "'rotation>0.5alpha', 'rotation>10deg', 'slip>50mm' or 'residual>10mm'"


def parse_damage(text: str) -> DamageState:
    """Read a ``--damage`` state: ``overturn``, ``rotation>0.5alpha``, ``rotation>10deg``,
    ``slip>50mm`` or ``residual>10mm`` (a length or an angle needs its unit).

    Raises
    ------
    CaseError
        Naming ``--damage`` and the text.
    """
    compact = "".join(str(text).split())
    if compact.lower() in ("overturn", "overturning", "overturned"):
        return OVERTURN
    match = _DAMAGE.match(compact.lower())
    if match is None:
        raise CaseError(f"cannot read {text!r} as a damage state; expected 'overturn', {_DAMAGE_EXAMPLES}",
                        source="damage")
    what, value = match.group("what"), compact[len(match.group("what")) + 1:]
    if what == "rotation" and value.lower().endswith("alpha"):
        number = value[:-len("alpha")].rstrip("*") or "1"
        ratio = parse_quantity(number, "dimensionless", source="damage")
        _positive(ratio, text)
        return DamageState(compact, "max_rotation_ratio", ratio, f"max |rotation| > {ratio:g} alpha")
    kind = "angle" if what == "rotation" else "length"
    if re.fullmatch(r"[-+]?[\d.]+(?:[eE][-+]?\d+)?", value):
        unit = "10deg" if kind == "angle" else "50mm"
        raise CaseError(f"{text!r}: give the threshold's unit (e.g. {what}>{unit})", source="damage")
    threshold = parse_quantity(value, kind, source="damage")
    _positive(threshold, text)
    if what == "rotation":
        return DamageState(compact, "max_rotation", threshold,
                           f"max |rotation| > {threshold:g} rad ({math.degrees(threshold):g} deg)")
    if what == "slip":
        return DamageState(compact, "max_slip", threshold, f"max |slip| > {threshold * 1000:g} mm")
    return DamageState(compact, "residual_slip", threshold, f"|residual slip| > {threshold * 1000:g} mm")


def _positive(value: float, text: str) -> None:
    if not value > 0:
        raise CaseError(f"{text!r}: the threshold must be positive", source="damage")


def damage_states(texts=()) -> list[DamageState]:
    """Overturning, then the states of ``texts`` (`parse_damage`), each once."""
    states = [OVERTURN]
    for text in texts:
        state = parse_damage(text)
        if state.name in [s.name for s in states]:
            raise CaseError(f"{text!r} is given twice (overturning is always included)", source="damage")
        states.append(state)
    return states


def exceedances(variables: dict, alpha: np.ndarray, states) -> np.ndarray:
    """``int8[records, levels, states]``: 1 the run exceeds the state, 0 it does not, -1 it left the
    model (status flight or painleve; not used in the fits). ``variables`` are the per-run results
    (`sweep.sweep_variables`), ``alpha`` [rad] each run's block angle."""
    overturned = variables["overturned"][0].astype(bool)
    values = {"max_rotation": variables["max_rotation"][0], "max_slip": variables["max_slip"][0],
              "residual_slip": np.abs(variables["residual_slip"][0]),
              "max_rotation_ratio": variables["max_rotation"][0] / alpha}
    out = np.empty(overturned.shape + (len(states),), dtype=np.int8)
    for i, state in enumerate(states):
        exceeded = overturned if state.quantity == "overturned" else overturned | (values[state.quantity]
                                                                                  > state.threshold)
        out[..., i] = exceeded
    out[variables["status"][0] != L.STATUS_OK] = -1
    return out


# --------------------------------------------------------------------------------------------------
# Suites
# --------------------------------------------------------------------------------------------------


def suite_from(spec, *, units: str | None = None) -> Suite:
    """The suite of ``--suite``: a suite file (YAML, `case.load_suite`), a folder of horizontal
    records (every file but hidden ones and documentation, :data:`NOT_RECORDS`), or a glob pattern
    of them (quoted on the command line). Records are named by their file name without extension.

    Parameters
    ----------
    spec : str or Path
    units : str, optional
        The acceleration unit of a folder's or a glob's files that do not state theirs (``--units``).

    Raises
    ------
    CaseError
        Naming ``--suite`` (or the suite file): nothing found, no record in a folder, two files of
        one name, ``--units`` with a suite file.
    """
    text = str(spec)
    path = Path(text).expanduser()
    if units is not None:
        unit_factor(units, "acceleration", source="units")
    if path.is_file() and path.suffix.lower() in (".yaml", ".yml"):
        if units is not None:
            raise CaseError("applies to a folder or a glob of records; a suite file gives each "
                            "record's units: in its entries", source="units")
        return load_suite(path)
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.is_file() and not p.name.startswith(".")
                       and not p.name.lower().endswith(NOT_RECORDS))
        if not files:
            raise CaseError("the folder holds no record file", source=text)
    elif any(c in text for c in "*?[") and not path.exists():
        files = sorted(Path(p) for p in glob.glob(os.path.expanduser(text)) if Path(p).is_file())
        if not files:
            raise CaseError(f"no file matches {text!r}", source="suite")
    elif path.is_file():
        raise CaseError("expected a suite file (.yaml), a folder of records or a quoted glob of them "
                        "(like 'records/*.csv')", source=text)
    else:
        raise CaseError("not found: expected a suite file (.yaml), a folder of records or a quoted "
                        "glob of them (like 'records/*.csv')", source=text)
    entries, seen = [], {}
    for p in files:
        name = p.stem
        if name in seen:
            raise CaseError(f"{seen[name].name} and {p.name} would both be named {name!r}; list them in "
                            "a suite file with a name each", source=text)
        seen[name] = p
        entries.append(SuiteEntry(name=name, horizontal=RecordSpec(file=str(p.absolute()), units=units)))
    return Suite(entries=tuple(entries), source=text, base_dir=None,
                 text="\n".join(str(p) for p in files))


def suite_at_azimuths(suite: Suite, azimuth: str | None) -> Suite:
    """The suite of ``--azimuth`` (the block's orientations, a sweep axis: ``0:180:5``, degrees by
    default): each entry of two horizontal components run at each orientation, named
    ``NAME@30deg`` (`case.with_orientations`). The fits then pool the orientations, each as likely
    (the orientation unknown, uniform over the values); one value is a stated orientation. None:
    the suite as it is (the case's ``block.orientation``)."""
    if azimuth is None:
        return suite
    return with_orientations(suite, sw.parse_axis("azimuth", azimuth).values)


# --------------------------------------------------------------------------------------------------
# The plan: a sweep over records and levels
# --------------------------------------------------------------------------------------------------


@dataclass
class FragilityPlan:
    """Every run of a fragility analysis, not computed yet.

    Attributes
    ----------
    plan : sweep.Plan
        The runs as a sweep over the axes ``record`` and ``level`` (flat index
        ``record * n_levels + level``), its records concatenated in ``base``.
    suite : Suite
    im : IntensityMeasure
    levels : sweep.Axis
        The levels [SI of the IM], increasing.
    record_cases : list of Case
        Each record's case: the case file with the record in ``ground`` (files as resolved paths)
        and no scale; `point_case` adds the factor.
    measures : dict
        Per record (float64[records]): ``pga`` [m/s^2], ``pgv`` [m/s], ``pgv_pga`` [s], ``im``
        (the chosen measure) [SI], ``dt`` [s], ``duration`` [s] (samples x dt).
    files : list of dict
        Per record: ``horizontal`` and ``vertical`` file names and ``*_sha256`` ("" when absent).
    vertical_factor : float
        The case's ``ground.scale.vertical_factor``.
    vertical : str
        Where the vertical motion comes from: ``suite`` (the suite's records, where they have one),
        ``case`` (the case's vertical record under every horizontal one, ``case_vertical``) or
        ``none``.
    vertical_note : str
        What the user must know about it ("" when nothing): the case's vertical record left out.
    samples : int
        Parameter samples per record and level (0: the case's values only). With samples the plan
        has a third axis ``sample``: 0 is the case's own values, 1 ... samples the draws.
    parameter_values : dict
        Per quantity of the case's ``uncertain`` section: float64[records, samples + 1], each
        sample's value (factors; the restitution itself), column 0 the case's own.
    distributions : dict
        The distributions sampled (`case.Distribution`), by quantity.
    seed : int
        Seed of the Latin hypercube (record ``r``'s design uses ``seed + r``).
    """

    plan: Plan
    suite: Suite
    im: IntensityMeasure
    levels: sw.Axis
    record_cases: list
    measures: dict
    files: list
    vertical_factor: float
    vertical: str = "suite"
    vertical_note: str = ""
    samples: int = 0
    parameter_values: dict = field(default_factory=dict)
    distributions: dict = field(default_factory=dict)
    seed: int = 0

    @property
    def names(self) -> list[str]:
        return [e.name for e in self.suite.entries]

    @property
    def shape(self) -> tuple[int, int]:
        """``(records, levels)``."""
        return self.plan.shape[:2]

    def describe(self) -> str:
        """``18 records x 15 levels of PGA = 270 runs`` (and ``x 21 parameter sets`` with samples)."""
        text = _describe(*self.shape, self.im.label)
        if self.samples:
            text = (f"{text.rsplit(' = ', 1)[0]} x {self.samples + 1} parameter sets (the case's and "
                    f"{self.samples} drawn) = {self.plan.n_cases} runs")
        return text


def _describe(records: int, levels: int, label: str) -> str:
    def plural(k, word):
        return f"{k} {word}{'s' if k != 1 else ''}"

    return f"{plural(records, 'record')} x {plural(levels, 'level')} of {label} = {plural(records * levels, 'run')}"


def plan_fragility(case: Case, suite: Suite, im: IntensityMeasure, levels: sw.Axis, *,
                   records_dir: Path | None = None, chunk_size: int | None = None,
                   case_vertical: bool = False, samples: int = 0, seed: int = 1) -> FragilityPlan:
    """Read the suite's records, measure them, and build every run's kernel inputs.

    Parameters
    ----------
    case : Case
        The block, contact, solver and ``ground.tail`` (its records are replaced by the suite's).
    suite : Suite
    im : IntensityMeasure
    levels : sweep.Axis
        From `parse_levels`.
    records_dir : Path, optional
        Where records are looked for after the suite file's folder (`records.records_dir`).
    chunk_size : int, optional
        Runs per chunk (default `sweep.default_chunk_size`).
    case_vertical : bool
        When no record of the suite has a vertical component and the case has a vertical record:
        run each horizontal record with the case's vertical record, scaled by the same factor
        (times ``ground.scale.vertical_factor``). Without it the runs are horizontal only, and the
        plan's ``vertical_note`` says so.
    samples : int
        Draw this many sets of the block's and contact's parameters per record, from the case's
        ``uncertain`` section (size, slenderness, friction, restitution; Latin hypercube, ``seed``),
        and run each at every level beside the case's own values (`with_parameter_samples`).
    seed : int

    Raises
    ------
    CaseError
        The case does not use the kernel or gives ``ground.scale.pga_vertical``; a record entry is
        invalid for the case (its step finer than ``solver.dt`` allows, too long); a record's
        measure is zero; too many runs.
    RecordError
        A record cannot be found or read (naming the suite file and the entry).
    """
    from ..core import intensity  # numba and scipy: where records are measured (`risk` measures none)

    if case.solver.method != "kernel":
        raise CaseError(f"a fragility analysis runs the compiled kernel; got method {case.solver.method!r}",
                        source=case.source, field="solver.method")
    if case.ground.scale.pga_vertical is not None:
        raise CaseError("a fragility analysis scales each vertical record by its horizontal's factor; "
                        "remove pga_vertical (vertical_factor may stay)", source=case.source,
                        field="ground.scale.pga_vertical")
    _refuse_repeated_records(suite)
    n_records, n_levels = len(suite.entries), len(levels)
    n = n_records * n_levels
    if n > MAX_POINTS:
        raise CaseError(f"{n_records} records x {n_levels} levels = {n} runs; at most {MAX_POINTS}",
                        source="suite/levels")
    if chunk_size is not None and (isinstance(chunk_size, bool) or int(chunk_size) < 1):
        raise CaseError(f"must be a whole number >= 1, got {chunk_size!r}", source="chunk_size")
    chunk_size = default_chunk_size(n) if chunk_size is None else int(chunk_size)
    check_parameters(case)
    folder = records_dir if records_dir is not None else rec.records_dir()
    vertical_factor = float(case.ground.scale.vertical_factor)
    tan_alpha = min(case.block.corners) / case.block.half_height   # a body's weaker corner; a rectangle's b/h
    level_values = np.asarray(levels.values, dtype=np.float64)
    vertical, vertical_note, case_record = _vertical_source(case, suite, folder, case_vertical)

    params = np.empty((n, L.N_PARAMS))
    states = np.empty((n, L.N_STATE))
    factor_h, factor_v = np.empty(n), np.empty(n)
    first, count, record_end = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    bases, record_cases, files, entries = [], [], [], []
    measures = {key: np.empty(n_records) for key in ("pga", "pgv", "pgv_pga", "im", "dt", "duration")}
    offset = 0
    highest = (0.0, "")                   # the largest scaled peak, and which run
    flights = []                          # (warning of the first flying run of a record, its runs that fly)
    already_read: dict = {}               # records already read, by file and options
    rotd: dict = {}                       # RotD of a pair (the same at every orientation of --azimuth)
    records_of = []                       # each record's `records` (for the pilots of the step)
    for r, entry in enumerate(suite.entries):
        records, specs, found = _read_entry(suite, r, entry, folder, already_read)
        records_of.append(records)
        if case_record is not None:
            records["vertical"], specs["vertical"] = case_record
            found["vertical"], found["vertical_sha256"] = Path(case_record[0].path).name, case_record[0].sha256
        where = _entry_source(suite, r)
        pair = entry.horizontal_2 is not None
        if pair and entry is suite.entries[0]:
            sw.warn_one_plane(case, "a fragility analysis")
        if im.rotd is not None and not pair:
            raise CaseError(f"{im.label} needs two horizontal components; the record {where} has one "
                            "(give horizontal_1 and horizontal_2 in the suite file)", source="im")
        first_key = "ground.horizontal_1" if pair else "ground.horizontal"
        changes = {"ground.horizontal": None, "ground.horizontal_1": None,
                   first_key: specs["horizontal"], "ground.horizontal_2": specs["horizontal_2"],
                   "ground.vertical": specs["vertical"],
                   "ground.scale": {"vertical_factor": vertical_factor} if specs["vertical"] else {},
                   "block.orientation": (entry.orientation if entry.orientation is not None
                                         else case.block.orientation) if pair else None}
        try:
            record_case = case_with(case, changes)
            if pair:
                read = ground_along(record_case, records, scaled=False)[0]
            else:
                read = rec.combine(records["horizontal"], records["vertical"], source=where)
            check_step(record_case, read)
            ground = floor_ground(record_case, read)     # what the block stands on: the floor's, if any
            check_size(record_case, ground, history=False)
        except CaseError as exc:
            raise CaseError(f"{exc.message} (with the record {where})", source=exc.source,
                            field=exc.field) from None
        record_cases.append(record_case)
        h, dt = read.horizontal, read.dt
        measures["pga"][r] = intensity.peak_acceleration(h)
        measures["pgv"][r] = intensity.peak_velocity(h, dt)
        measures["pgv_pga"][r] = measures["pgv"][r] / measures["pga"][r] if measures["pga"][r] else math.nan
        if im.period is not None:                      # the oscillator's memory, known before it runs
            points = (h.size - 1) * intensity.substeps_for(dt, im.period) + 1
            if points > MAX_OSCILLATOR_POINTS:
                raise CaseError(f"{im.label} of the record {where} takes {points:.3g} points of the oscillator's "
                                f"response; expected at most {MAX_OSCILLATOR_POINTS:.0e} (a longer period, or a "
                                "shorter record)", source="im")
        if im.rotd is not None:
            key = (id(records["horizontal"]), id(records["horizontal_2"]))   # `already_read` gives the same objects
            if key not in rotd:
                rotd[key] = im.of_pair(records["horizontal"].data, records["horizontal_2"].data, dt)
            value = rotd[key]
        else:
            measured = ground if im.of_support else read
            value = im.of_record(measured.horizontal, measured.dt, case.gravity, tan_alpha)
        measures["im"][r] = value
        measures["dt"][r], measures["duration"][r] = dt, (h.size - 1) * dt
        dt = ground.dt
        if not (math.isfinite(value) and value > 0):
            raise RecordError(f"its {im.label} is {value:g}: a record without motion cannot be scaled "
                              "to a level", source=where, field="horizontal")
        files.append(found)
        entries.extend({**e, "role": f"{entry.name}.{e['role']}"} for e in ground.files)

        base = ground_array(ground.horizontal, ground.vertical, dt,
                            settings_for(record_case, history=False, energy=False).tail)
        start = ground.start + case.ground.time_shift
        rows = slice(r * n_levels, (r + 1) * n_levels)
        params[rows], states[rows] = case_inputs(record_case, dt, start)
        factors = level_values / value
        if not np.isfinite(factors).all():
            raise RecordError(f"its {im.label} ({value:g}) is too small to scale to the levels",
                              source=where, field="horizontal")
        factor_h[rows] = factors
        # records.combine's arithmetic: vertical = (k * vertical_factor) * samples
        factor_v[rows] = factors * vertical_factor if specs["vertical"] else 1.0
        # the checks of `rockslide run` at the highest level (the peaks grow with the level), and
        # flight at the lowest level that flies: those runs end with the status 'flight'
        peak = _check_level(record_case, records, factors[-1], where)
        if peak > highest[0]:
            highest = (peak, f"record {entry.name}, level {levels.texts[-1]}")
        if ground.vertical.size:
            flying = np.flatnonzero(case.gravity + factor_v[rows] * float(np.min(ground.vertical)) <= 0.0)
            if flying.size:
                text = flight_warning(*_at_level(record_case, records, factors[flying[0]]))
                flights.append((f"{text} [at record {entry.name}, level {levels.texts[flying[0]]}]", flying.size))
        if offset + base.shape[1] > MAX_SUITE_SAMPLES:
            raise CaseError(f"the suite's records hold more than {MAX_SUITE_SAMPLES:.0e} ground samples together "
                            f"(records and tails; reached at records[{r}], {entry.name}, of {n_records}); a "
                            "suite of fewer or shorter records, or a shorter ground.tail",
                            source=suite.source)
        first[rows], count[rows] = offset, base.shape[1]
        record_end[rows] = start + base.shape[1] * dt
        bases.append(base)
        offset += base.shape[1]
    pilots = []
    for r, record_case in enumerate(record_cases if case.solver.auto else record_cases[:1]):
        middle = r * n_levels + n_levels // 2
        level_case, level_ground = _at_level(record_case, records_of[r], factor_h[middle])
        pilots.append((slice(r * n_levels, (r + 1) * n_levels), level_case, level_ground))
    middle_level = levels.texts[n_levels // 2]
    sample = (f"each record at the middle level {middle_level}" if case.solver.auto else
              f"the first record ({suite.entries[0].name}) at the middle level {middle_level}")
    step_plan = SimpleNamespace(case=case, params=params, step=0.0, key="", step_study=None)
    study_step(step_plan, pilots, sample)
    warning = coarse_step_warning(case.source, params, lambda i: f"record {suite.entries[i // n_levels].name}")
    if warning:
        warnings.warn(warning, RunWarning, stacklevel=2)
    if flights:
        warnings.warn(f"{flights[0][0]}; {sum(k for _, k in flights)} of {n} runs fly", RunWarning, stacklevel=2)
    if highest[0] > ABSURD_ACCELERATION_IN_G * STANDARD_GRAVITY:
        warnings.warn(f"{absurd_acceleration(case.source, highest[0])} [at {highest[1]}]", RunWarning, stacklevel=2)
    record_kind = sw.AxisKind("record", "record", "dimensionless", "", "record of the suite", "1", "record")
    record_axis = sw.Axis("record", tuple(float(i) for i in range(n_records)),
                          tuple(e.name for e in suite.entries), suite.source, record_kind)
    plan = assemble(case, [record_axis, levels], params=params, states=states, factor_h=factor_h, factor_v=factor_v,
                    base=np.ascontiguousarray(np.concatenate(bases, axis=1)), first=first, count=count,
                    record_end=record_end, records=entries, chunk_size=chunk_size, step_study=step_plan.step_study)
    fplan = FragilityPlan(plan=plan, suite=suite, im=im, levels=levels, record_cases=record_cases,
                          measures=measures, files=files, vertical_factor=vertical_factor, vertical=vertical,
                          vertical_note=vertical_note)
    return with_parameter_samples(fplan, samples, seed, chunk_size) if samples else fplan


def _refuse_repeated_records(suite: Suite) -> None:
    """Refuse a suite that lists one record twice (the same files and orientation): it would weigh
    that record twice in the fits, and hundreds of copies ran for minutes, then out of memory."""
    seen: dict = {}
    for r, entry in enumerate(suite.entries):
        key = (entry.horizontal, entry.vertical, entry.horizontal_2, entry.orientation)
        if key in seen:
            first = suite.entries[seen[key]]
            raise CaseError(f"records[{r}] ({entry.name}) is records[{seen[key]}] ({first.name}) again: the same "
                            "files (and orientation); list each record once", source=suite.source)
        seen[key] = r


def with_parameter_samples(fplan: FragilityPlan, samples: int, seed: int, chunk_size: int | None = None
                           ) -> FragilityPlan:
    """The plan with ``samples`` draws of the case's uncertain parameters at every record and
    level (issue: fragility with uncertain parameters). Record ``r`` gets its own Latin hypercube
    of ``samples`` draws (seed ``seed + r``), the same draws at every level, so that each (record,
    draw) is one realisation whose capacity the method of moments reads, and sample 0 keeps the
    case's own values (the curve without parameter uncertainty, computed beside it).

    Raises
    ------
    CaseError
        ``samples`` out of range, or ``uncertain.intensity`` (the levels set the intensity).

    Without an ``uncertain`` section the draws are from the stated neighbourhood of ``rockslide run
    --ensemble`` (`ensemble.DEFAULTS`: friction +-5 %, size and slenderness +-2 %, restitution the
    case's +-0.05), less the intensity; the file and the JSON list the distributions drawn from.
    """
    from . import ensemble as ens

    case, plan = fplan.plan.case, fplan.plan
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 0:
        raise CaseError(f"expected a whole number >= 0, got {samples!r}", source="samples")
    dists = case.uncertain.given()
    if not dists:
        # the stated neighbourhood of `rockslide run --ensemble` (`ensemble.DEFAULTS`), less the
        # intensity, which the levels set
        dists = {name: d for name, d in ens.distributions(case)[0].items() if name != "intensity"}
    if "intensity" in dists:
        raise CaseError("does not apply to a fragility analysis, whose levels set the intensity (remove it, or "
                        "run the case's neighbourhood with rockslide run --ensemble)", source=case.source,
                        field="uncertain.intensity")
    if "orientation" in dists:
        raise CaseError("is not drawn in a fragility analysis: give the orientations with --azimuth (e.g. "
                        "0:175:5, each as likely)", source=case.source, field="uncertain.orientation")
    n_records, n_levels = plan.shape
    width = samples + 1
    n = plan.n_cases * width
    if n > MAX_POINTS:
        raise CaseError(f"{n_records} records x {n_levels} levels x {width} parameter sets = {n} runs; at most "
                        f"{MAX_POINTS}", source="samples")
    own = {name: (case.contact.restitution if name == "restitution" else 1.0) for name in dists}
    values = {name: np.empty((n_records, width)) for name in dists}
    for r in range(n_records):
        drawn = ens.sample(dists, samples, seed + r)
        for name in dists:
            values[name][r, 0] = own[name]
            values[name][r, 1:] = drawn[name]
    row = np.repeat(np.arange(plan.n_cases), width)                  # (record, level, sample), C order
    record, draw = row // n_levels, np.tile(np.arange(width), plan.n_cases)
    params, restitution = ens.member_parameters(case, plan.case_params(row),
                                                {name: v[record, draw] for name, v in values.items()})
    if case.solver.auto:          # each record's step, each drawn block resolved
        keep_resolved(params)
    if "restitution" in values:
        values["restitution"] = restitution[np.arange(n_records)[:, None] * n_levels * width + np.arange(width)]
    kind = sw.AxisKind("sample", "sample", "dimensionless", "", "parameter sample (0: the case's own values)",
                       "1", "sample")
    axis = sw.Axis("sample", tuple(float(k) for k in range(width)), tuple(str(k) for k in range(width)),
                   str(samples), kind)
    expanded = assemble(case, [*plan.axes, axis], params=params, states=plan.case_states(row),
                        factor_h=plan.factor_h[row], factor_v=plan.factor_v[row], base=plan.base,
                        first=plan.first[row], count=plan.count[row], record_end=plan.record_end[row],
                        records=plan.records, step_study=plan.step_study,
                        chunk_size=default_chunk_size(n) if chunk_size is None else int(chunk_size))
    return replace(fplan, plan=expanded, samples=int(samples), parameter_values=values, distributions=dists,
                   seed=int(seed))


def _at_level(record_case: Case, records: dict, factor: float):
    """A record's run at the scale ``factor``: ``(its case, its ground motion)``, from the records
    already read (`records.combine`, as ``rockslide run`` of that case scales them)."""
    level_case = case_with(record_case, {"ground.scale.factor": float(factor)})
    if level_case.ground.two_components:
        return level_case, floor_ground(level_case, ground_along(level_case, records)[0])
    scale = level_case.ground.scale
    ground = rec.combine(records["horizontal"], records["vertical"], factor=scale.factor,
                         vertical_factor=scale.vertical_factor, source=record_case.source,
                         still_dt=still_step(record_case))
    return level_case, floor_ground(level_case, ground)


def _check_level(record_case: Case, records: dict, factor: float, where: str) -> float:
    """`prepare.check_against_ground` of a record's run scaled by ``factor``, its errors naming the
    record. Returns the peak scaled acceleration [m/s^2]."""
    try:
        return check_against_ground(*_at_level(record_case, records, factor), warn=False)
    except CaseError as exc:
        raise CaseError(f"{exc.message} (with the record {where})", source=exc.source, field=exc.field) from None


def _vertical_source(case: Case, suite: Suite, folder: Path, case_vertical: bool):
    """Where the runs' vertical motion comes from: ``(vertical, note, case_record)``, with
    ``case_record`` the case's vertical record and its spec for `case.case_with` when it stands in for
    the suite's missing verticals (``case_vertical``)."""
    suite_has = any(entry.vertical is not None for entry in suite.entries)
    case_has = isinstance(case.ground.vertical, RecordSpec)
    if suite_has:
        return "suite", "", None
    if not case_has:
        if case_vertical:
            raise CaseError("the case has no vertical record to scale with the suite's horizontal ones",
                            source="case_vertical")
        return "none", "", None
    spec = case.ground.vertical
    if not case_vertical:
        return "none", (f"the suite has no vertical records: the runs are horizontal only, without the case's "
                        f"vertical record {Path(spec.file).name} (--case-vertical scales it with each "
                        "horizontal record)"), None
    path = rec.resolve_record_path(spec.file, case_dir=case.base_dir, records_dir=folder, source=case.source,
                                   field="ground.vertical.file")
    record = rec.load_record(path, format=spec.format, units=spec.units, time_column=spec.time_column,
                             column=spec.column, dt=spec.dt, skip_lines=spec.skip_lines)
    given = {k: v for k, v in vars(spec).items() if v is not None and k != "file"}
    return "case", "", (record, {**given, "file": str(path.absolute())})


def _entry_source(suite: Suite, r: int) -> str:
    """How messages name a suite's record ``r``."""
    entry = suite.entries[r]
    if suite.base_dir is None:                  # a folder or a glob: the file names itself
        return entry.horizontal.file
    return f"{suite.source}: records[{r}] ({entry.name})"


def _read_entry(suite: Suite, r: int, entry: SuiteEntry, folder: Path, read: dict | None = None):
    """A suite entry's records: records by role, their specs for `case.case_with` (files as found)
    and their file names and checksums. ``read`` keeps the records read, by file and options: a
    file listed many times is read once."""
    read = {} if read is None else read
    records, specs, found = {}, {}, {}
    for role in ("horizontal", "vertical", "horizontal_2"):
        spec = getattr(entry, role)
        found[role], found[f"{role}_sha256"] = "", ""
        if spec is None:
            records[role], specs[role] = None, None
            continue
        field = f"records[{r}].{role}" if suite.base_dir is not None else None
        source = suite.source if suite.base_dir is not None else None
        path = rec.resolve_record_path(spec.file, case_dir=suite.base_dir, records_dir=folder,
                                       source=source, field=f"{field}.file" if field else None)
        key = (str(path.absolute()), spec.format, spec.units, spec.time_column, spec.column, spec.dt,
               spec.skip_lines)
        try:
            if key not in read:
                read[key] = rec.load_record(path, format=spec.format, units=spec.units,
                                            time_column=spec.time_column, column=spec.column, dt=spec.dt,
                                            skip_lines=spec.skip_lines, source=source, field=field)
            record = read[key]
        except RecordError as exc:
            if suite.base_dir is None and spec.units is None and "units" in str(exc):
                raise RecordError(f"{exc.message} (for a folder or a glob of records: --units)",
                                  source=exc.source, field=exc.field) from None
            raise
        records[role] = record
        specs[role] = {k: v for k, v in vars(spec).items() if v is not None and k != "file"}
        specs[role]["file"] = str(path.absolute())
        found[role] = path.name
        found[f"{role}_sha256"] = record.sha256
    return records, specs, found


def point_case(fplan: FragilityPlan, record: int, level: int) -> Case:
    """The case file of one run, as a user would give it to ``rockslide run``: the record's case
    (`FragilityPlan.record_cases`) with ``ground.scale.factor`` = the run's factor."""
    width = fplan.samples + 1
    factor = float(fplan.plan.factor_h[(record * len(fplan.levels) + level) * width])
    return case_with(fplan.record_cases[record], {"ground.scale.factor": factor})


# --------------------------------------------------------------------------------------------------
# Fits
# --------------------------------------------------------------------------------------------------


@dataclass
class StateFit:
    """The fits of one damage state (SI units of the IM; None where there is no fit).

    Attributes
    ----------
    median, beta : float or None
        The maximum-likelihood fit.
    median_ci, beta_ci : tuple of float or None
        Their bootstrap confidence intervals (:data:`CONFIDENCE`).
    note : str
        Why there is no fit ("" when there is).
    resamples : int
        Bootstrap resamples drawn (0: no intervals).
    resamples_fitted : int
        Of them, those that supported a maximum-likelihood fit (the intervals are theirs).
    moments_median, moments_beta : float or None
        The method of moments on the capacities the stripes bracket (`_first_exceedance`).
    moments_median_ci, moments_beta_ci : tuple of float or None
    moments_note : str
    n_runs, n_outside_model, n_exceeded : int
    n_censored : int
        Records that never exceed the state up to the highest level.
    n_records : int
        Records the bootstrap resamples.
    tested : tuple of float
        The lowest and the highest intensity level run [SI of the IM] (`caveats`).
    samples : numpy.ndarray
        ``float64[k, 2]``: the (median, beta) of the fitted resamples (for the figure's band).
    goodness : goodness.GoodnessOfFit or None
        The lognormal against the per-level fractions and the fractions' monotonicity
        (`goodness.lognormal_goodness`); None without runs.
    isotonic : numpy.ndarray
        ``float64[L]``: the monotone maximum-likelihood curve at the levels (`goodness.isotonic`;
        NaN where no run is inside the model).
    isotonic_band : numpy.ndarray or None
        ``float64[2, L]``: its percentile band over the bootstrap resamples of the records (None
        without resamples).
    """

    median: float | None = None
    beta: float | None = None
    median_ci: tuple | None = None
    beta_ci: tuple | None = None
    note: str = ""
    resamples: int = 0
    resamples_fitted: int = 0
    moments_median: float | None = None
    moments_beta: float | None = None
    moments_median_ci: tuple | None = None
    moments_beta_ci: tuple | None = None
    moments_note: str = ""
    n_runs: int = 0
    n_outside_model: int = 0
    n_exceeded: int = 0
    n_censored: int = 0
    n_records: int = 0
    tested: tuple = ()
    samples: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    goodness: object = None
    isotonic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    isotonic_band: np.ndarray | None = None


def stripe_counts(exceeded: np.ndarray):
    """``(n, z)``: runs inside the model and runs exceeding, per level (the last axis of
    ``exceeded``), summed over records (the second last axis)."""
    inside = exceeded >= 0
    return inside.sum(axis=-2).astype(np.float64), (exceeded == 1).sum(axis=-2).astype(np.float64)


def _separation(n: np.ndarray, z: np.ndarray):
    """Per row of counts ``(..., levels)``: the index of the lowest level with an exceedance and of
    the highest with a run below the state (-1 when none)."""
    levels = n.shape[-1]
    index = np.arange(levels)
    lowest_exceeding = np.where(z > 0, index, levels).min(axis=-1)
    highest_surviving = np.where(n - z > 0, index, -1).max(axis=-1)
    return np.where(lowest_exceeding == levels, -1, lowest_exceeding), highest_surviving


def _support_note(levels: np.ndarray, n: np.ndarray, z: np.ndarray, show) -> str:
    """Why these stripe counts cannot support a fit, or ""."""
    if n.sum() == 0:
        return "no run inside the model: no fit"
    if z.sum() == 0:
        return "no run exceeds the state: no fit"
    if z.sum() == n.sum():
        return "every run exceeds the state: no fit"
    low, high = _separation(n, z)
    if high == low:
        return (f"the runs separate at {show(levels[low])} (every run below it stays below the state, "
                "every run above it reaches it), so the data cannot fix beta (it tends to 0): no fit")
    if high < low:
        return (f"the runs separate between {show(levels[high])} and {show(levels[low])} (no run up to "
                "the first reaches the state, every run from the second on does), so the data cannot "
                "fix beta (it tends to 0): no fit; add levels between")
    index = np.arange(levels.size)
    highest_exceeding = np.where(z > 0, index, -1).max()
    lowest_surviving = np.where(n - z > 0, index, levels.size).min()
    if highest_exceeding <= lowest_surviving:        # the separation below, the other way round
        return (f"the runs reach the state up to {show(levels[highest_exceeding])} and stay below it "
                f"from {show(levels[lowest_surviving])} on: the probability falls as the intensity rises, "
                "no fit")
    return ""


def _log_likelihood(a, b, s, n, z):
    """The log-likelihood of each data set at ``(a, b)``, and ``ln Phi(eta)``, ``ln Phi(-eta)``
    at its levels (what Newton's next step at ``(a, b)`` takes)."""
    eta = a[:, None] + b[:, None] * s
    log_p, log_q = log_normal_cdf_pair(eta)
    return np.sum(z * log_p + (n - z) * log_q, axis=-1), log_p, log_q


def probit_mle(s: np.ndarray, n: np.ndarray, z: np.ndarray):
    """Maximum-likelihood probit regression ``P = Phi(a + b s)`` of binomial counts, many at once.

    Parameters
    ----------
    s : float64[L]
        The covariate (``ln`` of the levels).
    n, z : float64[B, L]
        Trials and successes of ``B`` data sets. Each must overlap (`_separation`: some success at
        a level below some failure); otherwise the maximum is at infinity.

    Returns
    -------
    a, b : float64[B]
        The estimates; ``median = exp(-a / b)``, ``beta = 1 / b``.
    converged : bool[B]

    Notes
    -----
    Newton's method on the log-likelihood ``sum z ln Phi(eta) + (n - z) ln Phi(-eta)``, which is
    concave in ``(a, b)``, with step halving so that it never decreases; started from the
    weighted least-squares line through the probits of ``(z + 1/2) / (n + 1)``. The derivatives in
    ``eta`` use the ratios ``phi / Phi`` evaluated through `core.normal.log_normal_cdf_pair` (no underflow in the
    tails).
    """
    s = np.asarray(s, dtype=np.float64)
    n = np.atleast_2d(np.asarray(n, dtype=np.float64))
    z = np.atleast_2d(np.asarray(z, dtype=np.float64))
    y = normal_quantile((z + 0.5) / (n + 1.0))
    w0, w1, w2 = n.sum(-1), (n * s).sum(-1), (n * s * s).sum(-1)
    y0, y1 = (n * y).sum(-1), (n * s * y).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        b = (w0 * y1 - w1 * y0) / (w0 * w2 - w1 * w1)
        start_ok = np.isfinite(b) & (b > 0)
        b = np.where(start_ok, b, 2.0)                      # else beta 0.5 about the mean level
        a = np.where(start_ok, (y0 - b * w1) / w0, -b * w1 / w0)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        # resamples far from any fit overflow on their way to failing (left out); nothing to say
        return _newton(a, b, s, n, z)


def _newton(a, b, s, n, z):
    """`probit_mle`'s iterations from the start ``(a, b)``, each on the data sets not yet converged
    (a data set's iterates depend on its own rows only). A step's derivatives take ``ln Phi(+-eta)``
    from the line search's last evaluation, which was at that very point (the same numbers)."""
    ll, log_p, log_q = _log_likelihood(a, b, s, n, z)
    converged = np.zeros(a.shape, dtype=bool)
    active = np.arange(a.size)
    log_phi_const = 0.5 * math.log(2.0 * math.pi)
    for _ in range(FIT_ITERATIONS):
        ai, bi, ni, zi, lli = a[active], b[active], n[active], z[active], ll[active]
        eta = ai[:, None] + bi[:, None] * s
        log_phi = -0.5 * eta * eta - log_phi_const
        up = np.exp(log_phi - log_p)                      # phi / Phi
        down = np.exp(log_phi - log_q)                    # phi / (1 - Phi)
        d1 = zi * up - (ni - zi) * down                   # d ll / d eta
        d2 = zi * up * (eta + up) + (ni - zi) * down * (down - eta)   # -d2 ll / d eta2 >= 0
        g0, g1 = d1.sum(-1), (d1 * s).sum(-1)
        h00, h01, h11 = d2.sum(-1), (d2 * s).sum(-1), (d2 * s * s).sum(-1)
        det = h00 * h11 - h01 * h01
        with np.errstate(divide="ignore", invalid="ignore"):
            da = np.nan_to_num((h11 * g0 - h01 * g1) / det)
            db = np.nan_to_num((h00 * g1 - h01 * g0) / det)
        t = np.ones_like(ai)
        for _ in range(60):
            trial, log_p, log_q = _log_likelihood(ai + t * da, bi + t * db, s, ni, zi)
            worse = ~(trial >= lli - 1e-13 * np.abs(lli))
            if not worse.any():
                break
            t = np.where(worse, 0.5 * t, t)
        else:                       # 60 halvings, none better: the point taken (the last t) is untried
            _, log_p, log_q = _log_likelihood(ai + t * da, bi + t * db, s, ni, zi)
        ai, bi = ai + t * da, bi + t * db
        a[active], b[active], ll[active] = ai, bi, np.where(np.isfinite(trial), trial, lli)
        done = (np.abs(t * da) <= FIT_TOLERANCE * (1.0 + np.abs(ai))) & \
               (np.abs(t * db) <= FIT_TOLERANCE * (1.0 + np.abs(bi)))
        converged[active[done]] = True
        active = active[~done]
        if active.size == 0:
            break
        log_p, log_q = log_p[~done], log_q[~done]
    return a, b, converged


def fit_state(levels, exceeded: np.ndarray, *, resamples: int = BOOTSTRAP_RESAMPLES,
              seed: int = BOOTSTRAP_SEED, show=None, per_record: int = 1) -> StateFit:
    """The fits of one damage state.

    Parameters
    ----------
    levels : array_like
        float64[L], increasing [SI of the IM].
    exceeded : numpy.ndarray
        int8[R, L]: 1 exceeds, 0 does not, -1 outside the model (`exceedances`).
    resamples : int
        Bootstrap resamples of the records (0: no intervals).
    seed : int
        Seed of the resampling.
    show : callable, optional
        Formats a level for the notes (default ``{:g}``).
    per_record : int
        Rows of ``exceeded`` per record, consecutive (its parameter samples, its block orientations
        or both: R is then records x per_record): the bootstrap resamples records, each with all
        its rows, and ``n_records`` counts records.

    Returns
    -------
    StateFit
    """
    levels = np.asarray(levels, dtype=np.float64)
    exceeded = np.asarray(exceeded)
    show = show or (lambda x: f"{x:g}")
    if exceeded.shape[0] // per_record < 2:
        resamples = 0                   # one record: every resample is that record, no interval
    s = np.log(levels)
    n, z = stripe_counts(exceeded)
    out = StateFit(n_runs=int(exceeded.size), n_outside_model=int((exceeded < 0).sum()),
                   n_exceeded=int((exceeded == 1).sum()), resamples=int(resamples),
                   n_records=int(exceeded.shape[0] // per_record), tested=(float(levels[0]), float(levels[-1])))
    out.note = _support_note(levels, n, z, show)
    if not out.note:
        a, b, converged = probit_mle(s, n[None, :], z[None, :])
        if not converged[0] and not b[0] < 0:                # pragma: no cover - concave, overlapping data
            out.note = "the maximum-likelihood fit did not converge: no fit"
        elif not b[0] > 0:
            out.note = "the fitted probability falls as the intensity rises: no fit"
        else:
            out.median, out.beta = float(math.exp(-a[0] / b[0])), float(1.0 / b[0])
    out.isotonic = gf.isotonic(n, z)
    if n.sum() > 0:
        out.goodness = gf.lognormal_goodness(levels, n, z, out.median, out.beta)
    if resamples > 0 and n.sum() > 0:
        out.isotonic_band = _isotonic_band(exceeded, resamples, seed, per_record)
    capacity, out.n_censored, out.moments_note = _first_exceedance(levels, exceeded, show)
    if capacity is not None:
        logs = np.log(capacity)
        out.moments_median, out.moments_beta = float(np.exp(logs.mean())), float(logs.std(ddof=1))
    if resamples > 0 and (out.median is not None or out.moments_median is not None):
        _bootstrap(out, s, exceeded, capacity, resamples, seed, per_record)
    return out


def _resample_weights(records: int, resamples: int, seed: int, per_record: int):
    """The bootstrap's draws of the records with replacement, each record with its ``per_record``
    rows: ``float64[resamples, records * per_record]``, how often each row is drawn, and
    ``int[resamples, records * per_record]``, the rows drawn."""
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, records, size=(resamples, records))
    weights = np.zeros((resamples, records))
    np.add.at(weights, (np.repeat(np.arange(resamples), records), picks.ravel()), 1.0)
    if per_record > 1:
        weights = np.repeat(weights, per_record, axis=1)
        picks = (picks[:, :, None] * per_record + np.arange(per_record)).reshape(resamples, -1)
    return weights, picks


def _distinct_rows(n: np.ndarray, z: np.ndarray):
    """The distinct rows of the counts ``(n, z)`` (float64[B, L] each) and, for each row, the index
    of its distinct row. A resample's fits depend on its counts only, and few records give few
    distinct resamples (at most C(2R-1, R): 462 for 6 records), so each is fitted once. What
    ``np.unique(rows, axis=0, return_inverse=True)`` gives, in the same order, by a lexicographic
    sort of the columns: numpy sorts the rows as one structured type, 11.5 ms against 0.5 ms for
    1000 rows of 30 counts."""
    rows = np.concatenate([n, z], axis=1)
    order = np.lexsort(rows.T[::-1])
    rows = rows[order]
    first = np.ones(len(rows), dtype=bool)            # the first of its kind in sorted order
    first[1:] = (rows[1:] != rows[:-1]).any(axis=1)
    which = np.empty(len(rows), dtype=np.intp)
    which[order] = np.cumsum(first) - 1
    distinct = rows[first]
    return distinct[:, :n.shape[1]], distinct[:, n.shape[1]:], which


def _isotonic_band(exceeded, resamples: int, seed: int, per_record: int) -> np.ndarray:
    """The percentile band (:data:`CONFIDENCE`) of the isotonic curve over resamples of the records."""
    weights, _ = _resample_weights(exceeded.shape[0] // per_record, resamples, seed, per_record)
    n = weights @ (exceeded >= 0).astype(np.float64)
    z = weights @ (exceeded == 1).astype(np.float64)
    n_distinct, z_distinct, which = _distinct_rows(n, z)
    curves = gf.isotonic(n_distinct, z_distinct)[which]
    tails = (50.0 * (1.0 - CONFIDENCE), 100.0 - 50.0 * (1.0 - CONFIDENCE))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)          # a level without runs in every resample
        return np.nanpercentile(curves, tails, axis=0)


def _first_exceedance(levels, exceeded, show):
    """Each record's capacity as the stripes bracket it (None where the moments are undefined), the
    number of records that never exceed, and why there are no moments ("" when there are).

    A record that first exceeds the state at level ``k`` has its capacity (the level at which it
    would first reach the state, as incremental dynamic analysis finds it) in ``(L[k-1], L[k]]``;
    it is taken at the bracket's geometric midpoint ``sqrt(L[k-1] L[k])``. The first exceeding
    level itself is an upper bound: a review found it biased the median high by about half the
    level spacing (+12 % for lognormal capacities of median 1 g, beta 0.3, levels 0.25 g apart;
    the midpoint: +0.3 %). A record that never exceeds (right-censored) or exceeds already at the
    lowest level (left-censored) leaves the moments undefined, as does a suite whose records all
    first exceed at one level (beta 0)."""
    hits = exceeded == 1
    censored = int((~hits.any(axis=1)).sum())
    if censored:
        return None, censored, (f"{censored} of {hits.shape[0]} records never exceed the state up to "
                                f"{show(levels[-1])}: no moments (they need every record's first "
                                "exceedance)")
    first = hits.argmax(axis=1)
    if first.size < 2:
        return None, 0, "one record: no moments"
    at_lowest = int((first == 0).sum())
    if at_lowest:
        return None, 0, (f"{at_lowest} of {first.size} records exceed the state already at the lowest "
                         f"level, {show(levels[0])}: no moments (their capacities are only known to be "
                         "below it; add lower levels)")
    if (first == first[0]).all():
        return None, 0, (f"every record first exceeds the state at {show(levels[first[0]])}: no moments "
                         "(beta would be 0)")
    return np.sqrt(levels[first - 1] * levels[first]), 0, ""


def _bootstrap(out: StateFit, s, exceeded, capacity, resamples, seed, per_record: int = 1) -> None:
    """Percentile intervals of both fits over resamples of the records (each record with its
    ``per_record`` consecutive rows)."""
    weights, picks = _resample_weights(exceeded.shape[0] // per_record, resamples, seed, per_record)
    inside = (exceeded >= 0).astype(np.float64)
    hits = (exceeded == 1).astype(np.float64)
    n, z = weights @ inside, weights @ hits
    tails = (50.0 * (1.0 - CONFIDENCE), 100.0 - 50.0 * (1.0 - CONFIDENCE))
    if out.median is not None:
        low, high = _separation(n, z)
        ok = (low >= 0) & (high > low)
        n_distinct, z_distinct, which = _distinct_rows(n[ok], z[ok])
        a, b, converged = (v[which] for v in probit_mle(s, n_distinct, z_distinct))
        good = converged & (b > 0)
        samples = np.column_stack([np.exp(-a[good] / b[good]), 1.0 / b[good]])
        out.samples, out.resamples_fitted = samples, int(good.sum())
        if good.sum() >= 2:
            out.median_ci = tuple(float(v) for v in np.percentile(samples[:, 0], tails))
            out.beta_ci = tuple(float(v) for v in np.percentile(samples[:, 1], tails))
    if capacity is not None:
        logs = np.log(capacity)[picks]
        medians, betas = np.exp(logs.mean(axis=1)), logs.std(axis=1, ddof=1)
        out.moments_median_ci = tuple(float(v) for v in np.percentile(medians, tails))
        out.moments_beta_ci = tuple(float(v) for v in np.percentile(betas, tails))


def fragility(x, median: float, beta: float) -> np.ndarray:
    """``Phi(ln(x / median) / beta)``: the probability of reaching the state at intensity ``x``."""
    return normal_cdf(np.log(np.asarray(x, dtype=np.float64) / median) / beta)


# --------------------------------------------------------------------------------------------------
# The analysis, its file, its figure and its JSON
# --------------------------------------------------------------------------------------------------


@dataclass
class Analysis:
    """Everything computed: per-run results, exceedances and fits.

    Attributes
    ----------
    variables : dict
        Per run (`sweep.sweep_variables`, plus ``max_rotation_ratio`` and ``scale_factor``):
        ``name -> (array[records, levels], attributes)``.
    exceeded : numpy.ndarray
        int8[records, levels, states] (`exceedances`).
    states : list of DamageState
    fits : list of StateFit
        One per state.
    rows : numpy.ndarray or None
        With parameter samples: `fitted`'s array (else None).
    nominal_fits : list of StateFit
        With parameter samples: the fits of the case's own values alone (no parameter uncertainty).
    model : str
        The curve the analysis offers (`MODELS`): what ``rockslide risk`` takes from its file unless
        told otherwise, and what its pelicun export writes.
    """

    variables: dict
    exceeded: np.ndarray
    states: list
    fits: list
    rows: np.ndarray | None = None
    nominal_fits: list = field(default_factory=list)
    model: str = "lognormal"

    @property
    def fitted(self) -> np.ndarray:
        """int8[realisations, levels, states]: the exceedances the fits use (with parameter samples:
        each record's drawn samples, record by record; else `exceeded`)."""
        return self.exceeded if self.rows is None else self.rows


#: The fragility curves an analysis offers: the lognormal fit, the isotonic curve (monotone maximum
#: likelihood) and the per-level fractions (empirical). The lognormal is the default: where it
#: holds it is the more precise (docs/guide/fragility.md), and where its runs reject it the
#: printout says so first.
MODELS = ("lognormal", "isotonic", "empirical")


def analyse(fplan: FragilityPlan, final_states: np.ndarray, states, *, resamples: int = BOOTSTRAP_RESAMPLES,
            seed: int = BOOTSTRAP_SEED, model: str = "lognormal") -> Analysis:
    """The results of every run (from the kernel's final states), the exceedances and the fits;
    ``model`` the curve offered (`MODELS`)."""
    if model not in MODELS:
        raise CaseError(f"unknown model {model!r}; expected {', '.join(MODELS)}", source="model")
    plan = fplan.plan
    variables = sw.sweep_variables(plan, final_states)
    alpha = plan.case_column(L.P_ALPHA).reshape(plan.shape)
    variables["max_rotation_ratio"] = (variables["max_rotation"][0] / alpha,
                                       {"units": "1", "long_name": "largest rotation |phi| / alpha"})
    variables["scale_factor"] = (plan.factor_h.reshape(plan.shape).copy(),
                                 {"units": "1", "long_name": "factor on the records (horizontal; the "
                                  f"vertical's is this times {fplan.vertical_factor:g})"})
    exceeded = exceedances(variables, alpha, states)
    levels = np.asarray(fplan.levels.values)
    turns = fplan.suite.orientations               # rows of one record at several orientations
    if not fplan.samples:
        fits = [fit_state(levels, exceeded[..., i], resamples=resamples, seed=seed, show=fplan.im.show,
                          per_record=turns) for i in range(len(states))]
        return Analysis(variables=variables, exceeded=exceeded, states=list(states), fits=fits, model=model)
    records, n_levels = fplan.shape
    rows = np.ascontiguousarray(np.moveaxis(exceeded[:, :, 1:, :], 2, 1).reshape(records * fplan.samples,
                                                                                   n_levels, len(states)))
    fits = [fit_state(levels, rows[..., i], resamples=resamples, seed=seed, show=fplan.im.show,
                      per_record=fplan.samples * turns) for i in range(len(states))]
    nominal = [fit_state(levels, exceeded[:, :, 0, i], resamples=resamples, seed=seed, show=fplan.im.show,
                         per_record=turns) for i in range(len(states))]
    return Analysis(variables=variables, exceeded=exceeded, states=list(states), fits=fits, rows=rows,
                    nominal_fits=nominal, model=model)


_FIT_FIELDS = (("median", "m"), ("beta", "b"), ("moments_median", "m"), ("moments_beta", "b"))


def dataset(fplan: FragilityPlan, analysis: Analysis, command_line: str = "") -> tuple[list, dict, dict]:
    """``(coords, variables, attrs)`` of ``OUT/NAME.fragility.h5`` (`results.write_dataset`)."""
    im, plan = fplan.im, fplan.plan
    levels = np.asarray(fplan.levels.values, dtype=np.float64)
    coords = [
        ("record", np.array(fplan.names, dtype=object), {"long_name": "record of the suite, in its order"}),
        ("level", levels, {"units": im.units, "long_name": f"intensity level: {im.long_name}",
                           "intensity_measure": im.name, "given_as": fplan.levels.spec}),
        ("damage_state", np.array([s.name for s in analysis.states], dtype=object),
         {"long_name": "damage state"}),
    ]
    run = ("record", "level")
    if fplan.samples:
        coords.append(("sample", np.arange(fplan.samples + 1, dtype=np.float64),
                       {"long_name": "parameter sample of the record: 0 the case's own values, 1 ... drawn "
                        "from the case's uncertain section (Latin hypercube)"}))
        run = ("record", "level", "sample")
    variables = {name: (run, values, attrs) for name, (values, attrs) in analysis.variables.items()}
    variables["exceeded"] = ((*run, "damage_state"), analysis.exceeded,
                             {"units": "1", "long_name": "the run reached the damage state",
                              "flag_values": np.array([-1, 0, 1], dtype=np.int8),
                              "flag_meanings": "outside_the_model not_exceeded exceeded"})
    n, z = stripe_counts(np.moveaxis(analysis.fitted, -1, 0))
    with np.errstate(invalid="ignore", divide="ignore"):
        fraction = np.where(n > 0, z / n, np.nan)
    variables["fraction_exceeded"] = (("damage_state", "level"), fraction,
                                      {"units": "1", "long_name": "fraction of the runs inside the model "
                                       "that reach the state (NaN: none inside)"})
    low, high = gf.wilson_interval(n, z, CONFIDENCE)
    for side, values in (("lower", low), ("upper", high)):
        variables[f"fraction_{side}"] = (("damage_state", "level"), values, {
            "units": "1",
            "long_name": f"{side} bound of the fraction's {CONFIDENCE:.0%} Wilson interval (NaN: no run)"})
    variables["isotonic"] = (("damage_state", "level"), np.array([f.isotonic for f in analysis.fits]), {
        "units": "1", "long_name": "monotone maximum-likelihood fragility (pool adjacent violators on the fractions, "
        "weighted by the runs; NaN: no run)"})
    for k, side in enumerate(("lower", "upper")):
        band = np.array([f.isotonic_band[k] if f.isotonic_band is not None else np.full(levels.size, np.nan)
                         for f in analysis.fits])
        variables[f"isotonic_{side}"] = (("damage_state", "level"), band, {
            "units": "1", "long_name": f"{side} bound of the isotonic curve's {CONFIDENCE:.0%} percentile band over "
            "the bootstrap resamples of the records (NaN: none)"})
    goods = [f.goodness for f in analysis.fits]
    for name, text, kind in (
            ("deviance", "deviance of the lognormal against the per-level binomial (saturated) model", np.float64),
            ("dof", "degrees of freedom of the deviance: levels with runs minus 2", np.int32),
            ("p_value", "chi-squared p-value of the deviance (NaN: no test)", np.float64),
            ("monotone_statistic", "likelihood ratio of the isotonic fit against the saturated model", np.float64),
            ("monotone_p_value", "its p-value by parametric bootstrap from the isotonic fit", np.float64),
            ("rejected", f"the lognormal is rejected (p < {gf.REJECT_LEVEL:g})", np.int8),
            ("not_monotone", f"the fractions fall by more than sampling noise (p < {gf.REJECT_LEVEL:g})", np.int8)):
        missing = -1 if kind is not np.float64 else math.nan
        values = np.array([missing if g is None else getattr(g, name) for g in goods], dtype=kind)
        variables[f"gof_{name}"] = (("damage_state",), values, {"units": "1", "long_name": text})
    per_state = ("damage_state",)
    variables["definition"] = (per_state, np.array([s.long_name for s in analysis.states], dtype=object),
                               {"long_name": "what reaching the state means (an overturned block reaches "
                                "every state)"})
    units = {"m": im.units, "b": "1"}
    words = {"median": "median of the maximum-likelihood lognormal fit",
             "beta": "logarithmic standard deviation of the maximum-likelihood lognormal fit",
             "moments_median": "median by the method of moments on the first-exceedance levels",
             "moments_beta": "logarithmic standard deviation by the method of moments"}
    for name, unit in _FIT_FIELDS:
        values = np.array([_nan(getattr(f, name)) for f in analysis.fits])
        variables[name] = (per_state, values, {"units": units[unit], "long_name": f"{words[name]} (NaN: "
                                               "no fit, see fit_note)"})
        for side, i in (("lower", 0), ("upper", 1)):
            bounds = np.array([_nan(None if getattr(f, f"{name}_ci") is None else getattr(f, f"{name}_ci")[i])
                               for f in analysis.fits])
            variables[f"{name}_{side}"] = (per_state, bounds, {
                "units": units[unit], "long_name": f"{side} bound of the {CONFIDENCE:.0%} bootstrap "
                f"interval of {name} (NaN: none)"})
    fitted = max((f.samples.shape[0] for f in analysis.fits), default=0)
    if fitted:
        # the fits of the bootstrap resamples themselves, for what is computed from the curve
        # (`rockslide risk` propagates them to an interval on a rate)
        coords.append(("resample", np.arange(fitted, dtype=np.float64),
                       {"long_name": "bootstrap resample of the records whose maximum-likelihood fit converged"}))
        for column, (name, unit) in enumerate((("median", "m"), ("beta", "b"))):
            values = np.full((len(analysis.fits), fitted), np.nan)
            for i, f in enumerate(analysis.fits):
                values[i, :f.samples.shape[0]] = f.samples[:, column]
            variables[f"bootstrap_{name}"] = (("damage_state", "resample"), values, {
                "units": units[unit], "long_name": f"{words[name]} of each bootstrap resample (NaN: past the "
                "state's resamples_fitted)"})
    if fplan.samples:
        for name, unit in (("median", "m"), ("beta", "b")):
            values = np.array([_nan(getattr(f, name)) for f in analysis.nominal_fits])
            variables[f"{name}_without_samples"] = (per_state, values, {
                "units": units[unit], "long_name": f"{words[name]} over the case's own values alone (sample "
                "0: without parameter uncertainty; NaN: no fit)"})
        for name, values in fplan.parameter_values.items():
            what = "coefficient of restitution" if name == "restitution" else f"factor on the {name}"
            variables[f"parameter_{name}"] = (("record", "sample"), values, {"units": "1", "long_name": what})
    for name, text in (("note", "fit_note"), ("moments_note", "moments_note")):
        variables[text] = (per_state, np.array([getattr(f, name) for f in analysis.fits], dtype=object),
                           {"long_name": "why there is no fit (empty: there is)"})
    for name, text in (("n_runs", "runs"), ("n_outside_model", "runs outside the model (flight or "
                                                               "painleve; not in the fits)"),
                       ("n_exceeded", "runs that reach the state"),
                       ("n_censored", "records that never reach the state up to the highest level"),
                       ("resamples_fitted", "bootstrap resamples that support a fit")):
        variables[name] = (per_state, np.array([getattr(f, name) for f in analysis.fits], dtype=np.int32),
                           {"units": "1", "long_name": text})
    m = fplan.measures
    per_record = ("record",)
    for key, unit, text in (("pga", "m/s^2", "peak horizontal ground acceleration"),
                            ("pgv", "m/s", "peak horizontal ground velocity (baseline-corrected)"),
                            ("pgv_pga", "s", "PGV / PGA"),
                            ("im", im.units, f"intensity measure: {im.long_name}"),
                            ("dt", "s", "sampling step"),
                            ("duration", "s", "time the samples span: (samples - 1) x sampling step")):
        variables[f"record_{key}"] = (per_record, m[key], {"units": unit, "long_name": f"{text} of the "
                                                            "record as read (unscaled)"})
    for key in ("horizontal", "vertical"):
        for name, text in ((f"{key}_file", "file name"), (f"{key}_sha256", "SHA-256 of the file")):
            values = np.array([f[name.replace("_file", "")] for f in fplan.files], dtype=object)
            variables[name] = (per_record, values, {"long_name": f"{key} record's {text} (empty: none)"})
    attrs = {key: value for key, value in sw.root_attributes(plan, command_line).items()
             if not key.startswith("record_") and key not in ("sweep_key", "mu_kinetic_ratio")}
    attrs.update({
        "title": f"rockslide fragility of {plan.case.name}: {fplan.describe()}",
        "suite": str(fplan.suite.source),
        "suite_text": fplan.suite.text,
        "intensity_measure": im.name,
        "intensity_measure_units": im.units,
        "intensity_measure_long_name": im.long_name,
        "intensity_measure_label": im.label,
        "intensity_measure_display_unit": im.display_unit,
        "intensity_measure_display_scale": im.display_scale,
        "fit_method": "maximum likelihood over the stripes (binomial likelihood, Baker 2015), probit "
                      "regression on ln(level); method of moments on the first-exceedance levels",
        "bootstrap_resamples": analysis.fits[0].resamples if analysis.fits else 0,
        "bootstrap_seed": BOOTSTRAP_SEED,
        "confidence_level": CONFIDENCE,
        "fragility_model": analysis.model,
        "goodness_of_fit": "deviance of the lognormal against the per-level binomial (saturated) model, chi-squared "
                           "with levels - 2 degrees of freedom; monotonicity: likelihood ratio of the isotonic fit "
                           f"against the saturated model, p by parametric bootstrap ({gf.MONOTONE_RESAMPLES} draws); "
                           f"rejected below {gf.REJECT_LEVEL:g}",
        "fragility_key": plan.key,
        "vertical_factor": fplan.vertical_factor,
        "vertical_motion": fplan.vertical,
        "vertical_note": fplan.vertical_note,
        "orientations_per_record": fplan.suite.orientations,
    })
    if fplan.samples:
        attrs.update({"parameter_samples": fplan.samples, "parameter_seed": fplan.seed,
                      "parameter_distributions": json.dumps({k: d.spec() for k, d in fplan.distributions.items()})})
    return coords, variables, attrs


def _nan(value) -> float:
    return math.nan if value is None else float(value)


def json_summary(fplan: FragilityPlan, analysis: Analysis) -> dict:
    """The ``--json`` object (SI units; null where there is no fit)."""
    im = fplan.im
    n, z = stripe_counts(np.moveaxis(analysis.fitted, -1, 0))
    out = {}
    nominal = analysis.nominal_fits or [None] * len(analysis.fits)
    for state, fit, ns, zs, own in zip(analysis.states, analysis.fits, n, z, nominal, strict=True):
        out[state.name] = {
            "definition": state.long_name,
            "median": fit.median, "beta": fit.beta,
            "median_ci": _pair(fit.median_ci), "beta_ci": _pair(fit.beta_ci),
            "n_runs": fit.n_runs, "n_outside_model": fit.n_outside_model, "n_exceeded": fit.n_exceeded,
            "note": fit.note or None,
            "resamples_fitted": fit.resamples_fitted,
            "moments": {"median": fit.moments_median, "beta": fit.moments_beta,
                        "median_ci": _pair(fit.moments_median_ci), "beta_ci": _pair(fit.moments_beta_ci),
                        "n_censored": fit.n_censored, "note": fit.moments_note or None},
            "fraction_exceeded": [None if k == 0 else float(x / k) for x, k in zip(zs, ns, strict=True)],
            "fraction_interval": [[_finite(a), _finite(b)] for a, b in zip(*gf.wilson_interval(ns, zs, CONFIDENCE),
                                                                          strict=True)],
            "isotonic": [_finite(v) for v in fit.isotonic],
            "isotonic_band": None if fit.isotonic_band is None else [[_finite(v) for v in row]
                                                                     for row in fit.isotonic_band],
            "goodness_of_fit": _goodness_json(fit.goodness),
            "caveats": caveats(fit, im),
        }
        if own is not None:
            out[state.name]["without_parameter_uncertainty"] = {"median": own.median, "beta": own.beta,
                                                                "note": own.note or None}
    status = analysis.variables["status"][0]
    return {
        "name": fplan.plan.case.name,
        "intensity_measure": {"name": im.name, "units": im.units, "long_name": im.long_name},
        "levels": [float(v) for v in fplan.levels.values],
        "records": fplan.names,
        "vertical": {"source": fplan.vertical, "note": fplan.vertical_note or None},
        "damage_states": out,
        "model": analysis.model,
        "n_runs": int(status.size),
        "n_outside_model": int((status != L.STATUS_OK).sum()),
        "n_undecided": int(analysis.variables["undecided"][0].sum()),
        "parameter_samples": None if not fplan.samples else {
            "n": fplan.samples, "seed": fplan.seed,
            "quantities": {k: d.spec() for k, d in fplan.distributions.items()}},
        "bootstrap": {"resamples": analysis.fits[0].resamples if analysis.fits else 0, "seed": BOOTSTRAP_SEED,
                      "confidence": CONFIDENCE},
    }


def _finite(value):
    value = float(value)
    return value if math.isfinite(value) else None


def _goodness_json(g) -> dict | None:
    if g is None:
        return None
    return {"deviance": _finite(g.deviance), "dof": g.dof, "p_value": _finite(g.p_value),
            "test": "likelihood ratio of the lognormal against the per-level binomial model, chi-squared with "
                    "levels - 2 degrees of freedom",
            "rejected": g.rejected, "reject_below": gf.REJECT_LEVEL, "max_deviation": _finite(g.max_deviation),
            "monotone": {"statistic": _finite(g.monotone_statistic), "p_value": _finite(g.monotone_p_value),
                         "not_monotone": g.not_monotone,
                         "test": "likelihood ratio of the isotonic fit against the per-level binomial model, p by "
                                 f"parametric bootstrap ({gf.MONOTONE_RESAMPLES} draws from the isotonic fit)"},
            "summary": g.sentence(), "note": g.note or None}


def _pair(pair):
    return None if pair is None else [float(pair[0]), float(pair[1])]


def figure(fplan: FragilityPlan, analysis: Analysis, *, size=None):
    """The PNG: fitted curves, the stripes' observed fractions and the confidence bands, and what
    was computed (`caption`)."""
    from ..plots import fragility_figure

    title = f"{fplan.plan.case.name}: {fplan.describe()}"
    levels = np.asarray(fplan.levels.values)
    grid, curves = _curves(levels, analysis.fitted, analysis.states, analysis.fits, fplan.im, analysis.nominal_fits)
    text = caption(fplan.plan.case.text, suite=str(fplan.suite.source), records=len(fplan.suite.entries), im=fplan.im,
                   levels=levels, step=fplan.plan.step, vertical_note=fplan.vertical_note)
    return fragility_figure(levels / fplan.im.display_scale, grid / fplan.im.display_scale, curves,
                            xlabel=fplan.im.axis_label(), confidence=CONFIDENCE, title=title, size=size, caption=text)


def caption(case_text: str, *, suite: str, records: int, im: IntensityMeasure, levels, step, version=None,
            vertical_note: str = "") -> str:
    """`plots.case_caption` of a fragility analysis: the suite, its records and the levels they
    were scaled to, in place of the case's records; ``vertical_note`` (the case's vertical record
    left out, `FragilityPlan.vertical_note`) said after them."""
    from .._version import __version__
    from ..plots import case_caption

    levels = np.asarray(levels, dtype=float) / im.display_scale
    unit = f" {im.display_unit}" if im.display_unit else ""
    ground = (f"suite {Path(suite).name} ({records} records) scaled to {im.label} "
              f"{levels.min():.4g} to {levels.max():.4g}{unit} ({levels.size} levels)")
    if vertical_note:
        ground += "; HORIZONTAL ONLY: the case's vertical record is left out (the suite has none; --case-vertical)"
    return case_caption(case_text, ground=ground, step=step, version=version or __version__)


def _curves(levels, exceeded, states, fits, im: IntensityMeasure, nominal_fits=()):
    """The grid [SI of the measure] and the curves of `plots.fragility_figure` (in SI: divide by
    ``im.display_scale``) of fitted damage states."""
    grid = np.linspace(levels[-1] * 1e-3, levels[-1] * 1.1, 300)
    lower_tail, upper_tail = 50.0 * (1.0 - CONFIDENCE), 100.0 - 50.0 * (1.0 - CONFIDENCE)
    curves = []
    for i, (state, fit) in enumerate(zip(states, fits, strict=True)):
        n, z = stripe_counts(exceeded[..., i])
        with np.errstate(invalid="ignore", divide="ignore"):
            fraction = np.where(n > 0, z / n, np.nan)
        label = _legend(state, fit, im)
        if fit.goodness is not None and fit.goodness.rejected:
            p = fit.goodness.p_value
            label += f" (lognormal REJECTED, p {'< 1e-6' if p < 1e-6 else f'= {p:.2g}'})"
        curve = {"label": label, "fraction": fraction,
                 "fraction_interval": np.array(gf.wilson_interval(n, z, CONFIDENCE)), "isotonic": gf.isotonic(n, z)}
        if fit.median is not None:
            curve["fitted"] = fragility(grid, fit.median, fit.beta)
        if fit.moments_median is not None and fit.moments_beta > 0:
            curve["moments"] = fragility(grid, fit.moments_median, fit.moments_beta)
        if fit.samples.shape[0] >= 2:
            band = fragility(grid[None, :], fit.samples[:, :1], fit.samples[:, 1:])
            curve["band"] = np.percentile(band, [lower_tail, upper_tail], axis=0)
        own = nominal_fits[i] if nominal_fits else None
        if own is not None and own.median is not None:
            curve["nominal"] = fragility(grid, own.median, own.beta)
        curves.append(curve)
    return grid, curves


def describe_fit(state: DamageState, fit: StateFit, im: IntensityMeasure) -> str:
    """One line on a state's fits (``rockslide fragility``'s summary): the maximum-likelihood fit,
    the method of moments or why it is left out, the counts (`caveats` follow it)."""
    counts = f"{fit.n_exceeded} of {fit.n_runs - fit.n_outside_model} runs reach it"
    if fit.median is None:
        line = f"{state.name}: {fit.note}"
    elif fit.goodness is not None and fit.goodness.rejected:
        # first, before any number of the curve: it does not describe the data
        line = (f"{state.name}: {fit.goodness.sentence()}: its median and beta do not describe these runs "
                f"(use --model isotonic or --model empirical); {_legend(state, fit, im).split(': ', 1)[1]}")
    else:
        line = _legend(state, fit, im)
        if fit.resamples and fit.resamples_fitted < fit.resamples:
            line += f" ({fit.resamples_fitted} of {fit.resamples} resamples fitted)"
    if fit.moments_median is not None:
        line += f"; moments: median {im.show(fit.moments_median)}, β {fit.moments_beta:.2f}"
    elif fit.moments_note:
        line += f"; no method-of-moments estimate: {fit.moments_note.replace(': no moments', '')}"
    return f"{line}; {counts}"


def isotonic_line(fit: StateFit, levels, im: IntensityMeasure) -> str:
    """``isotonic: 0 at 0.4, 0.14 at 0.45, ... g``: the monotone curve at the levels."""
    levels = np.asarray(levels, dtype=np.float64)
    unit = f" {im.display_unit}" if im.display_unit else ""
    points = ", ".join(f"{p:.3g} at {im.number(x)}" for x, p in zip(levels, fit.isotonic, strict=True)
                       if math.isfinite(p))
    return f"isotonic (monotone maximum likelihood): {points}{unit}"


def goodness_lines(fit: StateFit) -> list[str]:
    """The goodness of fit of a state's lognormal and the monotonicity of its fractions, one line
    each (`goodness.GoodnessOfFit`); [] without runs."""
    g = fit.goodness
    if g is None:
        return []
    parts = [] if g.rejected else [g.sentence()]           # a rejection leads `describe_fit`'s line
    if not math.isnan(g.max_deviation):
        parts.append(f"the curve is {g.max_deviation:.2f} from a per-level fraction at most")
    if g.note:
        parts.append(g.note)
    return ["; ".join(parts), g.monotone_sentence()] if parts else [g.monotone_sentence()]


def caveats(fit: StateFit, im: IntensityMeasure) -> list[str]:
    """What a reader of a state's fits must know: intervals from fewer than
    `MIN_BOOTSTRAP_RECORDS` records, and medians or confidence bounds outside the levels tested
    (extrapolated: no run supports them). One sentence each; [] when there is nothing to say."""
    out = []
    has_interval = fit.median_ci is not None or fit.moments_median_ci is not None
    if fit.resamples and has_interval and fit.n_records < MIN_BOOTSTRAP_RECORDS:
        out.append(f"the {CONFIDENCE:.0%} intervals resample only {fit.n_records} records (at least "
                   f"{MIN_BOOTSTRAP_RECORDS} are needed for the bootstrap to mean much): take them as rough")
    if not fit.tested:
        return out
    low, high = fit.tested
    for what, median, interval in (("median", fit.median, fit.median_ci),
                                   ("moments median", fit.moments_median, fit.moments_median_ci)):
        if median is None:
            continue
        bounds = interval if interval is not None else (None, None)
        named = [("", median)] + [(side, value) for side, value in zip(("lower", "upper"), bounds, strict=True)
                                  if value is not None]
        # within EXTRAPOLATION_MARGIN of a level run, an estimate rests on that level's runs
        above = [(side, value) for side, value in named if value > high * (1 + EXTRAPOLATION_MARGIN)]
        below = [(side, value) for side, value in named if value < low * (1 - EXTRAPOLATION_MARGIN)]
        for flagged, where in ((above, f"beyond the highest level tested, {im.show(high)}"),
                               (below, f"below the lowest level tested, {im.show(low)}")):
            if not flagged:
                continue
            # "median 2.3 g and its upper 95% bound 4.9 g lie", "the median's upper 95% bound 1.7 g lies"
            owner = "its" if flagged[0][0] == "" else f"the {what}'s"
            texts = [f"{what} {im.show(value)}" if not side else f"{owner} {side} {CONFIDENCE:.0%} bound "
                     f"{im.show(value)}" for side, value in flagged]
            verb = "lies" if len(texts) == 1 else "lie"
            out.append(f"{' and '.join(texts)} {verb} {where}: extrapolated")
    return out


def _legend(state: DamageState, fit: StateFit, im: IntensityMeasure) -> str:
    """``overturn: median 0.62 [0.55, 0.71] g, β 0.31 [0.22, 0.40]`` (with the confidence
    intervals), or why there is no fit."""
    if fit.median is None:
        return f"{state.name}: {fit.note}"

    def interval(pair, fmt):
        return "" if pair is None else f" [{fmt(pair[0])}, {fmt(pair[1])}]"

    unit = f" {im.display_unit}" if im.display_unit else ""
    return (f"{state.name}: median {im.number(fit.median)}{interval(fit.median_ci, im.number)}{unit}, "
            f"β {fit.beta:.2f}{interval(fit.beta_ci, lambda b: f'{b:.2f}')}")


def stored_figure(stored, *, size=None) -> object:
    """The same figure from a fragility file read back (`results.read_dataset`), for ``rockslide
    plot``: the fits are recomputed from the stored exceedances (same resamples, same seed)."""
    from ..plots import fragility_figure

    drawn = stored_curves(stored)
    im = drawn["im"]
    return fragility_figure(drawn["levels"] / im.display_scale, drawn["grid"] / im.display_scale, drawn["curves"],
                            xlabel=im.axis_label(), confidence=CONFIDENCE, title=drawn["title"], size=size,
                            caption=drawn["caption"])


def overlay_figure(stored_files, names, *, size=None):
    """Fragility curves of several files on one plot (``rockslide plot A B``): a colour for each
    file, a line style for each damage state, each curve with its band; the legend names the
    files (``names``: their cases). The files must use one intensity measure."""
    from ..plots import FRAGILITY_COLOURS, fragility_figure

    drawn = [stored_curves(stored) for stored in stored_files]
    first = drawn[0]["im"]
    for d, name in zip(drawn[1:], names[1:], strict=True):
        if (d["im"].label, d["im"].display_unit) != (first.label, first.display_unit):
            raise CaseError(f"{name} is over {d['im'].label} and {names[0]} over {first.label}; overlay fragility "
                            "files of one intensity measure", source="rockslide plot")
    styles = ("-", (0, (6, 2)), (0, (1, 1.5)), (0, (6, 2, 1, 2)))
    curves = []
    for k, (d, name) in enumerate(zip(drawn, names, strict=True)):
        for i, curve in enumerate(d["curves"]):
            curve = {key: value for key, value in curve.items() if key not in ("moments", "nominal")}   # one fit each
            curves.append({**curve, "label": f"{name}, {curve['label']}",
                           "colour": FRAGILITY_COLOURS[(k + 1) % len(FRAGILITY_COLOURS)],
                           "style": styles[i % len(styles)], "levels": d["levels"] / first.display_scale,
                           "grid": d["grid"] / first.display_scale})
    top = max(float(d["grid"][-1]) for d in drawn) / first.display_scale
    return fragility_figure(drawn[0]["levels"] / first.display_scale, np.array([0.0, top]), curves,
                            xlabel=first.axis_label(), confidence=CONFIDENCE,
                            title="fragility: " + " and ".join(names), size=size,
                            caption="\n".join(f"{name}: {d['caption']}" for d, name in zip(drawn, names, strict=True)))


def stored_curves(stored) -> dict:
    """What the figure of a fragility file read back draws: ``levels`` and ``grid`` [SI of the
    measure], ``curves`` (`plots.fragility_figure`), ``im``, ``title`` and ``caption``."""
    attrs = stored.attrs
    coords = {name: values for name, values, _ in stored.coords}
    variables = stored.variables
    levels = np.asarray(coords["level"], dtype=np.float64)
    exceeded = np.asarray(variables["exceeded"][1])
    names = [str(v) for v in coords["damage_state"]]
    definitions = [str(v) for v in variables["definition"][1]]
    states = [DamageState(n, "", 0.0, d) for n, d in zip(names, definitions, strict=True)]
    im = IntensityMeasure(str(attrs.get("intensity_measure", "")), "", str(attrs.get("intensity_measure_units", "")),
                          str(attrs.get("intensity_measure_long_name", "")),
                          str(attrs.get("intensity_measure_label", "IM")),
                          str(attrs.get("intensity_measure_display_unit", "")),
                          float(attrs.get("intensity_measure_display_scale", 1.0)))
    resamples = int(attrs.get("bootstrap_resamples", BOOTSTRAP_RESAMPLES))
    seed = int(attrs.get("bootstrap_seed", BOOTSTRAP_SEED))
    title = f"{attrs.get('name', 'fragility')}: {_describe(*exceeded.shape[:2], im.label)}"
    step = attrs.get("integration_step")
    text = caption(str(attrs.get("case_text", "")), suite=str(attrs.get("suite", "?")), records=exceeded.shape[0],
                   im=im, levels=levels, step=None if step is None else float(step),
                   version=str(attrs.get("rockslide_version", "?")), vertical_note=str(attrs.get("vertical_note", "")))
    nominal = ()
    turns = int(attrs.get("orientations_per_record", 1))
    if "sample" not in coords:
        fits = [fit_state(levels, exceeded[..., i], resamples=resamples, seed=seed, show=im.show,
                          per_record=turns) for i in range(len(states))]
    else:
        records, n_levels, width = exceeded.shape[:3]
        title += f" x {width} parameter sets"
        nominal = [fit_state(levels, exceeded[:, :, 0, i], resamples=resamples, seed=seed, show=im.show,
                             per_record=turns) for i in range(len(states))]
        exceeded = np.moveaxis(exceeded[:, :, 1:, :], 2, 1).reshape(records * (width - 1), n_levels, len(states))
        fits = [fit_state(levels, exceeded[..., i], resamples=resamples, seed=seed, show=im.show,
                          per_record=(width - 1) * turns) for i in range(len(states))]
    grid, curves = _curves(levels, exceeded, states, fits, im, nominal)
    return {"levels": levels, "grid": grid, "curves": curves, "im": im, "title": title, "caption": text}


# --------------------------------------------------------------------------------------------------
# Two measures: the probit surface (``--im pga,pgv``, ``--im pga,pgv/pga``)
# --------------------------------------------------------------------------------------------------

#: The second measures of a two-measure fragility: name -> (label, display unit, its size [SI], whether it
#: scales with the record).
SECOND_MEASURES = {"pgv": ("PGV", "cm/s", 0.01, True), "pgv/pga": ("PGV/PGA", "s", 1.0, False)}


def split_measures(text: str) -> tuple[str, str | None]:
    """``"pga,pgv"`` -> ``("pga", "pgv")``; one measure -> ``(text, None)``.

    Raises
    ------
    CaseError
        Naming ``--im``: a second measure other than ``pgv`` or ``pgv/pga``.
    """
    parts = [p.strip().lower().replace(" ", "") for p in str(text).split(",")]
    if len(parts) == 1:
        return str(text), None
    second = {"pgv_pga": "pgv/pga"}.get(parts[1], parts[1])
    if len(parts) != 2 or second not in SECOND_MEASURES:
        raise CaseError(f"two measures are given as 'pga,pgv' or 'pga,pgv/pga' (the records scaled on the first), "
                        f"got {text!r}", source="im")
    return parts[0], second


def second_measure_values(fplan: FragilityPlan, second: str) -> np.ndarray:
    """``float64[records, levels]``: the second measure of each run [SI]: the record's PGV times the
    run's factor (PGV scales with the record), or its PGV/PGA (which does not)."""
    records, n_levels = fplan.shape
    factors = fplan.plan.factor_h.reshape(records, n_levels, -1)[:, :, 0]
    if second == "pgv":
        return fplan.measures["pgv"][:, None] * factors
    return np.broadcast_to(fplan.measures["pgv_pga"][:, None], (records, n_levels)).copy()


def fit_surface(fplan: FragilityPlan, analysis: Analysis, second: str, *, resamples: int = BOOTSTRAP_RESAMPLES,
                seed: int = BOOTSTRAP_SEED) -> list[dict]:
    """Per damage state, ``P = Phi(a + b ln IM1 + c ln IM2)`` over every run inside the model
    (`goodness.probit_surface`), with percentile intervals (:data:`CONFIDENCE`) of ``a, b, c`` over
    resamples of the records. IM1 is the level [SI], IM2 `second_measure_values` [SI]."""
    levels = np.asarray(fplan.levels.values, dtype=np.float64)
    exceeded = analysis.exceeded                              # [records, levels, (samples,) states]
    records = exceeded.shape[0]
    im2 = second_measure_values(fplan, second)
    extra = exceeded.shape[2:-1]
    shape = exceeded.shape[:-1]
    x1 = np.broadcast_to(levels.reshape((1, -1) + (1,) * len(extra)), shape)
    x2 = np.broadcast_to(im2.reshape(im2.shape + (1,) * len(extra)), shape)
    owner = np.broadcast_to(np.arange(records).reshape((-1, 1) + (1,) * len(extra)), shape)
    out = []
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, records, size=(resamples if records >= 2 else 0, records))
    tails = (50.0 * (1.0 - CONFIDENCE), 100.0 - 50.0 * (1.0 - CONFIDENCE))
    for i, state in enumerate(analysis.states):
        y = exceeded[..., i]
        inside = y >= 0
        fit = gf.probit_surface(x1[inside], x2[inside], y[inside])
        entry = {"state": state.name, "fit": fit, "intervals": None, "resamples_fitted": 0,
                 "im1": x1[inside], "im2": x2[inside], "outcome": y[inside]}
        if fit.converged and picks.shape[0]:
            rows = [np.flatnonzero((owner == r).ravel() & inside.ravel()) for r in range(records)]
            taken = []
            for pick in picks:
                chosen = np.concatenate([rows[r] for r in pick])
                again = gf.probit_surface(x1.ravel()[chosen], x2.ravel()[chosen], y.ravel()[chosen], iterations=50)
                if again.converged:
                    taken.append(again.coefficients)
            if len(taken) >= 2:
                entry["intervals"] = np.percentile(np.array(taken), tails, axis=0)
                entry["resamples_fitted"] = len(taken)
        out.append(entry)
    return out


def surface_json(surfaces: list[dict], second: str) -> dict:
    """The ``--json`` object of `fit_surface`: per state the coefficients, their standard errors and
    intervals (null where there is no fit)."""
    out = {}
    for s in surfaces:
        fit = s["fit"]
        out[s["state"]] = {
            "model": f"P = Phi(a + b ln IM1 + c ln {SECOND_MEASURES[second][0]}), IM1 and {second} in SI",
            "coefficients": None if not fit.converged else dict(zip("abc", map(float, fit.coefficients), strict=True)),
            "standard_errors": None if not fit.converged else dict(zip("abc", map(float, fit.standard_errors),
                                                                        strict=True)),
            "intervals": None if s["intervals"] is None else {
                k: [float(s["intervals"][0][j]), float(s["intervals"][1][j])] for j, k in enumerate("abc")},
            "resamples_fitted": s["resamples_fitted"], "n_runs": int(s["outcome"].size), "note": fit.note or None}
    return {"second_measure": second, "scales_with_record": SECOND_MEASURES[second][3], "states": out}


def surface_figure(fplan: FragilityPlan, surfaces: list[dict], second: str, *, size=None):
    """The contour figure of each state's surface, the runs on it, and its curves in IM1 at the
    16th, 50th and 84th percentiles of the runs' IM2 (`plots.surface_figure`)."""
    from ..plots import surface_figure as draw

    label2, unit2, scale2, _ = SECOND_MEASURES[second]
    im = fplan.im
    panels = []
    for s in surfaces:
        if not s["fit"].converged:
            continue
        x1, x2 = s["im1"] / im.display_scale, s["im2"] / scale2
        g1 = np.geomspace(x1.min() * 0.8, x1.max() * 1.25, 120)
        g2 = np.geomspace(x2.min() * 0.8, x2.max() * 1.25, 120)
        p = s["fit"](g1[None, :] * im.display_scale, g2[:, None] * scale2)
        at = np.percentile(x2, [16, 50, 84])
        curves = [(f"{label2} = {v:.3g} {unit2}", s["fit"](g1 * im.display_scale, v * scale2)) for v in at]
        a, b, c = s["fit"].coefficients
        panels.append({"title": f"{s['state']}: P = Φ({a:.2f} + {b:.2f} ln {im.label} + {c:.2f} ln {label2})",
                       "g1": g1, "g2": g2, "p": p, "x1": x1, "x2": x2, "y": s["outcome"], "curves": curves})
    return draw(panels, xlabel=im.axis_label(), ylabel=f"{label2} [{unit2}]",
                title=f"{fplan.plan.case.name}: {fplan.describe()}", size=size)


def surface_lines(surfaces: list[dict], second: str) -> list[str]:
    """The printout of `fit_surface`: one line per state."""
    label = SECOND_MEASURES[second][0]
    lines = []
    for s in surfaces:
        fit = s["fit"]
        if not fit.converged:
            lines.append(f"{s['state']} on two measures: {fit.note}")
            continue
        parts = []
        for j, name in enumerate("abc"):
            interval = "" if s["intervals"] is None else \
                f" [{s['intervals'][0][j]:.3g}, {s['intervals'][1][j]:.3g}]"
            parts.append(f"{name} {fit.coefficients[j]:.3g} ± {fit.standard_errors[j]:.2g}{interval}")
        lines.append(f"{s['state']} on two measures: P = Phi(a + b ln IM + c ln {label}) (SI), " + ", ".join(parts))
    return lines
