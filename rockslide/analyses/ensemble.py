"""A verdict's neighbourhood: the case's ensemble of neighbours (``rockslide run --ensemble N``).

The response of a rocking block to a real record is chaotic: a 1 % change of intensity or 0.05 of
restitution flips many verdicts, and the time history of one run cannot be predicted, only the
statistics of the response over an ensemble. An ensemble is N cases drawn around the nominal one
over the quantities that are uncertain in practice (the case's ``uncertain`` section, or
:data:`DEFAULTS`), sampled by Latin hypercube with a seed, and computed on the engine as one plan
(chunked, on threads, a dask cluster or a GPU). It reports:

- the probability of overturning over the members that stay within the model, with its 95 %
  Wilson score interval (`wilson_interval`); a member drawn outside what the model takes (an
  infinite factor, a restitution above a body's e_max: `drawn_outside`) is left out and said, as
  one that leaves the model during the computation is;
- the distribution of the largest rotation over alpha (median, 5 % and 95 %);
- how the verdict depends on each varied quantity: the share overturning among the members in the
  lowest and in the highest third of its samples, and the quantity with the largest difference.

Each member is the nominal case with its block, contact and scale factors changed in the kernel's
inputs (`plan_ensemble`): the ground samples, the step and the checks are the nominal case's, so
a member drawn at the nominal values computes exactly what ``rockslide run`` computes (a test
says so, bit for bit).
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..case import Case, Distribution, other_plane
from ..core import layout as L
from ..core.normal import normal_quantile
from ..core.simulate import Model, set_model
from ..engine.execute import execute
from ..engine.plan import MAX_POINTS, Plan, assemble, default_chunk_size
from ..engine.prepare import RunWarning, coarse_step_warning
from ..engine.step import keep_resolved
from ..errors import CaseError
from ..mesh import rectangle_k2
from . import sweep as sw

__all__ = ["DEFAULTS", "DEFAULT_MEMBERS", "distributions", "sample", "plan_ensemble", "compute", "summarise",
           "wilson_interval", "latin_hypercube", "EnsemblePlan", "members_needed", "to_precision",
           "parse_members", "AUTO_PRECISION"]

#: Members of an ensemble without ``--ensemble N``'s N (``--robustness``).
DEFAULT_MEMBERS = 200
#: The neighbourhood without an ``uncertain`` section: what is rarely known better than this.
#: Intensity +-5 % (the scatter of a record's scaling), restitution +-0.05 around the case's (the
#: scatter of shake-table estimates), friction +-5 %, size and slenderness +-2 % (dimensions as
#: measured on site).
DEFAULTS = {
    "intensity": Distribution("uniform", 0.95, 1.05),
    "restitution": None,                          # the case's +-0.05 (`distributions`)
    "friction": Distribution("uniform", 0.95, 1.05),
    "size": Distribution("uniform", 0.98, 1.02),
    "slenderness": Distribution("uniform", 0.98, 1.02),
}
RESTITUTION_SPREAD = 0.05
#: The two-sided confidence of the interval of the probability of overturning.
CONFIDENCE = 0.95
#: Seed of the Latin hypercube unless one is given.
SEED = 1


def distributions(case: Case) -> tuple[dict[str, Distribution], bool]:
    """The quantities an ensemble of ``case`` varies: its ``uncertain`` section, or :data:`DEFAULTS`
    (restitution: the case's +-0.05 within [0, 1]). Returns ``(distributions, defaults used)``."""
    given = case.uncertain.given()
    if given:
        return given, False
    e = case.contact.restitution
    out = {name: d for name, d in DEFAULTS.items() if d is not None}
    out["restitution"] = Distribution("uniform", max(0.0, e - RESTITUTION_SPREAD), min(1.0, e + RESTITUTION_SPREAD))
    return out, True


def latin_hypercube(d: int, n: int, seed: int) -> np.ndarray:
    """``n`` points of a ``d``-dimensional Latin hypercube in [0, 1): stratum ``k / n`` of each
    dimension holds one point, placed uniformly in it, the strata paired by random permutations.
    scipy's ``stats.qmc.LatinHypercube(d, seed=seed).random(n)`` (scrambled, strength 1) to the last
    bit (tests/test_ensemble.py), written out so that an ensemble does not import ``scipy.stats``
    (about a second)."""
    rng = np.random.default_rng(seed)
    within = rng.uniform(size=(n, d))
    strata = np.tile(np.arange(1, n + 1), (d, 1))
    for row in strata:
        rng.shuffle(row)
    return (strata.T - within) / n


def sample(dists: dict[str, Distribution], n: int, seed: int = SEED) -> dict[str, np.ndarray]:
    """``n`` samples of each distribution, by Latin hypercube (one stratum of probability ``1/n``
    per member and quantity, the strata paired at random: `latin_hypercube`), through each
    distribution's inverse CDF. A quantity without spread gives its value to every member, exactly.
    Values as drawn, also those no model takes (a lognormal of huge beta overflows to infinity and
    underflows to 0): `drawn_outside` says which members they make."""
    varying = [name for name, d in dists.items() if d.spread]
    u = latin_hypercube(max(1, len(varying)), n, seed) if varying else np.empty((n, 0))
    out = {}
    for name, d in dists.items():
        if name not in varying:
            out[name] = np.full(n, d.nominal if d.kind == "uniform" else d.a)
            continue
        q = u[:, varying.index(name)]
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):    # said per member, not here
            if d.kind == "uniform":
                out[name] = d.a + (d.b - d.a) * q
            elif d.kind == "normal":
                out[name] = d.a + d.b * normal_quantile(q)
            else:
                out[name] = d.a * np.exp(d.b * normal_quantile(q))
    return out


