"""Intensity measures (`rockslide.core.intensity`) against closed forms.

The oscillator's recurrence is exact for an input linear between samples, so inputs that are
exactly piecewise linear (a step, a ramp, a triangle pulse) must match their closed-form responses
to round-off; a sampled sine carries the interpolation error ``O((Omega dt)^2)``, bounded below.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockslide.core import intensity as im

ZETA = 0.05


def damped(t, omega, zeta):
    """``exp(-zeta omega t)`` times cos and sin of the damped frequency, and that frequency."""
    wd = omega * math.sqrt(1.0 - zeta * zeta)
    decay = np.exp(-zeta * omega * t)
    return decay * np.cos(wd * t), decay * np.sin(wd * t), wd


@pytest.mark.parametrize("period, zeta, dt", [(0.5, 0.05, 0.01), (0.05, 0.02, 0.02), (3.0, 0.2, 0.005)])
def test_step_response_is_exact(period, zeta, dt):
    """``a(t) = a0`` from t = 0 (piecewise linear exactly): ``u = -(a0/w^2) [1 - e^(-zeta w t)
    (cos wd t + zeta/sqrt(1-zeta^2) sin wd t)]``. Round-off only: 1e-12 of the peak. The second case
    has a period shorter than the sampling step (w dt = 2.5)."""
    a0, n = 2.0, 801
    t = dt * np.arange(n)
    u, v = im.sdof_response(np.full(n, a0), dt, period, zeta)
    w = 2 * math.pi / period
    c, s, wd = damped(t, w, zeta)
    exact = -(a0 / w**2) * (1.0 - c - zeta / math.sqrt(1 - zeta**2) * s)
    exact_v = -(a0 / w**2) * (w**2 / wd) * s
    assert np.max(np.abs(u - exact)) <= 1e-12 * np.max(np.abs(exact))
    assert np.max(np.abs(v - exact_v)) <= 1e-12 * np.max(np.abs(exact_v))


def test_ramp_response_is_exact():
    """``a(t) = c t``: ``u = -(c/w^2)(t - 2 zeta/w) + e^(-zeta w t)(A cos wd t + B sin wd t)`` with
    ``u(0) = u'(0) = 0``. Round-off only."""
    period, zeta, dt, c = 0.4, 0.1, 0.01, 3.0
    t = dt * np.arange(1001)
    u, _ = im.sdof_response(c * t, dt, period, zeta)
    w = 2 * math.pi / period
    cos_, sin_, wd = damped(t, w, zeta)
    A = -2 * zeta * c / w**3                          # u(0) = 0
    B = (c / w**2 + zeta * w * A) / wd                # u'(0) = 0
    exact = -(c / w**2) * (t - 2 * zeta / w) + A * cos_ + B * sin_
    assert np.max(np.abs(u - exact)) <= 1e-12 * np.max(np.abs(exact))


def harmonic_response(t, amplitude, forcing, omega, zeta):
    """``u'' + 2 zeta w u' + w^2 u = -A sin(W t)`` from rest: steady state plus transient."""
    r = forcing / omega
    denominator = (1 - r * r) ** 2 + (2 * zeta * r) ** 2
    p = -amplitude / omega**2 / denominator
    steady = p * ((1 - r * r) * np.sin(forcing * t) - 2 * zeta * r * np.cos(forcing * t))
    cos_, sin_, wd = damped(t, omega, zeta)
    C = p * 2 * zeta * r                               # u(0) = 0
    D = (zeta * omega * C - p * (1 - r * r) * forcing) / wd   # u'(0) = 0
    return steady + C * cos_ + D * sin_


@pytest.mark.parametrize("ratio", [0.5, 1.0, 2.0])
def test_sa_under_a_harmonic_input_equals_the_closed_form(ratio):
    """A sine of 2 Hz sampled 200 times per cycle, 12 s long (the transient of the 5 %-damped
    oscillator has decayed to e^(-zeta w t) < 1 % at resonance): the recurrence against the closed-form
    response (steady state and transient) at every sample, and Sa against omega^2 max|u| of the
    closed form on a 40-times finer grid. The sampled sine differs from the sine by at most
    (W dt)^2 / 8 = 1.2e-4 of its amplitude between samples, so 5e-4 of the peak bounds both."""
    amplitude, forcing, dt = 3.0, 2 * math.pi * 2.0, 1.0 / 400
    omega = ratio * forcing
    period = 2 * math.pi / omega
    t = dt * np.arange(int(12.0 / dt) + 1)
    u, _ = im.sdof_response(amplitude * np.sin(forcing * t), dt, period, ZETA)
    exact = harmonic_response(t, amplitude, forcing, omega, ZETA)
    peak = np.max(np.abs(exact))
    assert np.max(np.abs(u - exact)) <= 5e-4 * peak
    fine = np.linspace(0.0, t[-1], 40 * t.size)
    expected = omega**2 * np.max(np.abs(harmonic_response(fine, amplitude, forcing, omega, ZETA)))
    sa = im.spectral_acceleration(amplitude * np.sin(forcing * t), dt, period)
    assert sa == pytest.approx(expected, rel=5e-4 + 1 - math.cos(math.pi / im.POINTS_PER_PERIOD))
    # at resonance the steady amplitude is A / (2 zeta): Sa tends to it
    if ratio == 1.0:
        assert sa == pytest.approx(amplitude / (2 * ZETA), rel=0.01)


