"""The equations of the model, one implementation each.

Every function here is a pure function of plain floats, compiled with numba so that the fixed-step
kernel (`kernel.py`), the adaptive reference solver (`reference.py`) and the criteria maps
(`criteria.py`) all call the same code. Accelerations and forces are per unit mass [m/s^2].

Symbols follow the paper (Taniguchi) and `docs/model.md`:

- ``R`` [m]: distance from a bottom edge to the centre of gravity, ``sqrt(b^2 + h^2)``
- ``alpha`` [rad]: slenderness angle, ``atan(b/h)``
- ``theta`` [rad]: liftoff angle about the pivoting edge (``>= 0``)
- ``lam``: pivoting edge, +1 left (the right edge lifts), -1 right (eq. 4)
- ``sigma``: slip direction, ``sign(xdot)``
- ``ah``, ``av`` [m/s^2]: horizontal and vertical ground acceleration (up positive)
- ``G`` [m/s^2]: apparent gravity ``g + av``
"""

from __future__ import annotations

import math

from numba import njit

from . import compiled  # noqa: F401  (before any cache=True: numba needs a cache folder)
from .layout import (  # noqa: F401  (state codes and impact branches, re-exported: `physics.REST` etc.)
    IMPACT_BRANCHES,
    IMPACT_FLAT,
    IMPACT_NONE,
    IMPACT_PAINLEVE,
    IMPACT_SLIP,
    IMPACT_STICK,
    OVERTURNED,
    REST,
    ROCK,
    ROCKSLIP,
    SLIP,
    STATE_NAMES,
)


@njit(cache=True)
def block_constants(half_width, half_height, gravity):
    """Derived constants of a rectangular block.

    Parameters
    ----------
    half_width, half_height : float
        ``b`` and ``h`` [m]: half the width and half the height.
    gravity : float
        ``g`` [m/s^2].

    Returns
    -------
    R : float
        ``sqrt(b^2 + h^2)`` [m].
    alpha : float
        ``atan(b/h)`` [rad].
    p2 : float
        ``p^2 = 3 g / (4 R)`` [1/s^2] (eq. 29), the frequency parameter of rocking.
    """
    R = math.sqrt(half_width * half_width + half_height * half_height)
    alpha = math.atan2(half_width, half_height)
    return R, alpha, 0.75 * gravity / R


@njit(cache=True)
def tilt(theta, alpha):
    """``(s, c) = (sin(alpha - theta), cos(alpha - theta))``: the trigonometry of every equation
    below, computed once per state by the solvers."""
    return math.sin(alpha - theta), math.cos(alpha - theta)


@njit(cache=True)
def rock_acceleration_sc(s, c, ah, G, lam, R):
    """Eq. 3 with ``s``, ``c`` from `tilt`: ``thetaddot = (3 / (4 R)) (-G s + lam ah c)``."""
    return 0.75 / R * (-G * s + lam * ah * c)


@njit(cache=True)
def rock_acceleration_k(s, c, ah, G, lam, kr):
    """Eq. 3 about pivot ``i`` of any body (model-asymmetric.md section 2): ``thetaddot = kr_i (-G s_i +
    lam ah c_i)`` with ``kr_i = R_i / rho_i^2`` [1/m]; ``kr = 0.75 / R`` is `rock_acceleration_sc` to the bit."""
    return kr * (-G * s + lam * ah * c)


@njit(cache=True)
def rock_acceleration(theta, ah, G, lam, R, alpha):
    """Angular acceleration of liftoff without slip, eq. 3 (eq. 29 in compact form).

    ``I0 thetaddot = -M G R sin(alpha - theta) + lam M ah R cos(alpha - theta)`` with
    ``I0 = 4 M R^2 / 3``.

    Returns
    -------
    float
        ``thetaddot`` [rad/s^2].
    """
    s, c = tilt(theta, alpha)
    return rock_acceleration_sc(s, c, ah, G, lam, R)


@njit(cache=True)
def slip_acceleration(ah, G, nu, sigma):
    """Slip acceleration of the upright block, eq. 9: ``xddot = -ah - nu sigma G`` [m/s^2]."""
    return -ah - nu * sigma * G


@njit(cache=True)
def rockslip_determinant(s, c, lam, sigma, nu, R):
    """The determinant of the ROCKSLIP system (eqs. 15, 16 with 22), ``D = R (4/3 - c^2 + lam nu
    sigma s c)`` [m] with ``s``, ``c`` from `tilt`. ``D <= 0`` is the Painleve case."""
    return rockslip_determinant_q(s, c, lam, sigma, nu, R, 4.0 / 3.0)