#: The quantities drawn as factors (on the intensity, the friction, the size, the width): finite and > 0.
FACTORS = ("intensity", "friction", "size", "slenderness", "b1", "b2", "radius_of_gyration")
#: The status of a member drawn outside the model in the members' variables (`member_variables`), after
#: the kernel's statuses (`core.kernel.STATUS_NAMES`): its outcomes are not data.
STATUS_DRAWN_OUTSIDE = len(L.STATUS_NAMES)


def drawn_outside(case: Case, values: dict, peaks: np.ndarray, params: np.ndarray | None = None
                  ) -> tuple[np.ndarray, dict]:
    """The members whose drawn ``values`` (`sample`) lie outside what the model accepts, and why.

    A member is outside when a factor (:data:`FACTORS`) is not finite or not above 0; when its
    intensity factor takes the scaled ground motion (``peaks`` [m/s^2], the nominal case's peak per
    member) beyond `engine.prepare.within_acceleration_bound`; when its block's height or width leaves
    `engine.prepare.LENGTH_RANGE`; when its restitution or orientation is not finite; and, for an
    asymmetric body, when its radius of gyration or restitution breaks `case.body_failures` (the
    checks of a case file). They are left out of the statistics and said, as the members that leave
    the model during the computation are.

    ``params``: the members' nominal kernel rows (`member_bodies`; needed for a mesh turned per
    member).

    Returns
    -------
    outside : bool[n]
    reasons : dict
        ``"uncertain.NAME: what"`` -> members (one member may have several reasons).
    """
    from ..case import body_failures
    from ..engine.prepare import LENGTH_RANGE, MAX_ACCELERATION_IN_G, within_acceleration_bound

    n = len(peaks)
    outside = np.zeros(n, dtype=bool)
    reasons: dict[str, int] = {}

    def say(mask: np.ndarray, label: str) -> None:
        mask = mask & ~outside          # one reason per member: the first found
        if mask.any():
            reasons[label] = reasons.get(label, 0) + int(mask.sum())
            outside[mask] = True

    for name in FACTORS:
        if name in values:
            v = values[name]
            say(~np.isfinite(v), f"uncertain.{name}: factor not finite")
            say(~(v > 0.0), f"uncertain.{name}: factor not above 0")
    for name in ("restitution", "orientation"):
        if name in values:
            say(~np.isfinite(values[name]), f"uncertain.{name}: not finite")
    one = np.ones(n)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        if "intensity" in values:
            peak = peaks * np.where(outside, 1.0, values["intensity"])
            say(~within_acceleration_bound(peak, case.gravity),
                f"uncertain.intensity: scaled ground motion beyond {MAX_ACCELERATION_IN_G:.0e} g")
        size, slender = values.get("size", one), values.get("slenderness", one)
        low, high = LENGTH_RANGE
        lengths = (case.block.height * size, case.block.width * size * slender)
        names = ", ".join(f"uncertain.{name}" for name in ("size", "slenderness") if name in values)
        say(~np.logical_and.reduce([(low <= x) & (x <= high) for x in lengths]),
            f"{names}: the block's height or width beyond {low:g} to {high:g} m")
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        bodies = member_bodies(case, params, values)
    if bodies is not None:
        e = (np.clip(values["restitution"], 0.0, 1.0) if "restitution" in values
             else np.full(n, case.contact.restitution))
        shaping = ("size", "slenderness", "b1", "b2", "radius_of_gyration") + (
            ("orientation",) if case.block.mesh is not None else ())        # a mesh's body turns with it
        drawn_body = [q for q in shaping if q in values]
        label = {"block.radius_of_gyration": (drawn_body, "the radius of gyration beyond the largest the "
                                              "body can have (sqrt(max(b1, b2)^2 + h^2))"),
                 "contact.restitution": (["restitution", *drawn_body], "restitution above e_max of the body "
                                         "(docs/asymmetric.md)")}
        failing: dict[str, list[int]] = {}
        for i in np.flatnonzero(~outside):
            b1, b2, h, k = (float(x[i]) for x in bodies)
            for key, _ in body_failures(b1, b2, h, None if math.isnan(k) else k, float(e[i])):
                names, what = label[key]
                quantities = [q for q in names if q in values] or ["restitution"]
                failing.setdefault(f"{', '.join(f'uncertain.{q}' for q in quantities)}: {what}",
                                   []).append(int(i))
        for text, members in failing.items():
            mask = np.zeros(n, dtype=bool)
            mask[members] = True
            say(mask, text)
    return outside, reasons


