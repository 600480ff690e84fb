"""Mode-initiation criteria (the paper's Figure 5): which motion a block at rest starts under a
ground acceleration held constant.

From eq. 11 (slip), eq. 6 (liftoff) and, once liftoff starts, eq. 26 (is friction sufficient to
hold the pivot: ``|Rx/N| <= mu`` at ``theta = thetadot = 0``), evaluated with the same functions the
solvers use (`physics.slip_margin`, `physics.liftoff_margin`, `physics.rock_acceleration`,
`physics.contact_forces`). The tie between slip and liftoff goes to slip (model.md decision 1), and
from slip, liftoff needs ``nu > tan(alpha)`` (eq. 23), which ``nu <= mu < tan(alpha)`` excludes.
"""

from __future__ import annotations

import math

import numpy as np

from .physics import (
    REST,
    ROCK,
    ROCKSLIP,
    SLIP,
    block_constants,
    contact_forces,
    contact_forces_sc,
    liftoff_margin,
    rock_acceleration,
    rock_acceleration_k,
    slip_margin,
)

MODE_NAMES = {REST: "rest", SLIP: "slip", ROCK: "liftoff", ROCKSLIP: "liftoff-slip"}


def initial_mode(ah: float, av: float, mu: float, half_width: float, half_height: float,
                 gravity: float = 9.80665, half_width_2: float | None = None,
                 radius_of_gyration: float | None = None) -> int:
    """The state a resting block enters under constant ``ah``, ``av`` [m/s^2] with friction ``mu``.

    An asymmetric body (``half_width_2`` = ``b2``, or a ``radius_of_gyration`` about its centre of
    mass; model-asymmetric.md sections 1-3) pivots about corner 1 (``half_width`` = ``b1``) under
    ``ah > 0`` and about corner 2 under ``ah < 0``: eq. 6 with that corner's ``b_i / h``, eq. 3 with
    its ``R_i / rho_i^2`` (`rock_acceleration_k`), eq. 26 with its ``R_i``, ``alpha_i``.

    Returns a state code: REST, SLIP, ROCK (liftoff) or ROCKSLIP (liftoff-slip, eq. 26 violated).
    """
    if half_width_2 is not None or radius_of_gyration is not None:
        return _body_mode(ah, av, mu, half_width, half_height, gravity, half_width_2, radius_of_gyration)
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


def _pivot(ah: float, b1: float, h: float, b2, k) -> tuple[float, float, float, float]:
    """The pivot an asymmetric body turns about under ``ah`` and its constants: ``(lam, b_i, R_i,
    kr_i = R_i / rho_i^2)`` (model-asymmetric.md section 1; ``k`` None: the uniform rectangle's)."""
    b2 = b1 if b2 is None else b2
    lam, b = (1.0, b1) if ah >= 0.0 else (-1.0, b2)
    k2 = k * k if k is not None else ((0.5 * (b1 + b2)) ** 2 + h * h) / 3.0
    R = math.sqrt(b * b + h * h)
    return lam, b, R, R / (k2 + R * R)


def _body_start(ah: float, G: float, b1: float, h: float, b2, k) -> tuple[float, float, float]:
    """``(b_i / h, Rx, N)``: the corner's slenderness and the contact forces per unit mass at the
    start of liftoff (eqs. 3, 19, 20 about the corner ``ah`` turns the body on)."""
    lam, b, R, kr = _pivot(ah, b1, h, b2, k)
    s, c = b / R, h / R                                     # sin, cos of alpha_i at theta = 0
    thetaddot = rock_acceleration_k(s, c, ah, G, lam, kr)
    Rx, N = contact_forces_sc(s, c, 0.0, thetaddot, ah, G, lam, R)
    return b / h, Rx, N


def _body_mode(ah, av, mu, b1, h, gravity, b2, k) -> int:
    G = gravity + av
    tan_alpha, Rx, N = _body_start(ah, G, b1, h, b2, k)
    slips = slip_margin(mu, G, ah) < 0.0
    lifts = liftoff_margin(tan_alpha, G, ah) < 0.0
    if slips and (not lifts or mu <= tan_alpha):
        return SLIP
    if not lifts:
        return REST
    return ROCKSLIP if slip_margin(mu, N, Rx) < 0.0 else ROCK


