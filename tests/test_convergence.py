"""Error against the step size dt, for both event modes (docs/model.md, 'Integration').

Within a state the motion is smooth and the kernel uses classical RK4 (global error O(h^4)); the
input is linear between record samples and every step divides the record interval, so its kinks
fall on step boundaries and do not spoil the order. What differs between the modes is the events:
'located' finds them inside the step (to ~1e-13 h), 'step-end' applies them at the end of the step
in which they happened, which delays each by a fraction of h: first order.

Observed orders p = log2(err(2h) / err(h)) are only meaningful while the error is well above the
rounding floor (~1e-15 relative after 1e3-1e4 steps); each test keeps to step sizes where the
smallest error is >= 10x that floor, so rounding moves p by < log2(1.1) = 0.14: hence the ranges
[3.5, 4.5] for RK4's 4.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from rocking_reference import quarter_period

from rockslide.core.simulate import Model, Settings, simulate

G0 = 9.80665
MODES = ["located", "step-end"]
DT_RECORD = 2e-3
STEPS = [2e-3, 1e-3, 5e-4, 2.5e-4]      # all divide DT_RECORD
REFERENCE_STEP = 1e-5                   # RK4 error (p h)^4 ~ 4e-17 relative: exact for this purpose


def _orders(errors):
    errors = np.asarray(errors, float)
    return np.log2(errors[:-1] / errors[1:])


# ================================================================================================
# Smooth motion: rocking under a smooth input, no event in the window
# ================================================================================================

def _smooth_input(duration):
    t = np.arange(0.0, duration + 0.5 * DT_RECORD, DT_RECORD)
    return 3.0 * np.sin(2 * np.pi * 2.0 * t), 1.5 * np.sin(2 * np.pi * 3.0 * t + 0.4)


def _smooth_final_state(dt, mode):
    """Released at 0.1 rad rising at 1 rad/s under a sine input; state at t = 0.2 s, before the
    first impact (no event at all: checked)."""
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 0.8)
    ah, av = _smooth_input(0.2)
    result = simulate(model, DT_RECORD, ah, av, Settings(dt=dt, events=mode, rotation=0.1,
                                                         rotation_rate=1.0))
    assert len(result.events) == 0
    hist = result.history
    assert hist["time"][-1] == pytest.approx(0.2, abs=1e-12)
    return np.array([hist["rotation"][-1], hist["rotation_rate"][-1]])


@pytest.mark.parametrize("mode", MODES)
def test_smooth_rocking_is_fourth_order(mode):
    reference = _smooth_final_state(REFERENCE_STEP, "located")
    errors = np.array([np.abs(_smooth_final_state(dt, mode) - reference) for dt in STEPS])
    # smallest error ~1.6e-14 rad for the rotation 0.03 rad: >= 10x the rounding floor
    assert errors[-1].min() > 10 * 1e-15 * np.abs(reference).max()
    for column in range(2):
        p = _orders(errors[:, column])
        assert np.all((p > 3.5) & (p < 4.5)), p
    assert errors[0].max() < 1e-8         # and small in absolute terms at dt = 2 ms


def test_smooth_rocking_identical_in_both_modes():
    """Without events, the two modes are the same RK4 integration, bit for bit."""
    for dt in STEPS[:2]:
        np.testing.assert_array_equal(_smooth_final_state(dt, "located"),
                                      _smooth_final_state(dt, "step-end"))


def test_liftoff_from_rest_located_stays_fourth_order():
    """From rest under a sine input stronger than tan(alpha) g: the liftoff is found exactly (REST's
    exits are linear in time) and the ROCK integration restarts mid-step, so located events keep
    RK4's order on a state at a fixed time after the liftoff."""
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 0.8)
    t = np.arange(0.0, 0.3 + 0.5 * DT_RECORD, DT_RECORD)
    ah = 0.9 * G0 * np.sin(2 * np.pi * 2.0 * t)
    av = 0.2 * G0 * np.sin(2 * np.pi * 3.0 * t + 0.4)

    def final(dt):
        result = simulate(model, DT_RECORD, ah, av, Settings(dt=dt))
        assert [c.decode() for c in result.events["cause"]] == ["liftoff"]
        return np.array([result.history["rotation"][-1], result.history["rotation_rate"][-1]])

    reference = final(REFERENCE_STEP)
    errors = np.array([np.abs(final(dt) - reference) for dt in STEPS])
    assert errors[-1].min() > 10 * 1e-15 * np.abs(reference).max()
    for column in range(2):
        p = _orders(errors[:, column])
        assert np.all((p > 3.5) & (p < 4.5)), p