def _nominal_peaks(plan: Plan, rows: np.ndarray) -> np.ndarray:
    """[m/s^2] The peak scaled ground acceleration of the nominal plan's ``rows`` (horizontal or
    vertical, whichever is larger), as `engine.prepare.check_against_ground` measures a run's."""
    peaks = np.empty(len(rows))
    windows: dict = {}
    for j, r in enumerate(rows):
        window = (int(plan.first[r]), int(plan.count[r]))
        if window not in windows:
            part = plan.base[:, window[0]:window[0] + window[1]]
            windows[window] = (float(np.max(np.abs(part[0:2]), initial=0.0)),
                               float(np.max(np.abs(part[2:4]), initial=0.0)))
        horizontal, vertical = windows[window]
        peaks[j] = max(abs(plan.factor_h[r]) * horizontal, abs(plan.factor_v[r]) * vertical)
    return peaks


@dataclass
class EnsemblePlan:
    """An ensemble, not computed yet.

    Attributes
    ----------
    plan : Plan
        The members as one engine plan over the axis ``member``.
    distributions : dict
        The quantities varied (`distributions`), by name.
    samples : dict
        Each quantity's value per member (float64[n]): factors, or the restitution itself.
    defaults : bool
        Whether :data:`DEFAULTS` stand in for a missing ``uncertain`` section.
    seed : int
    records : dict or None
        The case's records as read (`engine.prepare.read_records`), for the rounds that follow.
    precision : float or None
        The width of the 95 % interval asked for (`to_precision`): this plan is its first round.
    outside : bool[n] or None
        The members drawn outside the model (`drawn_outside`): computed at the nominal values, left
        out of the statistics; their ``samples`` hold the values drawn, NaN where not finite.
    outside_reasons : dict
        Why (`drawn_outside`): ``"uncertain.NAME: what"`` -> members.
    planes : bool
        Whether each member is screened in both planes (a box's depth or a mesh turned by
        ``uncertain.orientation``, model-asymmetric.md section 9): the plan's axes are then
        ``(member, plane)`` and `compute` keeps each member's worse plane (`worse_plane`).
    """

    plan: Plan
    distributions: dict
    samples: dict
    defaults: bool
    seed: int
    records: dict | None = None
    precision: float | None = None
    outside: np.ndarray | None = None
    outside_reasons: dict = field(default_factory=dict)
    planes: bool = False

    @property
    def n(self) -> int:
        """Members (a member in both planes is two of the plan's cases)."""
        return self.plan.n_cases // 2 if self.planes else self.plan.n_cases