def sufficient_friction(ah: float, av: float, half_width: float, half_height: float,
                        gravity: float = 9.80665, half_width_2: float | None = None,
                        radius_of_gyration: float | None = None) -> float:
    """``|Rx/N|`` at the start of liftoff (eq. 26): the friction needed to hold the pivot [-]; of an
    asymmetric body about the corner ``ah`` turns it on (`initial_mode`)."""
    if half_width_2 is not None or radius_of_gyration is not None:
        _, Rx, N = _body_start(ah, gravity + av, half_width, half_height, half_width_2, radius_of_gyration)
        return abs(Rx / N)
    R, alpha, _ = block_constants(half_width, half_height, gravity)
    G = gravity + av
    lam = 1.0 if ah >= 0.0 else -1.0
    thetaddot = rock_acceleration(0.0, ah, G, lam, R, alpha)
    Rx, N = contact_forces(0.0, 0.0, thetaddot, ah, G, lam, R, alpha)
    return abs(Rx / N)


def mode_map(ah_over_g, mu_values, av_over_g: float, half_width: float, half_height: float,
             gravity: float = 9.80665, **body) -> np.ndarray:
    """State codes over a grid: rows ``mu_values``, columns ``ah_over_g`` (both 1-D) at one
    vertical acceleration ``av_over_g`` (in g); ``body``: `initial_mode`'s ``half_width_2`` and
    ``radius_of_gyration`` (a signed ``ah_over_g`` then shows both corners)."""
    ah_over_g = np.asarray(ah_over_g, float)
    mu_values = np.asarray(mu_values, float)
    out = np.empty((mu_values.size, ah_over_g.size), dtype=np.int8)
    for i, mu in enumerate(mu_values):
        for j, a in enumerate(ah_over_g):
            out[i, j] = initial_mode(a * gravity, av_over_g * gravity, mu, half_width, half_height, gravity, **body)
    return out


def mode_boundaries(ah_over_g, av_over_g: float, half_width: float, half_height: float,
                    gravity: float = 9.80665, points: int = 2001, half_width_2: float | None = None,
                    radius_of_gyration: float | None = None) -> list:
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

    half_width_2, radius_of_gyration : float, optional
        An asymmetric body (`initial_mode`): each side of a signed ``ah_over_g`` has its corner's
        lines (``b1`` where ``A_h > 0``, ``b2`` mirrored where ``A_h < 0``).

    Returns
    -------
    list of (x, y)
        Polylines, ``x`` in g, ``y`` friction coefficients (NaN where a line is absent).
    """
    ah_over_g = np.asarray(ah_over_g, float)
    if half_width_2 is not None or radius_of_gyration is not None:
        body = {"half_width_2": half_width_2, "radius_of_gyration": radius_of_gyration}
        lines = []
        for sign, b in ((1.0, half_width), (-1.0, half_width if half_width_2 is None else half_width_2)):
            reach = float(np.max(sign * ah_over_g, initial=0.0))
            if reach <= 0.0:
                continue
            side = _side_boundaries(reach, av_over_g, b / half_height, points,
                                    lambda a, sign=sign: sufficient_friction(sign * a * gravity, av_over_g * gravity,
                                                                             half_width, half_height, gravity, **body))
            lines += [(sign * x, y) for x, y in side]
        return lines
    a_max = float(ah_over_g.max())
    return _side_boundaries(a_max, av_over_g, half_width / half_height, points,
                            lambda a: sufficient_friction(a * gravity, av_over_g * gravity, half_width, half_height,
                                                          gravity))


def _side_boundaries(a_max: float, av_over_g: float, tan_alpha: float, points: int, friction) -> list:
    """`mode_boundaries` over ``|A_h|`` in ``[0, a_max]`` [g] of a corner of slenderness
    ``tan_alpha``, with ``friction(|A_h|/g)`` the friction liftoff needs (eq. 26)."""
    scale = 1.0 + av_over_g
    lift = tan_alpha * scale                        # |A_h| / g where liftoff starts
    lines = [(np.array([0.0, min(lift, a_max)]), np.array([0.0, min(lift, a_max) / scale]))]
    if lift < a_max:
        lines.append((np.array([lift, a_max]), np.array([tan_alpha, tan_alpha])))
        lines.append((np.array([lift, lift]), np.array([tan_alpha, np.inf])))
        a = np.linspace(lift, a_max, points)[1:]
        needed = np.array([friction(x) for x in a])
        lines.append((a, np.where(needed > tan_alpha, needed, np.nan)))
    return lines
