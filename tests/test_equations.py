"""The paper's closed forms against the implemented equations (rockslide.core.physics).

Taniguchi's section 'COMMENTS ON VERTICAL GROUND MOTION EFFECTS' (eqs. 25-30) restates the
equations of motion and the contact forces in closed form for special cases. Each test here
evaluates the compiled physics function and the printed formula on seeded random geometries,
ground accelerations and friction coefficients, both edges ``lam`` and both slip directions
``sigma``.

Tolerances. Both sides are a few dozen rounded float operations on the same inputs, so they agree
to a small multiple of the machine epsilon relative to the *magnitudes of the terms that are added*
(not of the result, which can be small by cancellation). `_bound` computes that scale for each
formula; the factor ``ROUNDING = 64 * eps`` covers the ~30 roundings on each side with a margin.
Where a denominator nearly cancels (eq. 27-28 with nu close to 4/3), its condition number
``sum of |terms| / |sum|`` multiplies the bound.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockslide.core import physics as P

EPS = np.finfo(float).eps
ROUNDING = 64 * EPS          # ~30 roundings per side, x2 margin (see module docstring)
G0 = 9.80665
N_DRAWS = 300


def _geometry(rng):
    """A random block: half width b, half height h [m] (from squat to slender, 1 cm to 2 m)."""
    b = rng.uniform(0.01, 1.0)
    h = b * math.exp(rng.uniform(math.log(0.2), math.log(12.0)))     # gamma = h/b in [0.2, 12]
    R, alpha, p2 = P.block_constants(b, h, G0)
    return b, h, R, alpha, p2


def _ground(rng):
    """Random ground accelerations [m/s^2]: |ah| up to 2 g, av within +-0.8 g (so G > 0)."""
    return rng.uniform(-2.0, 2.0) * G0, rng.uniform(-0.8, 0.8) * G0


def _assert_close(actual, expected, scale, what):
    tol = ROUNDING * scale
    assert abs(actual - expected) <= tol, f"{what}: {actual!r} vs {expected!r} (|diff| > {tol:.3g})"


# ================================================================================================
# Block constants
# ================================================================================================

def test_block_constants_paper_block():
    """The paper's body (0.2 m x 0.1 m): b = 0.05, h = 0.1, tan(alpha) = 0.5, p^2 = 3 g / (4 R)."""
    R, alpha, p2 = P.block_constants(0.05, 0.1, G0)
    assert R == pytest.approx(math.sqrt(0.0125), rel=4 * EPS)
    assert math.tan(alpha) == pytest.approx(0.5, rel=4 * EPS)
    assert p2 == pytest.approx(3 * G0 / (4 * R), rel=4 * EPS)
    # B = R sin(alpha) = b and H = R cos(alpha) = h (the paper's notation of eq. 25)
    assert R * math.sin(alpha) == pytest.approx(0.05, rel=4 * EPS)
    assert R * math.cos(alpha) == pytest.approx(0.1, rel=4 * EPS)


# ================================================================================================
# LIFTOFF at theta = 0: eq. 25 (against eq. 3)
# ================================================================================================

@pytest.mark.parametrize("lam", [1.0, -1.0])
def test_eq25_rock_acceleration_at_liftoff(lam):
    """Eq. 25: thetaddot = 3 g (lam gamma A_h - (1 + A_v)) / (4 B (gamma^2 + 1)) at theta = 0."""
    rng = np.random.default_rng(25 + int(lam))
    for _ in range(N_DRAWS):
        b, h, R, alpha, _ = _geometry(rng)
        ah, av = _ground(rng)
        gamma, Ah, Av = h / b, ah / G0, av / G0
        expected = 3 * G0 * (lam * gamma * Ah - (1 + Av)) / (4 * b * (gamma ** 2 + 1))
        actual = P.rock_acceleration(0.0, ah, G0 + av, lam, R, alpha)
        scale = 3 * G0 * (gamma * abs(Ah) + abs(1 + Av)) / (4 * b * (gamma ** 2 + 1))
        _assert_close(actual, expected, scale, f"eq. 25, lam={lam}")


@pytest.mark.parametrize("lam", [1.0, -1.0])
def test_eq29_compact_form(lam):
    """Eq. 29 (Zhang's compact form of eq. 3) at any angle: -p^2 ((1 + A_v) s - lam A_h c)."""
    rng = np.random.default_rng(29 + int(lam))
    for _ in range(N_DRAWS):
        _, _, R, alpha, p2 = _geometry(rng)
        ah, av = _ground(rng)
        theta = rng.uniform(0.0, 0.5 * math.pi)
        s, c = math.sin(alpha - theta), math.cos(alpha - theta)
        expected = -p2 * ((1 + av / G0) * s - lam * ah / G0 * c)
        actual = P.rock_acceleration(theta, ah, G0 + av, lam, R, alpha)
        _assert_close(actual, expected, p2 * (abs(1 + av / G0) + abs(ah) / G0), "eq. 29")


