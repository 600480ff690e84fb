"""A verdict's neighbourhood: the case's ensemble of neighbours (``rockslide run --ensemble N``).

The response of a rocking block to a real record is chaotic: a 1 % change of intensity or 0.05 of
restitution flips many verdicts, and the time history of one run cannot be predicted, only the
statistics of the response over an ensemble. An ensemble is N cases drawn around the nominal one
over the quantities that are uncertain in practice (the case's ``uncertain`` section, or
:data:`DEFAULTS`), sampled by Latin hypercube with a seed, and computed on the engine as one plan
(chunked, on threads, a dask cluster or a GPU). It reports:

- the probability of overturning over the members that stay within the model, with its 95 %
  Wilson score interval (`wilson_interval`);
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
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..case import Case, Distribution
from ..core import kernel as K
from ..core.simulate import Model, set_model
from ..engine.execute import execute
from ..engine.plan import MAX_POINTS, Plan, default_chunk_size, definition_key
from ..engine.prepare import RunWarning, coarse_step_warning
from ..engine.step import keep_resolved
from ..errors import CaseError
from . import sweep as sw

__all__ = ["DEFAULTS", "DEFAULT_MEMBERS", "distributions", "sample", "plan_ensemble", "compute", "summarise",
           "wilson_interval", "EnsemblePlan"]

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


def sample(dists: dict[str, Distribution], n: int, seed: int = SEED) -> dict[str, np.ndarray]:
    """``n`` samples of each distribution, by Latin hypercube (one stratum of probability ``1/n``
    per member and quantity, the strata paired at random; scipy's ``qmc.LatinHypercube`` with
    ``seed``), through each distribution's inverse CDF. A quantity without spread gives its value
    to every member, exactly."""
    from scipy.stats import norm, qmc

    varying = [name for name, d in dists.items() if d.spread]
    u = qmc.LatinHypercube(d=max(1, len(varying)), seed=seed).random(n) if varying else np.empty((n, 0))
    out = {}
    for name, d in dists.items():
        if name not in varying:
            out[name] = np.full(n, d.nominal if d.kind == "uniform" else d.a)
            continue
        q = u[:, varying.index(name)]
        if d.kind == "uniform":
            out[name] = d.a + (d.b - d.a) * q
        elif d.kind == "normal":
            out[name] = d.a + d.b * norm.ppf(q)
        else:
            out[name] = d.a * np.exp(d.b * norm.ppf(q))
    return out


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
    """

    plan: Plan
    distributions: dict
    samples: dict
    defaults: bool
    seed: int

    @property
    def n(self) -> int:
        return self.plan.n_cases


