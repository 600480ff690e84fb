"""Exact reference solutions shared by the exact-solution and convergence tests (not a test module).

Everything here is independent of rockslide's kernel: scipy quadrature and root finding of the
closed forms of docs/model.md ('Reference solutions for tests').
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from rockslide.core import physics as P


def quarter_period(theta0, alpha, p2):
    """Time [s] for free rocking released at rest from ``theta0`` to reach ``theta = 0``:
    ``integral_0^theta0 dtheta / sqrt(2 p^2 (cos(alpha - theta0) - cos(alpha - theta)))``.

    Computed without cancellation: with ``theta = theta0 - u^2`` the integrand is finite,
    ``cos(alpha - theta0) - cos(alpha - theta) = 2 sin(alpha - theta0 + u^2/2) sin(u^2/2)`` and
    ``u / sqrt(sin(u^2/2)) -> sqrt(2)``. Relative accuracy ~1e-13 (quad's ``epsrel``).
    """
    def integrand(u):
        v = 0.5 * u * u
        ratio = math.sqrt(2.0) if v == 0.0 else u / math.sqrt(math.sin(v))
        return 2.0 * ratio / math.sqrt(4.0 * p2 * math.sin(alpha - theta0 + v))

    value, _ = quad(integrand, 0.0, math.sqrt(theta0), epsabs=0.0, epsrel=1e-13, limit=200)
    return value


def landing_rate(theta0, alpha, p2):
    """``|thetadot|`` [rad/s] on landing after a release at rest from ``theta0`` (energy):
    ``thetadot^2 = 2 p^2 (cos(alpha - theta0) - cos(alpha))``, written without cancellation."""
    return math.sqrt(2.0 * p2 * 2.0 * math.sin(alpha - 0.5 * theta0) * math.sin(0.5 * theta0))


def peak_angle(rate, alpha, p2):
    """The angle [rad] reached after lifting off from ``theta = 0`` at ``rate`` [rad/s] (inverse of
    `landing_rate`, by Brent's method to the float resolution)."""
    target = rate * rate / (2.0 * p2)
    if target == 0.0:
        return 0.0

    def f(th):
        return 2.0 * math.sin(alpha - 0.5 * th) * math.sin(0.5 * th) - target

    return brentq(f, 0.0, alpha, xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500)


def free_rocking_impacts(theta0, alpha, p2, e, n):
    """Times [s] of the first ``n`` impacts of free rocking released at rest from ``|theta0|``
    with restitution ``e`` (each impact multiplies the rate by ``e``; between impacts the block
    rises to the peak of the reduced energy and falls back: twice its quarter period)."""
    times = [quarter_period(abs(theta0), alpha, p2)]
    rate = landing_rate(abs(theta0), alpha, p2)
    for _ in range(n - 1):
        rate *= e
        times.append(times[-1] + 2.0 * quarter_period(peak_angle(rate, alpha, p2), alpha, p2))
    return np.array(times)


def time_to_angle_under_constant_push(theta1, a, alpha, p2):
    """Time [s] for a block lifting off from rest under a constant ground acceleration ``a = |ah|/g``
    (no vertical motion, no slip, ``a > tan(alpha)``) to reach ``theta1``.

    Energy in ROCK: ``thetadot^2 = 2 p^2 (cos(alpha) - cos(alpha - theta) + a (sin(alpha) -
    sin(alpha - theta)))`` which vanishes linearly at ``theta = 0``; with ``theta = u^2`` the
    integrand ``2 u / sqrt(...)`` is finite.
    """
    def rate2(th):
        # cos(alpha) - cos(alpha - th) = -2 sin(alpha - th/2) sin(th/2)
        # sin(alpha) - sin(alpha - th) = 2 cos(alpha - th/2) sin(th/2)
        return 2.0 * p2 * 2.0 * math.sin(0.5 * th) * (a * math.cos(alpha - 0.5 * th)
                                                      - math.sin(alpha - 0.5 * th))

    def integrand(u):
        if u == 0.0:
            return 2.0 / math.sqrt(2.0 * p2 * (a * math.cos(alpha) - math.sin(alpha)))
        return 2.0 * u / math.sqrt(rate2(u * u))

    value, _ = quad(integrand, 0.0, math.sqrt(theta1), epsabs=0.0, epsrel=1e-13, limit=200)
    return value


def mechanical_energy(model, history):
    """Mechanical energy per unit mass [J/kg] along a history, with rockslide.core.physics' functions:
    ``theta = |phi|``, ``lam = sign(phi)``, ``thetadot = lam * phidot``."""
    R, alpha, _ = model.constants
    phi = history["rotation"]
    out = np.empty(phi.size)
    for i in range(phi.size):
        lam = -1.0 if phi[i] < 0.0 else 1.0
        theta = abs(phi[i])
        out[i] = (P.kinetic_energy(theta, lam * history["rotation_rate"][i], history["slip_rate"][i],
                                   lam, R, alpha)
                  + P.potential_energy(theta, model.gravity, R, alpha))
    return out