@njit(cache=True)
def rockslip_determinant_q(s, c, lam, sigma, nu, R, q):
    """`rockslip_determinant` of pivot ``i`` of any body: ``D = R_i (q_i - c^2 + lam nu sigma s c)`` with
    ``q_i = rho_i^2 / R_i^2`` (4/3 for a rectangle; model-asymmetric.md section 2) [m]."""
    return R * (q - c * c + lam * nu * sigma * s * c)


@njit(cache=True)
def rockslip_determinant_rate(s, c, lam, sigma, nu, R):
    """``dD/dtheta = R (-2 s c + lam nu sigma (s^2 - c^2))`` [m/rad] (``ds/dtheta = -c``,
    ``dc/dtheta = s``): how fast the motion approaches the Painleve point."""
    return R * (-2.0 * s * c + lam * nu * sigma * (s * s - c * c))


@njit(cache=True)
def rockslip_loads(s, c, thetadot, ah, G, lam, sigma, nu, R):
    """The right-hand sides of the ROCKSLIP system (eqs. 15, 16 with 22, see
    `rockslip_accelerations`): ``b1 = -G s + lam ah c`` [m/s^2] and
    ``b2 = -ah - nu sigma G + R thetadot^2 (nu sigma c + lam s)`` [m/s^2]. ``D thetaddot =
    b1 + lam c b2``."""
    b1 = -G * s + lam * ah * c
    b2 = -ah - nu * sigma * G + R * thetadot * thetadot * (nu * sigma * c + lam * s)
    return b1, b2


@njit(cache=True)
def rockslip_accelerations_sc(s, c, thetadot, ah, G, lam, sigma, nu, R):
    """Eqs. 15, 16 and 22 with ``s``, ``c`` from `tilt`; see `rockslip_accelerations`."""
    return rockslip_accelerations_q(s, c, thetadot, ah, G, lam, sigma, nu, R, 4.0 / 3.0)


@njit(cache=True)
def rockslip_accelerations_q(s, c, thetadot, ah, G, lam, sigma, nu, R, q):
    """`rockslip_accelerations_sc` about pivot ``i`` of any body, ``q = rho_i^2 / R_i^2`` (4/3 for a
    rectangle): the first row's ``(4/3) R`` becomes ``rho_i^2 / R_i = q R_i`` (model-asymmetric.md
    section 2)."""
    b1, b2 = rockslip_loads(s, c, thetadot, ah, G, lam, sigma, nu, R)
    a21 = R * (nu * sigma * s - lam * c)
    D = rockslip_determinant_q(s, c, lam, sigma, nu, R, q)
    if D <= 0.0:
        return 0.0, 0.0, D
    thetaddot = (b1 + lam * c * b2) / D
    xddot = (q * R * b2 - a21 * b1) / D
    return thetaddot, xddot, D


@njit(cache=True)
def rockslip_accelerations(theta, thetadot, ah, G, lam, sigma, nu, R, alpha):
    """Liftoff-slip interaction: eqs. 15 and 16 with the friction force of eq. 22.

    Solves, per unit mass (``s = sin(alpha - theta)``, ``c = cos(alpha - theta)``)::

        (4/3) R thetaddot                 - lam c xddot = -G s + lam ah c
        R (nu sigma s - lam c) thetaddot  +       xddot = -ah - nu sigma G
                                                          + R thetadot^2 (nu sigma c + lam s)

    Returns
    -------
    thetaddot : float
        [rad/s^2]
    xddot : float
        [m/s^2]
    D : float
        The determinant ``R (4/3 - c^2 + lam nu sigma s c)`` [m]. ``D <= 0`` is the Painleve
        case (no unique solution); the accelerations are then returned as 0 and the caller must stop.
    """
    s, c = tilt(theta, alpha)
    return rockslip_accelerations_sc(s, c, thetadot, ah, G, lam, sigma, nu, R)


@njit(cache=True)
def contact_forces_sc(s, c, thetadot, thetaddot, ah, G, lam, R):
    """Eqs. 19 and 20 per unit mass with ``s``, ``c`` from `tilt`; see `contact_forces`."""
    w2 = thetadot * thetadot
    Rx = ah - lam * R * w2 * s - lam * R * thetaddot * c
    N = G - R * w2 * c + R * thetaddot * s
    return Rx, N


