"""Exact solutions of the whole simulation (rockslide.core.simulate as a black box).

docs/model.md, 'Reference solutions for tests': free rocking (quadrature), thresholds under ramps,
pure slip under piecewise-linear ground acceleration (polynomials in time), Newmark's rectangular
pulse, mirror symmetry, overturning, flight.

Tolerances, in general:
- Located events are found by Illinois regula falsi to ``1e-15 + 1e-13 h`` of local time on RK4
  sub-steps, and RK4's global error on these smooth motions is ~``(p h)^4 = (8e-4)^4 ~ 4e-13``
  relative at the default ``h = 1e-4`` s: event times agree with the quadrature to ~1e-12 s, so
  the brief's 1e-8 s is a loose, safe bound.
- Slip under a piecewise-linear ground acceleration is a cubic in time, which RK4 integrates
  exactly: only rounding remains, ~``n_steps * eps`` relative (1e4 steps: 2e-12).
- Quadratures use ``epsrel = 1e-13``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from rocking_reference import (
    free_rocking_impacts,
    landing_rate,
    mechanical_energy,
    peak_angle,
    quarter_period,
    time_to_angle_under_constant_push,
)

from rockslide.core import physics as P
from rockslide.core.simulate import Model, Settings, simulate

G0 = 9.80665
MODES = ["located", "step-end"]
STILL = (np.zeros(2), np.zeros(2))        # no ground motion; the tail sets the duration


def _free(model, duration, mode="located", dt_record=1e-3, **initial):
    return simulate(model, dt_record, *STILL, Settings(events=mode, tail=duration, **initial))


def _causes(result):
    return [c.decode() for c in result.events["cause"]]


# ================================================================================================
# Free rocking: impact times, constant peak with e = 1, decay and end of liftoff with e < 1
# ================================================================================================

FREE_CASES = [  # (height, width, theta0)
    (0.2, 0.1, 0.1), (0.2, 0.1, -0.3), (0.2, 0.1, 0.02), (0.2, 0.1, -0.42),
    (1.0, 0.2, 0.15), (1.0, 0.2, -0.05),
]


@pytest.mark.parametrize("height,width,theta0", FREE_CASES)
def test_free_rocking_elastic_impacts_at_odd_multiples_of_the_quarter_period(height, width, theta0):
    """e = 1: impacts at T, 3T, 5T, ... (100 impacts = 50 cycles), alternating edges, within 1e-8 s."""
    model = Model.from_block(width, height, 10.0, 10.0, 1.0)
    R, alpha, p2 = model.constants
    T = quarter_period(abs(theta0), alpha, p2)
    n = 100
    result = _free(model, (2 * n + 0.5) * T, rotation=theta0)
    ev = result.events
    assert _causes(result) == ["impact"] * n
    expected = T * (2 * np.arange(n) + 1)
    # 1e-8 s: see the module docstring (observed ~1e-12 s after 100 impacts)
    np.testing.assert_allclose(ev["time"], expected, rtol=0, atol=1e-8)
    lam0 = math.copysign(1.0, theta0)
    np.testing.assert_array_equal(ev["edge"], lam0 * (-1.0) ** (np.arange(n) + 1))   # flips each time
    assert result.summary.impacts == n


@pytest.mark.parametrize("height,width,theta0", FREE_CASES)
def test_free_rocking_elastic_peak_never_changes(height, width, theta0):
    """e = 1: the largest |rotation| between consecutive impacts stays theta0 over 50 cycles.

    The history samples every step h, so the sampled peak is below the true one by at most
    (1/2) |thetaddot_peak| (h/2)^2 with thetaddot_peak = -p^2 sin(alpha - theta0) (+1% margin);
    it may exceed theta0 only by the integration error: ~1e5 steps of RK4 at local error
    (p h)^5 theta0 < 1e-15 theta0 plus rounding (<= 1e5 eps theta0 = 2e-11 theta0): 1e-10 theta0."""
    model = Model.from_block(width, height, 10.0, 10.0, 1.0)
    R, alpha, p2 = model.constants
    T = quarter_period(abs(theta0), alpha, p2)
    n = 100
    result = _free(model, (2 * n + 0.5) * T, rotation=theta0)
    h = result.step
    times = result.history["time"]
    rot = np.abs(result.history["rotation"])
    edges = np.concatenate([[0.0], result.events["time"], [times[-1] + h]])
    sampling = 0.5 * p2 * math.sin(alpha - abs(theta0)) * (0.5 * h) ** 2 * 1.01
    peaks = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        inside = (times >= a) & (times <= b)
        peaks.append(rot[inside].max())
    peaks = np.array(peaks)
    assert len(peaks) == n + 1
    assert peaks.max() <= abs(theta0) * (1 + 1e-10)
    assert peaks.min() >= abs(theta0) - sampling - 1e-10 * abs(theta0)


@pytest.mark.parametrize("e", [0.8, 0.5])
@pytest.mark.parametrize("theta0", [0.2, -0.35])
def test_free_rocking_inelastic_impact_sequence(e, theta0):
    """e < 1: each impact multiplies the rate by e; the time between impacts k and k+1 is twice
    the quarter period of the peak reached with the reduced rate. All impact times within 1e-8 s."""
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, e)
    R, alpha, p2 = model.constants
    result = _free(model, 3.0, rotation=theta0)
    ev = result.events
    assert _causes(result)[-1] == "liftoff-end"
    expected = free_rocking_impacts(theta0, alpha, p2, e, len(ev))
    np.testing.assert_allclose(ev["time"], expected, rtol=0, atol=1e-8)
    # intervals (each from two consecutive located events): same bound
    np.testing.assert_allclose(np.diff(ev["time"]), np.diff(expected), rtol=0, atol=1e-8)


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("e", [0.8, 0.5, 0.0])
@pytest.mark.parametrize("theta0", [0.2, -0.35])
def test_free_rocking_inelastic_ends_at_rest(mode, e, theta0):
    """e < 1: finitely many impacts, then REST with rotation and rate exactly 0 (decision 3).

    model.md leaves the rule to the implementation ('for example a free-rocking peak angle below
    1e-7 rad'). Whatever the rule, with the exact rates e^k w0 (w0 the first landing rate, k
    counting the impacts including the last one, 'liftoff-end'): the rebound dropped must be small,
    a predicted peak below 1e-6 rad, and the last one kept must not be absurdly small, a peak above
    1e-12 rad (for e = 0.8 from 0.2 rad, ~115 impacts: the count is finite and bounded). With
    e = 0 there is no rebound: the first impact is a flat landing (decision 2) that stops the block
    (mu = 10 > 1 / tan(alpha), the friction a plastic landing needs)."""
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, e)
    R, alpha, p2 = model.constants
    result = _free(model, 4.0, mode=mode, rotation=theta0)
    s, hist = result.summary, result.history
    assert s.status == "ok" and not s.overturned
    assert 1 <= s.impacts < 200
    if e == 0.0:
        assert _causes(result) == ["impact"] and list(result.events["impact"]) == [b"flat"]
    else:
        assert _causes(result)[-1] == "liftoff-end"
        assert _causes(result)[:-1] == ["impact"] * (s.impacts - 1)
        assert set(result.events["impact"]) == {b"stick"}
    assert result.events[-1]["to"] == b"REST"
    end = result.events[-1]["time"]
    after = hist["time"] > end
    assert after.any()
    assert np.all(hist["state"][after] == P.REST)
    assert np.all(hist["rotation"][after] == 0.0) and np.all(hist["rotation_rate"][after] == 0.0)
    assert s.energy["kinetic"] == 0.0 and s.energy["potential"] == 0.0
    if mode == "located" and e > 0.0:
        w0 = landing_rate(abs(theta0), alpha, p2)
        dropped = peak_angle(e ** s.impacts * w0, alpha, p2)
        assert dropped <= 1e-6
        if s.impacts > 1:
            kept = peak_angle(e ** (s.impacts - 1) * w0, alpha, p2)
            assert kept > 1e-12


# ================================================================================================
# Energy never rises in free motion
# ================================================================================================
#
# Per-sample tolerance 1e-12 E0: on these smooth motions RK4's local energy error is
# ~(p h)^5 E0 ~ 4e-16 E0 per step, and evaluating E costs ~10 roundings (2e-15 E0); an impact
# (located) only lowers the rate, and a located slip stop happens where xdot = 0 already.

ENERGY_CASES = {   # name: (mu, e, rotation, slip_rate)
    "rock e<1": (10.0, 0.8, 0.2, 0.0),
    "rock e=1": (10.0, 1.0, -0.3, 0.0),
    "slip": (0.3, 0.8, 0.0, 1.0),
    "slip backwards": (0.3, 0.8, 0.0, -0.7),
    "rockslip e=1": (0.3, 1.0, 0.05, 0.3),
    "rockslip e=1 to rest": (0.3, 1.0, 0.08, -0.4),
    "rockslip e<1": (0.3, 0.8, 0.1, 0.5),
}


def _energy_run(name, mode):
    mu, e, rot, xd = ENERGY_CASES[name]
    model = Model.from_block(0.1, 0.2, mu, mu, e)
    return model, _free(model, 2.0, mode=mode, rotation=rot, slip_rate=xd)


@pytest.mark.parametrize("name", list(ENERGY_CASES))
def test_energy_never_rises_in_free_motion_located(name):
    model, result = _energy_run(name, "located")
    E = mechanical_energy(model, result.history)
    E0 = E[0]
    assert E0 > 0
    assert np.diff(E).max() <= 1e-12 * E0
    assert result.summary.energy["initial"] == pytest.approx(E0 * model.mass, rel=1e-14)
    # the ledger: kinetic + potential - initial - (ground + friction + impact work) = 0; its terms are
    # integrated by the same RK4 (relative error ~(p h)^4 per unit time): 1e-10 E0
    assert abs(result.summary.energy["balance_residual"]) <= 1e-10 * E0


@pytest.mark.parametrize("name", ["rock e<1", "rock e=1", "slip", "slip backwards"])
def test_energy_never_rises_in_free_motion_step_end(name):
    """Step-end switching: impacts are found after theta went below 0 and the kernel brings the
    block back to theta = 0 at constant energy; a slip stop found late sets an overshooting xdot
    to 0. Neither adds energy in ROCK or SLIP: same per-sample bound as located."""
    model, result = _energy_run(name, "step-end")
    E = mechanical_energy(model, result.history)
    assert np.diff(E).max() <= 1e-12 * E[0]


@pytest.mark.parametrize("name", ["rockslip e=1", "rockslip e<1"])
def test_energy_rise_in_free_rockslip_step_end_is_first_order(name):
    """Step-end switching in ROCKSLIP: a slip stop found at the end of a step sets the overshooting
    xdot (|xdot| <= max|xddot| h) to 0, which changes the coupling term -lam R c xdot thetadot of
    the kinetic energy; the impact's return to theta = 0 ignores that term too. So energy may rise
    by O(h) at such events: bounded here by max|xddot| h (R max|thetadot| + max|xdot|)."""
    model, result = _energy_run(name, "step-end")
    hist = result.history
    E = mechanical_energy(model, hist)
    R = model.constants[0]
    h = result.step
    xddot = np.abs(np.diff(hist["slip_rate"])).max() / h
    bound = xddot * h * (R * np.abs(hist["rotation_rate"]).max() + np.abs(hist["slip_rate"]).max())
    assert np.diff(E).max() <= bound


@pytest.mark.parametrize("mu,e,rotation,slip_rate", [(0.2, 0.5, 0.1, -1.0), (0.2, 0.5, 0.1, 1.0),
                                                     (0.05, 0.5, 0.05, 1.0)])
def test_energy_never_rises_at_rockslip_impacts_with_restitution(mu, e, rotation, slip_rate):
    """Free liftoff-slip interaction with impacts (the cases that found the 0.1 impact rule adding
    energy when the block slid toward the landing edge): the mechanical energy never rises, impacts
    included (per sample, 1e-12 E0: RK4's energy error), and the run has impacts of the slip branch."""
    model = Model.from_block(0.1, 0.2, mu, mu, e)
    result = _free(model, 1.0, rotation=rotation, slip_rate=slip_rate)
    E = mechanical_energy(model, result.history)
    assert np.diff(E).max() <= 1e-12 * E[0]
    assert result.summary.impacts >= 1


@pytest.mark.parametrize("mu,e,rotation,slip_rate", [(0.2, 0.5, 0.1, -1.0), (0.2, 0.5, 0.1, 1.0),
                                                     (0.05, 0.5, 0.05, 1.0), (0.3, 0.9, 0.2, 0.5)])
def test_impact_loss_is_the_sum_of_per_impact_losses_each_non_negative(mu, e, rotation, slip_rate):
    """The ledger's impact loss is the sum of the event log's per-impact losses (to rounding,
    1e-12 of the initial energy), each >= 0: a negative loss would be an impact that creates energy,
    a bug. The balance closes (1e-10 E0, the RK4 ledger)."""
    model = Model.from_block(0.1, 0.2, mu, mu, e)
    result = _free(model, 1.0, rotation=rotation, slip_rate=slip_rate)
    energy, ev = result.summary.energy, result.events
    impacts = ev[ev["impact"] != b""]
    assert len(impacts) == result.summary.impacts >= 1
    assert impacts["energy_loss"].min() >= -1e-15 * energy["initial"]
    assert energy["impact_loss"] == pytest.approx(impacts["energy_loss"].sum(), abs=1e-12 * energy["initial"])
    assert abs(energy["balance_residual"]) <= 1e-10 * energy["initial"]


# ================================================================================================
# Thresholds under ramps ah = k t (eqs. 6 and 11 with G = g + av)
# ================================================================================================

RAMP_SLOPES = [5.0, -7.3, 12.0, -30.0]


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_peak_exactly_at_the_liftoff_threshold_does_not_lift_off(mode, sign):
    """Eq. 6 is strict: a record whose peak is exactly tan(alpha) g (b/h = 0.5: 0.5 g is exact in
    binary) touches the threshold without passing it, and the block stays at rest. (v0.1 took the
    touch at the end of the rising interval for a crossing: liftoff and liftoff-end at one instant.)
    A peak one ulp above lifts it off."""
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 0.8)
    peak = 0.5 * G0
    for value, lifts in ((peak, False), (np.nextafter(peak, np.inf), True)):
        ah = sign * np.array([0.0, 0.3 * G0, value, 0.2 * G0, 0.0])
        result = simulate(model, 0.01, ah, np.zeros(ah.size), Settings(events=mode, tail=0.1))
        assert ("ROCK" in result.summary.states_seen) == lifts, (value, result.events)