def plan_ensemble(case: Case, n: int = DEFAULT_MEMBERS, *, seed: int = SEED, records_dir: Path | None = None,
                  chunk_size: int | None = None) -> EnsemblePlan:
    """Every member's kernel inputs: the nominal case's (`sweep.plan_sweep` at its own values: the
    checks of ``rockslide run``, once), with each member's block, contact and scale factors.

    Raises
    ------
    CaseError
        ``n`` out of range, a case for the reference solver, or what ``rockslide run`` refuses.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= MAX_POINTS:
        raise CaseError(f"expected a whole number of members within 1 ... {MAX_POINTS}, got {n!r}",
                        source="--ensemble")
    if case.solver.method != "kernel":
        raise CaseError(f"an ensemble runs the compiled kernel; got method {case.solver.method!r}",
                        source=case.source, field="solver.method")
    dists, defaults = distributions(case)
    values = sample(dists, int(n), seed)
    e = case.contact.restitution
    if "orientation" in values:         # a record per orientation: the members as an --azimuth sweep
        axis = sw.Axis("azimuth", tuple(float(v) for v in values["orientation"]),
                       tuple(f"{math.degrees(v):.6g}deg" for v in values["orientation"]), "uncertain.orientation")
        axes, rows = [axis], np.arange(int(n), dtype=np.int64)
    else:
        axes, rows = [sw.parse_axis("restitution", repr(e))], np.zeros(int(n), dtype=np.int64)
    with warnings.catch_warnings():         # the nominal case's warnings are its run's (`prepare`)
        warnings.simplefilter("ignore", RunWarning)
        nominal = sw.plan_sweep(case, axes, records_dir=records_dir, chunk_size=1)
    n = int(n)
    params, restitution = member_parameters(case, nominal.case_params(rows), values)
    if case.solver.auto:            # the nominal case's step, each member's block resolved
        keep_resolved(params)
    intensity = values.get("intensity", np.ones(n))
    if coarse_step_warning(case.source, nominal.params) is None:
        warning = coarse_step_warning(case.source, params, lambda i: f"ensemble member {i}: the smallest block")
        if warning:
            warnings.warn(warning, RunWarning, stacklevel=2)
    kind = sw.AxisKind("member", "--ensemble", "dimensionless", "", "member of the ensemble", "1", "member")
    axis = sw.Axis("member", tuple(float(i) for i in range(n)), tuple(str(i) for i in range(n)), str(n), kind)
    plan = Plan(case=case, axes=[axis], mu_kinetic_ratio=None, params=params, states=nominal.case_states(rows),
                factor_h=nominal.factor_h[rows] * intensity, factor_v=nominal.factor_v[rows] * intensity,
                base=nominal.base, first=nominal.first[rows], count=nominal.count[rows],
                record_end=nominal.record_end[rows], step=float(params[:, K.P_STEP].min()), records=nominal.records,
                chunk_size=default_chunk_size(n) if chunk_size is None else int(chunk_size),
                step_study=nominal.step_study)
    plan.key = definition_key(plan)
    stored = dict(values)
    stored["restitution"] = restitution
    return EnsemblePlan(plan=plan, distributions=dists, samples=stored, defaults=defaults, seed=seed)


def member_parameters(case: Case, params: np.ndarray, values: dict) -> tuple[np.ndarray, np.ndarray]:
    """Kernel parameter rows of members: ``params`` (the nominal case's row for each member) with
    each member's block and contact, from its sampled ``values`` (`sample`: factors on the size (h
    and b), on the width b alone (``slenderness``: b/h times it, the field's h/b divided by it) and
    on the friction, the restitution itself; a quantity not sampled keeps the case's
    value). The block's constants come from `core.simulate.Model`, as for a run, so a member at the
    nominal values has the nominal row exactly. Returns ``(params, restitution per member)``."""
    params = params.copy()
    n = params.shape[0]
    one = np.ones(n)
    size, slender, friction = values.get("size", one), values.get("slenderness", one), values.get("friction", one)
    width, height = case.block.width * size * slender, case.block.height * size
    mu, nu = case.contact.mu_static * friction, case.contact.mu_kinetic * friction
    restitution = (np.clip(values["restitution"], 0.0, 1.0) if "restitution" in values
                   else np.full(n, case.contact.restitution))
    for i in range(n):
        set_model(params[i], Model.from_block(float(width[i]), float(height[i]), float(mu[i]), float(nu[i]),
                                              float(restitution[i]), case.gravity, case.block.mass))
    return params, restitution


#: The attributes of the ensemble's dimension ``member`` in its files and datasets.
MEMBER_ATTRS = {"units": "1", "long_name": "member of the ensemble"}


def compute(eplan: EnsemblePlan, nominal_overturned: bool, **where) -> tuple[dict, tuple, dict]:
    """Compute the members on the engine (`engine.execute.execute`, with ``where``: the store,
    workers, scheduler, device, progress). Returns the summary (`summarise`), the dimension
    ``member`` as ``(name, values, attributes)`` and the members' variables (`member_variables`)."""
    done = execute(eplan.plan, **where)
    variables = sw.sweep_variables(eplan.plan, done.states)
    members = ("member", np.arange(eplan.n), dict(MEMBER_ATTRS))
    return summarise(eplan, variables, nominal_overturned), members, member_variables(eplan, variables)


def wilson_interval(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """The Wilson score interval of a proportion ``k / n`` (Wilson 1927; Brown, Cai and DasGupta
    2001 recommend it over the normal approximation, which collapses at 0 and n): with ``z`` the
    normal quantile, ``(p + z^2 / 2n +- z sqrt(p (1 - p) / n + z^2 / 4 n^2)) / (1 + z^2 / n)``.
    ``(nan, nan)`` for ``n = 0``."""
    if n == 0:
        return math.nan, math.nan
    from scipy.stats import norm

    z = float(norm.ppf(0.5 + confidence / 2.0))
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def summarise(eplan: EnsemblePlan, variables: dict, nominal_overturned: bool) -> dict:
    """The ensemble's statistics (`sweep.sweep_variables` of its members) as plain data: the JSON's
    ``ensemble`` object and the result file's ``ensemble`` attribute.

    Keys: ``n``, ``seed``, ``quantities`` (each distribution as the case file writes it),
    ``defaults``, ``n_within_model`` (members with status ok), ``n_overturned``, ``p_overturn``,
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
    ok = status == K.STATUS_OK
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
        "n_within_model": n_ok, "n_overturned": k, "p_overturn": k / n_ok if n_ok else math.nan,
        "interval": [low, high], "confidence": CONFIDENCE,
        "n_undecided": int(np.ravel(variables["undecided"][0])[ok].sum()),
        "rotation_ratio": {"median": float(quantiles[0]), "p05": float(quantiles[1]), "p95": float(quantiles[2])},
        "sensitivity": sensitivity, "most_sensitive": most,
        "nominal_overturned": bool(nominal_overturned), "flips": flips, "robust": flips == 0 and n_ok == eplan.n,
        "integration_step": eplan.plan.step,
        "step": {} if eplan.plan.step_study is None else eplan.plan.step_study.attributes(),
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
    outside = n - summary["n_within_model"]
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
                 "max_slip", "end_time"):
        values, attrs = variables[name]
        out[name] = (("member",), np.ravel(values), attrs)
    return out
