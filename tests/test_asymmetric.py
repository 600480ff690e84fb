"""The asymmetric planar body (docs/model-asymmetric.md): its constants, equations, impact law and
responses against the contract's reference numbers (an independent DOP853 solver at rtol 1e-12),
the reduction to the rectangle (section 7), the reference solver, the GPU path and the case file.

Tolerances: closed forms to 1e-9 relative (their rounding); event times of the fixed-step kernel
(0.1 ms, located events, RK4 error ~ (p h)^4 ~ 1e-13 per step) to 1e-7 s; history peaks, sampled
every step, to the parabola's error ``thetaddot h^2 / 8`` ~ 2e-8 rad; the half-sine thresholds,
given to 5 digits (2e-5 relative), bracketed at +-2e-4 relative.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from rockslide.case import parse_case
from rockslide.core import kernel as K
from rockslide.core import physics as P
from rockslide.core.reference import simulate_reference
from rockslide.core.simulate import Model, Settings, parameters, simulate
from rockslide.errors import CaseError
from rockslide.pulses import Pulse, sample

G0 = 9.80665
B1, B2, H = 0.044, 0.129, 0.294          # the contract's rock
REPO = Path(__file__).resolve().parents[1]


def rock(e=1.0, mu=10.0, nu=None, **kw):
    return Model(B1, H, mu, mu if nu is None else nu, e, G0, 330.0, half_width_2=B2, **kw)


def r_H(model):
    one, two = model.pivots
    return (model.k2 + H * H - B1 * B2) / math.sqrt(one["rho2"] * two["rho2"])


def still(duration, dt=0.01):
    n = int(round(duration / dt)) + 1
    return np.zeros(n), np.zeros(n), dt


def impacts(result):
    return [e for e in result.events if e["cause"] in (b"impact", b"liftoff-end")]


# ---------------------------------------------------------------------------------------------------
# Section 1: constants
# ---------------------------------------------------------------------------------------------------

def test_pivot_constants_are_the_contracts_table():
    one, two = rock().pivots
    expected = ((one, 0.2972742841, 0.1485572796, 0.1496598639, 0.1196780833, 2.483949240, 24.35922081),
                (two, 0.3210560699, 0.4134805321, 0.4387755102, 0.1343830833, 2.389110756, 23.42917300))
    for pv, R, alpha, tan_alpha, rho2, kr, p2 in expected:
        assert pv["R"] == pytest.approx(R, rel=1e-9)
        assert pv["alpha"] == pytest.approx(alpha, rel=1e-9)
        assert pv["tan_alpha"] == pytest.approx(tan_alpha, rel=1e-9)
        assert pv["rho2"] == pytest.approx(rho2, rel=1e-9)
        assert pv["kr"] == pytest.approx(kr, rel=1e-9)
        assert pv["p2"] == pytest.approx(p2, rel=1e-9)
    assert rock().k2 == pytest.approx(0.03130608333, rel=1e-9)
    assert r_H(rock()) == pytest.approx(0.8836790936, rel=1e-9)
    assert rock().restitution_max == pytest.approx(0.9963850738, rel=1e-9)
    assert Model(0.05, 0.1, 0.5, 0.5, 0.8).restitution_max == 1.0


# ---------------------------------------------------------------------------------------------------
# Section 6.1-6.2: thresholds, accelerations and forces
# ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("sign", "tan_alpha", "lam"), [(1.0, 0.1496598639, 1), (-1.0, 0.4387755102, -1)])
@pytest.mark.parametrize("av_over_g", [0.0, 0.2])
def test_static_liftoff_on_a_ramp_per_direction(sign, tan_alpha, lam, av_over_g):
    """ah = sign g t/s: liftoff about pivot lam at t = tan(alpha_lam) (1 + av/g) [s] (exact: the REST
    exits are linear crossings)."""
    dt = 0.01
    t = np.arange(0.0, 0.8, dt)
    result = simulate(rock(), dt, sign * G0 * t, np.full(t.size, av_over_g * G0), Settings(history_every=0))
    first = result.events[0]
    assert first["cause"] == b"liftoff" and first["edge"] == lam
    assert first["time"] == pytest.approx(tan_alpha * (1.0 + av_over_g), rel=1e-9)


def test_rocking_accelerations_and_contact_forces_at_the_contracts_states():
    p = parameters(rock(), 0.01, Settings())
    thdd, _ = K.accelerations(K.ROCK, 1.0, 1.0, 0.0, 0.0, 0.3 * G0, G0, p)
    assert thdd == pytest.approx(3.62183215111, rel=1e-10)
    thdd, _ = K.accelerations(K.ROCK, -1.0, 1.0, 0.0, 0.0, -0.6 * G0, G0, p)
    assert thdd == pytest.approx(3.45903069397, rel=1e-10)
    thdd, _ = K.accelerations(K.ROCK, 1.0, 1.0, 0.05, 0.4, 0.3 * G0, G0, p)
    Rx, N = P.contact_forces(0.05, 0.4, thdd, 0.3 * G0, G0, 1.0, p[K.P_R], p[K.P_ALPHA])
    assert (thdd, Rx, N) == pytest.approx((4.87540908486, 1.49501445552, 9.90192818709), rel=1e-10)


def test_rockslip_with_zero_friction_keeps_the_centre_of_mass_still_horizontally():
    """nu = 0 and no ground: no horizontal force, so the CM's horizontal acceleration
    xddot - lam (R c thetaddot + R s thetadot^2) vanishes, about either pivot (an independent check
    of the per-pivot 2x2 system, model-asymmetric.md section 2)."""
    p = parameters(rock(mu=0.0), 0.01, Settings())
    for lam in (1.0, -1.0):
        R, alpha = (p[K.P_R], p[K.P_ALPHA]) if lam > 0 else (p[K.P_R2], p[K.P_ALPHA2])
        th, thd = 0.05, 0.7
        thdd, xdd = K.accelerations(K.ROCKSLIP, lam, 1.0, th, thd, 0.0, G0, p)
        s, c = math.sin(alpha - th), math.cos(alpha - th)
        assert xdd - lam * (R * c * thdd + R * s * thd ** 2) == pytest.approx(0.0, abs=1e-12)


# ---------------------------------------------------------------------------------------------------
# Section 6.3-6.4: free rocking
# ---------------------------------------------------------------------------------------------------

def quarter_period(model, lam, theta0):
    """The time from theta0 (at rest) down to 0 by energy: the integral over theta of
    1 / sqrt(2 p^2 (cos(alpha - theta0) - cos(alpha - theta))), whose 1/sqrt singularity at theta0
    the substitution theta = theta0 - t^2 removes (the cosines' difference written as a product of
    sines, without cancellation)."""
    pv = model.pivots[0 if lam > 0 else 1]
    p2, alpha = pv["p2"], pv["alpha"]

    def integrand(t):
        return 2.0 * t / math.sqrt(4.0 * p2 * math.sin(alpha - theta0 + 0.5 * t * t) * math.sin(0.5 * t * t))

    return quad(integrand, 0.0, math.sqrt(theta0), epsabs=1e-14, epsrel=1e-13, limit=200)[0]


def test_free_rocking_period_alternates_pivots():
    model = rock(e=1.0)
    theta0 = 0.5 * model.pivots[0]["alpha"]
    assert theta0 == pytest.approx(0.07427863981, rel=1e-9)
    h, v, dt = still(2.0)
    result = simulate(model, dt, h, v, Settings(rotation=theta0))
    times = [e["time"] for e in impacts(result)]
    assert times[0] == pytest.approx(0.267006197511, abs=1e-7)
    assert quarter_period(model, 1, theta0) == pytest.approx(0.267006197511, rel=1e-9)
    assert times[1] - times[0] == pytest.approx(2 * 0.0655278742748, abs=1e-7)
    assert times[2] - times[0] == pytest.approx(0.665068143572, abs=1e-7)
    assert times[4] - times[2] == pytest.approx(0.665068143572, abs=1e-7)
    phi = result.history["rotation"]
    first = (result.history["time"] > times[0]) & (result.history["time"] < times[1])
    assert phi[first].min() == pytest.approx(-0.01946054618, abs=3e-8)     # about pivot 2
    assert abs(result.summary.energy["balance_residual"]) < 1e-9 * 330.0


def peaks(result):
    """The signed peaks phi between successive impacts (the first: the start)."""
    t, phi = result.history["time"], result.history["rotation"]
    bounds = [0.0] + [e["time"] for e in impacts(result)]
    out = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        inside = phi[(t >= a) & (t < b)]
        out.append(inside[np.argmax(np.abs(inside))])
    return np.array(out)


@pytest.mark.parametrize(("e", "expected_peaks", "n_impacts", "end"), [
    ("r_H", [0.0742786, -0.0151196, 0.0391468, -0.00915623], 51, 2.137571),
    (0.8, [0.0742786, -0.0123519, 0.0249286, -0.00501672], 29, 1.213002),
])
def test_peak_energies_fall_by_e_squared_whichever_corner_lands(e, expected_peaks, n_impacts, end):
    model = rock(e=1.0)
    e = r_H(model) if e == "r_H" else e
    model = rock(e=e)
    theta0 = 0.5 * model.pivots[0]["alpha"]
    h, v, dt = still(3.0)
    result = simulate(model, dt, h, v, Settings(rotation=theta0))
    found = peaks(result)
    assert found[:4] == pytest.approx(expected_peaks, abs=6e-8)      # given to 6 digits (5e-8), sampled
    pv = model.pivots

    def V(phi):
        p = pv[0] if phi > 0 else pv[1]
        return G0 * p["R"] * (math.cos(p["alpha"] - abs(phi)) - math.cos(p["alpha"]))
    energies = np.array([V(x) for x in found[:8]])
    assert energies[1:] / energies[:-1] == pytest.approx(e * e, rel=1e-5)
    assert result.summary.impacts == n_impacts
    assert impacts(result)[-1]["cause"] == b"liftoff-end"
    assert impacts(result)[-1]["time"] == pytest.approx(end, abs=2e-6)
    assert result.summary.states_seen == ["REST", "ROCK"]


# ---------------------------------------------------------------------------------------------------
# Section 6.7: mirror; section 8: direction-dependent overturning
# ---------------------------------------------------------------------------------------------------

def hann_bursts(dt=0.005, duration=4.0):
    t = np.arange(0.0, duration, dt)
    ah = np.zeros_like(t)
    for start, freq, amp in ((0.2, 2.0, 0.45), (1.4, 3.0, -0.5), (2.5, 1.5, 0.35)):
        x = (t - start) * freq / 3.0
        inside = (x > 0) & (x < 1)
        ah[inside] += amp * G0 * np.sin(2 * np.pi * freq * (t[inside] - start)) * np.sin(np.pi * x[inside]) ** 2
    av = 0.2 * np.roll(ah, 7)
    return t, ah, av, dt


def test_mirror_swaps_the_pivots():
    """(b1, b2, ah) -> (b2, b1, -ah): the same event times, lam, sigma and x mirrored."""
    _, ah, av, dt = hann_bursts()
    one = simulate(Model(B1, H, 0.2, 0.16, 0.85, G0, 1.0, half_width_2=B2), dt, ah, av, Settings(tail=1.0))
    two = simulate(Model(B2, H, 0.2, 0.16, 0.85, G0, 1.0, half_width_2=B1), dt, -ah, av, Settings(tail=1.0))
    assert len(one.events) == len(two.events) > 10
    assert {e["cause"] for e in one.events} >= {b"impact", b"slip-start", b"liftoff", b"slip-reversal"}
    np.testing.assert_allclose(one.events["time"], two.events["time"], rtol=1e-12)
    rocking = np.isin(one.events["to"], [b"ROCK", b"ROCKSLIP", b"OVERTURNED"])   # lam means nothing upright
    sliding = np.isin(one.events["to"], [b"SLIP", b"ROCKSLIP"])
    assert rocking.sum() > 5 and sliding.sum() > 2
    assert np.array_equal(one.events["edge"][rocking], -two.events["edge"][rocking])
    assert np.array_equal(one.events["slip_direction"][sliding], -two.events["slip_direction"][sliding])
    assert np.array_equal(one.events["cause"], two.events["cause"])
    np.testing.assert_allclose(one.history["rotation"], -two.history["rotation"], atol=1e-12)
    np.testing.assert_allclose(one.history["slip"], -two.history["slip"], atol=1e-12)


def half_sine(model, amplitude, Tp):
    pulse = Pulse(pulse="half-sine", amplitude=amplitude, duration=Tp)
    s = sample(pulse, None, 1e-3)
    return simulate(model, s.dt, amplitude * s.horizontal, s.vertical, Settings(tail=4.0, history_every=0),
                    start=s.start).summary


@pytest.mark.parametrize(("e", "Tp", "left", "right"), [
    ("r_H", 0.2, 0.35709, 0.65980),
    ("r_H", 0.5, 0.21692, 0.51522),
    ("r_H", 1.0, 0.17401, 0.47673),
    (0.8, 0.5, 0.21692, 0.52254),
])
def test_half_sine_thresholds_depend_on_the_direction(e, Tp, left, right):
    """Section 8: pushed toward its weak side (ah > 0) it falls left; pushed the other way it falls
    LEFT as well, after rocking on the right corner, at a higher threshold."""
    e = r_H(rock()) if e == "r_H" else e
    model = rock(e=e, mu=100.0)
    for sign, threshold in ((1.0, left), (-1.0, right)):
        above = half_sine(model, sign * threshold * (1 + 2e-4) * G0, Tp)
        below = half_sine(model, sign * threshold * (1 - 2e-4) * G0, Tp)
        assert above.overturned and above.direction == 1, (sign, above)
        assert not below.overturned and not below.undecided, (sign, below)


# ---------------------------------------------------------------------------------------------------
# Section 4.3: the impact law
# ---------------------------------------------------------------------------------------------------

def law(model, e, mu, nu, old=1):
    one, two = model.pivots
    o, n = (one, two) if old == 1 else (two, one)
    return lambda u, xi: P.impact_body(u, xi, e, mu, nu, H, o["b"], n["b"], o["rho2"], n["rho2"]), o, n


def kinetic_before(u, xi, o):
    return 0.5 * xi * xi + H * xi * u + 0.5 * o["rho2"] * u * u


def kinetic_after(w, xi_plus, n):
    return 0.5 * xi_plus ** 2 + H * xi_plus * w + 0.5 * n["rho2"] * w * w


@pytest.mark.parametrize("old", [1, 2])
def test_impact_without_slip_at_the_friction_bound_is_e_rho_ratio(old):
    """(a) xi = 0, mu at the no-slip bound: w = e (rho_o / rho_n) u."""
    model = rock()
    e = 0.85
    _, o, n = law(model, e, 1.0, 1.0, old)
    ratio = e * math.sqrt(o["rho2"] / n["rho2"])
    bound = abs(H * (1 - ratio)) / (o["b"] + n["b"] * ratio)
    impact, _, _ = law(model, e, bound * (1 + 1e-12), bound, old)
    branch, w, xi_plus = impact(1.3, 0.0)
    assert branch == P.IMPACT_STICK and xi_plus == 0.0
    assert w == pytest.approx(ratio * 1.3, rel=1e-14)
    branch, _, _ = law(model, e, bound * (1 - 1e-6), bound * (1 - 1e-6), old)[0](1.3, 0.0)
    assert branch != P.IMPACT_STICK


def rigid_impact(model, u, xi, mu, nu, old):
    """An independent free-body rigid impact at the new corner (impulse there only, no bounce, Coulomb
    friction), in the old pivot's frame: returns (branch, w, xi+)."""
    one, two = model.pivots
    o, n = (one, two) if old == 1 else (two, one)
    k2 = model.k2
    v = np.array([xi + H * u, -o["b"] * u])
    omega = -u
    corner = np.array([n["b"], -H])

    def after(Px, Py):
        vp = v + np.array([Px, Py])
        om = omega + (corner[0] * Py - corner[1] * Px) / k2
        return vp, om, vp + om * np.array([-corner[1], corner[0]])
    # stick: corner velocity (0, 0) after; the map (Px, Py) -> corner velocity is affine
    base = after(0.0, 0.0)[2]
    A = np.column_stack([after(1.0, 0.0)[2] - base, after(0.0, 1.0)[2] - base])
    Px, Py = np.linalg.solve(A, -base)
    _, om, _ = after(Px, Py)
    if abs(Px) <= mu * Py and -om > 0:
        return P.IMPACT_STICK, -om, 0.0
    for sig in (1.0, -1.0):   # slip: Px = -sig nu Py, corner vertical velocity 0, slides along sig
        dy = after(-sig * nu, 1.0)[2][1] - base[1]
        Py = -base[1] / dy
        _, om, vc = after(-sig * nu * Py, Py)
        if Py > 0 and sig * vc[0] > 0 and -om > 0:
            return P.IMPACT_SLIP, -om, vc[0]
    return P.IMPACT_FLAT, 0.0, math.nan