@pytest.mark.parametrize("k", RAMP_SLOPES)
@pytest.mark.parametrize("av", [0.0, 2.5, -3.0])
@pytest.mark.parametrize("kind", ["liftoff", "slip"])
def test_ramp_thresholds_located(k, av, kind):
    """Liftoff at tan(alpha) (g + av) / |k| (mu large) and slip at mu (g + av) / |k| (mu small),
    within 1e-8 s (REST's exits are computed in closed form: observed error ~1e-16 s). lam =
    sign(ah) (eq. 7), sigma = -sign(ah) (model.md)."""
    mu = 10.0 if kind == "liftoff" else 0.2
    model = Model.from_block(0.1, 0.2, mu, 0.8 * mu, 0.8)
    ratio = 0.5 if kind == "liftoff" else mu
    exact = ratio * (G0 + av) / abs(k)
    dt_record = 1e-3
    t = np.arange(0.0, exact + 0.05, dt_record)      # the record ends 50 ms after the threshold
    result = simulate(model, dt_record, k * t, np.full(t.size, av), Settings())
    first = result.events[0]
    assert first["time"] == pytest.approx(exact, abs=1e-8)
    if kind == "liftoff":
        assert (first["cause"], first["to"], first["edge"]) == (b"liftoff", b"ROCK", np.sign(k))
    else:
        assert (first["cause"], first["to"], first["slip_direction"]) == (b"slip-start", b"SLIP",
                                                                          -np.sign(k))


