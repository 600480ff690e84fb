"""Intensity measures of a ground-motion record: PGA, PGV, PGV/PGA and Sa(T, zeta). Pure numerics.

A record is a series of accelerations at a constant step, linear in between: the convention of the
kernel's input (`simulate.ground_array`, model.md: 'Ground motion between record samples is
linearly interpolated'). Every measure here is computed exactly for that piecewise-linear record,
so that a record's intensity and the motion the block feels are one and the same function of time
(PGV is that of the record with its mean acceleration removed, below; the block feels the record
as given: for a processed record the two are the same, for the review's raw records PGV moved by
0.5-1 %).

- **PGA** = max |a| over the samples (the peak of a piecewise-linear function is at a sample); it is
  also what `records.combine` scales to a ``pga_horizontal``.
- **PGV** = max |v| of the ground velocity ``v(t) = integral of (a - a_mean)`` from rest, where
  ``a_mean`` is the record's mean acceleration (its exact integral over the record divided by the
  duration). The baseline correction is that one constant: it removes the linear drift of the
  velocity that a constant offset of the acceleration (an instrument or digitisation zero error)
  causes, so the corrected velocity starts and ends at rest. A processed record (PEER, or any
  record that starts and ends at rest) has ``a_mean`` = v_end / duration = 0 and is left as it is.
  The velocity is piecewise quadratic; its peak is found exactly, at a sample or where the
  corrected acceleration crosses zero inside an interval.
- **Sa(T, zeta)** = omega^2 max |u|, the pseudo-spectral acceleration of a linear oscillator of
  period ``T`` and damping ratio ``zeta`` (5 % by default), ``u'' + 2 zeta omega u' + omega^2 u =
  -a(t)``, starting at rest. The response is stepped with the exact recurrence for an input linear
  within each step (Nigam & Jennings 1969, Bull. Seism. Soc. Am. 59(2)): ``[u, u']`` at the end of a
  step is ``A [u, u'] + B0 a_start + B1 a_end``, with ``A``, ``B0`` and ``B1`` read off the matrix
  exponential of the oscillator augmented with the linear input (a first-order hold), so there is
  no truncation error at all. Each record interval is cut into enough equal steps that the response
  is seen at least `POINTS_PER_PERIOD` times per period (the input stays exactly linear on them):
  the peak between two such points is missed by at most ``1 - cos(pi / POINTS_PER_PERIOD)``
  (0.3 %). The response is followed over the record only (no free vibration after it).
- **Two horizontal components**: the motion along a direction (`along`, what a planar block feels)
  and the rotated peaks of PGA, PGV and Sa over 0-179 degrees (`rotd_peaks`), whose median and
  maximum are RotD50 and RotD100 (Boore 2010, Bull. Seism. Soc. Am. 100(4); NGA-West2).
"""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = ["DAMPING", "POINTS_PER_PERIOD", "peak_acceleration", "ground_velocity", "peak_velocity",
           "sdof_coefficients", "sdof_response", "substeps_for", "oscillator_history", "spectral_acceleration",
           "spectral_absolute_acceleration", "floor_acceleration", "PARTS_PER_DEGREE", "ROTD_ANGLES",
           "direction_cosines", "along", "rotated_peaks", "rotd_peaks"]

#: Damping ratio of the response spectrum [-] (the 5 % of building codes and ground-motion models).
DAMPING = 0.05
#: Sa: the oscillator's response is evaluated at least this many times per period.
POINTS_PER_PERIOD = 40


def _samples(acceleration) -> np.ndarray:
    a = np.asarray(acceleration, dtype=np.float64)
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"expected a 1-D record of at least one sample, got shape {a.shape}")
    return a


def peak_acceleration(acceleration) -> float:
    """PGA: ``max |a|`` [m/s^2] of a record ``acceleration`` [m/s^2]."""
    return float(np.max(np.abs(_samples(acceleration))))


def ground_velocity(acceleration, dt: float) -> np.ndarray:
    """The baseline-corrected ground velocity at the samples [m/s].

    Parameters
    ----------
    acceleration : array_like
        [m/s^2] samples at step ``dt``, linear in between.
    dt : float
        [s] sampling step.

    Returns
    -------
    numpy.ndarray
        ``v_i = integral from 0 to t_i of (a - a_mean) dt`` (exact for the linear interpolation:
        the trapezoidal rule), ``a_mean`` the record's mean acceleration, so ``v_0 = v_end = 0``.
    """
    return _corrected(_samples(acceleration), dt)[1]


