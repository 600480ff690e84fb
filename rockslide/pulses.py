"""Analytic ground-motion pulses: shapes, their sampling, and the small-angle theory of overturning.

A pulse is a ground motion defined by a formula instead of a record file (`Pulse`; in a case file
``ground.horizontal: {pulse: one-sine, amplitude: 0.5 g, period: 0.4 s}``). Near-fault records are
pulse-like, and the rocking literature reads a block's safety off its response to pulses
(Housner 1963; Zhang and Makris 2001). Every shape starts at ``t = 0`` and is zero after its
length ``L``. With ``A`` the amplitude:

============== =========== ============================================ ==============================
shape          parameter   acceleration on ``0 <= t <= L``              length ``L``, frequency ``w_p``
============== =========== ============================================ ==============================
rectangular    duration    ``A`` (an exact step up at 0, down at ``L``) ``duration``; ``pi / L``
half-sine      duration    ``A sin(pi t / L)``                          ``duration``; ``pi / L``
one-sine       period      ``A sin(w_p t)``, one cycle                  ``period``; ``2 pi / T``
cycloidal-a    period      ``A sin(w_p t)`` (Zhang and Makris' type A)  ``cycles * period``; ``2 pi / T``
cycloidal-b    period      ``A cos(w_p t)`` (type B; steps at both ends) ``cycles * period``; ``2 pi / T``
ricker         period      ``A (1 - 2 u^2) exp(-u^2)``,                 ``2 x_c T``; ``2 pi / T``
                           ``u = pi (t - L/2) / T``
============== =========== ============================================ ==============================

A one-sine is a type-A cycloidal pulse of one cycle. The Ricker wavelet's Fourier amplitude peaks
at the frequency ``1 / T``; it is cut at ``t - L/2 = +-x_c T`` where it falls to
`INTERPOLATION_TOLERANCE` of its amplitude (``x_c = 1.325``), a step of that size.

**Sampling** (`sample`). The core takes ground motion interval by interval, linear inside an
interval and free to jump at its ends (`rockslide.core.simulate.ground_array`, ``(2, n)`` interval
end values). A pulse is sampled on a uniform grid whose points include every kink and step of it
(its start and its end), so steps are exact (no ramp) and piecewise-linear shapes (the
rectangular pulse) are represented exactly. Curved shapes are interpolated linearly between the
samples, whose error on an interval of length ``D`` is at most ``D^2 max|a''| / 8``; the step is
the largest that keeps it within `INTERPOLATION_TOLERANCE` (one part per million) of the
amplitude, ``D <= sqrt(8e-6 A / max|a''|)`` (``max|a''| = A w_p^2`` for the sines,
``6 A (pi / T)^2`` for the Ricker wavelet), and no larger than the solver's step. At the default
0.1 ms step this costs nothing for ``w_p <= 28 rad/s`` (sine periods from 0.22 s up) and samples
shorter pulses more finely. The response's error from it is of the same relative size (up to
1.6e-6 on Newmark's slip under a half-sine, `tests/test_pulse_closed_forms.py`), far below the
resolution of any spectrum. Two pulses (horizontal and vertical) share
one grid: the ratio of their lengths must be a fraction with a denominator of at most
`MAX_DENOMINATOR`.

**Theory** (`linear_overturning_ratio`). For a slender block (small ``alpha``) that pivots without
sliding, ``theta'' = p^2 (theta - alpha + lam ah / g)``: the small-angle equation of Housner (1963)
that Zhang and Makris (2001) solve for their overturning spectra. It gives the amplitude above
which a pulse overturns the block without an impact, drawn over computed overturning spectra.

numpy only: this module knows no case file, record or solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

__all__ = ["SHAPES", "Pulse", "Sampled", "grid", "sample", "common_intervals", "linear_overturning_ratio",
           "INTERPOLATION_TOLERANCE", "MAX_DENOMINATOR"]

#: Largest error of the linear interpolation between samples, relative to the amplitude.
INTERPOLATION_TOLERANCE = 1e-6
#: Two pulses share a grid when the ratio of their lengths is a fraction with at most this denominator.
MAX_DENOMINATOR = 1000


@dataclass(frozen=True)
class Shape:
    """What a pulse shape takes and how long it lasts.

    Attributes
    ----------
    parameter : str
        ``"duration"`` or ``"period"``: the time that sets its length.
    cycles : bool
        Whether it takes a number of cycles.
    doc : str
        One line for messages and the README.
    """

    parameter: str
    cycles: bool
    doc: str


#: The shapes, by the name a case file gives (``pulse:``).
SHAPES: dict[str, Shape] = {
    "rectangular": Shape("duration", False, "constant amplitude for the duration, exact steps at both ends"),
    "half-sine": Shape("duration", False, "half a sine wave lasting the duration"),
    "one-sine": Shape("period", False, "one full sine cycle of the period (cycloidal-a, one cycle)"),
    "cycloidal-a": Shape("period", True, "sine cycles (Zhang and Makris' type A: a forward velocity pulse)"),
    "cycloidal-b": Shape("period", True, "cosine cycles (type B: a forward-and-back velocity pulse)"),
    "ricker": Shape("period", False, "Ricker wavelet whose spectrum peaks at 1/period"),
}


def _ricker_cut(tolerance: float) -> float:
    """``x_c > 0.4``: where ``(2 pi^2 x^2 - 1) exp(-pi^2 x^2)``, decreasing there, equals ``tolerance``."""
    lo, hi = 0.4, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if (2.0 * math.pi ** 2 * mid * mid - 1.0) * math.exp(-math.pi ** 2 * mid * mid) > tolerance:
            lo = mid
        else:
            hi = mid
    return hi


RICKER_CUT = _ricker_cut(INTERPOLATION_TOLERANCE)


def _sin_turns(x: np.ndarray) -> np.ndarray:
    """``sin(2 pi x)``, exactly 0 at multiples of 1/2 and exactly +-1 at odd multiples of 1/4 (so that
    a sine pulse ends at exactly zero, without a spurious step of 1e-16)."""
    r = x - np.round(x)                                  # [-1/2, 1/2]
    r = np.where(r > 0.25, 0.5 - r, np.where(r < -0.25, -0.5 - r, r))
    return np.sin(2.0 * math.pi * r)


@dataclass(frozen=True)
class Pulse:
    """An analytic ground-acceleration pulse (the module notes give the shapes).

    Attributes
    ----------
    pulse : str
        The shape, a key of `SHAPES`.
    amplitude : float
        ``A`` [m/s^2]: the peak (signed: a negative amplitude mirrors the pulse).
    duration : float, optional
        [s] for the shapes that take a duration.
    period : float, optional
        ``T`` [s] for the shapes that take a period.
    cycles : int
        Number of cycles (cycloidal shapes), >= 1.
    """

    pulse: str
    amplitude: float
    duration: float | None = None
    period: float | None = None
    cycles: int = 1

    @property
    def length(self) -> float:
        """``L`` [s]: the pulse lasts from 0 to ``L``."""
        if self.pulse in ("rectangular", "half-sine"):
            return float(self.duration)
        if self.pulse == "ricker":
            return 2.0 * RICKER_CUT * self.period
        return self.cycles * self.period

    @property
    def frequency(self) -> float:
        """``w_p`` [rad/s]: ``pi / duration`` (half-sine convention) or ``2 pi / period``."""
        if SHAPES[self.pulse].parameter == "duration":
            return math.pi / self.duration
        return 2.0 * math.pi / self.period

    def with_frequency(self, frequency: float) -> Pulse:
        """The same pulse with its duration or period set for the frequency ``w_p`` [rad/s]."""
        if SHAPES[self.pulse].parameter == "duration":
            return replace(self, duration=math.pi / frequency)
        return replace(self, period=2.0 * math.pi / frequency)

    @property
    def curvature(self) -> float:
        """``max |a''| / |A|`` [1/s^2]; 0 for the rectangular pulse (piecewise constant)."""
        if self.pulse == "rectangular":
            return 0.0
        if self.pulse == "ricker":
            return 6.0 * (math.pi / self.period) ** 2
        return self.frequency ** 2

    def unit(self, s: np.ndarray) -> np.ndarray:
        """The pulse at amplitude 1 at times ``s L`` (``0 <= s <= 1``, both ends included: the
        values just after the start and just before the end)."""
        s = np.asarray(s, dtype=np.float64)
        if self.pulse == "rectangular":
            return np.ones_like(s)
        if self.pulse == "half-sine":
            return _sin_turns(0.5 * s)
        if self.pulse in ("one-sine", "cycloidal-a"):
            return _sin_turns(self.cycles * s)
        if self.pulse == "cycloidal-b":
            return _sin_turns(self.cycles * s + 0.25)
        if self.pulse == "ricker":
            u2 = (math.pi * RICKER_CUT * (2.0 * s - 1.0)) ** 2
            return (1.0 - 2.0 * u2) * np.exp(-u2)
        raise ValueError(f"unknown pulse shape {self.pulse!r}")

    def max_step(self) -> float:
        """[s] the largest sampling step that keeps the interpolation within tolerance."""
        c = self.curvature
        return math.inf if c == 0.0 else math.sqrt(8.0 * INTERPOLATION_TOLERANCE / c)


def common_intervals(lengths) -> int:
    """The smallest number of intervals ``q`` of the longest length that puts the end of every
    other length on the grid: the common denominator of the length ratios.

    Raises
    ------
    ValueError
        A ratio is not a fraction with a denominator of at most `MAX_DENOMINATOR` (within 1e-9).
    """
    from fractions import Fraction

    lengths = [float(x) for x in lengths]
    longest = max(lengths)
    q = 1
    for length in lengths:
        ratio = length / longest
        fraction = Fraction(ratio).limit_denominator(MAX_DENOMINATOR)
        if abs(ratio - float(fraction)) > 1e-9 * ratio:
            raise ValueError(f"the lengths {length:g} s and {longest:g} s have no common sampling step "
                             f"(their ratio must be a fraction p/q with q <= {MAX_DENOMINATOR}, e.g. "
                             "0.2 s and 0.5 s)")
        q = q * fraction.denominator // math.gcd(q, fraction.denominator)
    return q


def grid(horizontal: Pulse | None, vertical: Pulse | None, max_step: float) -> tuple[int, float]:
    """The sampling grid of `sample`: ``(N, dt)``, ``N`` intervals of ``dt`` [s] over the longer
    pulse: the smallest ``N`` that keeps ``dt`` within ``max_step`` and every pulse's
    `Pulse.max_step` and puts every pulse's end on the grid (a multiple of `common_intervals`)."""
    pulses = [p for p in (horizontal, vertical) if p is not None]
    if not pulses:
        raise ValueError("no pulse")
    length = max(p.length for p in pulses)
    q = common_intervals([p.length for p in pulses])
    step = min([max_step] + [p.max_step() for p in pulses])
    n = q * max(1, math.ceil(length / (q * step) * (1.0 - 1e-12)))
    return n, length / n