# ================================================================================================
# Impacts: time of the 3rd impact of free rocking (exact: 5 T by quadrature)
# ================================================================================================

THETA0S = np.linspace(0.05, 0.3, 15)
IMPACT_STEPS = [2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5]


def _third_impact_errors(mode, steps, theta0s):
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 1.0)
    R, alpha, p2 = model.constants
    errors = np.zeros((len(theta0s), len(steps)))
    for i, theta0 in enumerate(theta0s):
        T = quarter_period(theta0, alpha, p2)
        for j, dt in enumerate(steps):
            result = simulate(model, DT_RECORD, np.zeros(2), np.zeros(2),
                              Settings(dt=dt, events=mode, rotation=theta0, tail=5 * T + 0.05,
                                       history_every=0))
            assert result.events["cause"][2] == b"impact"
            errors[i, j] = result.events["time"][2] - 5 * T
    return errors


def test_impact_times_located_are_accurate_at_any_step():
    """Located: the 3rd impact time carries only RK4's error of the smooth flights between impacts
    (the landings are located to ~1e-13 h). Bound: (p h)^4 t, RK4's global error scale
    for a motion of rate p over the time t = 5 T, plus 1e-13 s of rounding (observed: 100x below
    it, e.g. 5e-10 s at h = 2 ms). It converges at RK4's order while above 1e-12 s."""
    steps = IMPACT_STEPS[:4]
    theta0s = THETA0S[::3]
    errors = np.abs(_third_impact_errors("located", steps, theta0s))
    model = Model.from_block(0.1, 0.2, 10.0, 10.0, 1.0)
    R, alpha, p2 = model.constants
    for i, theta0 in enumerate(theta0s):
        t_event = 5 * quarter_period(theta0, alpha, p2)
        bound = (math.sqrt(p2) * np.array(steps)) ** 4 * t_event + 1e-13
        assert np.all(errors[i] <= bound), (errors[i], bound)
    assert errors[:, 0].max() < 1e-9
    for row in errors:
        usable = row[row > 1e-12]
        if usable.size >= 2:
            p = _orders(usable)
            assert np.all(p > 3.5), p


def test_impact_times_step_end_are_first_order():
    """Step-end switching finds each landing at the end of its step, a delay uniform in [0, h):
    the 3rd impact is late by the sum of three such delays (the kernel restores the energy of a
    late landing, so the motion is not otherwise changed), 1.5 h on average over release angles.
    Averaged over 15 release angles, the error is first order in h: least-squares order of the mean
    error over 2e-3 .. 6.25e-5 s in [0.7, 1.5] (the fractional parts of t / h make single ratios
    noisy), every impact late (error > 0) and mean error / h within [0.5, 3] (~1.5)."""
    errors = _third_impact_errors("step-end", IMPACT_STEPS, THETA0S)
    assert np.all(errors > 0.0)
    mean = errors.mean(axis=0)
    order = np.polyfit(np.log(IMPACT_STEPS), np.log(mean), 1)[0]
    assert 0.7 < order < 1.5, order
    ratio = mean / np.array(IMPACT_STEPS)
    assert np.all((ratio > 0.5) & (ratio < 3.0)), ratio
    # located is better by orders of magnitude at every step
    located = np.abs(_third_impact_errors("located", IMPACT_STEPS[:2], THETA0S[::7]))
    assert located.max() < 1e-6 * mean[:2].min()
    assert math.isfinite(order)