def _corrected(a: np.ndarray, dt: float):
    """``(a - a_mean, v)``: the corrected acceleration and its exact integral at the samples."""
    if a.size == 1:
        return np.zeros(1), np.zeros(1)
    raw = np.concatenate([[0.0], np.cumsum(0.5 * dt * (a[:-1] + a[1:]))])
    mean = raw[-1] / (dt * (a.size - 1))
    return a - mean, raw - mean * dt * np.arange(a.size)


def peak_velocity(acceleration, dt: float) -> float:
    """PGV: ``max |v|`` [m/s] of the baseline-corrected velocity (`ground_velocity`), exact for the
    piecewise-linear record: inside an interval where the corrected acceleration changes sign from
    ``c_i`` to ``c_i+1``, the velocity's extremum ``v_i + c_i tau / 2`` at ``tau = dt c_i /
    (c_i - c_i+1)`` counts too."""
    corrected, v = _corrected(_samples(acceleration), dt)
    start, end = corrected[:-1], corrected[1:]
    crossing = start * end < 0.0
    tau = dt * start[crossing] / (start[crossing] - end[crossing])
    inside = v[:-1][crossing] + 0.5 * start[crossing] * tau
    return float(max(np.max(np.abs(v)), np.max(np.abs(inside), initial=0.0)))


def sdof_coefficients(period: float, damping: float, step: float):
    """The exact one-step recurrence of a linear oscillator under an input linear within the step.

    Parameters
    ----------
    period : float
        [s] natural period ``T = 2 pi / omega``, > 0.
    damping : float
        [-] damping ratio ``zeta``, within [0, 1).
    step : float
        [s] step ``h``.

    Returns
    -------
    A, B0, B1 : numpy.ndarray
        ``float64[2, 2]``, ``float64[2]``, ``float64[2]``: ``[u, u'](t + h) = A [u, u'](t) +
        B0 a(t) + B1 a(t + h)`` for ``u'' + 2 zeta omega u' + omega^2 u = -a``, ``a`` linear on
        ``[t, t + h]``.

    Notes
    -----
    With the input's value ``a`` and slope ``s`` carried as two more states (``a' = s``, ``s' =
    0``), the system is linear and time-invariant over the step, so its state after ``h`` is
    ``expm(M h)`` times its state before (Van Loan 1978): ``expm(M h)[:2, :2] = A`` and the input
    columns give ``[u, u'](t + h) = A [u, u'] + G0 a(t) + G1 s`` with ``s = (a(t + h) - a(t)) / h``.
    """
    from scipy.linalg import expm  # a third of a second: only where an oscillator is stepped

    omega = 2.0 * math.pi / period
    m = np.zeros((4, 4))
    m[0, 1] = 1.0
    m[1, 0] = -omega * omega
    m[1, 1] = -2.0 * damping * omega
    m[1, 2] = -1.0                   # the input a enters as -a
    m[2, 3] = 1.0                    # a' = s (the slope), s' = 0
    phi = expm(m * step)
    A = np.ascontiguousarray(phi[:2, :2])
    g0, g1 = phi[:2, 2], phi[:2, 3]
    return A, np.ascontiguousarray(g0 - g1 / step), np.ascontiguousarray(g1 / step)


@functools.cache
def _oscillator():
    """`_oscillate` compiled by numba (or loaded from its cache) at the first oscillator's response,
    so that the peak measures (PGA, PGV: plain numpy) load neither numba nor scipy.linalg."""
    from numba import njit

    from . import compiled  # noqa: F401  (before any cache=True: numba needs a cache folder)

    return njit(cache=True)(_oscillate)