class Sampled(NamedTuple):
    """Pulses sampled by `sample`."""

    start: float                 # [s] time of the first sample: -dt (one interval of still ground)
    dt: float                    # [s] the sampling step (`grid`)
    horizontal: np.ndarray       # float64[2, N + 1]: interval start and end values, amplitude 1
    vertical: np.ndarray         # the same


def sample(horizontal: Pulse | None, vertical: Pulse | None, max_step: float) -> Sampled:
    """The pulses at amplitude 1 on one grid (`grid`), as the core's interval end values.

    The grid starts one interval before the pulses, at ``-dt``, with still ground, so that a step
    at the start (a rectangular or type-B pulse) is a jump inside the ground motion, as the one at
    the end, and shows in the ground written back with the results.

    Parameters
    ----------
    horizontal, vertical : Pulse or None
        At least one. Their amplitudes are not used: the caller multiplies by them (a pulse's
        amplitude is its scale factor, exactly as a record's).
    max_step : float
        [s] the largest sampling step wanted (the solver's step).

    Returns
    -------
    Sampled
        ``horizontal`` and ``vertical`` are ``float64[2, N + 1]``: the value at the start and at the
        end of each interval (`rockslide.core.simulate.ground_array`); zeros for an absent pulse,
        before the start and after a pulse's end.
    """
    n, dt = grid(horizontal, vertical, max_step)
    longest = max(p.length for p in (horizontal, vertical) if p is not None)

    def intervals(pulse):
        out = np.zeros((2, n + 1))
        if pulse is None:
            return out
        j = n if pulse.length == longest else round(pulse.length / dt)
        values = pulse.unit(np.arange(j + 1) / j)
        out[0, 1:j + 1] = values[:-1]
        out[1, 1:j + 1] = values[1:]
        return out

    return Sampled(-dt, dt, intervals(horizontal), intervals(vertical))