@pytest.mark.parametrize("k", RAMP_SLOPES)
@pytest.mark.parametrize("mu", [10.0, 0.2, 0.5])
def test_ramp_thresholds_step_end(k, mu):
    """Step-end switching moves the threshold crossing to the end of its step (decision 1: with
    mu = tan(alpha) = 0.5 the block slips): t_event = ceil(t_exact / h) h (to 1e-12 s rounding)."""
    model = Model.from_block(0.1, 0.2, mu, 0.8 * mu, 0.8)
    exact = min(mu, 0.5) * G0 / abs(k)
    dt_record = 1e-3
    t = np.arange(0.0, exact + 0.05, dt_record)
    result = simulate(model, dt_record, k * t, np.zeros(t.size), Settings(events="step-end"))
    first = result.events[0]
    h = result.step
    assert first["time"] == pytest.approx(math.ceil(exact / h) * h, abs=1e-12)
    assert first["cause"] == (b"liftoff" if mu > 0.5 else b"slip-start")


# ================================================================================================
# Pure slip: parabola, stop, Newmark's rectangular pulse
# ================================================================================================

@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("ah", [0.5 * G0, -0.7 * G0])
@pytest.mark.parametrize("av", [0.0, 0.2 * G0])
def test_pure_slip_under_constant_acceleration_is_a_parabola(mode, ah, av):
    """xddot = -ah - nu sigma (g + av) with sigma = -sign(ah), from t = 0 (the block cannot lift
    off during SLIP: |xddot + ah| = nu G < tan(alpha) G). RK4 integrates the parabola exactly:
    rounding only, 1e4 steps x a few eps relative: 1e-11 of the largest |x| and |xdot|."""
    mu, nu = 0.3, 0.25
    model = Model.from_block(0.1, 0.2, mu, nu, 0.8)
    result = simulate(model, 0.01, np.full(101, ah), np.full(101, av), Settings(events=mode))
    hist = result.history
    assert _causes(result) == ["slip-start"] and result.events[0]["time"] == 0.0
    sigma = -math.copysign(1.0, ah)
    xddot = -ah - nu * sigma * (G0 + av)
    t = hist["time"]
    x, v = 0.5 * xddot * t * t, xddot * t
    assert np.all(hist["state"] == P.SLIP)
    np.testing.assert_allclose(hist["slip"], x, rtol=0, atol=1e-11 * np.abs(x).max())
    np.testing.assert_allclose(hist["slip_rate"], v, rtol=0, atol=1e-11 * np.abs(v).max())