@njit(cache=True)
def contact_forces(theta, thetadot, thetaddot, ah, G, lam, R, alpha):
    """Contact forces per unit mass at the pivot, eqs. 19 and 20 (divided by M).

    Returns
    -------
    Rx : float
        Horizontal force needed to hold the pivot [m/s^2]:
        ``ah - lam R thetadot^2 s - lam R thetaddot c``.
    N : float
        Normal force [m/s^2]: ``G - R thetadot^2 c + R thetaddot s``.
    """
    s, c = tilt(theta, alpha)
    return contact_forces_sc(s, c, thetadot, thetaddot, ah, G, lam, R)


@njit(cache=True)
def slip_liftoff_margin(s, c, ah, G, sigma, nu, tan_alpha):
    """Eq. 23 during SLIP, ``tan(alpha) G - abs(xddot + ah)`` with ``abs(xddot + ah) = nu G``: in exact
    arithmetic ``G (tan(alpha) - nu)``, whatever ``ah``. With ``nu <= tan_alpha`` (``b/h`` as given,
    compared exactly) the block cannot lift off from SLIP: ``inf``. Otherwise it is decided as the
    ROCKSLIP system it would enter decides it: the block lifts off about ``lam = -sigma`` (eq. 24:
    ``xddot + ah = -nu sigma G``) when the rotation it starts grows, ``D thetaddot = b1 + lam c b2 >
    0`` at ``theta = thetadot = 0`` (`rockslip_loads`; ``s = sin(alpha)``, ``c = cos(alpha)``, from
    `tilt`; ``b1 + lam c b2 = G (nu c - s)`` in exact arithmetic), so that it never lifts off into a
    rotation that falls back at once. The ``ah`` terms of ``b1`` and ``b2`` cancel only to their
    rounding, which alone used to decide the tie ``nu = tan(alpha)``: liftoffs from noise in about a
    quarter of the states. Returns ``-(b1 + lam c b2)`` [m/s^2]: liftoff when negative."""
    if not nu > tan_alpha:
        return math.inf
    lam = -sigma
    b1, b2 = rockslip_loads(s, c, 0.0, ah, G, lam, sigma, nu, 1.0)
    return -(b1 + lam * c * b2)


@njit(cache=True)
def slip_margin(mu, N, Rx):
    """Static friction margin ``mu N - |Rx|`` [m/s^2]; slip starts when it is negative.

    Eq. 11 at rest (``N = G``, ``Rx = ah``) and eq. 21 during liftoff.
    """
    return mu * N - abs(Rx)


@njit(cache=True)
def liftoff_margin(tan_alpha, G, push):
    """Liftoff margin ``tan(alpha) G - |push|`` [m/s^2]; liftoff starts when it is negative.

    Eq. 6 at rest (``push = ah``; during slip, eq. 23 is `slip_liftoff_margin`).
    ``tan_alpha`` is passed as ``b/h`` so that ties with ``mu`` are exact.
    """
    return tan_alpha * G - abs(push)