# ================================================================================================
# LIFTOFF-SLIP at theta = thetadot = 0: eqs. 27 and 28 (against the 2x2 system of eqs. 15, 16, 22)
# ================================================================================================
#
# Derivation (model.md's system at theta = thetadot = 0, s = sin(alpha) = b/R, c = cos(alpha) = h/R,
# k = lam nu sigma, sigma = sign(xdot)):
#     (4/3) R thetaddot - lam c xddot = -G s + lam ah c
#     R (nu sigma s - lam c) thetaddot + xddot = -ah - nu sigma G
# Eliminating xddot from the second row:
#     thetaddot R (4/3 - c^2 + k s c) = -G (s + k c)
# and with R^2 = b^2 + h^2, gamma = h/b, B = b:
#     thetaddot = -3 G (b + k h) / (4 b^2 + h^2 + 3 k b h)
#               = -3 G (1 + k gamma) / (B (gamma^2 + 4 + 3 k gamma))
# which is the printed eq. 27 with sign(xdot) = sigma: there is NO sign-convention difference between
# the paper's eq. 27 and the system (the horizontal ground acceleration drops out, as the paper says).
# Back-substituting, (nu sigma b - lam h)(b + k h) = nu sigma (b^2 - h^2) + lam b h (nu^2 - 1), and
#     xddot = -[G (3 lam gamma + nu sigma + 4 nu sigma gamma^2) + ah (gamma^2 + 3 k gamma + 4)]
#             / (gamma^2 + 4 + 3 k gamma)
# which is the printed eq. 28 (again sign(xdot) = sigma). Both are tested below, and the system's
# general solution (any theta, thetadot) is checked against numpy.linalg.solve.

SIGNS = [(lam, sigma) for lam in (1.0, -1.0) for sigma in (1.0, -1.0)]


@pytest.mark.parametrize("lam,sigma", SIGNS)
def test_eq27_eq28_rockslip_at_liftoff(lam, sigma):
    rng = np.random.default_rng(2728 + int(3 * lam + sigma))
    for _ in range(N_DRAWS):
        b, h, R, alpha, _ = _geometry(rng)
        ah, av = _ground(rng)
        nu = rng.uniform(0.0, 1.3)                  # nu < 4/3 keeps D > 0 (see test_D_positive...)
        gamma, Ah, Av = h / b, ah / G0, av / G0
        k = lam * nu * sigma
        den = gamma ** 2 + 4 + 3 * k * gamma
        den_abs = gamma ** 2 + 4 + 3 * abs(k) * gamma
        cond = den_abs / abs(den)                   # condition number of the denominator
        thdd_27 = -3 * G0 * (1 + Av) * (1 + k * gamma) / (b * den)
        xdd_28 = -G0 * ((1 + Av) * (3 * lam * gamma + nu * sigma + 4 * nu * sigma * gamma ** 2)
                        + Ah * (gamma ** 2 + 3 * k * gamma + 4)) / den
        thdd, xdd, D = P.rockslip_accelerations(0.0, 0.0, ah, G0 + av, lam, sigma, nu, R, alpha)
        assert D > 0.0
        scale_th = 3 * G0 * abs(1 + Av) * (1 + abs(k) * gamma) / (b * abs(den)) * cond
        scale_x = G0 * (abs(1 + Av) * (3 * gamma + nu + 4 * nu * gamma ** 2)
                        + abs(Ah) * den_abs) / abs(den) * cond
        _assert_close(thdd, thdd_27, scale_th, f"eq. 27 lam={lam} sigma={sigma}")
        _assert_close(xdd, xdd_28, scale_x, f"eq. 28 lam={lam} sigma={sigma}")


@pytest.mark.parametrize("lam,sigma", SIGNS)
def test_eq27_independent_of_horizontal_ground_acceleration(lam, sigma):
    """The paper: 'effects of horizontal ground acceleration on the angular acceleration are
    eliminated' at the start of liftoff-slip. Exactly (not just to rounding) would be too strong:
    the implementation computes b1 + lam c b2 in which the ah terms cancel in floating point."""
    rng = np.random.default_rng(270 + int(3 * lam + sigma))
    for _ in range(50):
        b, h, R, alpha, _ = _geometry(rng)
        nu = rng.uniform(0.0, 1.3)
        av = rng.uniform(-0.8, 0.8) * G0
        values = [P.rockslip_accelerations(0.0, 0.0, a, G0 + av, lam, sigma, nu, R, alpha)[0]
                  for a in np.linspace(-2 * G0, 2 * G0, 9)]
        D = R * (4 / 3 - math.cos(alpha) ** 2 + lam * nu * sigma * math.sin(alpha) * math.cos(alpha))
        # the ah terms are ~|ah| c (1 + c) in magnitude before cancelling, divided by D
        scale = 2 * G0 * 2 / D
        assert max(values) - min(values) <= ROUNDING * scale


