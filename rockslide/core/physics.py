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

# State codes, in the order of docs/model.md's table. They are stored in results as int8.
REST, SLIP, ROCK, ROCKSLIP, OVERTURNED = 0, 1, 2, 3, 4
STATE_NAMES = ("REST", "SLIP", "ROCK", "ROCKSLIP", "OVERTURNED")


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
def rockslip_accelerations_sc(s, c, thetadot, ah, G, lam, sigma, nu, R):
    """Eqs. 15, 16 and 22 with ``s``, ``c`` from `tilt`; see `rockslip_accelerations`."""
    b1 = -G * s + lam * ah * c
    b2 = -ah - nu * sigma * G + R * thetadot * thetadot * (nu * sigma * c + lam * s)
    a21 = R * (nu * sigma * s - lam * c)
    D = (4.0 / 3.0) * R + lam * c * a21
    if D <= 0.0:
        return 0.0, 0.0, D
    thetaddot = (b1 + lam * c * b2) / D
    xddot = ((4.0 / 3.0) * R * b2 - a21 * b1) / D
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
def slip_margin(mu, N, Rx):
    """Static friction margin ``mu N - |Rx|`` [m/s^2]; slip starts when it is negative.

    Eq. 11 at rest (``N = G``, ``Rx = ah``) and eq. 21 during liftoff.
    """
    return mu * N - abs(Rx)


@njit(cache=True)
def liftoff_margin(tan_alpha, G, push):
    """Liftoff margin ``tan(alpha) G - |push|`` [m/s^2]; liftoff starts when it is negative.

    Eq. 6 at rest (``push = ah``) and eq. 23 during slip (``push = xddot + ah``).
    ``tan_alpha`` is passed as ``b/h`` so that ties with ``mu`` are exact.
    """
    return tan_alpha * G - abs(push)


@njit(cache=True)
def rebound(thetadot_before, restitution):
    """Impact, eq. 8 with model.md's decision 2: ``thetadot+ = e |thetadot-|`` [rad/s].

    The pivot changes to the other edge (``lam -> -lam``); the slip velocity is unchanged.
    """
    return restitution * abs(thetadot_before)


@njit(cache=True)
def potential_energy(theta, gravity, R, alpha):
    """Potential energy per unit mass [J/kg]: ``g R (cos(alpha - theta) - cos(alpha))``, zero upright
    (the last term of the Lagrangian, eq. 13)."""
    return gravity * R * (math.cos(alpha - theta) - math.cos(alpha))


@njit(cache=True)
def kinetic_energy(theta, thetadot, xdot, lam, R, alpha):
    """Kinetic energy per unit mass relative to the foundation [J/kg], from the Lagrangian (eq. 13):
    ``xdot^2/2 - lam R cos(alpha - theta) xdot thetadot + (2/3) R^2 thetadot^2``."""
    return (0.5 * xdot * xdot - lam * R * math.cos(alpha - theta) * xdot * thetadot
            + (2.0 / 3.0) * R * R * thetadot * thetadot)
