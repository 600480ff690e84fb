"""From a fragility curve and a site's hazard curve to an annual rate of reaching a damage state
(``rockslide risk``). Pure numerics (numpy, scipy): no files, no figures.

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
from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr, ndtr

#: Fraction of the rate below which the hazard curve's ends are of no consequence (no note).
NEGLIGIBLE = 1e-3
#: Points of the disaggregation's density per hazard interval (for the curve drawn).
DENSITY_POINTS = 8


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


@dataclass(frozen=True)
class Lognormal:
    """``P(F | x) = Phi(ln(x / median) / beta)``; ``median`` [SI of the IM], ``beta`` [-]."""

    median: float
    beta: float

    def __call__(self, x) -> np.ndarray:
        return ndtr(np.log(np.asarray(x, dtype=np.float64) / self.median) / self.beta)

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
        log_width = log_ndtr(high) + np.log(-np.expm1(log_ndtr(low) - log_ndtr(high)))
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
        inner = self.levels[(self.levels > x[0]) & (self.levels < x[-1])]
        # a fragility level within rounding of a hazard level is that level (no piece of width ~0)
        near = np.searchsorted(x, inner)
        apart = np.minimum(np.abs(np.log(inner / x[near - 1])), np.abs(np.log(x[near] / inner))) > 1e-9
        grid = np.unique(np.r_[x, inner[apart]])
        below, at = self._sides(grid)
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
    p = fragility(curve.levels)
    lam = curve.rates
    integrals = fragility.piece_integrals(curve)
    # eq. (1) on each interval, by parts: P_i lambda_i - P_{i+1} lambda_{i+1} + integral lambda dP
    contributions = np.r_[p[:-1] * lam[:-1] - p[1:] * lam[1:] + integrals, p[-1] * lam[-1]]
    total = float(p[0] * lam[0] + integrals.sum())
    return Rate(rate=total, missing=float(lam[-1] * (1.0 - p[-1])), contributions=contributions,
                below=float(p[0] * lam[0]))


def rate_range(fragilities, curve: HazardCurve) -> tuple[float, float]:
    """The smallest and largest ``lambda_F`` [1/yr] over ``fragilities`` (e.g. the fits of bootstrap
    resamples, or a grid over the intervals of median and beta)."""
    values = [rate(f, curve).rate for f in fragilities]
    return float(min(values)), float(max(values))


def lognormal_box(median_interval, beta_interval, points: int = 9) -> list[Lognormal]:
    """Lognormals on a ``points x points`` grid (geometric in the median, linear in beta) over the
    rectangle of two intervals: `rate_range` over them bounds the rate over that rectangle."""
    medians = np.geomspace(*median_interval, points)
    betas = np.linspace(*beta_interval, points)
    return [Lognormal(float(m), float(b)) for m in medians for b in betas]


def density(fragility, curve: HazardCurve, points: int = DENSITY_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """The integrand of eq. (1) per unit of ``ln x``, ``P(F | x) k_i lambda(x)`` [1/yr], at
    ``points`` levels per interval of the hazard curve (geometric): ``(levels, density)``."""
    u = np.log(curve.levels)
    steps = np.linspace(0.0, 1.0, points + 1)[:-1]
    grid = np.r_[(u[:-1, None] + np.diff(u)[:, None] * steps).ravel(), u[-1]]
    x = np.exp(grid)
    k = np.r_[np.repeat(curve.slopes, points), curve.slopes[-1]]
    return x, fragility(x) * k * curve.rate(x)


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