def _oscillate(a, m, A, B0, B1, u, v):
    """Step the recurrence over the record ``a`` with each interval cut into ``m`` equal steps;
    write ``u``, ``u'`` at every step end (``u[0] = v[0] = 0``: at rest). Compiled by `_oscillator`."""
    x = 0.0
    y = 0.0
    u[0] = 0.0
    v[0] = 0.0
    j = 0
    for i in range(a.size - 1):
        a0 = a[i]
        da = (a[i + 1] - a0) / m
        for k in range(m):
            start = a0 + k * da
            end = a[i + 1] if k == m - 1 else a0 + (k + 1) * da
            x, y = (A[0, 0] * x + A[0, 1] * y + B0[0] * start + B1[0] * end,
                    A[1, 0] * x + A[1, 1] * y + B0[1] * start + B1[1] * end)
            j += 1
            u[j] = x
            v[j] = y


def sdof_response(acceleration, dt: float, period: float, damping: float = DAMPING, substeps: int = 1):
    """Displacement and velocity of a linear oscillator on the record, from rest.

    Parameters
    ----------
    acceleration : array_like
        [m/s^2] ground acceleration at step ``dt``, linear in between.
    dt : float
        [s] sampling step.
    period : float
        [s] the oscillator's natural period.
    damping : float
        [-] its damping ratio.
    substeps : int
        Equal steps per record interval (the input is linear on each).

    Returns
    -------
    u, velocity : numpy.ndarray
        [m], [m/s] relative displacement and velocity at ``t = j dt / substeps``,
        ``j = 0 ... (n - 1) substeps``.
    """
    a = _samples(acceleration)
    m = int(substeps)
    if m < 1:
        raise ValueError(f"substeps must be >= 1, got {substeps}")
    if not (period > 0 and 0.0 <= damping < 1.0 and dt > 0):
        raise ValueError(f"expected period > 0, 0 <= damping < 1 and dt > 0, got {period}, {damping}, {dt}")
    A, B0, B1 = sdof_coefficients(period, damping, dt / m)
    u = np.empty((a.size - 1) * m + 1)
    velocity = np.empty_like(u)
    _oscillator()(a, m, A, B0, B1, u, velocity)
    return u, velocity


def _omega_squared(period: float) -> float:
    """``omega^2 = (2 pi / T)^2`` [1/s^2] of an oscillator of period ``T`` [s]: Sa = omega^2 max |u|."""
    omega = 2.0 * math.pi / period
    return omega * omega


def substeps_for(dt: float, period: float) -> int:
    """Equal steps per record interval so that an oscillator of ``period`` [s] is seen at least
    `POINTS_PER_PERIOD` times per period on a record of step ``dt`` [s]."""
    return max(1, math.ceil(POINTS_PER_PERIOD * dt / period - 1e-9))


def oscillator_history(acceleration, dt: float, period: float, damping: float = DAMPING,
                       substeps: int | None = None):
    """The response history of a linear oscillator on the record, from rest: the one source of the
    spectra (`spectral_acceleration`, `spectral_absolute_acceleration`) and of floor motions
    (`floor_acceleration`).

    The parameters are `sdof_response`'s, with ``substeps`` by default `substeps_for` (dt, period).

    Returns
    -------
    u, velocity, absolute : numpy.ndarray
        [m], [m/s], [m/s^2] at ``t = j dt / substeps``: `sdof_response`'s relative displacement and
        velocity, and the absolute acceleration ``a + u'' = -(2 zeta omega u' + omega^2 u)`` (the equation of
        motion), exact at every step for the piecewise-linear input.
    """
    m = substeps_for(dt, period) if substeps is None else substeps
    u, velocity = sdof_response(acceleration, dt, period, damping, m)
    omega = 2.0 * math.pi / period
    return u, velocity, -(2.0 * damping * omega * velocity + omega * omega * u)


def spectral_acceleration(acceleration, dt: float, period: float, damping: float = DAMPING) -> float:
    """Sa(T, zeta) = omega^2 max |u| [m/s^2], the pseudo-spectral acceleration (module notes)."""
    u, _, _ = oscillator_history(acceleration, dt, period, damping)
    return float(_omega_squared(period) * np.max(np.abs(u)))


def spectral_absolute_acceleration(acceleration, dt: float, period: float, damping: float = DAMPING) -> float:
    """max |a + u''| [m/s^2], the absolute-acceleration spectrum at (T, zeta), seen at the same steps
    as `spectral_acceleration` (equal to it for zeta = 0): the PFA of a one-mode floor of unit
    participation (`floor_acceleration`)."""
    _, _, absolute = oscillator_history(acceleration, dt, period, damping)
    return float(np.max(np.abs(absolute)))