@pytest.mark.parametrize("lam,sigma", SIGNS)
def test_rockslip_solves_the_2x2_system(lam, sigma):
    """At any theta, thetadot: the returned accelerations solve model.md's system (eqs. 15, 16, 22)
    and D is its determinant R (4/3 - c^2 + lam nu sigma s c)."""
    rng = np.random.default_rng(1516 + int(3 * lam + sigma))
    for _ in range(N_DRAWS):
        _, _, R, alpha, p2 = _geometry(rng)
        ah, av = _ground(rng)
        G = G0 + av
        nu = rng.uniform(0.0, 1.3)
        theta = rng.uniform(0.0, 0.5 * math.pi)
        thetadot = rng.uniform(-5.0, 5.0) * math.sqrt(p2)
        s, c = math.sin(alpha - theta), math.cos(alpha - theta)
        A = np.array([[4 / 3 * R, -lam * c], [R * (nu * sigma * s - lam * c), 1.0]])
        rhs = np.array([-G * s + lam * ah * c,
                        -ah - nu * sigma * G + R * thetadot ** 2 * (nu * sigma * c + lam * s)])
        D_expected = R * (4 / 3 - c * c + lam * nu * sigma * s * c)
        thdd, xdd, D = P.rockslip_accelerations(theta, thetadot, ah, G, lam, sigma, nu, R, alpha)
        _assert_close(D, D_expected, 3 * R, "determinant")
        assert D == pytest.approx(np.linalg.det(A), rel=1e-12, abs=1e-12 * R)
        exact = np.linalg.solve(A, rhs)
        # condition of the 2x2 solve: |A| |A^-1|; the rhs terms set the magnitude
        cond = np.linalg.cond(A, 1)
        mag = np.abs(np.linalg.solve(np.abs(A), np.abs(rhs))).max() + np.abs(rhs).max() / R
        _assert_close(thdd, exact[0], cond * mag / R, "thetaddot")
        _assert_close(xdd, exact[1], cond * mag, "xddot")
        # residuals of the two equations (each row balanced to rounding of its terms)
        r1 = 4 / 3 * R * thdd - lam * c * xdd - rhs[0]
        r2 = R * (nu * sigma * s - lam * c) * thdd + xdd - rhs[1]
        assert abs(r1) <= ROUNDING * (4 / 3 * R * abs(thdd) + abs(xdd) + abs(G) + abs(ah))
        assert abs(r2) <= ROUNDING * (R * (nu + 1) * abs(thdd) + abs(xdd) + abs(ah) + nu * abs(G)
                                      + R * thetadot ** 2 * (nu + 1))


# ================================================================================================
# The determinant D and the Painleve case
# ================================================================================================

def _min_D_over_angles(nu, n=721):
    """min over alpha - theta in (-pi/2, pi/2) and lam sigma = +-1 of D/R, via the compiled function
    (R = 1, alpha = pi/4, theta spanning the full range of alpha - theta)."""
    best = math.inf
    alpha = 0.25 * math.pi
    for theta in np.linspace(alpha - 0.5 * math.pi, alpha + 0.5 * math.pi, n)[1:-1]:
        for ls in (1.0, -1.0):
            _, _, D = P.rockslip_accelerations(theta, 0.0, 0.0, G0, ls, 1.0, nu, 1.0, alpha)
            best = min(best, D)
    return best


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.95, 1.2, 1.3, 4 / 3 - 1e-3])
def test_D_positive_below_four_thirds(nu):
    """D/R = 4/3 - c^2 + lam nu sigma s c >= 5/6 - sqrt(1 + nu^2)/2 > 0 for nu < 4/3.

    The minimum over psi = alpha - theta of 4/3 - cos^2 psi - nu |sin psi cos psi| is
    5/6 - sqrt(1 + nu^2)/2 (at tan 2 psi = nu); the grid of 721 angles (step pi/720) finds it to
    O(step^2) = 2e-5 (a smooth minimum)."""
    found = _min_D_over_angles(nu)
    analytic = 5 / 6 - 0.5 * math.sqrt(1 + nu * nu)
    assert found > 0.0
    assert found == pytest.approx(analytic, abs=1e-4)
    assert found >= analytic - 1e-12


