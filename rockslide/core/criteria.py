"""Mode-initiation criteria (the paper's Figure 5): which motion a block at rest starts under a
ground acceleration held constant.

From eq. 11 (slip), eq. 6 (liftoff) and, once liftoff starts, eq. 26 (is friction sufficient to
hold the pivot: ``|Rx/N| <= mu`` at ``theta = thetadot = 0``), evaluated with the same functions the
solvers use (`physics.slip_margin`, `physics.liftoff_margin`, `physics.rock_acceleration`,
`physics.contact_forces`). The tie between slip and liftoff goes to slip (model.md decision 1), and
from slip, liftoff needs ``nu > tan(alpha)`` (eq. 23), which ``nu <= mu < tan(alpha)`` excludes.
"""

from __future__ import annotations

import numpy as np

from .physics import (
    REST,
    ROCK,
    ROCKSLIP,
    SLIP,
    block_constants,
    contact_forces,
    liftoff_margin,
    rock_acceleration,
    slip_margin,
)

MODE_NAMES = {REST: "rest", SLIP: "slip", ROCK: "liftoff", ROCKSLIP: "liftoff-slip"}


def initial_mode(ah: float, av: float, mu: float, half_width: float, half_height: float,
                 gravity: float = 9.80665) -> int:
    """The state a resting block enters under constant ``ah``, ``av`` [m/s^2] with friction ``mu``.

    Returns a state code: REST, SLIP, ROCK (liftoff) or ROCKSLIP (liftoff-slip, eq. 26 violated).
    """
    R, alpha, _ = block_constants(half_width, half_height, gravity)
    G = gravity + av
    slips = slip_margin(mu, G, ah) < 0.0
    lifts = liftoff_margin(half_width / half_height, G, ah) < 0.0
    if slips and (not lifts or mu <= half_width / half_height):
        return SLIP          # slip first, or tie (decision 1); liftoff from slip needs nu > tan(alpha)
    if not lifts:
        return REST
    lam = 1.0 if ah > 0.0 else -1.0
    thetaddot = rock_acceleration(0.0, ah, G, lam, R, alpha)
    Rx, N = contact_forces(0.0, 0.0, thetaddot, ah, G, lam, R, alpha)
    return ROCKSLIP if slip_margin(mu, N, Rx) < 0.0 else ROCK


def sufficient_friction(ah: float, av: float, half_width: float, half_height: float,
                        gravity: float = 9.80665) -> float:
    """``|Rx/N|`` at the start of liftoff (eq. 26): the friction needed to hold the pivot [-]."""
    R, alpha, _ = block_constants(half_width, half_height, gravity)
    G = gravity + av
    lam = 1.0 if ah >= 0.0 else -1.0
    thetaddot = rock_acceleration(0.0, ah, G, lam, R, alpha)
    Rx, N = contact_forces(0.0, 0.0, thetaddot, ah, G, lam, R, alpha)
    return abs(Rx / N)


def mode_map(ah_over_g, mu_values, av_over_g: float, half_width: float, half_height: float,
             gravity: float = 9.80665) -> np.ndarray:
    """State codes over a grid: rows ``mu_values``, columns ``ah_over_g`` (both 1-D) at one
    vertical acceleration ``av_over_g`` (in g)."""
    ah_over_g = np.asarray(ah_over_g, float)
    mu_values = np.asarray(mu_values, float)
    out = np.empty((mu_values.size, ah_over_g.size), dtype=np.int8)
    for i, mu in enumerate(mu_values):
        for j, a in enumerate(ah_over_g):
            out[i, j] = initial_mode(a * gravity, av_over_g * gravity, mu, half_width, half_height, gravity)
    return out


def mode_boundaries(ah_over_g, av_over_g: float, half_width: float, half_height: float,
                    gravity: float = 9.80665, points: int = 2001) -> list:
    """The boundaries between the regions of `mode_map`, as lines in its plane (``|A_h|/g`` across,
    ``mu`` up), from the same criteria (the closed forms, not the grid's cells).

    With ``G = g (1 + A_v/g)`` and ``tan(alpha) = b/h``: slip starts where ``mu G = |A_h|`` (eq.
    11), below ``mu = b/h`` (above it liftoff comes first); liftoff where ``|A_h| = (b/h) G`` (eq.
    6), above ``mu = b/h``; beyond it, the line ``mu = b/h`` parts slip from liftoff, and the
    friction liftoff needs (`sufficient_friction`, eq. 26) parts liftoff from liftoff-slip, drawn
    where it is above ``b/h``.

    Parameters
    ----------
    ah_over_g : 1-D array
        The map's horizontal accelerations [g]: the lines span its range.
    av_over_g : float
        Vertical acceleration [g], above -1.
    half_width, half_height : float
        ``b``, ``h`` [m].
    points : int
        Points of the curved boundary (eq. 26) over the range.

    Returns
    -------
    list of (x, y)
        Polylines, ``x`` in g, ``y`` friction coefficients (NaN where a line is absent).
    """
    ah_over_g = np.asarray(ah_over_g, float)
    a_max = float(ah_over_g.max())
    scale = 1.0 + av_over_g
    tan_alpha = half_width / half_height
    lift = tan_alpha * scale                        # |A_h| / g where liftoff starts
    lines = [(np.array([0.0, min(lift, a_max)]), np.array([0.0, min(lift, a_max) / scale]))]
    if lift < a_max:
        lines.append((np.array([lift, a_max]), np.array([tan_alpha, tan_alpha])))
        lines.append((np.array([lift, lift]), np.array([tan_alpha, np.inf])))
        a = np.linspace(lift, a_max, points)[1:]
        needed = np.array([sufficient_friction(x * gravity, av_over_g * gravity, half_width, half_height,
                                               gravity) for x in a])
        lines.append((a, np.where(needed > tan_alpha, needed, np.nan)))
    return lines