def linear_overturning_ratio(pulse: Pulse, frequency_ratio: float, *, largest: float = 200.0,
                             intervals: int = 2000) -> float:
    """The small-angle theory's least amplitude that overturns a block without impact.

    A block that pivots without sliding obeys, for small ``alpha`` and ``theta`` (``sin``, ``tan``
    replaced by their argument; Housner 1963), ``theta'' = p^2 (theta - alpha + lam ah / g)`` once
    ``|ah| > g alpha`` lifts it about the edge ``lam = sign(ah)``. With ``u = theta / alpha - 1`` and
    ``r = A / (g alpha)``: ``u'' = p^2 (u + r lam f(t))``, ``f`` the pulse at amplitude 1. The
    combination ``q = u + u' / p`` obeys ``q' = p (q + r lam f)``; after the pulse ``q`` grows or
    decays as ``exp(p t)``, so the block overturns without impact exactly when ``q >= 0`` at the end
    of the pulse and ``theta > 0`` until then (Zhang and Makris 2001 for cycloidal pulses). Both are
    integrated exactly for the pulse interpolated linearly between ``intervals`` samples.

    Parameters
    ----------
    pulse : Pulse
        The shape (its amplitude and duration or period are not used).
    frequency_ratio : float
        ``w_p / p``.
    largest : float
        The largest ``A / (g alpha)`` searched.
    intervals : int
        Samples of the pulse (its interpolation error is about ``(w_p L / intervals)^2 / 8``).

    Returns
    -------
    float
        ``A / (g alpha)`` on the boundary of overturning without impact, or NaN when no amplitude up
        to ``largest`` overturns the block without an impact (the theory has no boundary there).
    """
    shape = pulse.with_frequency(frequency_ratio)          # time in units of 1/p
    if shape.length > 600.0:                               # exp(p L) would overflow
        return math.nan
    f = shape.unit(np.arange(intervals + 1) / intervals)
    theory = _SmallAngle(f, shape.length / intervals)
    ratios = np.geomspace(1.0 + 1e-9, largest, 100)
    values = np.array([theory.margin(r) for r in ratios])
    found = np.flatnonzero(values >= 0.0)
    if found.size == 0 or found[0] == 0:
        return math.nan
    lo, hi = ratios[found[0] - 1], ratios[found[0]]
    while hi - lo > 1e-13 * hi:
        mid = 0.5 * (lo + hi)
        if theory.margin(mid) >= 0.0:
            hi = mid
        else:
            lo = mid
    return float(hi)