def plan_ensemble(case: Case, n: int = DEFAULT_MEMBERS, *, seed: int = SEED, records_dir: Path | None = None,
                  chunk_size: int | None = None, records: dict | None = None) -> EnsemblePlan:
    """Every member's kernel inputs: the nominal case's (`sweep.plan_sweep` at its own values: the
    checks of ``rockslide run``, once), with each member's block, contact and scale factors;
    ``records``: the case's records already read (`engine.prepare.read_records`).

    Raises
    ------
    CaseError
        ``n`` out of range, a case for the reference solver, or what ``rockslide run`` refuses.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_POINTS:
        raise CaseError(f"expected a whole number of members within 1 ... {MAX_POINTS}, got {n!r}",
                        source="n")
    if case.solver.method != "kernel":
        raise CaseError(f"an ensemble runs the compiled kernel; got method {case.solver.method!r}",
                        source=case.source, field="solver.method")
    dists, defaults = distributions(case)
    drawn = sample(dists, int(n), seed)
    e = case.contact.restitution
    planes = case.block.both_planes and "orientation" in drawn
    if "orientation" in drawn:         # a record per orientation: the members as an --azimuth sweep
        orientation = np.where(np.isfinite(drawn["orientation"]), drawn["orientation"],
                               _nominal_value(case, "orientation", dists["orientation"]))
        if planes:                     # each member's width plane, then its depth plane
            orientation = np.column_stack([orientation, _across(orientation)]).ravel()
        axis = sw.Axis("azimuth", tuple(float(v) for v in orientation),
                       tuple(f"{math.degrees(v):.6g}deg" for v in orientation), "uncertain.orientation")
        axes, rows = [axis], np.arange(len(orientation), dtype=np.int64)
    else:
        axes, rows = [sw.parse_axis("restitution", repr(e))], np.zeros(int(n), dtype=np.int64)
    with warnings.catch_warnings():         # the nominal case's warnings are its run's (`prepare`)
        warnings.simplefilter("ignore", RunWarning)
        nominal = sw.plan_sweep(case, axes, records_dir=records_dir, chunk_size=1, records=records)
    n = int(n)
    width_rows = rows[0::2] if planes else rows
    outside, reasons = drawn_outside(case, drawn, _nominal_peaks(nominal, width_rows), nominal.case_params(width_rows))
    if planes:
        across = other_plane(case, float(_across(case.block.orientation or 0.0)))
        across_drawn = {name: v for name, v in drawn.items() if name not in BODY_FACTORS}
        also, more = drawn_outside(across, across_drawn, _nominal_peaks(nominal, rows[1::2]),
                                   nominal.case_params(rows[1::2]))
        for text, count in more.items():
            reasons[f"{text} (depth plane)"] = count
        outside |= also
    if outside.all():
        first = max(reasons, key=reasons.get)
        raise CaseError(f"every one of the {n} members is drawn outside the model ({_reasons_text(reasons)}); "
                        "expected a distribution whose draws the model takes (a smaller spread)",
                        source=case.source, field=first.split(":", 1)[0].split(",", 1)[0])
    values = {name: np.where(outside, _nominal_value(case, name, dists[name]), v) for name, v in drawn.items()}
    params, restitution = member_parameters(case, nominal.case_params(width_rows), values)
    intensity = values.get("intensity", np.ones(n))
    if planes:                      # the depth plane's body (the box's depth, the mesh turned), the same draws
        depth, _ = member_parameters(across, nominal.case_params(rows[1::2]),
                                     {k: v for k, v in values.items() if k not in BODY_FACTORS})
        params = np.stack([params, depth], axis=1).reshape(2 * n, -1)
        intensity = np.repeat(intensity, 2)
    if case.solver.auto:            # the nominal case's step, each member's block resolved
        keep_resolved(params)
    if coarse_step_warning(case.source, nominal.params) is None:
        warning = coarse_step_warning(case.source, params, lambda i: f"ensemble member {i}: the smallest block")
        if warning:
            warnings.warn(warning, RunWarning, stacklevel=2)
    kind = sw.AxisKind("member", "member", "dimensionless", "", "member of the ensemble", "1", "member")
    axes = [sw.Axis("member", tuple(float(i) for i in range(n)), tuple(str(i) for i in range(n)), str(n), kind)]
    if planes:
        axes.append(sw.Axis("plane", (0.0, 1.0), ("width", "depth"), "width,depth", PLANE_KIND))
    plan = assemble(case, axes, params=params, states=nominal.case_states(rows),
                    factor_h=nominal.factor_h[rows] * intensity, factor_v=nominal.factor_v[rows] * intensity,
                    base=nominal.base, first=nominal.first[rows], count=nominal.count[rows],
                    record_end=nominal.record_end[rows], records=nominal.records, step_study=nominal.step_study,
                    chunk_size=default_chunk_size(n) if chunk_size is None else int(chunk_size))
    with np.errstate(invalid="ignore"):
        stored = {name: np.where(np.isfinite(v), np.clip(v, 0.0, 1.0) if name == "restitution" else v, np.nan)
                  for name, v in drawn.items()}
    stored.setdefault("restitution", restitution)
    return EnsemblePlan(plan=plan, distributions=dists, samples=stored, defaults=defaults, seed=seed, records=records,
                        outside=outside, outside_reasons=reasons, planes=planes)


#: What the printout says of a member's two planes (as a run's, `api.runs.SCREENING`).
PLANES_NOTE = ("an uncoupled screening: each member's verdict is the worse of its width plane and its depth plane, "
               "each under the component along it")
#: The quantities that draw a body's own shape in its width plane (not carried to its depth plane).
BODY_FACTORS = ("b1", "b2", "radius_of_gyration")
#: The axis of the two planes of a member screened in both (`EnsemblePlan.planes`).
PLANE_KIND = sw.AxisKind("plane", "plane", "dimensionless", "", "plane of the screening (0: width, 1: depth)", "1",
                         "plane")


def _across(orientation):
    """The depth plane's azimuth [rad]: ``orientation + 90 deg``, within +-360 deg."""
    across = np.asarray(orientation, dtype=float) + 0.5 * math.pi
    return np.where(across > 2.0 * math.pi, across - 2.0 * math.pi, across)


def worse_plane(variables: dict) -> dict:
    """Each member's variables (`sweep.sweep_variables` over ``(member, plane)``) from its worse plane:
    a plane that left the model (its status), else the one that overturns, else the larger rotation
    ratio (as a run's screening, `api.runs`); and ``plane``, which it was (0 width, 1 depth)."""
    status, over = variables["status"][0], np.asarray(variables["overturned"][0]).astype(bool)
    ratio = np.where(over, np.inf, np.nan_to_num(np.asarray(variables["max_rotation_ratio"][0], dtype=float),
                                                 nan=-1.0))
    bad = status != L.STATUS_OK
    depth = np.where(bad[:, 0] | bad[:, 1], bad[:, 1] & ~bad[:, 0],
                     (over[:, 1] > over[:, 0]) | ((over[:, 1] == over[:, 0]) & (ratio[:, 1] > ratio[:, 0])))
    pick = depth.astype(np.int64)
    members = np.arange(len(pick))
    out = {name: (np.asarray(values)[members, pick], attrs) for name, (values, attrs) in variables.items()}
    out["plane"] = (pick.astype(np.int8), {"long_name": "the plane of the member's worse verdict (model-asymmetric.md "
                                                        "section 9, an uncoupled screening)",
                                           "flag_values": np.array([0, 1], dtype=np.int8),
                                           "flag_meanings": "width depth"})
    return out


