"""The reference solver: the same state machine, integrated adaptively with located events.

It shares everything with the kernel except the integrator: the equations of motion
(`kernel.evaluate`, from `physics`), the event functions of each state (`kernel.event_values`),
the transitions (`kernel.apply_event`, `kernel.settle`), the exact exits from REST
(`kernel.rest_exit`) and the bookkeeping (`kernel.accept`). Between transitions it integrates with
scipy's DOP853 (8th order) at tight tolerances, record interval by record interval (the input is
piecewise linear, so each interval is smooth), and locates each event by scipy's root finding on
the dense output. Slow (Python in the loop): meant for short inputs and for checking the kernel.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from . import kernel as K
from .physics import REST, STATE_NAMES
from .simulate import (
    Model,
    Result,
    Settings,
    event_table,
    ground_array,
    ground_series,
    history_dict,
    initial_state,
    parameters,
    summarise,
)

RTOL = 1e-12
ATOL = 1e-14


#: The reference solver calls ``progress`` after this many record intervals.
PROGRESS_INTERVALS = 100


def simulate_reference(model: Model, dt_record: float, horizontal, vertical,
                       settings: Settings = Settings(), start: float = 0.0,
                       rtol: float = RTOL, atol: float = ATOL, progress=None) -> Result:
    """Same inputs and result as `simulate.simulate`, computed with DOP853 and located events.

    The history is sampled on the same grid as the kernel's (every ``history_every``-th multiple of
    the kernel's step ``h``), from the solver's dense output. ``settings.events`` is ignored (events
    are always located); ``settings.dt`` only sets the history grid. ``progress(reached, end)`` is
    called every `PROGRESS_INTERVALS` record intervals, as `simulate` calls it between chunks (it
    may raise to stop the run).
    """
    ground = ground_array(horizontal, vertical, dt_record, settings.tail)
    p = parameters(model, dt_record, settings, start)
    p[K.P_LOCATED] = 1.0
    h = p[K.P_STEP]
    n_sub = int(p[K.P_N_SUB])
    every = int(settings.history_every)
    st = initial_state(settings)
    events = np.zeros((100_000, len(K.EVENT_COLUMNS)))    # a reference run's log keeps its first 100 000
    rows = []

    st[K.S_STARTED] = 1.0
    st[K.S_E_INITIAL] = K.mechanical_energy(st, p)
    K.settle(st, p, start, ground[0, 0], ground[2, 0], events)
    K.note_extremes(st, start)
    if every > 0:
        rows.append(_row(st, start))

    n_intervals = ground.shape[1]
    for k in range(n_intervals):
        if K.finished(st):
            break
        if progress is not None and k % PROGRESS_INTERVALS == 0 and k:
            progress(start + k * dt_record, start + n_intervals * dt_record)
        a0, v0 = ground[0, k], ground[2, k]
        sa = (ground[1, k] - a0) / dt_record
        sv = (ground[3, k] - v0) / dt_record
        tk = start + k * dt_record
        grid = [j for j in range(1, n_sub + 1) if every > 0 and (k * n_sub + j) % every == 0]
        tau = 0.0
        while tau < dt_record and not K.finished(st):
            mode = int(st[K.S_MODE])
            if mode == REST:
                te, kind = K.rest_exit(tau, dt_record, a0, sa, v0, sv, p, False, h)
                end = dt_record if kind < 0 else te
                K.add_time(st, REST, end - tau)
                rows += [_row(st, start + (k * n_sub + j) * h) for j in grid
                         if tau < _local(j, n_sub, h, dt_record) <= end]
                tau = end
                if kind >= 0:
                    K.apply_event(kind, st, p, tk + te, a0 + sa * te, p[K.P_G] + v0 + sv * te, events)
                    K.settle(st, p, tk + te, a0 + sa * te, v0 + sv * te, events)
                continue
            tau = _integrate_moving(st, p, tau, dt_record, tk, a0, sa, v0, sv, events,
                                    grid, start, h, k * n_sub, n_sub, rows, rtol, atol)

    n_events = int(st[K.S_N_EVENTS])
    ground_time, ground_h, ground_v = ground_series(ground, dt_record, start)
    history_columns = np.array(rows).T if rows else np.zeros((6, 0))
    return Result(
        history=history_dict(history_columns),
        events=event_table(events[:n_events], model.mass),
        summary=summarise(st, model, start + n_intervals * dt_record),
        step=h,
        ground_time=ground_time,
        ground_horizontal=ground_h,
        ground_vertical=ground_v,
    )


def _row(st, t):
    lam = st[K.S_LAM]
    return [t, lam * st[K.S_THETA], lam * st[K.S_THETADOT], st[K.S_X], st[K.S_XDOT], st[K.S_MODE]]


def _local(j, n_sub, h, dt_record):
    """Local time of grid point ``j`` of an interval (the last one exactly at its end)."""
    return dt_record if j == n_sub else j * h


def _integrate_moving(st, p, tau, tau_end, tk, a0, sa, v0, sv, events,
                      grid, start, h, n_first, n_sub, rows, rtol, atol):
    """Integrate the current moving state from ``tau`` until the interval's end or its first event;
    apply the event. Returns the local time reached."""
    mode = int(st[K.S_MODE])
    lam, sigma = st[K.S_LAM], st[K.S_SIGMA]
    y0 = np.array([st[K.S_THETA], st[K.S_THETADOT], st[K.S_X], st[K.S_XDOT],
                   st[K.S_W_GROUND], st[K.S_W_FRICTION]])

    energy = p[K.P_ENERGY] != 0.0

    def rhs(t, y):
        thdd, xdd, pg, pf, _, _, _, _, _ = K.evaluate(mode, energy, lam, sigma, y[0], y[1], y[3], t, a0, sa, v0, sv, p)
        return [y[1], thdd, y[3], xdd, pg, pf]

    n_events = K.N_EVENTS[mode]
    event_kinds = K.EVENT_KINDS[mode][:n_events]

    def make_values(y, t):
        """The state's event functions at state ``y`` and local time ``t``."""
        return K.event_values(mode, lam, sigma, y[0], y[1], y[3], a0 + sa * t, p[K.P_G] + v0 + sv * t, p)

    starts_at_zero = [value == 0.0 for value in make_values(y0, tau)[:n_events]]

    def make_event(i):
        def event(t, y):
            # An event function that starts at exactly zero (theta after an impact or a liftoff,
            # the slip rate after a slip start) must first leave zero upwards; divided by the time
            # since the start, its root at the start disappears and the next root stays.
            if starts_at_zero[i]:
                return 1.0 if t <= tau else make_values(y, t)[i] / (t - tau)
            return make_values(y, t)[i]
        event.terminal = True
        event.direction = -1
        return event

    solution = solve_ivp(rhs, (tau, tau_end), y0, method="DOP853", rtol=rtol, atol=atol,
                         events=[make_event(i) for i in range(n_events)], dense_output=True)
    t_stop = solution.t[-1]
    fired = [(solution.t_events[i][0], i) for i in range(n_events) if len(solution.t_events[i])]
    # history rows on the grid up to the stop
    for j in grid:
        local = _local(j, n_sub, h, tau_end)
        if tau < local <= t_stop:
            y = solution.sol(local)
            rows.append([start + (n_first + j) * h, lam * y[0], lam * y[1], y[2], y[3], mode])
    # bookkeeping along the solver's steps (extremes, time in state, the fall past alpha)
    previous = tau
    for t_i, y_i in zip(solution.t[1:], solution.y.T[1:], strict=True):
        K.accept(st, y_i[0], y_i[1], y_i[2], y_i[3], y_i[4], y_i[5], mode, previous, t_i, tk, p, False)
        previous = t_i
    _exact_peaks(st, solution, tk)
    _exact_fall_start(st, solution, tk, p[K.P_ALPHA])
    if solution.status == -1:
        # The solver could not go on: in this model only the Painleve point (accelerations ~ 1/D as
        # D -> 0 in ROCKSLIP) makes the equations singular. Anything else is a failure to report.
        _set_state(st, solution.y[:, -1].copy())
        if mode == K.ROCKSLIP:
            st[K.S_STATUS] = K.STATUS_PAINLEVE
            K.log_event(st, events, tk + t_stop, float(mode), float(mode), float(K.C_PAINLEVE), 0.0, 0.0)
            K.stop(st, tk + t_stop)
            return t_stop
        raise RuntimeError(f"the reference solver failed at t = {tk + t_stop:.9g} s in state "
                           f"{STATE_NAMES[mode]}: {solution.message}")
    if not fired:
        return tau_end
    # The earliest event wins; an event of an earlier row of the table whose function has fallen to
    # zero at the same instant (to 1e-9 of its value at the start) is a tie and goes first, as in
    # the kernel (e.g. flight and the eq. 23 liftoff margin (tan(alpha) - nu) G at G = 0).
    te, index = min(fired)
    g_start = make_values(y0, tau)
    g_event = make_values(solution.y_events[index][0], te)
    tied = [i for i in range(index) if g_event[i] <= 1e-9 * abs(g_start[i])]
    if tied and event_kinds[index] != K.K_PAINLEVE:    # at D = 0 the other functions mean nothing
        index = tied[0]
    y_e = solution.y_events[index][0].copy() if len(solution.t_events[index]) else solution.y[:, -1].copy()
    _set_state(st, y_e)
    kind = event_kinds[index]
    if kind == K.K_IMPACT:
        st[K.S_THETA] = 0.0
    elif kind == K.K_SLIP_STOP:
        st[K.S_XDOT] = 0.0
    ah_e, av_e = a0 + sa * te, v0 + sv * te
    K.apply_event(kind, st, p, tk + te, ah_e, p[K.P_G] + av_e, events)
    K.settle(st, p, tk + te, ah_e, av_e, events)
    # grid rows exactly at the event time that were before the stop are already written
    return te if te < tau_end else tau_end