def _piece_integrals(start, width, value, slope, end):
    """``int e^{-s} F ds`` and ``int e^{s - end} F ds`` over ``[start, start + width]`` for the linear
    ``F = value + slope (s - start)``, exactly."""
    decay, grow = -np.expm1(-width), np.expm1(width)              # 1 - e^{-W}, e^{W} - 1
    minus = np.exp(-start) * (value * decay + slope * (decay - width * np.exp(-width)))
    plus = np.exp(start - end) * (value * grow + slope * (width * np.exp(width) - grow))
    return minus, plus


class _SmallAngle:
    """`linear_overturning_ratio`'s equation under one pulse ``f`` sampled every ``dt`` (time in
    units of ``1/p``), for any ``r = A / (g alpha)``.

    With ``F = r lam f`` from the liftoff ``t0`` on, ``q' = q + F`` and ``w' = -w - F`` for
    ``q = u + u'``, ``w = u - u'`` (``u = (q + w) / 2``), ``q = w = -1`` at ``t0``:
    ``q(t) e^{-t} = -e^{-t0} + int_{t0}^t e^{-s} F ds`` and
    ``w(t) e^{t - L} = -e^{t0 - L} - int_{t0}^t e^{s - L} F ds``; the integrals of ``f`` from 0 to
    every sample are computed once (`_piece_integrals`), so each ``r`` costs a few array operations.
    """

    def __init__(self, f: np.ndarray, dt: float):
        self.f, self.dt = f, dt
        self.t = dt * np.arange(f.size)
        self.end = self.t[-1]
        self.slope = np.diff(f) / dt
        minus, plus = _piece_integrals(self.t[:-1], dt, f[:-1], self.slope, self.end)
        self.minus = np.concatenate([[0.0], np.cumsum(minus)])
        self.plus = np.concatenate([[0.0], np.cumsum(plus)])

    def margin(self, r: float) -> float:
        """``q(L) e^{-L}``: >= 0 when the block overturns without impact; NaN when ``|r f|`` never
        exceeds 1 or the block (``u = -1``) lands before the pulse ends."""
        f = self.f
        over = np.flatnonzero(np.abs(r * f) > 1.0)
        if over.size == 0:
            return math.nan
        k = max(int(over[0]) - 1, 0)          # liftoff inside interval k, where |r f| exceeds 1
        lam = 1.0 if f[over[0]] > 0.0 else -1.0
        a, b = lam * r * f[k], lam * r * f[k + 1]
        frac = 0.0 if a > 1.0 else (1.0 - a) / (b - a)
        t0 = self.t[k] + frac * self.dt
        minus, plus = _piece_integrals(self.t[k], frac * self.dt, f[k], self.slope[k], self.end)
        after = slice(k + 1, None)                            # the samples after the liftoff
        q = -math.exp(-t0) + r * lam * (self.minus[after] - self.minus[k] - minus)          # q e^{-t}
        w = -math.exp(t0 - self.end) - r * lam * (self.plus[after] - self.plus[k] - plus)   # w e^{t - L}
        u = 0.5 * (q * np.exp(self.t[after]) + w * np.exp(self.end - self.t[after]))
        if np.any(u[:-1] < -1.0 - 1e-9):           # landed (round-off aside: u starts at -1)
            return math.nan
        return float(q[-1])