@njit(cache=True)
def impact(u, xi, restitution, mu, nu, R, alpha):
    """The impact of the landing edge: eq. 8 extended to a sliding block (model.md decision 2).

    Worked in the frame of the edge that pivoted before the impact (``lam = +1`` there, so the
    landing edge lies at ``+2b`` and the block rotated with ``thetadot = -u``). The paper's ``e``
    fixes the rotational impulse; the landing edge's friction impulse is bounded by Coulomb's law
    and acts through the coupled inertia of slip and rotation. With ``s = sin(alpha)``,
    ``c = cos(alpha)``, ``b = R s``, ``h = R c``, ``k = 1 + 3 s^2``, the first branch that holds:

    - *stick*: ``w = e u + (3 c / (4 R)) xi``; holds if ``w > 0`` and the friction impulse needed
      to stop the slip, ``|h (1 - e) u + (k / 4) xi|``, is within ``mu b (u + w)`` (``b (u + w)``
      is the normal impulse). Then ``xi+ = 0``. If that impulse is within the cone but ``w <= 0``,
      the edge cannot slide and the block cannot rebound: a flat landing (the contract would try
      the slip branch here, which can report Painleve for a plastic impact, ``e = 0``, with
      ``mu >= 4/3``, against its own property ``thetadot+ = e |thetadot-|``).
    - *slip*: the landing edge slides in direction ``sig = sign(xi + 4 h (1 - e) u / k)`` under the
      kinetic friction impulse ``nu b (u + w)``, and the angular momentum about the landing edge
      changes as the restitution says, ``(4/3) R^2 (w - e u) = -h (xi+ - xi)``:
      ``w = u (4 e - 3 c^2 + 3 sig nu s c) / den`` with ``den = k - 3 sig nu s c`` (``den <= 0``:
      the Painleve case, no solution), ``xi+ = xi + h (u - w) - sig nu b (u + w)``; holds if
      ``w > 0`` and ``sig xi+ > 0``.
    - *flat landing*: the block lands on its base; ``q = xi + h u`` is the horizontal velocity of
      the centre of mass, the normal impulse is ``b u``: it stops if ``|q| <= mu b u``, else slides
      on at ``sign(q) (|q| - nu b u)``.

    The kinetic energy never rises (for ``nu <= mu`` below the Painleve bound); with
    ``e = 1 - 1.5 sin^2(alpha)`` (Housner) the stick branch conserves the angular momentum about the
    landing edge; with ``xi = 0`` and ``mu >= (1 - e) / ((1 + e) tan(alpha))`` it is the paper's
    ``thetadot+ = e |thetadot-|``; the old edge's share of the impulse is implied, not modelled, and
    the slip direction is constant within one impact.

    Parameters
    ----------
    u : float
        ``|thetadot-|`` [rad/s], > 0: the rotation rate before the impact.
    xi : float
        ``lam xdot-`` [m/s]: the slip velocity before the impact, positive toward the landing edge.
    restitution, mu, nu : float
        ``e``, ``mu``, ``nu`` [-].
    R, alpha : float
        [m], [rad]: `block_constants`.

    Returns
    -------
    branch : int
        ``IMPACT_STICK``, ``IMPACT_SLIP``, ``IMPACT_FLAT`` or ``IMPACT_PAINLEVE``.
    w : float
        ``thetadot+`` [rad/s] about the landing edge (0 for a flat landing).
    xi_plus : float
        ``lam xdot+`` [m/s] with the old ``lam`` (0 when the block sticks or stops).
    """
    e = restitution
    s = math.sin(alpha)
    c = math.cos(alpha)
    b = R * s
    h = R * c
    k = 1.0 + 3.0 * s * s
    if u > 0.0:                # (u = 0: a landing without speed, flat by the formulas below)
        w = e * u + 0.75 * c / R * xi
        edge_holds = abs(h * (1.0 - e) * u + 0.25 * k * xi) <= mu * b * (u + max(w, 0.0))
        if edge_holds and w > 0.0:
            return IMPACT_STICK, w, 0.0
        if not edge_holds:     # the landing edge slides
            sig = 1.0 if xi + 4.0 * h * (1.0 - e) * u / k >= 0.0 else -1.0
            den = k - 3.0 * sig * nu * s * c
            if den <= 0.0:
                return IMPACT_PAINLEVE, 0.0, xi
            w = u * (4.0 * e - 3.0 * c * c + 3.0 * sig * nu * s * c) / den
            xi_plus = xi + h * (u - w) - sig * nu * b * (u + w)
            if w > 0.0 and sig * xi_plus > 0.0:
                return IMPACT_SLIP, w, xi_plus
    q = xi + h * u
    if abs(q) <= mu * b * u:
        return IMPACT_FLAT, 0.0, 0.0
    return IMPACT_FLAT, 0.0, math.copysign(abs(q) - nu * b * u, q)


@njit(cache=True)
def zeno_rate(theta_z, p2, alpha):
    """``w_z`` [rad/s]: the rebound rate whose free-rocking peak is ``theta_z`` [rad] (energy
    ``(2/3) R^2 w_z^2 = g R (cos(alpha - theta_z) - cos(alpha))``), so
    ``w_z = sqrt(2 p^2 (cos(alpha - theta_z) - cos(alpha)))``; a rebound below it is too small to
    matter (model.md decision 3). ``cos(alpha - t) - cos(alpha) = 2 sin(alpha - t/2) sin(t/2)``
    avoids the cancellation of the difference."""
    return math.sqrt(4.0 * p2 * math.sin(alpha - 0.5 * theta_z) * math.sin(0.5 * theta_z))


@njit(cache=True)
def potential_energy(theta, gravity, R, alpha):
    """Potential energy per unit mass [J/kg]: ``g R (cos(alpha - theta) - cos(alpha))``, zero upright
    (the last term of the Lagrangian, eq. 13)."""
    return gravity * R * (math.cos(alpha - theta) - math.cos(alpha))