@pytest.mark.parametrize("nu", [4 / 3 + 1e-3, 1.5, 2.0])
def test_D_nonpositive_reached_above_four_thirds(nu):
    """Above nu = 4/3 some angle makes D <= 0; the function then returns (0, 0, D) and no
    division by a tiny number (model.md decision 5)."""
    found = _min_D_over_angles(nu, n=2881)
    assert found <= 0.0
    assert found == pytest.approx(5 / 6 - 0.5 * math.sqrt(1 + nu * nu), abs=1e-5)
    psi = 0.5 * math.atan(nu)                      # the worst angle, with lam sigma = -1
    alpha = 0.25 * math.pi
    thdd, xdd, D = P.rockslip_accelerations(alpha - psi, 3.0, 5.0, G0, -1.0, 1.0, nu, 0.7, alpha)
    assert D <= 0.0 and thdd == 0.0 and xdd == 0.0


# ================================================================================================
# Sufficient friction: eq. 26 (theta = thetadot = 0) and eq. 30 (any theta, thetadot)
# ================================================================================================

@pytest.mark.parametrize("lam", [1.0, -1.0])
def test_eq26_contact_force_ratio_at_liftoff(lam):
    """Eq. 26: R_x / R_y with eq. 25 at theta = thetadot = 0.

    Derivation (for the record): Rx = ah - lam h thetaddot and N = G + b thetaddot with eq. 25 give
    4 (1 + gamma^2) Rx = ah (4 + gamma^2) + 3 lam gamma G and 4 (1 + gamma^2) N = G (1 + 4 gamma^2)
    + 3 lam gamma ah: the printed numerator and denominator times g / (4 (1 + gamma^2))."""
    rng = np.random.default_rng(26 + int(lam))
    n_checked = 0
    for _ in range(N_DRAWS):
        b, h, R, alpha, _ = _geometry(rng)
        ah, av = _ground(rng)
        G = G0 + av
        gamma, Ah, Av = h / b, ah / G0, av / G0
        thdd = P.rock_acceleration(0.0, ah, G, lam, R, alpha)
        Rx, N = P.contact_forces(0.0, 0.0, thdd, ah, G, lam, R, alpha)
        num = 3 * lam * gamma * (1 + Av) + Ah * gamma ** 2 + 4 * Ah
        den = 4 * gamma ** 2 + 1 + 3 * lam * Ah * gamma + Av * (4 * gamma ** 2 + 1)
        scale = G0 / (4 * (1 + gamma ** 2))
        num_mag = 3 * gamma * abs(1 + Av) + abs(Ah) * (gamma ** 2 + 4)
        den_mag = (4 * gamma ** 2 + 1) * (1 + abs(Av)) + 3 * abs(Ah) * gamma
        _assert_close(Rx, num * scale, num_mag * scale, "eq. 26 numerator")
        _assert_close(N, den * scale, den_mag * scale, "eq. 26 denominator")
        if abs(den) > 0.05 * den_mag:                # the ratio itself, away from N = 0
            ratio_tol = ROUNDING * (num_mag + abs(num / den) * den_mag) / abs(den)
            assert abs(Rx / N - num / den) <= ratio_tol
            n_checked += 1
    assert n_checked > N_DRAWS // 2


@pytest.mark.parametrize("lam", [1.0, -1.0])
def test_eq30_contact_force_ratio_during_liftoff(lam):
    """Eq. 30 with eq. 29: with 6 g / p^2 = 8 R, the printed numerator is 8 Rx / M and the printed
    denominator 8 N / M (derivation: 8 - 6 c^2 = 5 - 3 cos 2(alpha - theta), 6 s c = 3 sin 2(...))."""
    rng = np.random.default_rng(30 + int(lam))
    n_checked = 0
    for _ in range(N_DRAWS):
        _, _, R, alpha, p2 = _geometry(rng)
        ah, av = _ground(rng)
        G = G0 + av
        theta = rng.uniform(0.0, 0.5 * math.pi)
        thetadot = rng.uniform(-3.0, 3.0) * math.sqrt(p2)
        psi = alpha - theta
        k = 6 * G0 / p2
        num = (ah * (5 - 3 * math.cos(2 * psi)) + 3 * lam * G * math.sin(2 * psi)
               - lam * k * thetadot ** 2 * math.sin(psi))
        den = (3 * lam * ah * math.sin(2 * psi) + G * (5 + 3 * math.cos(2 * psi))
               - k * thetadot ** 2 * math.cos(psi))
        num_mag = 8 * abs(ah) + 3 * abs(G) + k * thetadot ** 2
        den_mag = 3 * abs(ah) + 8 * abs(G) + k * thetadot ** 2
        thdd = P.rock_acceleration(theta, ah, G, lam, R, alpha)
        Rx, N = P.contact_forces(theta, thetadot, thdd, ah, G, lam, R, alpha)
        _assert_close(8 * Rx, num, num_mag, "eq. 30 numerator")
        _assert_close(8 * N, den, den_mag, "eq. 30 denominator")
        if abs(den) > 0.05 * den_mag:
            ratio_tol = ROUNDING * (num_mag + abs(num / den) * den_mag) / abs(den)
            assert abs(Rx / N - num / den) <= ratio_tol
            n_checked += 1
    assert n_checked > N_DRAWS // 3