def test_sa_of_a_step_is_the_closed_form_overshoot():
    """The peak of the step response is ``a0 (1 + exp(-zeta pi / sqrt(1 - zeta^2)))`` at t = pi/wd;
    seen at least `POINTS_PER_PERIOD` times per period, Sa misses it by at most 1 - cos(pi / 40)."""
    a0, period, dt = 1.5, 0.37, 0.02            # 0.37 s sampled at 0.02 s: 2 steps per interval
    sa = im.spectral_acceleration(np.full(200, a0), dt, period)
    exact = a0 * (1 + math.exp(-ZETA * math.pi / math.sqrt(1 - ZETA**2)))
    assert exact * math.cos(math.pi / im.POINTS_PER_PERIOD) - 1e-12 <= sa <= exact * (1 + 1e-12)


def test_steps_within_an_interval_change_nothing_at_the_samples():
    """The input is linear within each interval, so cutting it into m steps is exact: the response
    at the record's samples is the same to round-off."""
    rng = np.random.default_rng(7)
    a, dt = rng.normal(size=500), 0.01
    u1, v1 = im.sdof_response(a, dt, 0.3, ZETA)
    u5, v5 = im.sdof_response(a, dt, 0.3, ZETA, substeps=5)
    assert np.max(np.abs(u5[::5] - u1)) <= 1e-12 * np.max(np.abs(u1))
    assert np.max(np.abs(v5[::5] - v1)) <= 1e-12 * np.max(np.abs(v1))


def test_coefficients_against_the_closed_form_free_vibration():
    """``A`` of the recurrence is the free vibration over one step: ``u(h)`` for ``u(0) = 1`` is
    ``e^(-zeta w h) (cos wd h + zeta / sqrt(1 - zeta^2) sin wd h)``."""
    period, zeta, h = 0.7, 0.05, 0.013
    A, B0, B1 = im.sdof_coefficients(period, zeta, h)
    w = 2 * math.pi / period
    cos_, sin_, wd = damped(np.array(h), w, zeta)
    assert A[0, 0] == pytest.approx(float(cos_ + zeta / math.sqrt(1 - zeta**2) * sin_), rel=1e-13)
    assert A[0, 1] == pytest.approx(float(sin_ / wd), rel=1e-13)
    # a constant input a0 held forever settles at -a0 / w^2: the fixed point of the recurrence
    fixed = np.linalg.solve(np.eye(2) - A, B0 + B1)
    assert fixed == pytest.approx([-1 / w**2, 0.0], abs=1e-14)


@pytest.mark.parametrize("shift", [0.0, 0.3])
def test_pgv_of_a_cosine_with_and_without_an_offset(shift):
    """``a = A cos(W t) (+ c)`` over whole cycles: v = (A/W) sin(W t) once the constant offset c is
    removed by the baseline correction, so PGV = A / W. The linear interpolation's velocity at the
    samples is the trapezoidal rule's, (A/W) sin(W t) times (W dt/2) / tan(W dt/2) = 1 - (W dt)^2/12
    - ...: 1.05 (W dt)^2 / 12 bounds the relative error."""
    amplitude, forcing, dt = 3.0, 2 * math.pi * 2.0, 0.001
    t = np.arange(0.0, 4.0 + dt / 2, dt)
    pgv = im.peak_velocity(amplitude * np.cos(forcing * t) + shift, dt)
    assert pgv == pytest.approx(amplitude / forcing, rel=1.05 * (forcing * dt) ** 2 / 12)
    v = im.ground_velocity(amplitude * np.cos(forcing * t) + shift, dt)
    assert v[0] == 0.0 and abs(v[-1]) <= 1e-12


def test_pgv_of_a_full_cycle_triangle_pulse_is_exact():
    """A triangle of height A and base Tp up, then the same down (piecewise linear exactly; the
    ground ends at rest, so the baseline correction changes nothing): the velocity peaks at the end of
    the first triangle at A Tp / 2."""
    A, Tp, dt = 4.0, 0.3, 0.01
    t = np.arange(0.0, 1.0 + dt / 2, dt)
    a = A * np.interp(t, [0.1, 0.1 + Tp / 2, 0.1 + Tp, 0.1 + 1.5 * Tp, 0.1 + 2 * Tp], [0, 1, 0, -1, 0])
    assert im.peak_velocity(a, dt) == pytest.approx(A * Tp / 2, rel=1e-12)


def test_pgv_between_samples_is_exact():
    """Samples 0, A, -A, 0: the velocity is A dt / 2 at the second and third samples, but peaks
    where the acceleration crosses zero, half-way between them, at 3 A dt / 4."""
    A, dt = 2.0, 0.02
    assert np.max(im.ground_velocity([0.0, A, -A, 0.0], dt)) == pytest.approx(A * dt / 2, rel=1e-14)
    assert im.peak_velocity([0.0, A, -A, 0.0], dt) == pytest.approx(0.75 * A * dt, rel=1e-14)


def test_pga_is_the_largest_sample():
    assert im.peak_acceleration([0.1, -2.5, 2.4]) == 2.5
    with pytest.raises(ValueError):
        im.peak_acceleration([])