def _nominal_value(case: Case, name: str, dist: Distribution) -> float:
    """What a member drawn outside the model computes with for ``name``: the case's own value (a
    factor of 1, its restitution) or the distribution's nominal orientation."""
    if name == "restitution":
        return case.contact.restitution
    return dist.nominal if name == "orientation" else 1.0


def _reasons_text(reasons: dict) -> str:
    """``uncertain.intensity: factor not finite`` (one reason) or each with its count."""
    if len(reasons) == 1:
        return next(iter(reasons))
    return "; ".join(f"{text} ({count})" for text, count in reasons.items())


def member_bodies(case: Case, params: np.ndarray | None, values: dict) -> tuple[np.ndarray, ...] | None:
    """Each member's body ``(b1, b2, h, k)`` [m] (``k`` NaN: the rectangle's default), for an
    asymmetric body or a case whose ``uncertain`` section draws ``b1``, ``b2`` or the radius of
    gyration; None for a rectangle (`member_parameters` then builds it from its width and height).
    The corners scale as the width (``size`` x ``slenderness`` x their own factor), ``h`` and ``k``
    as the size, ``k`` also by its own factor; a mesh turned per member (``orientation``) starts from
    each member's own body in ``params``, the nominal plan's rows (`case.Block.mesh`)."""
    block = case.block
    if block.half_widths is None and block.radius_of_gyration is None \
            and not any(name in values for name in ("b1", "b2", "radius_of_gyration")):
        return None
    n = len(next(iter(values.values()), ())) if params is None else params.shape[0]
    one = np.ones(n)
    size, slender = values.get("size", one), values.get("slenderness", one)
    b1, b2 = np.full(n, block.corners[0]), np.full(n, block.corners[1])
    half_height = np.full(n, 0.5 * block.height)
    k = np.full(n, np.nan if block.radius_of_gyration is None else block.radius_of_gyration)
    if block.mesh is not None and "orientation" in values:      # each member's body from the mesh
        b1, b2, half_height = params[:, L.P_B1].copy(), params[:, L.P_B2].copy(), params[:, L.P_H].copy()
        k = np.sqrt(params[:, L.P_K2])
    stretch = size * slender
    b1, b2 = b1 * stretch * values.get("b1", one), b2 * stretch * values.get("b2", one)
    half_height, k = half_height * size, k * size
    if "radius_of_gyration" in values:
        default = np.sqrt(rectangle_k2(b1, b2, half_height))
        k = np.where(np.isnan(k), default, k) * values["radius_of_gyration"]
    return b1, b2, half_height, k


def member_parameters(case: Case, params: np.ndarray, values: dict) -> tuple[np.ndarray, np.ndarray]:
    """Kernel parameter rows of members: ``params`` (the nominal case's row for each member) with
    each member's block and contact, from its sampled ``values`` (`sample`: factors on the size (h
    and b), on the width b alone (``slenderness``: b/h times it, the field's h/b divided by it), on
    either corner alone (``b1``, ``b2``), on the radius of gyration and on the friction, the
    restitution itself; a quantity not sampled keeps the case's value). A mesh turned per member
    (``orientation``) starts from each member's own body in ``params`` (`case.Block.mesh`). The
    block's constants come from `core.simulate.Model`, as for a run, so a member at the nominal
    values has the nominal row exactly. Returns ``(params, restitution per member)``."""
    params = params.copy()
    n = params.shape[0]
    one = np.ones(n)
    size, slender, friction = values.get("size", one), values.get("slenderness", one), values.get("friction", one)
    width, height = case.block.width * size * slender, case.block.height * size
    mu, nu = case.contact.mu_static * friction, case.contact.mu_kinetic * friction
    restitution = (np.clip(values["restitution"], 0.0, 1.0) if "restitution" in values
                   else np.full(n, case.contact.restitution))
    bodies = member_bodies(case, params, values)
    for i in range(n):
        if bodies is not None:      # an asymmetric body (docs/asymmetric.md)
            m1, m2, mh, mk = (float(x[i]) for x in bodies)
            model = Model(m1, mh, float(mu[i]), float(nu[i]), float(restitution[i]), case.gravity, case.block.mass,
                          half_width_2=m2, radius_of_gyration=None if math.isnan(mk) else mk)
        else:
            model = Model.from_block(float(width[i]), float(height[i]), float(mu[i]), float(nu[i]),
                                     float(restitution[i]), case.gravity, case.block.mass)
        set_model(params[i], model)
    return params, restitution


#: The attributes of the ensemble's dimension ``member`` in its files and datasets.
MEMBER_ATTRS = {"units": "1", "long_name": "member of the ensemble"}