def test_contact_forces_are_newtons_law_for_the_centre_of_gravity():
    """Eqs. 19-20 are Rx = ah + a_x and N = g + av + a_y (per unit mass), with a the acceleration of
    the centre of gravity relative to the foundation; relative to the pivot it sits at
    (lam R sin(alpha - theta), R cos(alpha - theta)). Checked by a central second difference of
    that position along theta(t) = theta0 + w t + acc t^2 / 2 with step 1e-5 s: truncation
    (dt^2 / 12) max|x''''| < 1e-10 R (w^4 + ...) and rounding 4 eps R / dt^2 < 1e-5 R, both below
    1e-5 of the force scale |ah| + g + R (w^2 + |acc|)."""
    rng = np.random.default_rng(1920)
    dt = 1e-5
    for _ in range(100):
        _, _, R, alpha, p2 = _geometry(rng)
        ah, av = _ground(rng)
        lam = float(rng.choice([-1.0, 1.0]))
        th0 = rng.uniform(0.0, 1.2)
        w = rng.uniform(-3.0, 3.0) * math.sqrt(p2)
        acc = rng.uniform(-3.0, 3.0) * p2

        def cog(t, th0=th0, w=w, acc=acc, lam=lam, R=R, alpha=alpha):
            th = th0 + w * t + 0.5 * acc * t * t
            return np.array([lam * R * math.sin(alpha - th), R * math.cos(alpha - th)])

        a = (cog(dt) - 2 * cog(0.0) + cog(-dt)) / dt ** 2
        Rx, N = P.contact_forces(th0, w, acc, ah, G0 + av, lam, R, alpha)
        scale = abs(ah) + G0 + R * (w * w + abs(acc))
        assert abs(Rx - (ah + a[0])) <= 1e-5 * scale
        assert abs(N - (G0 + av + a[1])) <= 1e-5 * scale


# ================================================================================================
# Slip, thresholds, impact, energies (eqs. 6, 8, 9, 11, 13, 21, 23)
# ================================================================================================

def test_eq9_slip_acceleration():
    rng = np.random.default_rng(9)
    for _ in range(N_DRAWS):
        ah, av = _ground(rng)
        nu, sigma = rng.uniform(0, 1.3), rng.choice([-1.0, 1.0])
        expected = -ah - nu * sigma * (G0 + av)
        assert P.slip_acceleration(ah, G0 + av, nu, sigma) == pytest.approx(
            expected, abs=4 * EPS * (abs(ah) + nu * abs(G0 + av)))


def test_margins_eq6_eq11_eq21_eq23():
    """slip_margin = mu N - |Rx| (eq. 11 at rest, 21 lifting off); liftoff_margin = tan(alpha) G -
    |push| (eq. 6 with push = ah, eq. 23 with push = xddot + ah). The sign decides the transition;
    a margin that is exactly zero is not a transition (strict inequalities in the paper)."""
    assert P.slip_margin(0.5, 2.0, 1.0) == 0.0
    assert P.slip_margin(0.5, 2.0, -1.0 - 1e-12) < 0.0
    assert P.slip_margin(0.5, 2.0, 0.999) > 0.0
    assert P.liftoff_margin(0.5, G0, 0.5 * G0) == 0.0
    assert P.liftoff_margin(0.5, G0, -0.5 * G0 * (1 + 1e-12)) < 0.0
    rng = np.random.default_rng(11)
    for _ in range(N_DRAWS):
        mu, N, Rx = rng.uniform(0, 2), rng.uniform(0, 20), rng.uniform(-20, 20)
        assert P.slip_margin(mu, N, Rx) == pytest.approx(mu * N - abs(Rx), abs=4 * EPS * 40)
        ta, G, push = rng.uniform(0.05, 5), rng.uniform(0, 20), rng.uniform(-40, 40)
        assert P.liftoff_margin(ta, G, push) == pytest.approx(ta * G - abs(push), abs=4 * EPS * 150)