def floor_acceleration(acceleration, dt: float, modes, substeps: int | None = None) -> tuple[np.ndarray, float]:
    """Absolute acceleration of a floor of a linear building on the ground record (modal superposition).

    Parameters
    ----------
    acceleration : array_like
        [m/s^2] ground acceleration ``a_g`` at step ``dt``, linear in between.
    dt : float
        [s] sampling step.
    modes : sequence of (period, damping, participation)
        Each mode ``i``: period ``T_i`` [s] (> 0), damping ratio ``zeta_i`` [-] in [0, 1) and
        participation ``p_i = Gamma_i phi_i`` [-] at the floor (the mode's participation factor
        times its shape at the floor; 1 for one mode that carries the floor alone).
    substeps : int, optional
        Equal steps per record interval ``m``; default `substeps_for` (dt, shortest period), 1
        without modes (a common ``m`` puts two components on one grid).

    Returns
    -------
    floor : numpy.ndarray
        [m/s^2] ``a_f = a_g + sum_i p_i u_i''`` with ``u_i'' + 2 zeta_i omega_i u_i' + omega_i^2 u_i =
        -a_g`` from rest, at the steps ``dt / m``; for one mode with ``p = 1`` this is the
        oscillator's absolute acceleration ``-(2 zeta omega u' + omega^2 u)``. Exact at every step
        (Nigam-Jennings, module notes); ``a_g`` at the steps is the record's linear interpolation.
    step : float
        [s] ``dt / m``; by default the floor motion is seen `POINTS_PER_PERIOD` times per period of
        its fastest mode, as the spectra see it.
    """
    a = _samples(acceleration)
    modes = [tuple(float(x) for x in mode) for mode in modes]
    m = substeps if substeps is not None else max((substeps_for(dt, p) for p, _, _ in modes), default=1)
    if m == 1 and not modes:
        return a.copy(), float(dt)
    fine = np.linspace(0.0, 1.0, m + 1)[:-1]
    ground = np.append((a[:-1, None] * (1.0 - fine) + a[1:, None] * fine).ravel(), a[-1]) if a.size > 1 else a.copy()
    floor = ground.copy()
    for period, damping, participation in modes:
        _, _, absolute = oscillator_history(a, dt, period, damping, m)
        floor += participation * (absolute - ground)      # u'' = absolute - a_g
    return floor, dt / m


# --------------------------------------------------------------------------------------------------
# Two horizontal components: the motion along a direction, and rotated peaks (RotD50, RotD100)
# --------------------------------------------------------------------------------------------------

#: Angles are rounded to this many parts of a degree (a nanodegree) before their cosine is taken
#: (`direction_cosines`): the motion then depends on the angles' differences only, bit for bit, and
#: multiples of 90 degrees give cosines of exactly 0 and +-1.
PARTS_PER_DEGREE = 10**9
#: RotD angles: 0, 1, ..., 179 degrees from the first component (Boore 2010).
ROTD_ANGLES = tuple(range(180))