def compute(eplan: EnsemblePlan, nominal_overturned: bool, **where) -> tuple[dict, tuple, dict]:
    """Compute the members on the engine (`engine.execute.execute`, with ``where``: the store,
    workers, scheduler, device, progress). Returns the summary (`summarise`), the dimension
    ``member`` as ``(name, values, attributes)`` and the members' variables (`member_variables`)."""
    done = execute(eplan.plan, **where)
    variables = sw.sweep_variables(eplan.plan, done.states)
    if eplan.planes:
        variables = worse_plane(variables)
    variables = mark_drawn_outside(eplan, variables)
    members = ("member", np.arange(eplan.n), dict(MEMBER_ATTRS))
    return summarise(eplan, variables, nominal_overturned), members, member_variables(eplan, variables)


#: The outcomes of a member drawn outside the model (`mark_drawn_outside`): computed at the nominal
#: values, they are no member's data.
_NOT_DATA = {"overturned": 0, "undecided": 0, "impacts": 0, "direction": 0, "overturn_mode": 0, "modes": 0}


def mark_drawn_outside(eplan: EnsemblePlan, variables: dict) -> dict:
    """The members' variables (`sweep.sweep_variables`) with the members drawn outside the model
    (`EnsemblePlan.outside`) marked: status :data:`STATUS_DRAWN_OUTSIDE` (``drawn_outside`` among its
    ``flag_meanings``), their floating-point outcomes NaN and their coded ones 0, so that nothing
    reads them as data."""
    outside = eplan.outside if eplan.outside is not None else np.zeros(eplan.n, dtype=bool)
    status, attrs = variables["status"]
    attrs = {**attrs, "flag_values": np.arange(STATUS_DRAWN_OUTSIDE + 1, dtype=np.int8),
             "flag_meanings": f"{attrs['flag_meanings']} drawn_outside",
             "long_name": "ok, or where the computation left the model, or drawn_outside: a member whose drawn "
                          "values the model does not take (not computed)"}
    out = {**variables, "status": (np.where(np.reshape(outside, np.shape(status)), STATUS_DRAWN_OUTSIDE,
                                            status).astype(np.int8), attrs)}
    if not outside.any():
        return out
    for name, (values, var_attrs) in variables.items():
        if name == "status":
            continue
        mask = np.reshape(outside, np.shape(values))
        if np.issubdtype(np.asarray(values).dtype, np.floating):
            out[name] = (np.where(mask, np.nan, values), var_attrs)
        elif name in _NOT_DATA:
            out[name] = (np.where(mask, _NOT_DATA[name], values).astype(np.asarray(values).dtype), var_attrs)
    return out