# ------------------------------------------------------------------------------------------------
# The impact law (eq. 8 and model.md decision 2), against rigid-body mechanics written out here
# ------------------------------------------------------------------------------------------------
#
# At theta = 0 a block pivoting on edge lam has its centre of gravity at (lam b, h) from the pivot:
# its velocity is (xdot - lam h thetadot, b thetadot) and its angular velocity lam thetadot
# (counter-clockwise positive). Impulses per unit mass are the changes of the centre's velocity.
# Quantities are O(1), so relative rounding tolerances of 1e-13 cover every comparison.

def _body(thetadot, xdot, lam, b, h):
    """Centre-of-gravity velocity (vx, vz) and angular velocity of the block at theta = 0."""
    return xdot - lam * h * thetadot, b * thetadot, lam * thetadot


def _impact_outcome(u, xdot, lam, e, mu, nu, b, h):
    """The law's branch and the state after: (branch, thetadot+, xdot+, lam+)."""
    R, alpha, _ = P.block_constants(b, h, G0)
    branch, w, xi_plus = P.impact(u, lam * xdot, e, mu, nu, R, alpha)
    return P.IMPACT_BRANCHES[branch], w, lam * xi_plus, -lam


def _kinetic(thetadot, xdot, lam, b, h):
    vx, vz, omega = _body(thetadot, xdot, lam, b, h)
    return 0.5 * (vx * vx + vz * vz) + 0.5 * (b * b + h * h) / 3.0 * omega * omega


def _momentum_about_landing_edge(thetadot, xdot, lam, lam_before, b, h):
    """I omega + (r_G - r_edge) x v_G about the edge that lands when pivot ``lam_before`` lifts off
    it: the edge at (lam_before b, -h) from the centre of gravity (opposite the old pivot)."""
    vx, vz, omega = _body(thetadot, xdot, lam, b, h)
    rx, rz = -lam_before * b, h                   # the centre of gravity from the landing edge
    return (b * b + h * h) / 3.0 * omega + rx * vz - rz * vx


def _friction_bound(e, b, h):
    """mu above which a rocking block (xdot- = 0) sticks at the impact: (1 - e) / ((1 + e) tan(alpha))."""
    return (1.0 - e) / ((1.0 + e) * (b / h))


@pytest.mark.parametrize("e", [0.0, 0.3, 0.8, 1.0])
@pytest.mark.parametrize("gamma", [0.3, 2.0, 6.0])          # h / b
def test_impact_of_a_rocking_block_is_the_papers_rule_above_the_friction_bound(e, gamma):
    """xdot- = 0 and mu >= (1 - e) / ((1 + e) tan(alpha)): thetadot+ = e |thetadot-| and xdot+ = 0
    exactly (eq. 8; every ROCK impact of Table 1). e = 0 is a flat landing that stops the block.
    Just below the bound the landing edge slides: xdot+ != 0 (a rocking block slips at the impact)."""
    b = 0.1
    h = gamma * b
    bound = _friction_bound(e, b, h)
    for mu in (bound * (1 + 1e-12), 1.01 * bound, 5.0 * bound + 0.1):   # (at the bound itself: rounding)
        for nu in (0.0, 0.5 * mu, mu):
            for lam in (1.0, -1.0):
                for u in (1e-6, 0.37, 4.2):
                    branch, w, xdot, _ = _impact_outcome(u, 0.0, lam, e, mu, nu, b, h)
                    assert branch == ("flat" if e == 0.0 else "stick")
                    assert w == e * u and xdot == 0.0
    if bound > 0.0:
        s, c = b / math.hypot(b, h), h / math.hypot(b, h)
        nu = 0.9 * min(bound, (1 + 3 * s * s) / (3 * s * c))      # below the Painleve bound
        branch, w, xdot, _ = _impact_outcome(1.0, 0.0, 1.0, e, 0.99 * bound, nu, b, h)
        assert branch in ("slip", "flat") and xdot != 0.0