def _exact_peaks(st, solution, tk):
    """Peaks of theta and |x| inside the solver's (long) steps, from its dense output."""
    t, y = solution.t, solution.y
    for i in range(len(t) - 1):
        for component, rate, slot in ((0, 1, K.S_MAX_THETA), (2, 3, K.S_MAX_X)):
            r0, r1 = y[rate, i], y[rate, i + 1]
            if r0 * r1 < 0.0 and (component == 2 or r0 > 0.0):
                t_peak = brentq(lambda s, r=rate: solution.sol(s)[r], t[i], t[i + 1], xtol=1e-15)
                value = abs(solution.sol(t_peak)[component])
                if value > st[slot]:
                    st[slot] = value
                    if slot == K.S_MAX_THETA:
                        st[K.S_THETA_MAX_TIME] = tk + t_peak


def _exact_fall_start(st, solution, tk, alpha):
    """The time theta last passed alpha upwards (`kernel.track` takes it as linear inside a step,
    which across the solver's long steps was off by up to 1e-4 s), from its dense output."""
    t, theta = solution.t, solution.y[0]
    for i in range(len(t) - 2, -1, -1):
        if theta[i] <= alpha < theta[i + 1]:
            if not math.isnan(st[K.S_FALL_CANDIDATE]):      # still the fall: theta stayed above alpha
                try:
                    st[K.S_FALL_CANDIDATE] = tk + brentq(lambda s: solution.sol(s)[0] - alpha, t[i], t[i + 1],
                                                         xtol=1e-15)
                except ValueError:         # the dense output does not bracket it: keep the linear time
                    pass
            return


def _set_state(st, y):
    st[K.S_THETA], st[K.S_THETADOT], st[K.S_X], st[K.S_XDOT] = y[0], y[1], y[2], y[3]
    st[K.S_W_GROUND], st[K.S_W_FRICTION] = y[4], y[5]


__all__ = ["simulate_reference", "RTOL", "ATOL"]