def _pulse(A, t1, dt_record, duration):
    """Samples of a pulse of amplitude A for t in [0, t1] (samples 0..t1/dt), then 0: linearly
    interpolated, the input falls from A to 0 over [t1, t1 + dt_record]."""
    n1 = round(t1 / dt_record)
    n = round(duration / dt_record) + 1
    ah = np.zeros(n)
    ah[: n1 + 1] = A
    return ah


def _pulse_slip_exact(A, t1, d, nu, g=G0):
    """Exact slip of an upright block (SLIP from t = 0, sigma = -sign(A), no reversal) under the
    piecewise-linear pulse of `_pulse`: returns (stop time, final slip).

    For A > 0 (the other sign mirrors): xddot = -A + nu g on [0, t1]; -A (1 - s/d) + nu g on the
    ramp s = t - t1 in [0, d]; nu g afterwards until xdot = 0."""
    a = abs(A)
    v1 = -(a - nu * g) * t1
    x1 = 0.5 * v1 * t1
    v2 = v1 - a * d / 2 + nu * g * d
    x2 = x1 + v1 * d - a * d * d / 3 + nu * g * d * d / 2
    assert v2 < 0
    t_stop = t1 + d + (-v2) / (nu * g)
    x_end = x2 - v2 * v2 / (2 * nu * g)
    return t_stop, math.copysign(1.0, A) * x_end