def direction_cosines(angle: float) -> tuple[float, float]:
    """``(cos angle, sin angle)`` of an angle [rad] rounded to a nanodegree (`PARTS_PER_DEGREE`).

    The rounded angle, a whole number of nanodegrees, is reduced exactly (integer arithmetic) to a
    quarter turn and a rest within [0, 90) degrees; the quarter turns are applied by swapping and
    negating. So an angle of a whole number of quarter turns gives exactly 0 and +-1, and angles
    that differ by whole turns give the same pair bit for bit.
    """
    turn = 360 * PARTS_PER_DEGREE
    parts = round(math.degrees(angle) * PARTS_PER_DEGREE) % turn
    quarters, rest = divmod(parts, turn // 4)
    if rest:
        r = math.radians(rest / PARTS_PER_DEGREE)
        c, s = math.cos(r), math.sin(r)
    else:
        c, s = 1.0, 0.0
    for _ in range(quarters):
        c, s = -s, c                 # cos(x + 90 deg) = -sin x, sin(x + 90 deg) = cos x
    return c + 0.0, s + 0.0          # no negative zeros


def along(a1, a2, azimuth_1: float, azimuth_2: float, direction: float) -> np.ndarray:
    """The ground motion along ``direction`` from two orthogonal horizontal components.

    Parameters
    ----------
    a1, a2 : array_like
        The components' samples (any quantity: accelerations [m/s^2], displacements...), same length.
    azimuth_1, azimuth_2 : float
        [rad] the directions the components are measured along (clockwise from north), 90 degrees
        apart (either way round).
    direction : float
        [rad] the direction wanted.

    Returns
    -------
    numpy.ndarray
        ``a1 cos(direction - azimuth_1) + a2 cos(direction - azimuth_2)``, the cosines from
        `direction_cosines` of the angle differences (so turning all three angles together changes
        nothing). A term whose cosine is 0 is left out, so ``direction == azimuth_1`` gives ``a1``
        itself, bit for bit.
    """
    terms = [(direction_cosines(direction - azimuth)[0], np.asarray(a, dtype=np.float64))
             for a, azimuth in ((a1, azimuth_1), (a2, azimuth_2))]
    terms = [(c, a) for c, a in terms if c != 0.0]
    if not terms:
        return np.zeros_like(np.asarray(a1, dtype=np.float64))
    out = terms[0][1].copy() if terms[0][0] == 1.0 else terms[0][0] * terms[0][1]
    for c, a in terms[1:]:
        out = out + c * a
    return out


def rotated_peaks(x1, x2) -> np.ndarray:
    """``max_t |x1 cos theta + x2 sin theta|`` for theta = 0, 1, ..., 179 degrees (`ROTD_ANGLES`).

    ``x1``, ``x2`` are the two orthogonal components of any response (accelerations, the
    oscillator's displacements) at the same times. Returns float64[180].
    """
    x1 = np.asarray(x1, dtype=np.float64)
    x2 = np.asarray(x2, dtype=np.float64)
    peaks = np.empty(len(ROTD_ANGLES))
    for k, degrees in enumerate(ROTD_ANGLES):
        c, s = direction_cosines(math.radians(degrees))
        peaks[k] = np.max(np.abs(c * x1 + s * x2), initial=0.0)
    return peaks


def rotd_peaks(a1, a2, dt: float, measure: str, period: float | None = None,
               damping: float = DAMPING) -> np.ndarray:
    """A measure's peaks over the 180 rotation angles of two orthogonal components (Boore 2010).

    Parameters
    ----------
    a1, a2 : array_like
        [m/s^2] the two horizontal components at step ``dt``, linear in between.
    dt : float
        [s] sampling step.
    measure : {"pga", "pgv", "sa"}
        PGA [m/s^2], PGV [m/s] (`peak_velocity` of each rotated record, exact between samples) or
        Sa(T, zeta) [m/s^2] (the oscillator's response is linear in its input, so the responses to
        the two components are rotated, `spectral_acceleration`'s sampling).
    period : float, optional
        [s] the oscillator's period, for ``sa``.
    damping : float
        [-] its damping ratio.

    Returns
    -------
    numpy.ndarray
        float64[180], the peak at theta = 0 ... 179 degrees from component 1. RotD50 is their
        median (``numpy.median``: the mean of the 90th and 91st), RotD100 their maximum.
    """
    a1, a2 = _samples(a1), _samples(a2)
    if a1.shape != a2.shape:
        raise ValueError(f"the two components differ in length: {a1.size} and {a2.size} samples")
    if measure == "pga":
        return rotated_peaks(a1, a2)
    if measure == "pgv":
        peaks = np.empty(len(ROTD_ANGLES))
        for k, degrees in enumerate(ROTD_ANGLES):
            c, s = direction_cosines(math.radians(degrees))
            peaks[k] = peak_velocity(c * a1 + s * a2, dt)
        return peaks
    if measure == "sa":
        if period is None:
            raise ValueError("measure 'sa' needs a period")
        u1, _, _ = oscillator_history(a1, dt, period, damping)
        u2, _, _ = oscillator_history(a2, dt, period, damping)
        return _omega_squared(period) * rotated_peaks(u1, u2)
    raise ValueError(f"unknown measure {measure!r}; expected 'pga', 'pgv' or 'sa'")