def test_impact_with_housners_restitution_conserves_angular_momentum_about_the_landing_edge():
    """e = 1 - 1.5 sin^2(alpha) (Housner 1963): in the stick branch the angular momentum about the
    landing edge, I w + (r_G - r_edge) x v_G from the rigid body's velocities, is the same before
    and after (the landing edge's impulse has no moment about it); in the slip branch
    w / u = (1/3 - s^2 + sig nu s c) / (1/3 + s^2 - sig nu s c)."""
    rng = np.random.default_rng(3)
    seen = set()
    for _ in range(N_DRAWS):
        b, h, R, alpha, _ = _geometry(rng)
        s, c = math.sin(alpha), math.cos(alpha)
        e = 1.0 - 1.5 * s * s
        lam = rng.choice([-1.0, 1.0])
        u, xdot = rng.uniform(0.01, 5.0), rng.uniform(-1.0, 1.0) * R * 3.0
        mu = rng.uniform(0.0, 1.5)
        nu = rng.uniform(0.0, 1.0) * min(mu, 0.99 * (1 + 3 * s * s) / (3 * s * c))
        branch, w, xdot_plus, lam_plus = _impact_outcome(u, xdot, lam, e, mu, nu, b, h)
        seen.add(branch)
        if branch == "stick":
            before = _momentum_about_landing_edge(-u, xdot, lam, lam, b, h)
            after = _momentum_about_landing_edge(w, xdot_plus, lam_plus, lam, b, h)
            assert after == pytest.approx(before, rel=1e-12, abs=1e-13 * R * R * u)
            assert w == pytest.approx(e * u + 0.75 * c / R * lam * xdot, rel=1e-13)
        elif branch == "slip":
            sig = math.copysign(1.0, lam * xdot_plus)
            ratio = (1 / 3 - s * s + sig * nu * s * c) / (1 / 3 + s * s - sig * nu * s * c)
            assert w / u == pytest.approx(ratio, rel=1e-12)
    assert {"stick", "slip"} <= seen


def test_impact_without_friction_keeps_the_horizontal_velocity_of_the_centre():
    """mu = nu = 0: no horizontal impulse, so the centre of gravity keeps its horizontal velocity
    through the impact, whichever branch (slip or flat) the law takes."""
    rng = np.random.default_rng(5)
    seen = set()
    for _ in range(N_DRAWS):
        b, h, R, *_ = _geometry(rng)
        e, lam = rng.uniform(0, 1), rng.choice([-1.0, 1.0])
        u, xdot = rng.uniform(0.01, 5.0), rng.uniform(-3.0, 3.0) * R
        branch, w, xdot_plus, lam_plus = _impact_outcome(u, xdot, lam, e, 0.0, 0.0, b, h)
        seen.add(branch)
        vx_before = _body(-u, xdot, lam, b, h)[0]
        vx_after = _body(w, xdot_plus, lam_plus, b, h)[0]
        assert vx_after == pytest.approx(vx_before, rel=1e-12, abs=1e-14 * (abs(xdot) + R * u))
    assert seen == {"slip", "flat"}


@settings(max_examples=400, deadline=None)
@given(gamma=st.floats(0.15, 8.0), e=st.floats(0.0, 1.0), mu_share=st.floats(0.0, 0.99),
       nu_share=st.floats(0.0, 1.0), u=st.floats(1e-6, 20.0), xi_over_ru=st.floats(-5.0, 5.0),
       lam=st.sampled_from([-1.0, 1.0]))
def test_impact_never_creates_energy_and_respects_coulomb(gamma, e, mu_share, nu_share, u, xi_over_ru, lam):
    """Any block, e, mu below the Painleve bound (1 + 3 s^2) / (3 s c), nu <= mu, slip and rotation
    rates: the kinetic energy after <= before (to 1e-12 relative); stick: the friction impulse is
    within the cone |Px| <= mu Pz; slip: at its limit |Px| = nu Pz against the slip that follows;
    flat: within the cone if the block stops, at nu Pz against the slide otherwise; w >= 0;
    everything finite. Pz = b (u + w) for stick and slip (the landing edge alone)."""
    b = 0.1
    h = gamma * b
    R, alpha, _ = P.block_constants(b, h, G0)
    s, c = math.sin(alpha), math.cos(alpha)
    mu = mu_share * min(3.0, (1 + 3 * s * s) / (3 * s * c))
    nu = nu_share * mu
    xdot = lam * xi_over_ru * R * u
    branch, w, xdot_plus, lam_plus = _impact_outcome(u, xdot, lam, e, mu, nu, b, h)
    assert branch in ("stick", "slip", "flat")
    assert math.isfinite(w) and math.isfinite(xdot_plus) and w >= 0.0
    before = _kinetic(-u, xdot, lam, b, h)
    after = _kinetic(w, xdot_plus, lam_plus, b, h) if w > 0 else 0.5 * xdot_plus * xdot_plus
    assert after <= before * (1 + 1e-12) + 1e-300
    vx0, vz0, _ = _body(-u, xdot, lam, b, h)
    vx1, vz1, _ = _body(w, xdot_plus, lam_plus, b, h) if w > 0 else (xdot_plus, 0.0, 0.0)
    Px, Pz = vx1 - vx0, vz1 - vz0
    scale = 1e-12 * (abs(xdot) + R * u)
    if branch == "stick":
        assert xdot_plus == 0.0 and abs(Px) <= mu * Pz + scale
        assert Pz == pytest.approx(b * (u + w), rel=1e-12)
    elif branch == "slip":
        assert abs(Px) == pytest.approx(nu * Pz, abs=scale)
        assert Px * xdot_plus <= scale * abs(xdot_plus)       # friction opposes the slip
    elif xdot_plus == 0.0:
        assert abs(Px) <= mu * Pz + scale
    else:
        assert abs(Px) == pytest.approx(nu * Pz, abs=scale) and Px * xdot_plus <= scale * abs(xdot_plus)