@pytest.mark.parametrize("A", [0.62 * G0, -0.45 * G0])
def test_stepped_acceleration_slip_stops_exactly_located(A):
    """Slip while the ground accelerates, then the ground stops accelerating, the block decelerates
    at nu g and sticks: slip-stop time and final slip in closed form (cubic in time: RK4 exact;
    root finder to 1e-13 h). Tolerances 1e-10 s and 1e-12 m (rounding of ~5e3 steps)."""
    mu, nu, t1, dt_record = 0.4, 0.3, 0.3, 1e-3
    model = Model.from_block(0.1, 0.2, mu, nu, 0.8)
    result = simulate(model, dt_record, _pulse(A, t1, dt_record, 1.5), np.zeros(1501), Settings())
    t_stop, x_end = _pulse_slip_exact(A, t1, dt_record, nu)
    assert _causes(result) == ["slip-start", "slip-stop"]
    assert result.events[1]["to"] == b"REST"
    assert result.events[1]["time"] == pytest.approx(t_stop, abs=1e-10)
    assert result.summary.residual_slip == pytest.approx(x_end, abs=1e-12)
    assert result.history["slip"][-1] == result.summary.residual_slip
    assert result.history["state"][-1] == P.REST


@pytest.mark.parametrize("A", [0.62 * G0, -0.45 * G0])
def test_stepped_acceleration_slip_stops_step_end(A):
    """Step-end: the stop is taken at the end of its step; in between the block has accelerated
    backwards at nu g for delta < h, so the slip differs by (1/2) nu g delta^2 <= (1/2) nu g h^2."""
    mu, nu, t1, dt_record = 0.4, 0.3, 0.3, 1e-3
    model = Model.from_block(0.1, 0.2, mu, nu, 0.8)
    result = simulate(model, dt_record, _pulse(A, t1, dt_record, 1.5), np.zeros(1501),
                      Settings(events="step-end"))
    h = result.step
    t_stop, x_end = _pulse_slip_exact(A, t1, dt_record, nu)
    assert result.events[-1]["time"] == pytest.approx(math.ceil(t_stop / h) * h, abs=1e-12)
    assert abs(result.summary.residual_slip - x_end) <= 0.5 * nu * G0 * h * h + 1e-12


@pytest.mark.parametrize("A_over_mu_g", [1.5, 3.0, 8.0])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_newmark_rectangular_pulse(A_over_mu_g, sign):
    """Newmark (1965): a rectangular pulse (A, t1) slides a block with mu = nu by
    V^2 / (2 mu g) (1 - mu g / A), V = A t1. Liftoff is prevented by a squat block (width 10 x
    height: tan(alpha) = 10). The applied input ramps down over one sample interval d, which adds
    the impulse A d / 2: to first order a pulse of duration t1 + d/2, so Newmark's formula with
    t1 + d/2 holds to O(d^2) (tolerance 2 (d/t1)^2 relative), and the plain formula to d/t1
    relative (1.05 d / t1). The exact piecewise-linear answer holds to 1e-12 relative."""
    mu, t1, d = 0.3, 0.2, 1e-3
    A = sign * A_over_mu_g * mu * G0
    model = Model.from_block(1.0, 0.1, mu, mu, 0.8)
    duration = t1 * A_over_mu_g + 0.5
    ah = _pulse(A, t1, d, duration)
    result = simulate(model, d, ah, np.zeros(ah.size), Settings())
    assert result.summary.states_seen == ["REST", "SLIP"]
    slip = result.summary.residual_slip

    def newmark(t):
        V = abs(A) * t
        return -sign * V * V / (2 * mu * G0) * (1 - mu * G0 / abs(A))

    _, exact = _pulse_slip_exact(A, t1, d, mu)
    assert slip == pytest.approx(exact, rel=1e-12)
    assert slip == pytest.approx(newmark(t1 + d / 2), rel=2 * (d / t1) ** 2)
    assert slip == pytest.approx(newmark(t1), rel=1.05 * d / t1)
    assert abs(slip) > abs(newmark(t1))          # the ramp adds impulse