@pytest.mark.parametrize("old", [1, 2])
@pytest.mark.parametrize(("u", "xi", "mu"), [(1.0, 0.0, 1.0), (1.0, 0.0, 0.05), (0.7, 0.3, 0.2),
                                             (0.7, -0.2, 0.3), (2.0, 0.5, 0.6), (0.5, -0.05, 0.1)])
def test_impact_at_housners_e_is_the_rigid_free_body_impact(old, u, xi, mu):
    """(b) e = r_H: the law equals the rigid impact of the free body at the new corner."""
    model = rock()
    impact, _, _ = law(model, r_H(model), mu, mu, old)
    branch, w, xi_plus = impact(u, xi)
    expected = rigid_impact(model, u, xi, mu, mu, old)
    assert branch == expected[0]
    if branch != P.IMPACT_FLAT:
        assert (w, xi_plus) == pytest.approx(expected[1:], rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("old", [1, 2])
def test_frictionless_impact_keeps_the_centre_of_mass_horizontal_velocity(old):
    """(c) mu = nu = 0: xi + h u = xi+ + h w (xi+ for a flat landing)."""
    model = rock()
    for e in (0.3, r_H(model), 0.95):
        impact, _, _ = law(model, e, 0.0, 0.0, old)
        for u, xi in ((1.0, 0.0), (0.5, 0.4), (0.8, -0.6)):
            branch, w, xi_plus = impact(u, xi)
            assert branch in (P.IMPACT_SLIP, P.IMPACT_FLAT)
            assert xi_plus + H * w == pytest.approx(xi + H * u, rel=1e-13)


def test_impacts_never_add_energy_up_to_e_max():
    """(d) T+ <= T- for e <= e_max (sampled), in both directions."""
    model = rock()
    rng = np.random.default_rng(39)
    e_max = model.restitution_max
    for _ in range(4000):
        e = rng.uniform(0.0, e_max)
        mu = rng.uniform(0.0, 1.2)
        nu = mu * rng.uniform(0.0, 1.0)
        old = int(rng.choice([1, 2]))
        impact, o, n = law(model, e, mu, nu, old)
        u, xi = rng.uniform(0.01, 2.0), rng.normal(0.0, 1.0)
        branch, w, xi_plus = impact(u, xi)
        if branch == P.IMPACT_PAINLEVE:
            continue
        assert kinetic_after(w, xi_plus, n) <= kinetic_before(u, xi, o) * (1 + 1e-12) + 1e-15


def test_impact_law_of_a_symmetric_body_is_the_rectangles():
    """(e) b1 = b2, k2 = R^2/3: the generic law equals `physics.impact` to rounding."""
    b, h = 0.1, 0.25
    R, alpha, _ = P.block_constants(b, h, G0)
    rho2 = 4.0 / 3.0 * R * R
    rng = np.random.default_rng(7)
    for _ in range(2000):
        e, mu = rng.uniform(0, 1), rng.uniform(0, 1.2)
        nu = mu * rng.uniform(0, 1)
        u, xi = rng.uniform(0.01, 2), rng.normal(0, 0.5)
        one = P.impact(u, xi, e, mu, nu, R, alpha)
        two = P.impact_body(u, xi, e, mu, nu, h, b, b, rho2, rho2)
        assert one[0] == two[0]
        assert two[1:] == pytest.approx(one[1:], rel=1e-12, abs=1e-14)


# ---------------------------------------------------------------------------------------------------
# Section 7: the b1 = b2 reduction
# ---------------------------------------------------------------------------------------------------

def rectangle_case():
    _, ah, av, dt = hann_bursts()
    return ah * 1.65, av, dt


def test_equal_half_widths_without_inertia_run_the_rectangle_bit_for_bit():
    ah, av, dt = rectangle_case()
    today = simulate(Model.from_block(0.2, 0.5, 0.5, 0.4, 0.8), dt, ah, av, Settings(tail=1.0))
    same = simulate(Model(0.1, 0.25, 0.5, 0.4, 0.8, half_width_2=0.1), dt, ah, av, Settings(tail=1.0))
    assert not Model(0.1, 0.25, 0.5, 0.4, 0.8, half_width_2=0.1).asymmetric
    assert np.array_equal(today.events, same.events)
    for name in today.history:
        assert np.array_equal(today.history[name], same.history[name])


def test_the_generic_path_with_equal_half_widths_agrees_to_rounding():
    ah, av, dt = rectangle_case()
    today = simulate(Model.from_block(0.2, 0.5, 0.5, 0.4, 0.8), dt, ah, av, Settings(tail=1.0))
    R2 = 0.1 ** 2 + 0.25 ** 2
    generic_model = Model(0.1, 0.25, 0.5, 0.4, 0.8, half_width_2=0.1, radius_of_gyration=math.sqrt(R2 / 3.0))
    assert generic_model.asymmetric
    assert parameters(generic_model, dt, Settings())[K.P_ASYM] == 1.0
    generic = simulate(generic_model, dt, ah, av, Settings(tail=1.0))
    assert len(today.events) == len(generic.events) > 10
    assert {e["cause"] for e in today.events} >= {b"impact", b"slip-start", b"liftoff", b"overturn"}
    assert np.array_equal(today.events["cause"], generic.events["cause"])
    np.testing.assert_allclose(generic.events["time"], today.events["time"], rtol=1e-12)


# ---------------------------------------------------------------------------------------------------
# The reference solver, the GPU path
# ---------------------------------------------------------------------------------------------------

def test_kernel_and_reference_solver_agree_on_an_asymmetric_body_with_vertical_motion():
    _, ah, av, dt = hann_bursts(duration=3.0)
    model = Model(B1, H, 0.35, 0.3, 0.85, G0, 1.0, half_width_2=B2, radius_of_gyration=0.17)
    settings = Settings(tail=0.5, history_every=0)
    kernel = simulate(model, dt, ah, av, settings)
    reference = simulate_reference(model, dt, ah, av, settings)
    assert len(kernel.events) == len(reference.events) > 10
    assert np.array_equal(kernel.events["cause"], reference.events["cause"])
    assert np.array_equal(kernel.events["edge"], reference.events["edge"])
    np.testing.assert_allclose(kernel.events["time"], reference.events["time"], atol=2e-6)
    assert kernel.summary.max_rotation == pytest.approx(reference.summary.max_rotation, rel=1e-5)
    assert kernel.summary.max_slip == pytest.approx(reference.summary.max_slip, rel=1e-5, abs=1e-9)


GPU_SCRIPT = """
import json
import numpy as np
from rockslide.core import batch, gpu
from rockslide.core.simulate import Model, Settings, ground_array, initial_state, parameters
t = np.arange(0.0, 3.0, 0.005)
ah = 4.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-t)
ground = ground_array(ah, 0.3 * np.roll(ah, 5), 0.005, 1.0)
models = [Model(0.044, 0.294, mu, mu, 0.8, half_width_2=0.129, radius_of_gyration=k)
          for mu in (0.1, 0.3, 1.0) for k in (None, 0.17)] + [Model.from_block(0.2, 0.5, 0.4, 0.4, 0.8)]
params = np.array([parameters(m, 0.005, Settings()) for m in models])
states = np.array([initial_state(Settings()) for _ in models])
n = len(models)
inputs = (params, states, ground, np.zeros(n, np.int64), np.full(n, ground.shape[1], np.int64),
          np.linspace(0.5, 1.5, n), np.ones(n))
cpu = batch.compute(*inputs)
device = gpu.compute(*inputs)
print(json.dumps({"identical": bool(np.array_equal(cpu, device, equal_nan=True)),
                  "moved": int((cpu[:, 18:21].sum(axis=1) > 0).sum()), "simulator": gpu.cuda_simulator()}))
"""


@pytest.mark.skipif(__import__("importlib").util.find_spec("numba_cuda") is None, reason="needs numba-cuda")
def test_simulated_device_gives_the_cpu_final_states_of_asymmetric_bodies():
    import json
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1"}
    done = subprocess.run([sys.executable, "-c", GPU_SCRIPT], env=env, capture_output=True, text=True,
                          timeout=600, cwd=REPO)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["simulator"] and out["identical"] and out["moved"] >= 5


# ---------------------------------------------------------------------------------------------------
# The case file
# ---------------------------------------------------------------------------------------------------

CASE = """\
name: rock
block:
  centre_of_mass_height: 0.294 m
  half_widths: [0.044 m, 0.129 m]
{extra}  mass: 330 kg
contact: {{mu_static: 0.6, restitution: {e}}}
ground:
  horizontal: {{pulse: half-sine, amplitude: 0.3 g, duration: 0.5 s}}
  tail: 1 s
"""


def body_case(e=0.8, extra=""):
    return parse_case(CASE.format(e=e, extra=extra))


def test_a_case_gives_a_body_by_its_centre_of_mass_and_half_widths():
    case = body_case(extra="  radius_of_gyration: 0.177 m\n")
    assert case.block.half_widths == (0.044, 0.129)
    assert case.block.height == pytest.approx(0.588) and case.block.width == pytest.approx(0.173)
    assert case.block.radius_of_gyration == 0.177
    assert case.block.tipping_angles == pytest.approx((0.1485572796, 0.4134805321), rel=1e-9)
    assert "α1 = 0.1486 rad" in case.block.describe() and "α2 = 0.4135 rad" in case.block.describe()
    again = parse_case(__import__("yaml").safe_dump(case.to_dict()))
    assert again.block == case.block
    changed = case.with_({"block.half_widths": ["0.129 m", "0.044 m"]})
    assert changed.block.half_widths == (0.129, 0.044)
    from rockslide.engine.prepare import model_for
    model = model_for(case)
    assert model.asymmetric and model.half_widths == (0.044, 0.129) and model.radius_of_gyration == 0.177


def test_a_rectangle_case_is_todays():
    text = CASE.replace("  centre_of_mass_height: 0.294 m\n  half_widths: [0.044 m, 0.129 m]\n",
                        "  height: 0.5 m\n  width: 0.2 m\n").format(e=0.8, extra="")
    case = parse_case(text)
    assert case.block.half_widths is None and not case.block.asymmetric
    assert "half_widths" not in case.to_dict()["block"]
    from rockslide.engine.prepare import model_for
    assert model_for(case) == Model.from_block(0.2, 0.5, 0.6, 0.6, 0.8, G0, 330.0)


@pytest.mark.parametrize(("extra", "e", "key", "words"), [
    ("", 0.999, "contact.restitution", "e_max = 0.9963850738"),
    ("  radius_of_gyration: 0.4 m\n", 0.5, "block.radius_of_gyration", "0.321056 m"),
    ("  radius_of_gyration: 0 m\n", 0.5, "block.radius_of_gyration", "(0, "),
    ("  width: 0.2 m\n", 0.5, "block.half_widths", "exclusive"),
])
def test_bad_bodies_are_one_line_naming_the_key(extra, e, key, words):
    with pytest.raises(CaseError) as err:
        body_case(e=e, extra=extra)
    message = str(err.value)
    assert key in message and words in message and "\n" not in message


@pytest.mark.parametrize("pair", ["[0.044 m, -0.1 m]", "[0.044 m]", "0.1 m"])
def test_half_widths_must_be_two_positive_lengths(pair):
    with pytest.raises(CaseError, match="block.half_widths"):
        parse_case(CASE.replace("[0.044 m, 0.129 m]", pair).format(e=0.5, extra=""))


def test_a_body_case_runs_and_says_both_tipping_angles():
    from rockslide.engine.prepare import model_for
    case = body_case(e=0.8)
    model = model_for(case)
    s = sample(case.ground.horizontal, None, 1e-3)
    summary = simulate(model, s.dt, case.ground.horizontal.amplitude * s.horizontal, s.vertical,
                       Settings(tail=1.0, history_every=0)).summary
    assert summary.overturned and summary.direction == 1          # 0.3 g > 0.217 g toward the weak side
    assert textwrap.dedent(case.block.describe()).startswith("body: centre of mass 0.294 m high")