def wilson_interval(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The Wilson score interval of a proportion ``k / n`` (Wilson 1927; Brown, Cai and DasGupta
    2001 recommend it over the normal approximation, which collapses at 0 and n): with ``z`` the
    normal quantile, ``(p + z^2 / 2n +- z sqrt(p (1 - p) / n + z^2 / 4 n^2)) / (1 + z^2 / n)``.
    ``(nan, nan)`` for ``n = 0``."""
    if n == 0:
        return math.nan, math.nan
    z = float(normal_quantile(0.5 + confidence / 2.0))
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def summarise(eplan: EnsemblePlan, variables: dict, nominal_overturned: bool) -> dict:
    """The ensemble's statistics (`sweep.sweep_variables` of its members) as plain data: the JSON's
    ``ensemble`` object and the result file's ``ensemble`` attribute.

    Keys: ``n``, ``seed``, ``quantities`` (each distribution as the case file writes it),
    ``defaults``, ``n_within_model`` (members with status ok, not drawn outside the model),
    ``n_drawn_outside`` and ``drawn_outside`` (members drawn outside the model, `drawn_outside`, and
    why: ``"uncertain.NAME: what"`` -> members; left out of every statistic), ``n_overturned``, ``p_overturn``,
    ``interval`` ([low, high], 95 % Wilson), ``n_undecided``, ``rotation_ratio`` (``median``,
    ``p05``, ``p95`` of max rotation / alpha over the members within the model), ``sensitivity``
    (per quantity that varies: ``p_low``, ``p_high``, the probability of overturning in the lowest
    and highest third of its samples), ``most_sensitive`` (the quantity with the largest
    ``|p_high - p_low|``, or None), ``nominal_overturned``, ``flips`` (members within the model whose
    verdict differs from the nominal run's) and ``robust`` (no member flips).
    """
    status = np.ravel(variables["status"][0])
    over = np.ravel(variables["overturned"][0]).astype(bool)
    ratio = np.ravel(variables["max_rotation_ratio"][0])
    outside = eplan.outside if eplan.outside is not None else np.zeros(status.shape, dtype=bool)
    ok = (status == L.STATUS_OK) & ~outside
    n_ok, k = int(ok.sum()), int((over & ok).sum())
    low, high = wilson_interval(k, n_ok)
    sensitivity = {}
    for name, d in eplan.distributions.items():
        if not d.spread:
            continue
        values = eplan.samples[name][ok]
        if values.size < 3:
            continue
        lo, hi = np.quantile(values, [1 / 3, 2 / 3])
        sensitivity[name] = {"p_low": float(over[ok][values <= lo].mean()),
                             "p_high": float(over[ok][values >= hi].mean())}
    most = max(sensitivity, key=lambda q: abs(sensitivity[q]["p_high"] - sensitivity[q]["p_low"]), default=None)
    if most is not None and sensitivity[most]["p_high"] == sensitivity[most]["p_low"]:
        most = None
    flips = int((over[ok] != nominal_overturned).sum())
    quantiles = np.quantile(ratio[ok], [0.5, 0.05, 0.95]) if n_ok else [math.nan] * 3
    return {
        "n": eplan.n, "seed": eplan.seed, "defaults": eplan.defaults,
        "quantities": {name: d.spec() for name, d in eplan.distributions.items()},
        "n_within_model": n_ok, "n_drawn_outside": int(outside.sum()), "drawn_outside": dict(eplan.outside_reasons),
        "n_overturned": k, "p_overturn": k / n_ok if n_ok else math.nan,
        "interval": [low, high], "confidence": CONFIDENCE,
        "n_undecided": int(np.ravel(variables["undecided"][0])[ok].sum()),
        "rotation_ratio": {"median": float(quantiles[0]), "p05": float(quantiles[1]), "p95": float(quantiles[2])},
        "sensitivity": sensitivity, "most_sensitive": most,
        "nominal_overturned": bool(nominal_overturned), "flips": flips, "robust": flips == 0 and n_ok == eplan.n,
        "integration_step": eplan.plan.step,
        "step": {} if eplan.plan.step_study is None else eplan.plan.step_study.attributes(),
        **({"planes": {"depth_decides": int((np.ravel(variables["plane"][0])[ok] == 1).sum()),
                       "screening": PLANES_NOTE}} if "plane" in variables else {}),
    }


def describe(summary: dict, nominal_verdict: str) -> list[str]:
    """The printout's lines: the first leads with the probability when the nominal verdict is not
    robust (``standing (nominal); overturns in 38 % [31, 45] of 200 neighbours``)."""
    n, p = summary["n"], summary["p_overturn"]
    low, high = summary["interval"]

    def pct(x):
        return f"{100 * x:.0f}" if math.isfinite(x) else "nan"

    share = f"overturns in {pct(p)} % [{pct(low)}, {pct(high)}] of {summary['n_within_model']} neighbours"
    lines = [f"{nominal_verdict} (nominal); {share}" if not summary["robust"] else
             f"{nominal_verdict}: robust, every one of {n} neighbours agrees"]
    quantities = ", ".join(f"{name} {_spec_text(spec, 180.0 / math.pi)} deg" if name == "orientation"
                           else f"{name} {_spec_text(spec)}" for name, spec in summary["quantities"].items())
    origin = "default neighbourhood" if summary["defaults"] else "the case's uncertain section"
    lines.append(f"  ensemble of {n} ({origin}: {quantities}; Latin hypercube, seed {summary['seed']}); "
                 f"95 % Wilson interval")
    r = summary["rotation_ratio"]
    lines.append(f"  max rotation / alpha: median {r['median']:.2f}, 5-95 % {r['p05']:.2f} to {r['p95']:.2f}")
    note = summary.get("step", {}).get("step_note")
    if note:
        lines.append(f"  {note}")
    planes = summary.get("planes")
    if planes:
        lines.append(f"  both planes ({planes['screening']}): the depth plane decides {planes['depth_decides']} of "
                     f"{summary['n_within_model']}")
    drawn = summary.get("n_drawn_outside", 0)
    if drawn:
        lines.append(f"  {drawn} of {n} members drawn outside the model ({_reasons_text(summary['drawn_outside'])}): "
                     "left out")
    outside = n - summary["n_within_model"] - drawn
    if outside:
        lines.append(f"  {outside} of {n} neighbours left the model (flight or painleve): not counted")
    most = summary["most_sensitive"]
    if most is not None:
        s = summary["sensitivity"][most]
        # the name says what its draws scale: slenderness is a factor on the width (case.Uncertain)
        name = {"slenderness": "slenderness (the factor on the width b)"}.get(most, most)
        lines.append(f"  most sensitive to {name}: overturns in {pct(s['p_low'])} % of its lowest third, "
                     f"{pct(s['p_high'])} % of its highest")
    return lines


def _spec_text(spec, scale: float = 1.0) -> str:
    """A distribution in short (``U[0.95, 1.05]``), its values times ``scale`` (not a lognormal's beta)."""
    if not isinstance(spec, dict):
        return f"{spec * scale:g}"
    (kind, value), = spec.items()
    if kind == "uniform":
        return f"U[{value[0] * scale:g}, {value[1] * scale:g}]"
    if kind == "normal":
        return f"N({value['mean'] * scale:g}, {value['std'] * scale:g})"
    return f"LN({value['median'] * scale:g}, {value['beta']:g})"


def attributes(summary: dict) -> dict:
    """The result file's root attributes of an ensemble: ``ensemble`` (the summary as JSON) and a
    few of its numbers on their own (``ensemble_p_overturn``, ``ensemble_interval_low``/``_high``,
    ``ensemble_n``, ``ensemble_seed``, ``verdict_robust``)."""
    return {"ensemble": json.dumps(summary, allow_nan=True), "ensemble_n": summary["n"],
            "ensemble_seed": summary["seed"], "ensemble_p_overturn": summary["p_overturn"],
            "ensemble_interval_low": summary["interval"][0], "ensemble_interval_high": summary["interval"][1],
            "verdict_robust": summary["robust"]}


def member_variables(eplan: EnsemblePlan, variables: dict) -> dict:
    """Per member (``member`` dimension): the sampled quantities and the outcome variables, as
    `results.write_dataset` and `io.datasets.study_dataset` take them."""
    out = {}
    units = {"restitution": "1", "orientation": "rad"}
    words = {"restitution": "coefficient of restitution",
             "orientation": "the block's orientation (azimuth of its width, clockwise from north)"}
    for name, values in eplan.samples.items():
        what = words.get(name, f"factor: {name}")
        out[f"sample_{name}"] = (("member",), values, {"units": units.get(name, "1"), "long_name": what})
    for name in ("overturned", "max_rotation", "max_rotation_ratio", "status", "undecided", "impacts",
                 "max_slip", "end_time", "plane"):
        if name in variables:
            values, attrs = variables[name]
            out[name] = (("member",), np.ravel(values), attrs)
    return out


#: The width of the 95 % interval of the probability of overturning that ``--ensemble auto`` asks for.
AUTO_PRECISION = 0.1
#: Members of the first ensemble of ``--ensemble auto`` (then as many as the width asks).
PILOT_MEMBERS = 100


def parse_members(text) -> tuple[int | None, float | None]:
    """Read ``--ensemble``: a number of members ``N``, ``auto`` (the interval narrower than
    :data:`AUTO_PRECISION`) or ``precision:W`` (narrower than ``W``). Returns ``(N, None)`` or
    ``(None, W)``.

    Raises
    ------
    CaseError
        Naming ``--ensemble``.
    """
    value = str(text).strip().lower()
    if value == "auto":
        return None, AUTO_PRECISION
    if value.startswith("precision:"):
        try:
            width = float(value.split(":", 1)[1])
        except ValueError:
            width = math.nan
        if not 0.0 < width < 1.0:
            raise CaseError(f"expected precision:W with W within 0 and 1 (e.g. precision:0.05), got {text!r}",
                            source="ensemble")
        return None, width
    try:
        return int(value), None
    except ValueError:
        raise CaseError(f"expected a number of members, 'auto' or 'precision:W', got {text!r}",
                        source="ensemble") from None


def members_needed(k: int, n: int, width: float, confidence: float = CONFIDENCE) -> int:
    """The fewest members ``m`` whose Wilson interval (`wilson_interval`) at the proportion ``k / n``
    seen so far (at least ``1 / 2n`` from 0 and 1: a proportion of 0 still has a width) is at most
    ``width`` wide; at most `MAX_POINTS`."""
    p = min(max(k / n, 0.5 / n), 1.0 - 0.5 / n) if n else 0.5

    def wide(m: int) -> float:
        low, high = wilson_interval(p * m, m, confidence)
        return high - low

    low, high = 1, MAX_POINTS
    if wide(high) > width:
        return high
    while low < high:                     # the width falls as m grows (p fixed)
        middle = (low + high) // 2
        if wide(middle) <= width:
            high = middle
        else:
            low = middle + 1
    return low


def to_precision(case: Case, width: float, nominal_overturned: bool, *, seed: int = SEED,
                 records_dir: Path | None = None, start: int = PILOT_MEMBERS, records: dict | None = None, **where):
    """An ensemble grown until the 95 % Wilson interval of its probability of overturning is at
    most ``width`` wide (``--ensemble auto``, ``precision:W``).

    Starts with ``start`` members; while the interval is wider, plans a new Latin hypercube of the
    members `members_needed` asks for at the proportion seen (at least 1.5 times as many, so that it
    ends in a few rounds), and computes it. Each round is one Latin hypercube of its own size (they
    do not nest), and the one reported is the last; the rounds before cost at most about as much
    again. The rounds look at the data before stopping, which widens the interval's true
    coverage by little at these sizes (the stopping rule depends on the width, not on the estimate
    crossing a threshold).

    Returns
    -------
    eplan, summary, members, variables
        As `plan_ensemble` and `compute`; ``summary`` has ``precision`` (the width asked) and
        ``rounds`` (the members of each round).
    """
    n, rounds = int(start), []
    while True:
        eplan = plan_ensemble(case, n, seed=seed, records_dir=records_dir, records=records)
        summary, members, variables = compute(eplan, nominal_overturned, **where)
        rounds.append(n)
        low, high = summary["interval"]
        if high - low <= width or n >= MAX_POINTS:
            break
        # the members asked for are those counted: as many more as were left out (drawn or left outside)
        needed = members_needed(summary["n_overturned"], summary["n_within_model"], width)
        counted = summary["n_within_model"] / n
        n = min(MAX_POINTS, max(int(math.ceil(needed / counted)) if counted else needed, int(math.ceil(1.5 * n))))
    summary.update({"precision": width, "rounds": rounds})
    return eplan, summary, members, variables