@pytest.mark.parametrize("A_over_mu_g", [1.5, 3.0, 8.0])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_newmark_exact_rectangular_pulse_as_interval_values(A_over_mu_g, sign):
    """The same pulse given as interval end values (`simulate.ground_array`, shape (2, n)): the
    ground jumps to A at t = 0 and back to 0 at t1 exactly, with no ramp, so Newmark's formula
    V^2 / (2 mu g) (1 - mu g / A) holds to rounding (RK4 is exact on the piecewise-constant slip
    acceleration; the slip stop is located to ~1e-17 s of local time): 1e-12 relative. The ground
    as written back (`simulate.ground_series`) repeats the jump times with both values."""
    mu, t1, d = 0.3, 0.2, 1e-3
    A = sign * A_over_mu_g * mu * G0
    model = Model.from_block(1.0, 0.1, mu, mu, 0.8)
    n_pulse = round(t1 / d)
    values = np.zeros((2, n_pulse + round((t1 * A_over_mu_g + 0.5) / d)))
    values[:, :n_pulse] = A
    result = simulate(model, d, values, np.zeros_like(values), Settings())
    assert result.summary.states_seen == ["REST", "SLIP"]
    V = abs(A) * t1
    exact = -sign * V * V / (2 * mu * G0) * (1 - mu * G0 / abs(A))
    assert result.summary.residual_slip == pytest.approx(exact, rel=1e-12)
    t, h = result.ground_time, result.ground_horizontal
    assert np.count_nonzero(t == t1) == 2 and list(h[t == t1]) == [A, 0.0]
    assert t[0] == 0.0 and h[0] == A and np.all(np.diff(t) >= 0.0)


# ================================================================================================
# Mirror symmetry
# ================================================================================================

def _mirror_input():
    dt_record = 0.005
    t = np.arange(0.0, 3.0 + 0.5 * dt_record, dt_record)
    ah = 0.9 * G0 * (0.45 * np.sin(2 * np.pi * 1.3 * t + 0.3) + 0.3 * np.sin(2 * np.pi * 3.1 * t + 1.1)
                     + 0.15 * np.sin(2 * np.pi * 7.3 * t))
    av = 0.4 * G0 * (np.sin(2 * np.pi * 2.2 * t + 0.7) + 0.4 * np.sin(2 * np.pi * 5.9 * t))
    return dt_record, ah, av


@pytest.mark.parametrize("mode", MODES)
def test_mirror_symmetry(mode):
    """Reversing the horizontal input mirrors the response exactly: every formula is odd or even
    in (ah, lam, sigma) and computes the mirrored values with the same operations, and IEEE negation
    is exact, so equality is bit for bit (no tolerance). The edge is compared for events that
    involve rocking, the slip direction for events that involve slipping (otherwise they are the
    kernel's unused defaults)."""
    dt_record, ah, av = _mirror_input()
    model = Model.from_block(0.1, 0.2, 0.53, 0.8 * 0.53, 0.8)
    settings = Settings(events=mode, tail=0.5)
    a = simulate(model, dt_record, ah, av, settings)
    b = simulate(model, dt_record, -ah, av, settings)
    # the case exercises slip, rocking, their interaction and impacts
    assert {"SLIP", "ROCK", "ROCKSLIP"} <= set(a.summary.states_seen)
    assert a.summary.impacts > 10 and not a.summary.overturned and a.summary.status == "ok"
    ea, eb = a.events, b.events
    assert len(ea) == len(eb)
    np.testing.assert_array_equal(ea["time"], eb["time"])
    for field in ("from", "to", "cause"):
        np.testing.assert_array_equal(ea[field], eb[field])
    rocking = (np.isin(ea["to"], [b"ROCK", b"ROCKSLIP", b"OVERTURNED"])
               | np.isin(ea["from"], [b"ROCK", b"ROCKSLIP"]))
    slipping = np.isin(ea["to"], [b"SLIP", b"ROCKSLIP"]) | np.isin(ea["from"], [b"SLIP", b"ROCKSLIP"])
    assert rocking.sum() > 10 and slipping.sum() > 5
    np.testing.assert_array_equal(ea["edge"][rocking], -eb["edge"][rocking])
    np.testing.assert_array_equal(ea["slip_direction"][slipping], -eb["slip_direction"][slipping])
    ha, hb = a.history, b.history
    np.testing.assert_array_equal(ha["time"], hb["time"])
    np.testing.assert_array_equal(ha["state"], hb["state"])
    for name in ("rotation", "rotation_rate", "slip", "slip_rate"):
        np.testing.assert_array_equal(ha[name], -hb[name])
    sa, sb = a.summary, b.summary
    assert (sa.max_rotation, sa.max_rotation_time, sa.max_slip, sa.impacts) == \
        (sb.max_rotation, sb.max_rotation_time, sb.max_slip, sb.impacts)
    assert sa.residual_slip == -sb.residual_slip
    assert sa.time_in_state == sb.time_in_state
    assert sa.energy == sb.energy


