"""From a fragility curve and a site's hazard curve to an annual rate of reaching a damage state
(``rockslide risk``). Pure numerics (numpy; the normal distribution of `core.normal`): no files, no figures.

The rate of the damage state F at a site is the fragility integrated over the hazard curve,

    lambda_F = integral of P(F | x) |d lambda(x)|,                                        (1)

where ``lambda(x)`` [1/yr] is the annual rate at which the intensity measure (IM) exceeds ``x``
and ``P(F | x)`` the fragility. Integrating (1) by parts gives the same number as the hazard curve
averaged over the capacity ``C`` whose distribution function is the fragility,

    lambda_F = P(F | x_0) lambda(x_0) + integral_{x_0}^{x_m} lambda(x) dP(F | x),            (2)

which is how it is computed here, with what lies outside the hazard curve's levels
``x_0 ... x_m`` treated so:

- **above** ``x_m`` the rate is not given: the capacities above ``x_m`` (probability
  ``1 - P(F | x_m)``) would add at most ``lambda(x_m) (1 - P(F | x_m))`` (`missing_rate`). Eq. (2)
  counts the motions above ``x_m`` as failing with ``P(F | x_m)`` (a fragility does not fall), so
  it is a lower bound, short by at most that much; the command warns when it matters.
- **below** ``x_0``: capacities below ``x_0`` are counted at ``lambda(x_0)``, a lower bound again
  (their rate is at least that); the note `below_note` says when ``P(F | x_0)`` is not negligible.

**Interpolation and integration.** Between two levels of the hazard curve the rate is a power
law, ``lambda(x) = lambda_i (x / x_i)^(-k_i)`` (linear in log-log), as hazard curves are
interpolated in practice; a rate of 0 has no logarithm and is refused by the readers. With that
hazard curve, (2) is integrated exactly, in closed form, segment by segment (no quadrature):

- a lognormal fragility ``Phi(ln(x / theta) / beta)`` (`Lognormal`): on a segment, with
  ``u = ln x``, ``integral lambda_i exp(-k_i (u - u_i)) phi((u - ln theta) / beta) du / beta =
  lambda_i exp(k_i (u_i - ln theta) + k_i^2 beta^2 / 2) [Phi((u - ln theta) / beta + k_i beta)]``;
  for a power law over all x this is the closed form ``k0 theta^-k exp(k^2 beta^2 / 2)``;
- a tabulated fragility (`Tabulated`: the empirical stripes, or a step), linear in ``ln x``
  between its points, constant outside them, with jumps where a level repeats: on a piece of
  slope ``s = dP/du``, ``s lambda_a (1 - exp(-k Delta u)) / k``; a jump ``Delta P`` at ``x`` adds
  ``Delta P lambda(x)``. A step at ``theta`` gives ``lambda(theta)`` exactly.

The result therefore depends on the hazard curve only through its own interpolation: the power
law ``k0 x^-k`` sampled at 20 or at 200 levels gives the same rate to rounding.

**Disaggregation** (`disaggregate`): the part of (1) from each interval of the hazard curve
``[x_i, x_{i+1}]`` (motions with the IM in it that reach the state) and the tail above ``x_m``
counted as in (2); they sum to ``lambda_F``. Its density ``d lambda_F / d ln x = P(F | x) k_i
lambda(x)`` is `density`.

**Over a time** ``T`` (a Poisson process of rate ``lambda_F``): the probability of at least one
occurrence ``1 - exp(-lambda_F T)`` (`probability_in`), the return period ``1 / lambda_F``; for a
precariously balanced rock that has stood for its age ``T_age`` the probability of surviving that
long ``exp(-lambda_F T_age)`` (`survival`): a hazard curve under which it is below ``1 -
confidence`` is rejected at that confidence (Baker et al. 2013, Anooshehpoor et al. 2013: the
hazard branches under which the rock would have toppled with more than 95 % probability).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.normal import log_normal_cdf, normal_cdf
from ..errors import CaseError, numbers_from

#: Fraction of the rate below which the hazard curve's ends are of no consequence (no note).
NEGLIGIBLE = 1e-3
#: Intervals of the hazard curve the printout names, those that contribute most first.
TOP_INTERVALS = 3
#: Relative distance [-] within which a tabulated fragility's level is a hazard level (`Tabulated.snapped`):
#: far above the rounding of levels computed in floating point (~1e-15), far below any spacing of them.
SNAP = 1e-9
#: The logarithmic standard deviations [-] of a lognormal fragility that `rate` takes (`beta_problem`).
#: Below 1e-3 the capacity would be known to 0.1 %, finer than any hazard curve's levels are, and
#: the closed form's terms underflow (beta 1e-300 gave NaN); above 5 one standard deviation spans a
#: factor e^10 (2e4) about the median, wider than a hazard curve's levels (0.005 ... 5 g is 1e3):
#: the rate would say only what the curve's ends do, and (k beta)^2 overflows for beta ~1e154.
#: Fitted fragilities have 0.1 ... 1.5 (FEMA P-58's 0.2 ... 0.8; rocking blocks' 0.3 ... 0.8).
BETA_RANGE = (1e-3, 5.0)
#: Levels the disaggregation's density is given at (geometric over the hazard curves' levels).
DENSITY_POINTS = 400


# --------------------------------------------------------------------------------------------------
# Hazard curves
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HazardCurve:
    """A hazard curve: annual rates of exceedance at increasing IM levels.

    Attributes
    ----------
    name : str
        Which curve (a site, a branch, a quantile).
    levels : numpy.ndarray
        [SI of the IM] increasing, positive.
    rates : numpy.ndarray
        [1/yr] the annual rate at which the IM exceeds each level: positive, not increasing.
    """

    name: str
    levels: np.ndarray
    rates: np.ndarray

    @property
    def slopes(self) -> np.ndarray:
        """``k_i = -d ln(lambda) / d ln(x)`` on each interval (``len(levels) - 1``)."""
        return -np.diff(np.log(self.rates)) / np.diff(np.log(self.levels))

    def rate(self, x) -> np.ndarray:
        """``lambda(x)`` [1/yr], log-log interpolated; NaN outside the levels."""
        x = np.asarray(x, dtype=np.float64)
        inside = (x >= self.levels[0]) & (x <= self.levels[-1])
        log_rate = np.interp(np.log(np.where(inside, x, self.levels[0])), np.log(self.levels),
                             np.log(self.rates))
        return np.where(inside, np.exp(log_rate), np.nan)

    def scaled(self, factor: float) -> HazardCurve:
        """Every rate times ``factor``."""
        return HazardCurve(self.name, self.levels, self.rates * factor)


# --------------------------------------------------------------------------------------------------
# Fragilities
# --------------------------------------------------------------------------------------------------


#: The fragility models `rockslide risk --model` takes from a fragility file.
MODELS = ("lognormal", "isotonic", "empirical")


def evidence(levels, fractions, isotonic=None) -> dict:
    """What a fragility file's stripes say for `FragilityUsed`: ``first_exceedance`` (the lowest
    level with a fraction above 0) and ``highest_tested`` [SI of the IM], and ``stripes``: the
    isotonic curve as a `Tabulated` (``isotonic`` as stored; else pooled with equal weights, as a
    file of an older version has no counts per level). Levels without runs (NaN) are left out."""
    levels = np.asarray(levels, dtype=np.float64)
    fractions = np.asarray(fractions, dtype=np.float64)
    known = np.isfinite(fractions)
    if not known.any():
        return {"first_exceedance": None, "highest_tested": float(levels[-1]), "stripes": None}
    if isotonic is None or not np.isfinite(np.asarray(isotonic, dtype=np.float64)[known]).all():
        from .goodness import isotonic as pava
        isotonic = pava(np.where(known, 1.0, 0.0), np.where(known, fractions, 0.0))
    isotonic = np.asarray(isotonic, dtype=np.float64)
    hit = np.flatnonzero(known & (fractions > 0))
    return {"first_exceedance": float(levels[hit[0]]) if hit.size else None, "highest_tested": float(levels[-1]),
            "stripes": Tabulated(levels[known], isotonic[known])}


def beta_problem(beta) -> str:
    """Why ``beta`` [-] is not a lognormal fragility's logarithmic standard deviation that `rate`
    takes (not a number, or outside `BETA_RANGE`), or "" when it is."""
    low, high = BETA_RANGE
    try:
        value = float(beta)
    except (TypeError, ValueError):
        value = math.nan
    if low <= value <= high:
        return ""
    shown = f"{value:g}" if not math.isnan(value) else repr(beta) if not isinstance(beta, float) else "NaN"
    return (f"beta {shown} is not within {low:g} ... {high:g}: below, the capacity would be known more finely "
            "than a hazard curve's levels; above, its spread would be wider than their range (fitted fragilities "
            "have 0.1 ... 1.5)")


@dataclass(frozen=True)
class Lognormal:
    """``P(F | x) = Phi(ln(x / median) / beta)``; ``median`` [SI of the IM], ``beta`` [-]."""

    median: float
    beta: float

    def __call__(self, x) -> np.ndarray:
        return normal_cdf(np.log(np.asarray(x, dtype=np.float64) / self.median) / self.beta)

    def snapped(self, levels) -> Lognormal:
        """Itself: a lognormal has no levels to move (`Tabulated.snapped`)."""
        return self

    def piece_integrals(self, curve: HazardCurve) -> np.ndarray:
        """``integral lambda dP`` over each interval ``(x_i, x_{i+1}]`` of ``curve`` [1/yr]: the closed
        form of the module docstring, in logarithms (no overflow of ``exp(k^2 beta^2 / 2)``)."""
        u = np.log(curve.levels)
        mu, beta, k = math.log(self.median), self.beta, curve.slopes
        a = (u[:-1] - mu) / beta + k * beta
        b = (u[1:] - mu) / beta + k * beta
        # Phi(b) - Phi(a) from the side where both are small (no cancellation of numbers near 1)
        upper = a > 0
        low, high = np.where(upper, -b, a), np.where(upper, -a, b)
        log_width = log_normal_cdf(high) + np.log(-np.expm1(log_normal_cdf(low) - log_normal_cdf(high)))
        return np.exp(np.log(curve.rates[:-1]) + k * (u[:-1] - mu) + 0.5 * (k * beta) ** 2 + log_width)


@dataclass(frozen=True)
class Tabulated:
    """A fragility given at levels: linear in ``ln x`` between them, constant outside them; a
    level given twice is a jump (right-continuous: the second value holds at the level).

    Attributes
    ----------
    levels : numpy.ndarray
        [SI of the IM] positive, not decreasing.
    probabilities : numpy.ndarray
        ``P(F | level)`` within 0 ... 1.
    """

    levels: np.ndarray
    probabilities: np.ndarray

    @classmethod
    def step(cls, threshold: float) -> Tabulated:
        """``P(F | x) = 1`` for ``x >= threshold``, else 0: a capacity known exactly."""
        return cls(np.array([threshold, threshold]), np.array([0.0, 1.0]))

    def snapped(self, levels) -> Tabulated:
        """The fragility with each of its levels within `SNAP` (relative) of one of ``levels`` (a
        hazard curve's) moved onto it: a jump that close to a hazard level is at that level, not
        in a piece of width ~0 beside it (where its ``Delta P`` would be lost or spread over the
        next interval). The order of the levels is kept (moving onto the nearest is monotonic)."""
        levels = np.asarray(levels, dtype=np.float64)
        nearest = np.clip(np.searchsorted(levels, self.levels), 1, levels.size - 1)
        below, above = levels[nearest - 1], levels[nearest]
        target = np.where(np.abs(np.log(self.levels / below)) <= np.abs(np.log(above / self.levels)), below, above)
        close = np.abs(np.log(self.levels / target)) <= SNAP
        if not close.any():
            return self
        return Tabulated(np.where(close, target, self.levels), self.probabilities)

    def _sides(self, x):
        """``P`` just below and at ``x`` (they differ at a jump)."""
        u = np.log(np.asarray(x, dtype=np.float64))
        levels, p = np.log(self.levels), self.probabilities
        return self._linear(u, levels, p, "left"), self._linear(u, levels, p, "right")

    @staticmethod
    def _linear(u, levels, p, side: str):
        """Linear between the points around ``u`` (left: the first of a repeated level counts, the
        left limit; right: the last), constant outside."""
        found = np.searchsorted(levels, u, side=side)
        j = np.clip(found, 1, levels.size - 1)
        u0, u1 = levels[j - 1], levels[j]
        width = np.where(u1 > u0, u1 - u0, 1.0)
        value = p[j - 1] + np.clip((u - u0) / width, 0.0, 1.0) * (p[j] - p[j - 1])
        return np.where(found == 0, p[0], np.where(found == levels.size, p[-1], value))

    def __call__(self, x) -> np.ndarray:
        return self._sides(x)[1]

    def piece_integrals(self, curve: HazardCurve) -> np.ndarray:
        """``integral lambda dP`` over each interval ``(x_i, x_{i+1}]`` of ``curve`` [1/yr], exactly:
        the intervals cut at the fragility's levels, where ``P`` is linear in ``ln x`` and
        ``lambda`` a power law."""
        x = curve.levels
        own = self.snapped(x)
        grid = np.unique(np.r_[x, own.levels[(own.levels > x[0]) & (own.levels < x[-1])]])
        below, at = own._sides(grid)
        rate = curve.rate(grid)
        u = np.log(grid)
        du = np.diff(u)
        k = -np.diff(np.log(rate)) / du
        slope = (below[1:] - at[:-1]) / du
        # s lambda_a (1 - exp(-k du)) / k, written with expm1 so that k -> 0 gives s lambda_a du
        kdu = k * du
        factor = np.where(np.abs(kdu) > 1e-12, -np.expm1(-kdu) / np.where(kdu == 0, 1.0, kdu), 1.0) * du
        pieces = slope * rate[:-1] * factor + (at[1:] - below[1:]) * rate[1:]
        owner = np.searchsorted(x, grid[1:], side="left") - 1     # the hazard interval of each piece
        return np.bincount(owner, weights=pieces, minlength=x.size - 1)


# --------------------------------------------------------------------------------------------------
# The rate and its pieces
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Rate:
    """The rate of a damage state under one hazard curve (`rate`).

    Attributes
    ----------
    rate : float
        [1/yr] ``lambda_F`` by eq. (2) (a lower bound where the hazard curve is truncated).
    missing : float
        [1/yr] the most that the capacities above the last level could add
        (``lambda(x_m) (1 - P(F | x_m))``).
    contributions : numpy.ndarray
        [1/yr] the part of ``lambda_F`` from each interval of the hazard curve (``len(levels) -
        1``) and, last, from the motions above ``x_m`` (at ``P(F | x_m)``); they sum to ``rate``.
    below : float
        [1/yr] the part counted for the capacities below the first level: ``P(F | x_0) lambda(x_0)``
        (a lower bound of theirs).
    """

    rate: float
    missing: float
    contributions: np.ndarray
    below: float


def rate(fragility, curve: HazardCurve) -> Rate:
    """``lambda_F``, eq. (2) of the module docstring, with its disaggregation and truncation bound.

    Parameters
    ----------
    fragility : Lognormal or Tabulated
    curve : HazardCurve
    """
    fragility = fragility.snapped(curve.levels)     # the same fragility for both terms of eq. (2)
    p = fragility(curve.levels)
    lam = curve.rates
    integrals = fragility.piece_integrals(curve)
    # eq. (1) on each interval, by parts: P_i lambda_i - P_{i+1} lambda_{i+1} + integral lambda dP
    contributions = np.r_[p[:-1] * lam[:-1] - p[1:] * lam[1:] + integrals, p[-1] * lam[-1]]
    total = float(p[0] * lam[0] + integrals.sum())
    return Rate(rate=total, missing=float(lam[-1] * (1.0 - p[-1])), contributions=contributions,
                below=float(p[0] * lam[0]))


def rate_below(fragility, curve: HazardCurve, x: float) -> float:
    """The part of ``lambda_F`` [1/yr] from motions with the IM below ``x`` [SI]: eq. (1) over the
    hazard curve's levels up to ``x`` (``x`` is put among the levels, where the curve's log-log
    interpolation is the curve itself). All of it from ``x`` above the last level (the tail is
    counted at ``P(F | x_m)``, eq. (2)); 0 at or below the first."""
    levels = curve.levels
    if x <= levels[0]:
        return 0.0
    if x > levels[-1]:
        return rate(fragility, curve).rate
    cut = HazardCurve(curve.name, np.unique(np.r_[levels, x]), np.empty(0))
    cut = HazardCurve(curve.name, cut.levels, curve.rate(cut.levels))
    parts = rate(fragility, cut).contributions
    return float(parts[:int(np.searchsorted(cut.levels, x))].sum())


@dataclass(frozen=True)
class RestsOn:
    """What a rate rests on (`rests_on`): shares of ``lambda_F`` [-] from where no run supports it.

    Attributes
    ----------
    below_first_exceedance : float
        From intensities below the lowest level at which any run reached the state.
    above_tested : float
        From intensities above the highest level tested (with the tail above the hazard curve).
    extrapolated : float
        Their sum.
    stripes_rate : float
        [1/yr] the rate with the per-level fractions made monotone (isotonic), NaN when not known.
    deviation : float
        ``rate / stripes_rate - 1`` for a fitted curve (NaN otherwise).
    """

    below_first_exceedance: float
    above_tested: float
    extrapolated: float
    stripes_rate: float = math.nan
    deviation: float = math.nan


#: A rate with more than this share from intensities where no run supports it draws a warning.
EXTRAPOLATED_WARNING = 0.10


def rests_on(fragility, curve: HazardCurve, total: float, *, first_exceedance: float | None,
             highest_tested: float | None, stripes=None) -> RestsOn:
    """The shares of ``total`` (the rate of ``fragility`` under ``curve``) from intensities below
    ``first_exceedance`` and above ``highest_tested`` [SI], and the rate of ``stripes`` (a
    `Tabulated` of the per-level fractions) to compare a fitted curve with."""
    if not total > 0:
        return RestsOn(math.nan, math.nan, math.nan)
    below = 0.0 if first_exceedance is None else rate_below(fragility, curve, first_exceedance) / total
    above = 0.0 if highest_tested is None else 1.0 - rate_below(fragility, curve, highest_tested) / total
    other = rate(stripes, curve).rate if stripes is not None else math.nan
    deviation = total / other - 1.0 if stripes is not None and other > 0 else math.nan
    return RestsOn(below, max(above, 0.0), below + max(above, 0.0), other, deviation)


def rate_range(fragilities, curve: HazardCurve, confidence: float | None = None) -> tuple[float, float]:
    """The range of ``lambda_F`` [1/yr] over ``fragilities``: with ``confidence``, its central
    percentile interval (the fragilities are samples, e.g. the fits of bootstrap resamples); without,
    the smallest and largest (e.g. over a grid spanning the intervals of median and beta)."""
    values = np.array([rate(f, curve).rate for f in fragilities])
    if confidence is None:
        return float(values.min()), float(values.max())
    tails = 50.0 * (1.0 - confidence)
    low, high = np.percentile(values, (tails, 100.0 - tails))
    return float(low), float(high)


def lognormal_box(median_interval, beta_interval, points: int = 9) -> list[Lognormal]:
    """Lognormals on a ``points x points`` grid (geometric in the median, linear in beta) over the
    rectangle of two intervals: `rate_range` over them bounds the rate over that rectangle."""
    medians = np.geomspace(*median_interval, points)
    betas = np.linspace(*beta_interval, points)
    return [Lognormal(float(m), float(b)) for m in medians for b in betas]


def density(fragility, curve: HazardCurve, x) -> np.ndarray:
    """The integrand of eq. (1) per unit of ``ln x``, ``P(F | x) k_i lambda(x)`` [1/yr], at the
    levels ``x`` [SI of the IM] (NaN outside the hazard curve's levels)."""
    x = np.asarray(x, dtype=np.float64)
    interval = np.clip(np.searchsorted(curve.levels, x, side="right") - 1, 0, curve.levels.size - 2)
    return fragility(x) * curve.slopes[interval] * curve.rate(x)


def density_grid(curves, points: int = DENSITY_POINTS) -> np.ndarray:
    """Levels [SI] to draw the densities of ``curves`` at: geometric over all their levels."""
    low = min(float(c.levels[0]) for c in curves)
    high = max(float(c.levels[-1]) for c in curves)
    return np.geomspace(low, high, points)


def probability_in(rate_per_year, years: float):
    """Probability of at least one occurrence in ``years`` [yr] of a Poisson process of rate
    ``rate_per_year`` [1/yr]: ``1 - exp(-lambda T)``."""
    return -np.expm1(-np.asarray(rate_per_year, dtype=np.float64) * years)


def return_period(rate_per_year):
    """``1 / lambda`` [yr] (infinite for a rate of 0)."""
    rate_per_year = np.asarray(rate_per_year, dtype=np.float64)
    with np.errstate(divide="ignore"):
        return np.where(rate_per_year > 0, 1.0 / rate_per_year, np.inf)


def survival(rate_per_year, age: float):
    """Probability that a rock stands for ``age`` [yr] under a rate ``rate_per_year`` [1/yr] of
    toppling: ``exp(-lambda T_age)``."""
    return np.exp(-np.asarray(rate_per_year, dtype=np.float64) * age)


def rejected(survival_probability, confidence: float):
    """Whether a hazard curve is rejected at ``confidence`` by a rock that stands: its survival
    probability is below ``1 - confidence`` (it would have toppled with more than ``confidence``)."""
    return np.asarray(survival_probability) < 1.0 - confidence


def below_note(result: Rate) -> str:
    """A note when the capacities below the first hazard level carry more than `NEGLIGIBLE` of
    the rate (their rate is only bounded from below), else ""."""
    if result.rate > 0 and result.below > NEGLIGIBLE * result.rate:
        return (f"{100 * result.below / result.rate:.2g} % of the rate comes from capacities below the hazard "
                "curve's first level, counted at that level's rate (a lower bound): extend the curve to lower "
                "levels")
    return ""


def truncated(result: Rate) -> bool:
    """Whether the motions above the hazard curve's last level could change the rate by more than
    `NEGLIGIBLE` of it."""
    return result.missing > NEGLIGIBLE * result.rate


# --------------------------------------------------------------------------------------------------
# The analysis, its dataset, its JSON and its printout
# --------------------------------------------------------------------------------------------------


@dataclass
class FragilityUsed:
    """The fragility of an analysis and where it comes from.

    Attributes
    ----------
    curve : Lognormal or Tabulated
    damage_state : str
        ``overturn``, ``rotation>0.5alpha``...
    source : str
        The fragility file, or ``--median/--beta``.
    form : str
        ``lognormal fit``, ``empirical stripes`` or ``lognormal given``.
    median, beta : float
        [SI of the IM], [-]: the lognormal's (NaN for the stripes).
    variants : list
        Fragilities spanning its uncertainty (`rate_range` over them); empty: none known.
    uncertainty : str
        How ``variants`` were made ("" without).
    variants_level : float or None
        The ``variants`` are samples: the rate's interval is their central percentile interval of
        this level. None: the rate's smallest and largest over them.
    along_block : bool
        Its intensity measure is of the motion along the block, from records of two horizontal
        components (the fragility file's suite says so).
    first_exceedance, highest_tested : float or None
        [SI of the IM] the lowest level at which any run reached the state and the highest level
        run (`rests_on`); None: not known (a lognormal given).
    stripes : Tabulated or None
        The per-level fractions made monotone (isotonic), to compare a fitted curve's rate with.
    rejection : str
        The goodness-of-fit test's sentence when it rejected the lognormal used ("" otherwise).
    vertical_note : str
        The fragility's runs left out the case's vertical record ("" otherwise).
    """

    curve: object
    damage_state: str
    source: str
    form: str
    median: float = math.nan
    beta: float = math.nan
    variants: list = field(default_factory=list)
    uncertainty: str = ""
    variants_level: float | None = None
    along_block: bool = False
    first_exceedance: float | None = None
    highest_tested: float | None = None
    stripes: object = None
    rejection: str = ""
    vertical_note: str = ""


@dataclass
class Analysis:
    """A fragility over hazard curves (`analyse`).

    Attributes
    ----------
    fragility : FragilityUsed
    measure : dict
        The IM: ``name``, ``units`` (SI), ``long_name``, ``label``, ``display_unit``, ``display_scale``.
    curves : list of HazardCurve
    about : list of dict
        Per curve: ``source``, ``kind``, ``lon``, ``lat``, ``investigation_time`` [yr] and, when
        known, ``dropped_low``, ``dropped_high``: the levels [SI] left out at its ends (`dropped_text`).
    results : list of Rate
    intervals : list of tuple
        Per curve, the rate's range over the fragility's uncertainty [1/yr] (NaNs: none).
    life : float
        [yr] the service life of ``probability_in``.
    age : float or None
        [yr] a precariously balanced rock's age.
    confidence : float
        Of the rejection of a hazard curve by the rock's survival.
    notes : list of str
        Conditions of the result printed once (`io.hazard.component_note`).
    rests : list of RestsOn
        Per curve, the shares of the rate where no run supports it (`rests_on`).
    """

    fragility: FragilityUsed
    measure: dict
    curves: list
    about: list
    results: list
    intervals: list
    life: float
    age: float | None
    confidence: float
    notes: list = field(default_factory=list)
    rests: list = field(default_factory=list)

    @property
    def rates(self) -> np.ndarray:
        return np.array([r.rate for r in self.results])

    @property
    def survivals(self) -> np.ndarray | None:
        return None if self.age is None else survival(self.rates, self.age)


def analyse(fragility: FragilityUsed, measure: dict, curves, about, *, life: float, age: float | None = None,
            confidence: float = 0.95, notes=()) -> Analysis:
    """The rate of ``fragility``'s damage state under each hazard curve, with its interval over the
    fragility's uncertainty (arguments as the attributes of `Analysis`)."""
    results, intervals = [], []
    for c, a in zip(curves, list(about) + [{}] * len(curves), strict=False):
        with numbers_from(str(a.get("source") or c.name), what="the rates of this hazard curve"):
            results.append(rate(fragility.curve, c))
            intervals.append(rate_range(fragility.variants, c, fragility.variants_level) if fragility.variants
                             else (math.nan, math.nan))
    rests = [rests_on(fragility.curve, c, r.rate, first_exceedance=fragility.first_exceedance,
                      highest_tested=fragility.highest_tested,
                      stripes=fragility.stripes if fragility.stripes is not fragility.curve else None)
             for c, r in zip(curves, results, strict=True)]
    notes = list(notes) + ([fragility.vertical_note] if fragility.vertical_note else [])
    return Analysis(fragility=fragility, measure=dict(measure), curves=list(curves), about=list(about),
                    results=results, intervals=intervals, life=life, age=age, confidence=confidence,
                    notes=notes, rests=rests)


def rests_text(r: RestsOn, fragility: FragilityUsed, show) -> str:
    """``rests on: 21 % of the rate from below 0.45 g (no run reached the state there), 3 % from
    above 0.75 g (beyond the levels run)``, with the per-level curve's rate for a fitted one; "" when
    nothing is known."""
    if fragility.first_exceedance is None and fragility.highest_tested is None or math.isnan(r.extrapolated):
        return ""
    parts = []
    if fragility.first_exceedance is not None:
        parts.append(f"{100 * r.below_first_exceedance:.3g} % of the rate from below {show(fragility.first_exceedance)}"
                     " (no run reached the state there)")
    if fragility.highest_tested is not None:
        parts.append(f"{100 * r.above_tested:.3g} % from above {show(fragility.highest_tested)} (beyond the levels "
                     "run)")
    text = "rests on: " + ", ".join(parts)
    if math.isfinite(r.stripes_rate):
        text += (f"; the per-level fractions (isotonic) give {r.stripes_rate:.4g} /yr, this curve "
                 f"{100 * r.deviation:+.3g} % from it")
    return text


INTEGRATION = ("lambda_F = integral of P(F|x) |d lambda(x)|, the hazard curve log-log interpolated between its "
               "levels (a power law on each interval) and integrated exactly in closed form; capacities below "
               "the first level counted at its rate, motions above the last at P(F|x_max) (a lower bound, short "
               "by at most rate_missing_max)")


def dataset(analysis: Analysis, command_line: str = "") -> tuple[list, dict, dict]:
    """``(coords, variables, attrs)`` of ``NAME.risk.h5`` (`io.results.write_dataset`) and of the
    API's dataset (`io.datasets.study_dataset`)."""
    im, f = analysis.measure, analysis.fragility
    n = max(c.levels.size for c in analysis.curves)
    grid = density_grid(analysis.curves)
    coords = [
        ("curve", np.array([c.name for c in analysis.curves], dtype=object),
         {"long_name": "hazard curve (site, branch or quantile)"}),
        ("point", np.arange(n, dtype=np.float64), {"long_name": "level of a hazard curve, in its order"}),
        ("im", grid, {"units": im["units"], "long_name": f"intensity level: {im['long_name']} (geometric grid "
                      "over the hazard curves' levels)"}),
    ]
    per_curve = ("curve",)
    padded = {name: np.full((len(analysis.curves), n), np.nan) for name in ("levels", "rates", "parts")}
    for i, (c, r) in enumerate(zip(analysis.curves, analysis.results, strict=True)):
        m = c.levels.size
        padded["levels"][i, :m], padded["rates"][i, :m], padded["parts"][i, :m] = c.levels, c.rates, r.contributions
    rates = analysis.rates
    missing = np.array([r.missing for r in analysis.results])
    intervals = np.array(analysis.intervals, dtype=np.float64).reshape(-1, 2)
    rate_unit = "1/yr"
    variables = {
        "rate": (per_curve, rates, {"units": rate_unit, "long_name": f"annual rate of the damage state {f.damage_state}"
                                    " (a lower bound where the hazard curve is truncated)"}),
        "rate_missing_max": (per_curve, missing, {"units": rate_unit, "long_name": "the most that the motions above "
                                                  "the hazard curve's last level could add: lambda(x_max) (1 - "
                                                  "P(F|x_max))"}),
        "rate_lower": (per_curve, intervals[:, 0], {"units": rate_unit, "long_name": "smallest rate over the "
                                                    "fragility's uncertainty (NaN: none known)"}),
        "rate_upper": (per_curve, intervals[:, 1], {"units": rate_unit, "long_name": "largest rate over the "
                                                    "fragility's uncertainty (NaN: none known)"}),
        "probability_in_life": (per_curve, probability_in(rates, analysis.life),
                                {"units": "1", "long_name": f"probability of the damage state in {analysis.life:g} "
                                 "years: 1 - exp(-rate T)"}),
        "return_period": (per_curve, return_period(rates), {"units": "yr", "long_name": "1 / rate"}),
        "below_rate": (per_curve, np.array([r.below for r in analysis.results]),
                       {"units": rate_unit, "long_name": "part of the rate from capacities below the first level "
                        "(counted at its rate: a lower bound)"}),
        "hazard_level": (("curve", "point"), padded["levels"], {"units": im["units"], "long_name": "the hazard "
                         "curve's intensity levels (NaN: past its last)"}),
        "hazard_rate": (("curve", "point"), padded["rates"], {"units": rate_unit, "long_name": "annual rate of "
                        "exceeding the level"}),
        "contribution": (("curve", "point"), padded["parts"], {"units": rate_unit, "long_name": "disaggregation: the "
                         "part of the rate from motions between this level and the next (at the last level: above "
                         "it, at P(F|x_max)); they sum to rate"}),
        "density": (("curve", "im"), np.array([density(f.curve, c, grid) for c in analysis.curves]),
                    {"units": rate_unit, "long_name": "disaggregation density d rate / d ln(x) = P(F|x) |d lambda / "
                     "d ln x| (NaN outside the curve's levels)"}),
        "fragility": (("im",), f.curve(grid), {"units": "1", "long_name": f"P({f.damage_state} | x): {f.form}"}),
        "curve_source": (per_curve, np.array([a["source"] for a in analysis.about], dtype=object),
                         {"long_name": "hazard file"}),
        "curve_kind": (per_curve, np.array([a["kind"] for a in analysis.about], dtype=object),
                       {"long_name": "OpenQuake's kind: mean, quantile-q, rlz-n (empty: a plain table)"}),
        "site_lon": (per_curve, np.array([a["lon"] for a in analysis.about], dtype=np.float64),
                     {"units": "degree", "long_name": "site longitude (NaN: not given)"}),
        "site_lat": (per_curve, np.array([a["lat"] for a in analysis.about], dtype=np.float64),
                     {"units": "degree", "long_name": "site latitude (NaN: not given)"}),
        "investigation_time": (per_curve, np.array([a["investigation_time"] for a in analysis.about],
                                                   dtype=np.float64),
                               {"units": "yr", "long_name": "OpenQuake's investigation time of the PoE (NaN: rates "
                                "given)"}),
    }
    if analysis.rests:
        for name, text in (("below_first_exceedance", "share of the rate from intensities below the lowest level at "
                            "which any run reached the state (NaN: not known)"),
                           ("above_tested", "share of the rate from intensities above the highest level run"),
                           ("extrapolated", "the two shares together")):
            variables[f"share_{name}"] = (per_curve, np.array([getattr(r, name) for r in analysis.rests]),
                                          {"units": "1", "long_name": text})
        variables["isotonic_rate"] = (per_curve, np.array([r.stripes_rate for r in analysis.rests]), {
            "units": rate_unit, "long_name": "rate with the per-level fractions made monotone (NaN: not computed)"})
    if analysis.age is not None:
        alive = analysis.survivals
        variables["survival"] = (per_curve, alive, {"units": "1", "long_name": f"probability of standing "
                                                    f"{analysis.age:g} years: exp(-rate T_age)"})
        variables["survival_lower"] = (per_curve, survival(intervals[:, 1], analysis.age),
                                       {"units": "1", "long_name": "survival probability at rate_upper (NaN: no "
                                        "interval)"})
        variables["survival_upper"] = (per_curve, survival(intervals[:, 0], analysis.age),
                                       {"units": "1", "long_name": "survival probability at rate_lower (NaN: no "
                                        "interval)"})
        variables["rejected"] = (per_curve, rejected(alive, analysis.confidence).astype(np.int8),
                                 {"units": "1", "long_name": f"the rock standing rejects the curve at "
                                  f"{analysis.confidence:.0%} confidence (survival < {1 - analysis.confidence:g})"})
    attrs = {
        "title": f"rockslide risk: {f.damage_state} of {f.source} under {len(analysis.curves)} hazard curve(s)",
        "command_line": command_line,
        "damage_state": f.damage_state,
        "fragility_source": f.source,
        "fragility_form": f.form,
        "fragility_median": f.median,
        "fragility_beta": f.beta,
        "fragility_uncertainty": f.uncertainty,
        "intensity_measure": im["name"],
        "intensity_measure_units": im["units"],
        "intensity_measure_label": im["label"],
        "intensity_measure_display_unit": im["display_unit"],
        "intensity_measure_display_scale": im["display_scale"],
        "service_life": analysis.life,
        "integration": INTEGRATION,
        "notes": "\n".join(analysis.notes),
    }
    if analysis.age is not None:
        attrs.update({"age": analysis.age, "confidence_level": analysis.confidence})
    return coords, variables, attrs


def json_summary(analysis: Analysis) -> dict:
    """The ``--json`` object: per curve its rate [1/yr] and what follows from it (null for NaN)."""
    def number(value):
        value = float(value)
        return value if math.isfinite(value) else None

    f = analysis.fragility
    survivals = analysis.survivals
    curves = []
    for i, (c, r) in enumerate(zip(analysis.curves, analysis.results, strict=True)):
        entry = {"curve": c.name, "rate": r.rate, "rate_missing_max": r.missing,
                 "rate_interval": [number(v) for v in analysis.intervals[i]],
                 "probability_in_life": float(probability_in(r.rate, analysis.life)),
                 "return_period": number(return_period(r.rate)), "truncated": truncated(r),
                 "contributions": {"levels": [float(v) for v in c.levels], "rate": [float(v) for v in r.contributions]},
                 "levels_left_out": {"poe_1": [float(v) for v in analysis.about[i].get("dropped_low", ())],
                                     "poe_0": [float(v) for v in analysis.about[i].get("dropped_high", ())]}}
        if analysis.rests:
            rest = analysis.rests[i]
            entry["rests_on"] = {"share_below_first_exceedance": number(rest.below_first_exceedance),
                                 "share_above_tested": number(rest.above_tested),
                                 "share_extrapolated": number(rest.extrapolated),
                                 "warning": bool(rest.extrapolated > EXTRAPOLATED_WARNING),
                                 "isotonic_rate": number(rest.stripes_rate), "deviation": number(rest.deviation)}
        if survivals is not None:
            entry.update({"survival": float(survivals[i]),
                          "survival_interval": [number(v) for v in survival(analysis.intervals[i][::-1], analysis.age)],
                          "rejected": bool(rejected(survivals[i], analysis.confidence))})
        curves.append(entry)
    return {"damage_state": f.damage_state, "fragility": {"source": f.source, "form": f.form,
                                                          "median": number(f.median), "beta": number(f.beta),
                                                          "uncertainty": f.uncertainty,
                                                          "first_exceedance": f.first_exceedance,
                                                          "highest_tested": f.highest_tested,
                                                          "rejected": f.rejection or None,
                                                          "vertical_note": f.vertical_note or None},
            "intensity_measure": analysis.measure["name"],
            "units": {"rate": "1/yr", "levels": analysis.measure["units"], "return_period": "yr"},
            "service_life": analysis.life, "age": analysis.age,
            "confidence": analysis.confidence if analysis.age is not None else None,
            "integration": INTEGRATION, "notes": list(analysis.notes), "curves": curves}


def summary_lines(analysis: Analysis, show) -> list[str]:
    """The printout: one line per curve, then the warnings of truncation; ``show(x)`` writes a
    level [SI] in its display unit."""
    f = analysis.fragility
    lines = [f"{f.damage_state}: {f.form} from {f.source}"] + [f"  note: {note}" for note in analysis.notes]
    survivals = analysis.survivals
    for i, (c, r) in enumerate(zip(analysis.curves, analysis.results, strict=True)):
        low, high = analysis.intervals[i]
        interval = f" ({low:.3g} ... {high:.3g})" if math.isfinite(low) else ""
        text = (f"  {c.name}: {r.rate:.4g} /yr{interval}, return period {float(return_period(r.rate)):.4g} yr, "
                f"{100 * float(probability_in(r.rate, analysis.life)):.3g} % in {analysis.life:g} yr")
        if survivals is not None:
            verdict = "rejected" if rejected(survivals[i], analysis.confidence) else "not rejected"
            spread = survival(np.array([high, low]), analysis.age)
            shown = f" ({spread[0]:.3g} ... {spread[1]:.3g})" if math.isfinite(low) else ""
            text += (f"; survives {analysis.age:g} yr with probability {survivals[i]:.3g}{shown}: {verdict} at "
                     f"{analysis.confidence:.0%}")
        lines.append(text)
        dropped = dropped_text(analysis.about[i], show)
        if dropped:
            lines.append(f"    {dropped}")
        if r.rate <= 0:
            lines.append("    no contribution")
            continue
        parts = []
        for top in np.argsort(r.contributions)[::-1][:TOP_INTERVALS]:
            where = (f"above {show(c.levels[-1])}" if top == c.levels.size - 1 else
                     f"{show(c.levels[top])} ... {show(c.levels[top + 1])}")
            parts.append(f"{where} {100 * r.contributions[top] / r.rate:.3g} %")
        lines.append("    most from " + ", ".join(parts))
        if analysis.rests:
            rests = rests_text(analysis.rests[i], f, show)
            if rests:
                lines.append(f"    {rests}")
    return lines


def dropped_text(about: dict, show) -> str:
    """What the readers' ``trim`` left out of a curve (``about`` as `Analysis.about`), or ""; ``show(x)``
    writes a level [SI]."""
    def levels(values) -> str:
        shown = show(values[0]) if len(values) == 1 else f"{show(values[0])} ... {show(values[-1])}"
        return f"{len(values)} level{'s' if len(values) > 1 else ''} ({shown})"

    low, high = about.get("dropped_low", ()), about.get("dropped_high", ())
    parts = ([f"{levels(low)} at the low end with PoE 1 (an infinite rate)"] if low else []) + \
        ([f"{levels(high)} at the high end with PoE 0"] if high else [])
    return "left out " + " and ".join(parts) if parts else ""


def warnings_of(analysis: Analysis, show) -> list[str]:
    """Truncation and lower-end notes, one per curve that has one."""
    out = []
    for c, r in zip(analysis.curves, analysis.results, strict=True):
        if truncated(r):
            out.append(f"{c.name}: the hazard curve ends at {show(c.levels[-1])} where P(F) is "
                       f"{float(analysis.fragility.curve(c.levels[-1])):.3g}: the rate {r.rate:.4g} /yr is a lower "
                       f"bound; the motions above could add at most {r.missing:.3g} /yr "
                       f"({100 * r.missing / r.rate:.3g} %); extend the hazard curve to higher levels"
                       if r.rate > 0 else f"{c.name}: the hazard curve ends at {show(c.levels[-1])} before the "
                       f"fragility rises; the rate could be up to {r.missing:.3g} /yr")
        note = below_note(r)
        if note:
            out.append(f"{c.name}: {note}")
    for c, rest in zip(analysis.curves, analysis.rests, strict=False):
        if rest.extrapolated > EXTRAPOLATED_WARNING:
            out.append(f"{c.name}: {100 * rest.extrapolated:.3g} % of the rate comes from intensities where no run "
                       f"supports the curve (below the first exceedance or above the levels run; more than "
                       f"{100 * EXTRAPOLATED_WARNING:g} %): it rests on the curve's shape there, not on the runs")
    if analysis.fragility.rejection:
        out.append(f"the fragility's {analysis.fragility.rejection}: the rate rests on a curve its runs reject; "
                   "compare --model isotonic")
    return out


_YEARS = {"": 1.0, "yr": 1.0, "y": 1.0, "a": 1.0, "year": 1.0, "years": 1.0, "ka": 1e3, "kyr": 1e3, "ma": 1e6,
          "myr": 1e6}


def parse_years(value, *, source: str) -> float:
    """A time span in years [yr]: a number, or ``50yr``, ``50 years``, ``24ka``, ``24 kyr``, ``1.2Ma``.

    Raises
    ------
    CaseError
        Naming ``source``: not a positive number of years.
    """
    text = str(value).strip()
    number = text.rstrip("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ ")
    unit = text[len(number):].strip().lower()
    try:
        years = float(number) * _YEARS[unit]
    except (ValueError, KeyError):
        raise CaseError(f"cannot read {text!r} as a time in years (e.g. 50, 50yr, 24ka, 1.2Ma)",
                        source=source) from None
    if not (math.isfinite(years) and years > 0):
        raise CaseError(f"must be a positive time, got {text!r}", source=source)
    return years


def figure(analysis: Analysis, *, size=None):
    """`plots.risk_figure` of an analysis: `stored_figure` of its dataset."""
    return stored_figure(*dataset(analysis), size=size)


def stored_figure(coords, variables, attrs, *, size=None):
    """`plots.risk_figure` of a risk file's ``(coords, variables, attrs)`` (`dataset`, or a file read
    back by `io.results.read_dataset`), levels in the measure's display unit; ``size`` as
    `plots.figure_size`."""
    from ..plots import risk_figure

    names = [str(n) for n in dict((name, values) for name, values, _ in coords)["curve"]]
    grid = np.asarray(dict((name, values) for name, values, _ in coords)["im"], dtype=np.float64)
    value = {name: np.asarray(v[1]) for name, v in variables.items()}
    scale, unit = float(attrs["intensity_measure_display_scale"]), str(attrs["intensity_measure_display_unit"])
    curves = []
    for i, name in enumerate(names):
        kept = np.isfinite(value["hazard_level"][i])
        lam = float(value["rate"][i])
        share = value["density"][i] * math.log(10.0) / lam if lam > 0 else np.full(grid.size, np.nan)
        curves.append({"label": f"{name}: λ_F = {lam:.3g} /yr", "levels": value["hazard_level"][i][kept] / scale,
                       "rates": value["hazard_rate"][i][kept], "share": share})
    state = str(attrs["damage_state"])
    return risk_figure(curves, grid / scale, value["fragility"], xlabel=f"{attrs['intensity_measure_label']}"
                       + (f" [{unit}]" if unit else ""), state=state, title=_figure_title(state, len(names)),
                       caption=_figure_caption(attrs, scale, unit), size=size)


def _figure_title(state: str, count: int) -> str:
    """What a risk figure draws, in words."""
    curves = "a hazard curve" if count == 1 else f"{count} hazard curves"
    return f"Annual rate of '{state}': {curves} and the fragility (top); where the rate comes from (bottom)"


def _figure_caption(attrs, scale: float, unit: str) -> str:
    """The fragility a risk figure integrates: its form, its file's name (not its path: the folder
    says nothing a reader of the figure needs) and its median and beta."""
    source = str(attrs["fragility_source"])
    name = Path(source).name if source.endswith(".h5") else source
    text = f"fragility: {attrs['fragility_form']} ({name})"
    median, beta = float(attrs["fragility_median"]), float(attrs["fragility_beta"])
    if math.isfinite(median) and math.isfinite(beta):
        text += f", median {median / scale:.3g}{' ' + unit if unit else ''}, β {beta:.2f}"
    return text
