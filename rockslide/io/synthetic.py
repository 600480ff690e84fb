"""Synthetic accelerograms the project makes itself (for the shipped example, tests and benchmarks).

A stationary Kanai-Tajimi ground motion (white noise through a soil filter of frequency
``omega_g`` and damping ``zeta_g``, plus a Clough-Penzien high-pass to keep velocities bounded),
shaped by the Jennings envelope (rise, strong phase, exponential decay). Seeded, so the same
arguments always give the same record.

References: Kanai (1957), Tajimi (1960), Clough & Penzien (1975); Jennings, Housner & Tsai (1968).
"""

from __future__ import annotations

import numpy as np
from scipy import signal


def jennings_envelope(time, rise: float, strong_end: float, decay: float):
    """``(t/rise)^2`` up to ``rise``, 1 until ``strong_end``, then ``exp(-decay (t - strong_end))``."""
    t = np.asarray(time, float)
    return np.where(t < rise, (t / rise) ** 2, np.where(t < strong_end, 1.0, np.exp(-decay * (t - strong_end))))


def kanai_tajimi(duration: float, dt: float, *, seed: int, omega_g: float = 2 * np.pi * 2.5,
                 zeta_g: float = 0.6, omega_f: float = 2 * np.pi * 0.25, zeta_f: float = 0.6,
                 rise: float = 2.0, strong_end: float = 8.0, decay: float = 0.5):
    """A non-stationary Kanai-Tajimi / Clough-Penzien accelerogram, unit peak.

    Parameters
    ----------
    duration, dt : float
        [s] length and sampling step.
    seed : int
        Random seed.
    omega_g, zeta_g : float
        [rad/s], [-] soil filter (dominant frequency, damping).
    omega_f, zeta_f : float
        [rad/s], [-] Clough-Penzien high-pass filter.
    rise, strong_end, decay : float
        Jennings envelope: [s], [s], [1/s].

    Returns
    -------
    numpy.ndarray
        Accelerations with peak |a| = 1 (scale afterwards), ``round(duration/dt) + 1`` samples.
    """
    n = int(round(duration / dt)) + 1
    noise = np.random.default_rng(seed).standard_normal(n)
    # Kanai-Tajimi: H(s) = (2 zeta_g omega_g s + omega_g^2) / (s^2 + 2 zeta_g omega_g s + omega_g^2)
    kt = signal.cont2discrete(([2 * zeta_g * omega_g, omega_g ** 2], [1, 2 * zeta_g * omega_g, omega_g ** 2]),
                              dt, method="bilinear")
    # Clough-Penzien: H(s) = s^2 / (s^2 + 2 zeta_f omega_f s + omega_f^2)
    cp = signal.cont2discrete(([1, 0, 0], [1, 2 * zeta_f * omega_f, omega_f ** 2]), dt, method="bilinear")
    a = signal.lfilter(np.ravel(kt[0]), kt[1], noise)
    a = signal.lfilter(np.ravel(cp[0]), cp[1], a)
    a *= jennings_envelope(np.arange(n) * dt, rise, strong_end, decay)
    a -= np.linspace(a[0], a[-1], n)         # start and end at exactly zero
    return a / np.max(np.abs(a))


def example_pair(duration: float = 20.0, dt: float = 0.01, seed: int = 1995):
    """The shipped example's horizontal and vertical records [g]: peaks 0.6 g and 0.3 g, the
    vertical with a stiffer soil filter (higher frequency content), as real records usually show."""
    horizontal = 0.6 * kanai_tajimi(duration, dt, seed=seed)
    vertical = 0.3 * kanai_tajimi(duration, dt, seed=seed + 1, omega_g=2 * np.pi * 6.0, zeta_g=0.5)
    return horizontal, vertical


#: The shipped synthetic suite (``records/suite-synthetic``): name -> (seed, soil frequency [Hz],
#: soil damping, strong phase end [s], duration [s], horizontal peak [g]). Soft to firm soils,
#: short to long strong phases; each vertical has a stiffer soil filter (2.4 times the frequency)
#: and half the horizontal peak.
SUITE = {
    "kt01": (2101, 1.5, 0.4, 10.0, 25.0, 0.35),
    "kt02": (2102, 2.5, 0.6, 8.0, 20.0, 0.45),
    "kt03": (2103, 4.0, 0.6, 6.0, 18.0, 0.30),
    "kt04": (2104, 6.0, 0.5, 5.0, 15.0, 0.55),
    "kt05": (2105, 2.0, 0.3, 12.0, 25.0, 0.25),
    "kt06": (2106, 3.0, 0.5, 7.0, 20.0, 0.40),
}


def suite_pair(name: str, dt: float = 0.01):
    """One record of the synthetic suite (`SUITE`): horizontal and vertical accelerations [g]."""
    seed, frequency, damping, strong_end, duration, peak = SUITE[name]
    horizontal = peak * kanai_tajimi(duration, dt, seed=seed, omega_g=2 * np.pi * frequency, zeta_g=damping,
                                     strong_end=strong_end)
    vertical = 0.5 * peak * kanai_tajimi(duration, dt, seed=seed + 100, omega_g=2 * np.pi * 2.4 * frequency,
                                         zeta_g=0.5, strong_end=strong_end)
    return horizontal, vertical