# ================================================================================================
# Overturning
# ================================================================================================

@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("A", [0.8 * G0, -0.8 * G0, 0.6 * G0])
def test_overturning_under_a_long_constant_pulse(mode, A):
    """A long strong constant pulse (|ah| > tan(alpha) g) tips the block over toward sign(ah).

    The fall starts when theta passes alpha; until then the block rocks without slipping (mu = 10),
    so that time is a quadrature of the energy equation under a constant push. The kernel
    interpolates it linearly within the step: error <= thetaddot h^2 / (8 thetadot) at alpha
    (+10%), with thetaddot = p^2 |ah| / g there."""
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 0.8)
    R, alpha, p2 = model.constants
    dt_record = 1e-3
    n = 2001
    result = simulate(model, dt_record, np.full(n, A), np.zeros(n), Settings(events=mode))
    s, hist = result.summary, result.history
    h = result.step
    assert s.overturned and s.status == "ok" and s.verdict == "overturned"
    assert s.direction == np.sign(A)
    assert s.fall_start_time < s.overturn_time
    assert s.end_time == s.overturn_time
    assert result.events[-1]["cause"] == b"overturn" and result.events[-1]["time"] == s.overturn_time
    assert result.events[-1]["edge"] == np.sign(A)
    # the history stops at the overturn, with nothing computed after it
    assert s.overturn_time - h - 1e-12 <= hist["time"][-1] <= s.overturn_time + 1e-12
    assert np.all(np.isfinite(hist["rotation"])) and np.all(np.isfinite(hist["slip"]))
    assert np.all(np.sign(hist["rotation"][1:]) == np.sign(A))
    assert s.max_rotation >= 0.5 * math.pi - 1e-12
    # fall start against the quadrature
    a = abs(A) / G0
    exact = time_to_angle_under_constant_push(alpha, a, alpha, p2)
    rate = math.sqrt(2 * p2 * (math.cos(alpha) - 1 + a * math.sin(alpha)))
    tol = 1.1 * p2 * a * h * h / (8 * rate)
    assert abs(s.fall_start_time - exact) <= tol
    if mode == "located":
        assert s.max_rotation == pytest.approx(0.5 * math.pi, abs=1e-12)


# ================================================================================================
# Flight: g + av reaches 0
# ================================================================================================

def _flight_input(k, ah, duration=1.0, dt_record=1e-3):
    t = np.arange(0.0, duration + 0.5 * dt_record, dt_record)
    return dt_record, np.full(t.size, ah), -k * t


@pytest.mark.parametrize("k", [15.0, 20.0, 40.0])
def test_flight_from_rest(k):
    """av = -k t: G = g - k t reaches 0 at g/k; located: exactly (REST's exits are in closed form,
    1e-12 s); the run stops there, outside the model."""
    model = Model.from_block(0.1, 0.2, 0.3, 0.3, 0.8)
    dt_record, ah, av = _flight_input(k, 0.0)
    result = simulate(model, dt_record, ah, av, Settings())
    s = result.summary
    assert s.status == "flight" and "outside the model" in s.verdict
    assert s.end_time == pytest.approx(G0 / k, abs=1e-12)
    assert _causes(result) == ["flight"]
    assert result.history["time"][-1] <= s.end_time
    assert result.history["time"][-1] > s.end_time - result.step - 1e-12


@pytest.mark.parametrize("k", [15.0, 20.0, 40.0])
def test_flight_from_rest_step_end(k):
    model = Model.from_block(0.1, 0.2, 0.3, 0.3, 0.8)
    dt_record, ah, av = _flight_input(k, 0.0)
    result = simulate(model, dt_record, ah, av, Settings(events="step-end"))
    h = result.step
    assert result.summary.status == "flight"
    assert result.summary.end_time == pytest.approx(math.ceil(G0 / k / h) * h, abs=1e-12)