@njit(cache=True)
def kinetic_energy(theta, thetadot, xdot, lam, R, alpha):
    """Kinetic energy per unit mass relative to the foundation [J/kg], from the Lagrangian (eq. 13):
    ``xdot^2/2 - lam R cos(alpha - theta) xdot thetadot + (2/3) R^2 thetadot^2``."""
    return kinetic_energy_m(theta, thetadot, xdot, lam, R, alpha, (2.0 / 3.0) * R * R)


@njit(cache=True)
def kinetic_energy_m(theta, thetadot, xdot, lam, R, alpha, m):
    """`kinetic_energy` about pivot ``i`` of any body [J/kg]: ``xdot^2/2 - lam R_i c_i xdot thetadot +
    m thetadot^2`` with ``m = rho_i^2 / 2`` (``(2/3) R^2`` for a rectangle; model-asymmetric.md section 2)."""
    return (0.5 * xdot * xdot - lam * R * math.cos(alpha - theta) * xdot * thetadot
            + m * thetadot * thetadot)


@njit(cache=True)
def impact_body(u, xi, restitution, mu, nu, h, b_o, b_n, rho_o2, rho_n2):
    """The impact law of a body with corners at ``b_o`` (old pivot) and ``b_n`` (landing corner) from the
    vertical through its centre of mass (model-asymmetric.md section 4.3; `impact` is the rectangle's).

    ``e`` is the energy coefficient: a sticking impact without slip gives ``thetadot+ = e (rho_o /
    rho_n) |thetadot-|``, ``T+/T- = e^2`` (section 4.2). Worked in the old pivot's frame as `impact`;
    with ``D_n = rho_n^2 - h^2`` (``k2 + b_n^2``), the first branch that holds:

    - *stick*: ``w = e (rho_o/rho_n) u + (h / rho_n^2) xi``; holds if ``w > 0`` and
      ``|h (u - w) + xi| <= mu (b_o u + b_n w)``; within the cone with ``w <= 0``: a flat landing (as
      `impact`).
    - *slip*: ``sig = sign(xi + h u rho_n (rho_n - e rho_o) / D_n)``, ``den = D_n - sig nu h b_n``
      (``<= 0``: Painleve); ``w = u (e rho_o rho_n - h^2 + sig nu h b_o) / den``,
      ``xi+ = xi + h (u - w) - sig nu (b_o u + b_n w)``; holds if ``w > 0`` and ``sig xi+ > 0``.
    - *flat landing*: ``q = xi + h u``; stops if ``|q| <= mu b_o u``, else slides on at
      ``sign(q) (|q| - nu b_o u)``.

    Parameters
    ----------
    u, xi : float
        ``|thetadot-|`` [rad/s] and ``lam xdot-`` [m/s], as in `impact`.
    restitution, mu, nu : float
        ``e``, ``mu``, ``nu`` [-].
    h, b_o, b_n : float
        [m]: the centre of mass's height, the old and the new pivot's distance from its vertical.
    rho_o2, rho_n2 : float
        [m^2]: ``rho_i^2 = k2 + R_i^2`` of the old and the new pivot.

    Returns
    -------
    branch, w, xi_plus
        As `impact`.
    """
    e = restitution
    rho_o = math.sqrt(rho_o2)
    rho_n = math.sqrt(rho_n2)
    D_n = rho_n2 - h * h
    if u > 0.0:
        w = e * (rho_o / rho_n) * u + h / rho_n2 * xi
        edge_holds = abs(h * (u - w) + xi) <= mu * (b_o * u + b_n * max(w, 0.0))
        if edge_holds and w > 0.0:
            return IMPACT_STICK, w, 0.0
        if not edge_holds:
            sig = 1.0 if xi + h * u * rho_n * (rho_n - e * rho_o) / D_n >= 0.0 else -1.0
            den = D_n - sig * nu * h * b_n
            if den <= 0.0:
                return IMPACT_PAINLEVE, 0.0, xi
            w = u * (e * rho_o * rho_n - h * h + sig * nu * h * b_o) / den
            xi_plus = xi + h * (u - w) - sig * nu * (b_o * u + b_n * w)
            if w > 0.0 and sig * xi_plus > 0.0:
                return IMPACT_SLIP, w, xi_plus
    q = xi + h * u
    if abs(q) <= mu * b_o * u:
        return IMPACT_FLAT, 0.0, 0.0
    return IMPACT_FLAT, 0.0, math.copysign(abs(q) - nu * b_o * u, q)