@pytest.mark.parametrize("xdot,expected", [(-0.30, ("slip", -0.1824, 0.0945)), (-0.10, ("stick", 0.0, 0.200)),
                                           (0.0, ("stick", 0.0, 0.800)), (0.15, ("slip", 0.0529, 1.3828))])
def test_impact_of_the_papers_block(xdot, expected):
    """The paper's block (b = 0.05, h = 0.1, e = 0.8), lam = +1, |thetadot-| = 1 rad/s, mu = 0.52,
    nu = 0.494: the values worked out by hand in the issue that revised the law (4 digits)."""
    branch, w, xdot_plus, _ = _impact_outcome(1.0, xdot, 1.0, 0.8, 0.52, 0.494, 0.05, 0.1)
    assert (branch, round(xdot_plus, 4), round(w, 4)) == (expected[0], pytest.approx(expected[1], abs=1e-4),
                                                          pytest.approx(expected[2], abs=1e-4))


def test_a_dropped_rebound_never_adds_energy():
    """The end of liftoff (decision 3) drops a rebound w <= w_z. Keeping the law's slip velocity
    (the contract's words) when the block slides away from the landing edge (xi+ < 0) would leave
    0.5 xi+^2 > the kinetic energy before the impact: here (the paper's block, mu = nu = 0.05,
    sliding at 0.5 m/s, u = w_z / 2) by ~1e-4 J/kg. rockslide keeps the centre of gravity's velocity
    xi+ + h w there, which never exceeds the energy before (nor after) the impact."""
    b, h, e, mu = 0.05, 0.1, 0.8, 0.05
    R, alpha, p2 = P.block_constants(b, h, G0)
    w_z = P.zeno_rate(1e-7, p2, alpha)
    assert w_z == pytest.approx(math.sqrt(2 * p2 * (math.cos(alpha - 1e-7) - math.cos(alpha))), rel=1e-6)
    u, xi = 0.5 * w_z, -0.5
    branch, w, xi_plus = P.impact(u, xi, e, mu, mu, R, alpha)
    assert branch == P.IMPACT_SLIP and w <= w_z and xi_plus < 0.0
    before = _kinetic(-u, xi, 1.0, b, h)
    assert 0.5 * xi_plus ** 2 - before > 1e-5                      # the literal rule gains energy
    kept = xi_plus + h * w
    assert 0.5 * kept ** 2 <= _kinetic(w, xi_plus, -1.0, b, h) <= before


def test_energies_from_the_lagrangian_eq13():
    """kinetic_energy is 1/2 |v_G|^2 + 1/2 (R^2/3) thetadot^2 with the centre of gravity's velocity
    (xdot - lam R c thetadot, R s thetadot); potential_energy is g times the rise of the centre of
    gravity, R cos(alpha - theta) - R cos(alpha). Same operations up to reordering: 16 eps."""
    rng = np.random.default_rng(13)
    for _ in range(N_DRAWS):
        _, _, R, alpha, p2 = _geometry(rng)
        lam = rng.choice([-1.0, 1.0])
        theta, w, xd = rng.uniform(0, 0.5 * math.pi), rng.uniform(-3, 3) * math.sqrt(p2), rng.uniform(-2, 2)
        s, c = math.sin(alpha - theta), math.cos(alpha - theta)
        vx, vy = xd - lam * R * c * w, R * s * w
        expected = 0.5 * (vx * vx + vy * vy) + 0.5 * (R * R / 3) * w * w
        scale = 0.5 * (abs(xd) + R * abs(w)) ** 2 + R * R * w * w
        assert abs(P.kinetic_energy(theta, w, xd, lam, R, alpha) - expected) <= 16 * EPS * scale
        pe = G0 * (R * c - R * math.cos(alpha))
        assert abs(P.potential_energy(theta, G0, R, alpha) - pe) <= 16 * EPS * G0 * R
    assert P.potential_energy(0.0, G0, 0.3, 0.4) == 0.0