def _slip_until_flight(A, k, nu):
    """Exact slip from the slip start ts = (g - |A|/mu)/k to the flight at tf = g/k under ah = A,
    G = g - k t (sigma = -sign(A)): xddot = -A - nu sigma (g - k t), integrated twice."""
    sigma = -math.copysign(1.0, A)

    def x(t, ts):
        s = t - ts
        # xdot = (-A - nu sigma g) s + nu sigma k (t^2 - ts^2) / 2
        # x = (-A - nu sigma g) s^2 / 2 + nu sigma k ((t^3 - ts^3)/3 - ts^2 s) / 2
        return ((-A - nu * sigma * G0) * s * s / 2
                + nu * sigma * k * ((t ** 3 - ts ** 3) / 3 - ts * ts * s) / 2)

    return x


@pytest.mark.parametrize("k", [15.0, 25.0, 40.0])
@pytest.mark.parametrize("A", [0.2 * G0, -0.2 * G0])
def test_flight_while_slipping(k, A):
    """Slip starts at (g - |A|/mu)/k, the run stops at g/k: nothing is integrated beyond it, so the
    final slip is the exact cubic at g/k (RK4 exact for cubics: rounding only, 1e-12 m)."""
    mu = nu = 0.3
    model = Model.from_block(0.1, 0.2, mu, nu, 0.8)
    dt_record, ah, av = _flight_input(k, A)
    result = simulate(model, dt_record, ah, av, Settings())
    s = result.summary
    ts, tf = (G0 - abs(A) / mu) / k, G0 / k
    assert result.events[0]["cause"] == b"slip-start"
    assert result.events[0]["time"] == pytest.approx(ts, abs=1e-12)
    assert s.status == "flight" and s.end_time == pytest.approx(tf, abs=1e-12)
    assert result.events[-1]["cause"] == b"flight"
    assert s.residual_slip == pytest.approx(_slip_until_flight(A, k, nu)(tf, ts), abs=1e-12)
    assert result.history["time"][-1] <= s.end_time


def test_flight_while_slipping_logs_no_liftoff():
    """At G = 0 the eq. 23 liftoff margin (tan(alpha) - nu) G vanishes with the flight function G;
    the tie goes to flight (the first row), never an impossible SLIP -> ROCKSLIP liftoff first."""
    model = Model.from_block(0.1, 0.2, 0.3, 0.3, 0.8)
    logs = []
    for k in (10.0, 15.0, 20.0, 25.0, 30.0, 40.0):
        dt_record, ah, av = _flight_input(k, 0.2 * G0, duration=1.2)
        logs.append(_causes(simulate(model, dt_record, ah, av, Settings())))
    assert all(log == ["slip-start", "flight"] for log in logs), logs


# ================================================================================================
# End of liftoff with slip (decision 3) in both event modes
# ================================================================================================

ZENO_CASES = [(0.25, -0.1, 0.3), (0.25, 0.1, -0.3), (0.2, -0.1, 0.3)]


def _rockslip_free(mode, mu, rotation, slip_rate, tail):
    model = Model.from_block(0.1, 0.2, mu, 0.95 * mu, 0.8)
    return simulate(model, 0.01, *STILL, Settings(events=mode, tail=tail, rotation=rotation,
                                                  slip_rate=slip_rate, history_every=0))


@pytest.mark.parametrize("mu,rotation,slip_rate", ZENO_CASES)
def test_free_rockslip_impacts_end_located(mu, rotation, slip_rate):
    """Paper's block and restitution, released rotated and slipping: the impacts end (finite count,
    the same for 1 s and 2 s of free motion) and the block is at REST at the end."""
    short = _rockslip_free("located", mu, rotation, slip_rate, 1.0)
    long = _rockslip_free("located", mu, rotation, slip_rate, 2.0)
    assert short.summary.impacts == long.summary.impacts < 100
    assert long.events[-1]["to"] == b"REST"


@pytest.mark.parametrize("mu,rotation,slip_rate", ZENO_CASES)
def test_free_rockslip_impacts_end_step_end(mu, rotation, slip_rate):
    """Step-end switching cannot resolve flights of a few steps (they used to chatter for ever in a
    2-step cycle); they end the liftoff too (docs/model.md, decision 3)."""
    short = _rockslip_free("step-end", mu, rotation, slip_rate, 1.0)
    long = _rockslip_free("step-end", mu, rotation, slip_rate, 2.0)
    assert short.summary.impacts == long.summary.impacts < 100
    assert long.events[-1]["to"] == b"REST"
