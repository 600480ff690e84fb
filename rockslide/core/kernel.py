"""The compiled fixed-step state machine (docs/model.md, 'Transitions' and 'Integration').

Plain floats and arrays only, no I/O. `simulate.py` builds the inputs and reads the outputs;
`batch.run_batch` (sweeps, fragility) and `gpu` run `run` over many cases. Everything is
resumable: the integration state lives in the array ``st`` (indices ``S_*``), so a long record can
be computed in chunks with bounded memory.

Time is organised by ground-motion samples. The record (with its tail of zeros) is linear between
samples ``k`` and ``k+1`` (interval ``k``); each interval is cut into ``n_sub`` steps of length
``h = dt_record / n_sub <= dt``, so that the kinks of the input fall on step boundaries. Within an
interval, local time ``tau`` runs from 0 to ``dt_record``.

- REST costs no integration: the exit conditions (eqs. 6 and 11, and flight) are linear in
  ``tau`` within an interval, so their first crossing is computed exactly, per interval.
- A record is indexed once (`rest_bounds`: the largest ``abs(ah)`` and the extremes of ``av`` over
  blocks of `REST_BLOCK` intervals): a block whose bounds cannot reach the REST thresholds is
  skipped whole, and only a block where an exit can happen is scanned interval by interval.
- SLIP, ROCK and ROCKSLIP are integrated with the classical fourth-order Runge-Kutta method, with a
  loop specialised to each state (`glide`; `rk4_step` leaves out the terms that are exactly zero
  in that state). After each step the event functions of the state (``g >= 0`` while the state holds,
  in the order of model.md's table) are evaluated. With located events (``P_LOCATED = 1``) the earliest crossing
  inside the step is found by Illinois regula falsi on RK4 sub-steps from the step's start, the
  transition is applied there and the rest of the step is integrated in the new state. With
  step-end switching (``P_LOCATED = 0``, the paper's ACSL-like scheme) the first event in table
  order is applied at the end of the step with the state found there.
- After any transition, the tests of the new state apply at once (model.md: 'REST (then REST's
  tests apply at once)').

The block may be an asymmetric planar body (docs/model-asymmetric.md): every equation is taken about
the present pivot ``lam`` with that pivot's constants (`pivot`; ``P_R2``... for ``lam = -1``), liftoff
from rest compares ``ah > 0`` with pivot 1's ``tan(alpha_1)`` and ``ah < 0`` with pivot 2's, and
``P_ASYM`` selects the body's impact law (`physics.impact_body`). A symmetric block stores the
rectangle's expressions in the per-pivot slots, so its numbers are those of the rectangle to the bit.

The code allocates nothing and keeps its scratch values in tuples, so that the same source compiles
for a GPU (numba-cuda) as well as for the CPU. A case reads its record from a shared array of
unscaled records (``P_FIRST``) and scales it as it goes (``P_KH``, ``P_KV``): a batch of cases
needs no copy of the ground motion per case.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import compiled
from .layout import (  # noqa: F401  (the array layout, re-exported: `kernel.S_MODE` etc.)
    C_FLIGHT,
    C_IMPACT,
    C_LIFTOFF,
    C_LIFTOFF_END,
    C_OVERTURN,
    C_PAINLEVE,
    C_SLIP_REVERSAL,
    C_SLIP_START,
    C_SLIP_STOP,
    CAUSE_NAMES,
    EVENT_COLUMNS,
    GROUND_ROWS,
    HISTORY_COLUMNS,
    IMPACT_FLAT,
    IMPACT_PAINLEVE,
    IMPACT_STICK,
    K_FLIGHT,
    K_IMPACT,
    K_LIFTOFF,
    K_OVERTURN,
    K_PAINLEVE,
    K_SLIP_START,
    K_SLIP_STOP,
    N_PARAMS,
    N_STATE,
    OVERTURNED,
    P_ALPHA,
    P_ALPHA2,
    P_ASYM,
    P_B1,
    P_B2,
    P_DT_REC,
    P_E,
    P_ENERGY,
    P_FIRST,
    P_G,
    P_H,
    P_KH,
    P_KR1,
    P_KR2,
    P_KV,
    P_LOCATED,
    P_M1,
    P_M2,
    P_MU,
    P_N_SUB,
    P_NU,
    P_P2_1,
    P_P2_2,
    P_Q1,
    P_Q2,
    P_R,
    P_R2,
    P_STEP,
    P_T0,
    P_TAN_ALPHA,
    P_TAN_ALPHA2,
    REST,
    ROCK,
    ROCKSLIP,
    S_DIRECTION,
    S_E_INITIAL,
    S_END_TIME,
    S_EVENTS_AT_ONCE,
    S_FALL_CANDIDATE,
    S_FALL_START,
    S_IMPACTS,
    S_K,
    S_K1_PF,
    S_K1_PG,
    S_K1_THDD,
    S_K1_VALID,
    S_K1_XDD,
    S_LAM,
    S_LAST_EVENT_TIME,
    S_MAX_THETA,
    S_MAX_X,
    S_MODE,
    S_N_EVENTS,
    S_OVERTURN_TIME,
    S_ROWS,
    S_SIGMA,
    S_STARTED,
    S_STATUS,
    S_T_REST,
    S_T_ROCK,
    S_T_ROCKSLIP,
    S_T_SLIP,
    S_THETA,
    S_THETA_MAX_TIME,
    S_THETADOT,
    S_W_FRICTION,
    S_W_GROUND,
    S_W_IMPACT,
    S_X,
    S_XDOT,
    SLIP,
    STATUS_CHATTER,
    STATUS_FLIGHT,
    STATUS_NAMES,
    STATUS_OK,
    STATUS_PAINLEVE,
    new_state,
)
from .physics import (
    contact_forces_sc,
    impact,
    impact_body,
    kinetic_energy_m,
    liftoff_margin,
    potential_energy,
    rock_acceleration_k,
    rockslip_accelerations_q,
    rockslip_determinant_q,
    rockslip_determinant_rate,
    slip_acceleration,
    slip_liftoff_margin,
    slip_margin,
    tilt,
    zeno_rate,
)

HALF_PI = 0.5 * math.pi
THETA_END = 1e-7   # [rad] a rebound predicted to rise less than this ends the liftoff (decision 3)
STEP_END_FLIGHT_STEPS = 4.0   # step-end switching also ends liftoff for flights shorter than this
LOCATE_TOLERANCE = 1e-13      # event location: bracket width relative to the step
TIE_TOLERANCE = 1e-12         # located crossings closer than this (relative to the step) are ties
MAX_TRANSITIONS_PER_STEP = 200
SINGULAR_FRACTION = 0.05      # near a Painleve point a ROCKSLIP step may change D by this fraction at most
PAINLEVE_TIME = 1e-12         # [s] D would reach 0 sooner than this: the Painleve point is reached
MAX_SUBSTEPS = 2000           # sub-steps of one step approaching a Painleve point (~400 are needed)
MAX_EVENTS_AT_ONCE = 50       # transitions within EVENT_INSTANT beyond this: the run stops ('chatter')
EVENT_INSTANT = 1e-9          # [s] transitions closer than this to the first of a cluster are 'at once'
REST_BLOCK = 32               # record intervals per block of the REST index (`rest_bounds`)
REST_SAFETY = 1e-9            # a block is skipped only with this relative margin to every threshold


# ============================================================================================
# The equations of motion of each state and its event functions
# ============================================================================================

@njit(cache=True, inline='always')
def pivot(p, lam):
    """The constants of the pivot ``lam`` (model-asymmetric.md section 1; `layout`'s ``P_*``):
    ``(R_i, alpha_i, kr_i, q_i, m_i)``, pivot 1 for ``lam = +1``, pivot 2 for ``lam = -1`` (equal
    for a symmetric block)."""
    if lam > 0.0:
        return p[P_R], p[P_ALPHA], p[P_KR1], p[P_Q1], p[P_M1]
    return p[P_R2], p[P_ALPHA2], p[P_KR2], p[P_Q2], p[P_M2]


@njit(cache=True, inline='always')
def pivot_alpha(p, lam):
    """``alpha_i`` [rad] of the pivot ``lam``."""
    return p[P_ALPHA] if lam > 0.0 else p[P_ALPHA2]


@njit(cache=True, inline='always')
def accelerations_sc(mode, lam, sigma, s, c, thetadot, ah, G, p):
    """``(thetaddot, xddot, D)`` of a state (eqs. 3, 9, 15-16 with 22) about the pivot ``lam``;
    ``D = 1`` unless ROCKSLIP."""
    if mode == ROCK:
        _, _, kr, _, _ = pivot(p, lam)
        return rock_acceleration_k(s, c, ah, G, lam, kr), 0.0, 1.0
    if mode == SLIP:
        return 0.0, slip_acceleration(ah, G, p[P_NU], sigma), 1.0
    if mode == ROCKSLIP:
        R, _, _, q, _ = pivot(p, lam)
        return rockslip_accelerations_q(s, c, thetadot, ah, G, lam, sigma, p[P_NU], R, q)
    return 0.0, 0.0, 1.0


@njit(cache=True)
def accelerations(mode, lam, sigma, theta, thetadot, ah, G, p):
    """``(thetaddot, xddot)`` of a state at angle ``theta``."""
    s, c = tilt(theta, pivot_alpha(p, lam))
    thdd, xdd, _ = accelerations_sc(mode, lam, sigma, s, c, thetadot, ah, G, p)
    return thdd, xdd


@njit(cache=True, inline='always')
def evaluate(mode, energy, lam, sigma, th, thd, xd, t, a0, sa, v0, sv, p):
    """Everything the integrator needs at one instant (local time ``t``, ground linear in it).

    Returns ``(thetaddot, xddot, ground power, friction power, s, c, D, ah, G)``. The powers
    [W/kg] are those of the ground's inertia forces ``-ah``, ``-av`` on the centre of gravity, whose
    velocity relative to the foundation is ``(xdot - lam R c thetadot, R s thetadot)`` (the virtual
    displacements of eq. 14), and of kinetic friction, ``-nu N sigma xdot`` (eqs. 9 and 22: the
    force ``-sigma nu N`` on the slip rate; ``-nu N |xdot|`` while ``xdot`` has the sign
    ``sigma``, to the bit, and the work friction really does where it has not: past a slip stop
    found only at a step's end, or inside the reference solver's last step before one); they are
    computed only when the energy ledger is on (``energy``).

    ``mode`` and ``energy`` are compile-time constants in the integration loops (`glide_in` passes
    literals), so that each state gets code of its own without the others' branches.
    """
    ah = a0 + sa * t
    av = v0 + sv * t
    G = p[P_G] + av
    if mode == SLIP:            # upright: theta = 0, no trigonometry needed
        xdd = slip_acceleration(ah, G, p[P_NU], sigma)
        if energy:
            return 0.0, xdd, -ah * xd, -p[P_NU] * G * (sigma * xd), 0.0, 0.0, 1.0, ah, G
        return 0.0, xdd, 0.0, 0.0, 0.0, 0.0, 1.0, ah, G
    R, alpha, _, _, _ = pivot(p, lam)
    s, c = tilt(th, alpha)
    thdd, xdd, D = accelerations_sc(mode, lam, sigma, s, c, thd, ah, G, p)
    pg = 0.0
    pf = 0.0
    if energy and mode != REST:
        pg = -ah * (xd - lam * R * c * thd) - av * R * s * thd
        if mode == ROCKSLIP:
            _, N = contact_forces_sc(s, c, thd, thdd, ah, G, lam, R)
            pf = -p[P_NU] * N * (sigma * xd)
    return thdd, xdd, pg, pf, s, c, D, ah, G


@njit(cache=True)
def rk4_step(mode, energy, lam, sigma, th, thd, x, xd, wg, wf, tau, hh, a0, sa, v0, sv, p, a1, b1, pg1, pf1):
    """One classical fourth-order Runge-Kutta step of length ``hh`` from local time ``tau``.

    The state is ``theta, thetadot, x, xdot, w_ground, w_friction``; the ground is
    ``ah = a0 + sa t``, ``av = v0 + sv t`` (linear within the interval). ``a1, b1, pg1, pf1`` are
    the derivatives at the start (the first stage, from `evaluate`). Returns the new state and
    the smallest ROCKSLIP determinant ``D`` of the later stages (1 in other states): a stage with
    ``D <= 0`` evaluated the model where it has no solution, and the step must be shortened.

    ROCK does not slip and SLIP does not rotate: their stages leave out the terms that are exactly
    zero (``xdot``, ``xddot`` and the friction power in ROCK; ``thetadot``, ``thetaddot`` in SLIP),
    which gives the same numbers as the full step (they would add exact zeros).
    """
    half = 0.5 * hh
    f = hh / 6.0
    if mode == ROCK:
        th2 = th + half * thd
        thd2 = thd + half * a1
        a2, _, pg2, _, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th2, thd2, xd, tau + half, a0, sa, v0, sv, p)
        th3 = th + half * thd2
        thd3 = thd + half * a2
        a3, _, pg3, _, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th3, thd3, xd, tau + half, a0, sa, v0, sv, p)
        th4 = th + hh * thd3
        thd4 = thd + hh * a3
        a4, _, pg4, _, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th4, thd4, xd, tau + hh, a0, sa, v0, sv, p)
        return (th + f * (thd + 2.0 * thd2 + 2.0 * thd3 + thd4),
                thd + f * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
                x, xd,
                wg + f * (pg1 + 2.0 * pg2 + 2.0 * pg3 + pg4),
                wf, 1.0)
    if mode == SLIP:
        xd2 = xd + half * b1
        _, b2, pg2, pf2, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th, thd, xd2, tau + half, a0, sa, v0, sv, p)
        xd3 = xd + half * b2
        _, b3, pg3, pf3, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th, thd, xd3, tau + half, a0, sa, v0, sv, p)
        xd4 = xd + hh * b3
        _, b4, pg4, pf4, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th, thd, xd4, tau + hh, a0, sa, v0, sv, p)
        return (th, thd,
                x + f * (xd + 2.0 * xd2 + 2.0 * xd3 + xd4),
                xd + f * (b1 + 2.0 * b2 + 2.0 * b3 + b4),
                wg + f * (pg1 + 2.0 * pg2 + 2.0 * pg3 + pg4),
                wf + f * (pf1 + 2.0 * pf2 + 2.0 * pf3 + pf4), 1.0)
    th2 = th + half * thd
    thd2 = thd + half * a1
    xd2 = xd + half * b1
    a2, b2, pg2, pf2, _, _, D2, _, _ = evaluate(mode, energy, lam, sigma, th2, thd2, xd2, tau + half, a0, sa, v0, sv, p)
    th3 = th + half * thd2
    thd3 = thd + half * a2
    xd3 = xd + half * b2
    a3, b3, pg3, pf3, _, _, D3, _, _ = evaluate(mode, energy, lam, sigma, th3, thd3, xd3, tau + half, a0, sa, v0, sv, p)
    th4 = th + hh * thd3
    thd4 = thd + hh * a3
    xd4 = xd + hh * b3
    a4, b4, pg4, pf4, _, _, D4, _, _ = evaluate(mode, energy, lam, sigma, th4, thd4, xd4, tau + hh, a0, sa, v0, sv, p)
    return (th + f * (thd + 2.0 * thd2 + 2.0 * thd3 + thd4),
            thd + f * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            x + f * (xd + 2.0 * xd2 + 2.0 * xd3 + xd4),
            xd + f * (b1 + 2.0 * b2 + 2.0 * b3 + b4),
            wg + f * (pg1 + 2.0 * pg2 + 2.0 * pg3 + pg4),
            wf + f * (pf1 + 2.0 * pf2 + 2.0 * pf3 + pf4),
            min(D2, min(D3, D4)))


@njit(cache=True)
def first_stage(mode, lam, sigma, y, tau, a0, sa, v0, sv, p):
    """RK4's first stage at the state tuple ``y`` and local time ``tau``: ``(thetaddot, xddot,
    ground power, friction power)`` (`evaluate`). Every step from the same start shares it: event
    location computes it once for all its trial steps."""
    energy = p[P_ENERGY] != 0.0
    a1, b1, pg1, pf1, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, y[0], y[1], y[3], tau, a0, sa, v0, sv, p)
    return a1, b1, pg1, pf1


@njit(cache=True)
def rk4_from(mode, lam, sigma, y, k1, tau, hh, a0, sa, v0, sv, p):
    """`rk4_step` from the state tuple ``y`` = ``(theta, thetadot, x, xdot, w_ground, w_friction)``
    at local time ``tau``, its first stage ``k1`` given (`first_stage`). Returns the new state tuple
    and the smallest stage determinant (see `rk4_step`)."""
    energy = p[P_ENERGY] != 0.0
    th, thd, x, xd, wg, wf = y
    a1, b1, pg1, pf1 = k1
    th, thd, x, xd, wg, wf, d_min = rk4_step(mode, energy, lam, sigma, th, thd, x, xd, wg, wf, tau, hh,
                                             a0, sa, v0, sv, p, a1, b1, pg1, pf1)
    return (th, thd, x, xd, wg, wf), d_min


@njit(cache=True)
def time_to_painleve(lam, sigma, theta, thetadot, p):
    """In ROCKSLIP, the time [s] the determinant ``D`` would take to reach 0 at its present rate
    ``dD/dtheta thetadot`` (``inf`` while it does not fall; 0 at or past the Painleve point)."""
    R, alpha, _, q, _ = pivot(p, lam)
    s, c = tilt(theta, alpha)
    D = rockslip_determinant_q(s, c, lam, sigma, p[P_NU], R, q)
    rate = rockslip_determinant_rate(s, c, lam, sigma, p[P_NU], R) * thetadot
    if D <= 0.0:
        return 0.0
    if rate >= 0.0:
        return math.inf
    return D / -rate


# What each event function of a state is, in the order of model.md's table (-1: unused slot).
EVENT_KINDS = (
    (K_FLIGHT, K_SLIP_START, K_LIFTOFF, -1, -1),                        # REST (eqs. 11, 6)
    (K_FLIGHT, K_SLIP_STOP, K_LIFTOFF, -1, -1),                         # SLIP (eq. 23)
    (K_FLIGHT, K_SLIP_START, K_IMPACT, K_OVERTURN, -1),                 # ROCK (eq. 21)
    (K_FLIGHT, K_PAINLEVE, K_SLIP_STOP, K_IMPACT, K_OVERTURN),          # ROCKSLIP
)
N_EVENTS = tuple(sum(kind >= 0 for kind in row) for row in EVENT_KINDS)     # (3, 3, 4, 5)


@njit(cache=True, inline='always')
def event_functions(mode, lam, sigma, th, thd, xd, ah, G, s, c, thdd, D, p):
    """The event functions of ``mode`` (``g >= 0`` while the state holds), as a 5-tuple in the order
    of `EVENT_KINDS` (unused slots ``inf``). ``s``, ``c``, ``thdd``, ``D`` are `evaluate`'s at the
    same instant."""
    inf = math.inf
    if mode == SLIP:      # eq. 23 about the pivot lam = -sigma
        if sigma < 0.0:
            s0, c0 = tilt(0.0, p[P_ALPHA])
            ta = p[P_TAN_ALPHA]
        else:
            s0, c0 = tilt(0.0, p[P_ALPHA2])
            ta = p[P_TAN_ALPHA2]
        return G, sigma * xd, slip_liftoff_margin(s0, c0, ah, G, sigma, p[P_NU], ta), inf, inf
    if mode == ROCK:
        R = p[P_R] if lam > 0.0 else p[P_R2]
        Rx, N = contact_forces_sc(s, c, thd, thdd, ah, G, lam, R)
        return N, slip_margin(p[P_MU], N, Rx), th, HALF_PI - th, inf                   # eq. 21
    if mode == ROCKSLIP:
        R = p[P_R] if lam > 0.0 else p[P_R2]
        _, N = contact_forces_sc(s, c, thd, thdd, ah, G, lam, R)
        return N, D, sigma * xd, th, HALF_PI - th
    if mode == REST:      # N = G and Rx = ah at rest; both edges, both directions (eqs. 11 and 6):
        # ah > 0 lifts pivot 1's side off (tan(alpha_1)), ah < 0 pivot 2's (tan(alpha_2))
        ta = p[P_TAN_ALPHA] if ah > 0.0 else p[P_TAN_ALPHA2]
        return G, slip_margin(p[P_MU], G, ah), liftoff_margin(ta, G, ah), inf, inf
    return inf, inf, inf, inf, inf


@njit(cache=True)
def event_values(mode, lam, sigma, th, thd, xd, ah, G, p):
    """`event_functions` of ``mode`` at the state ``(th, thd, xd)`` (a 5-tuple; the state's own are
    the first ``N_EVENTS[mode]``, their kinds ``EVENT_KINDS[mode]``)."""
    s, c = tilt(th, pivot_alpha(p, lam))
    thdd, _, D = accelerations_sc(mode, lam, sigma, s, c, thd, ah, G, p)
    return event_functions(mode, lam, sigma, th, thd, xd, ah, G, s, c, thdd, D, p)


@njit(cache=True, inline='always')
def first_event(g, n):
    """Index of the first negative of the first ``n`` values of the 5-tuple ``g``, or -1."""
    for i in range(n):
        if g[i] < 0.0:
            return i
    return -1


# ============================================================================================
# Bookkeeping: events, outputs, summary
# ============================================================================================

@njit(cache=True)
def log_event(st, events, t, mode_from, mode_to, cause, branch, loss):
    """Append an event (`EVENT_COLUMNS`); ``branch`` and ``loss`` [J/kg] describe an impact (0
    otherwise). Events beyond the log's capacity are counted, not stored. (The codes are passed as
    floats, so that one compiled version serves every call.)"""
    n = int(st[S_N_EVENTS])
    if n < events.shape[0]:
        events[n, 0] = t
        events[n, 1] = mode_from
        events[n, 2] = mode_to
        events[n, 3] = cause
        events[n, 4] = st[S_LAM]
        events[n, 5] = st[S_SIGMA]
        events[n, 6] = branch
        events[n, 7] = loss
    st[S_N_EVENTS] = n + 1


@njit(cache=True)
def note_extremes(st, t):
    if st[S_THETA] > st[S_MAX_THETA]:
        st[S_MAX_THETA] = st[S_THETA]
        st[S_THETA_MAX_TIME] = t
    ax = abs(st[S_X])
    if ax > st[S_MAX_X]:
        st[S_MAX_X] = ax


@njit(cache=True, inline='always')
def store_row(st, history, every, offset, n, t, lam, th, thd, x, xd, mode):
    """Store a state at grid point ``n`` in column ``n // every - offset`` of ``history`` (rows:
    ``HISTORY_COLUMNS``) if ``n`` is on the output grid; count the columns written."""
    if every <= 0 or n % every != 0:
        return
    i = n // every - offset
    if 0 <= i < history.shape[1]:
        history[0, i] = t
        history[1, i] = lam * th
        history[2, i] = lam * thd
        history[3, i] = x
        history[4, i] = xd
        history[5, i] = mode
        if i + 1 > st[S_ROWS]:
            st[S_ROWS] = i + 1


@njit(cache=True)
def write_history(st, history, every, offset, n, t):
    """`store_row` of the state in ``st``."""
    store_row(st, history, every, offset, n, t, st[S_LAM], st[S_THETA], st[S_THETADOT], st[S_X],
              st[S_XDOT], st[S_MODE])


@njit(cache=True, inline='always')
def add_time(st, mode, duration):
    if mode == REST:
        st[S_T_REST] += duration
    elif mode == SLIP:
        st[S_T_SLIP] += duration
    elif mode == ROCK:
        st[S_T_ROCK] += duration
    elif mode == ROCKSLIP:
        st[S_T_ROCKSLIP] += duration


@njit(cache=True)
def stop(st, t):
    st[S_END_TIME] = t


@njit(cache=True)
def finished(st):
    return st[S_MODE] == OVERTURNED or st[S_STATUS] != STATUS_OK


# ============================================================================================
# Transitions (model.md's table)
# ============================================================================================

@njit(cache=True)
def mechanical_energy(st, p):
    """Kinetic and potential energy [J/kg] about the present pivot (``V_i`` is 0 upright about
    either pivot: continuous at impacts)."""
    R, alpha, _, _, m = pivot(p, st[S_LAM])
    return (kinetic_energy_m(st[S_THETA], st[S_THETADOT], st[S_XDOT], st[S_LAM], R, alpha, m)
            + potential_energy(st[S_THETA], p[P_G], R, alpha))


@njit(cache=True)
def apply_event(kind, st, p, t, ah, G, events):
    """Apply the transition of event ``kind`` to ``st`` at time ``t`` (ground ``ah``, ``G``).

    A state machine that keeps switching at one instant (a chatter that the end-of-liftoff rule,
    decision 3, should have ended; rounding may move it on by an ulp now and then) stops the run
    with status 'chatter' after `MAX_EVENTS_AT_ONCE` transitions within `EVENT_INSTANT` of the first,
    instead of looping for ever."""
    st[S_K1_VALID] = 0.0
    if t - st[S_LAST_EVENT_TIME] <= EVENT_INSTANT:
        st[S_EVENTS_AT_ONCE] += 1.0
        if st[S_EVENTS_AT_ONCE] > MAX_EVENTS_AT_ONCE:
            st[S_STATUS] = STATUS_CHATTER
            stop(st, t)
            return
    else:
        st[S_LAST_EVENT_TIME] = t
        st[S_EVENTS_AT_ONCE] = 0.0
    mode = int(st[S_MODE])
    fmode = float(mode)
    lam = st[S_LAM]
    sigma = st[S_SIGMA]
    R, alpha, kr, _, _ = pivot(p, lam)
    mu = p[P_MU]

    if kind == K_FLIGHT:
        st[S_STATUS] = STATUS_FLIGHT
        log_event(st, events, t, fmode, fmode, float(C_FLIGHT), 0.0, 0.0)
        stop(st, t)
    elif kind == K_PAINLEVE:
        st[S_STATUS] = STATUS_PAINLEVE
        log_event(st, events, t, fmode, fmode, float(C_PAINLEVE), 0.0, 0.0)
        stop(st, t)
    elif kind == K_OVERTURN:
        st[S_THETA] = HALF_PI
        st[S_MODE] = OVERTURNED
        st[S_OVERTURN_TIME] = t
        st[S_DIRECTION] = lam
        st[S_FALL_START] = st[S_FALL_CANDIDATE]
        # step-end switching finds theta a little past pi/2 at the step's end: the block lies there
        st[S_MAX_THETA] = HALF_PI
        st[S_THETA_MAX_TIME] = t
        log_event(st, events, t, fmode, float(OVERTURNED), float(C_OVERTURN), 0.0, 0.0)
        stop(st, t)
    elif kind == K_SLIP_START:
        if mode == REST:                                   # eq. 11: sigma = -sign(ah)
            st[S_SIGMA] = -1.0 if ah > 0.0 else 1.0
            st[S_XDOT] = 0.0
            st[S_MODE] = SLIP
            log_event(st, events, t, float(REST), float(SLIP), float(C_SLIP_START), 0.0, 0.0)
        else:                                              # ROCK, eq. 21: sigma = -sign(Rx)
            s, c = tilt(st[S_THETA], alpha)
            thdd = rock_acceleration_k(s, c, ah, G, lam, kr)
            Rx, _ = contact_forces_sc(s, c, st[S_THETADOT], thdd, ah, G, lam, R)
            st[S_SIGMA] = -1.0 if Rx > 0.0 else 1.0
            st[S_XDOT] = 0.0
            st[S_MODE] = ROCKSLIP
            log_event(st, events, t, float(ROCK), float(ROCKSLIP), float(C_SLIP_START), 0.0, 0.0)
    elif kind == K_LIFTOFF:
        st[S_THETA] = 0.0
        st[S_THETADOT] = 0.0
        if mode == REST:                                   # eq. 7: lam = sign(ah)
            st[S_LAM] = 1.0 if ah > 0.0 else -1.0
            st[S_MODE] = ROCK
            log_event(st, events, t, float(REST), float(ROCK), float(C_LIFTOFF), 0.0, 0.0)
        else:                                              # SLIP, eq. 24: lam = sign(xddot + ah)
            st[S_LAM] = -sigma                             # xddot + ah = -nu sigma G
            st[S_MODE] = ROCKSLIP
            log_event(st, events, t, float(SLIP), float(ROCKSLIP), float(C_LIFTOFF), 0.0, 0.0)
    elif kind == K_SLIP_STOP:
        st[S_XDOT] = 0.0
        # The pivot sticks if static friction holds the contact forces of the state without slip:
        # N = G, Rx = ah upright (SLIP -> REST), ROCK's Rx and N lifted off (ROCKSLIP -> ROCK).
        if mode == SLIP:
            Rx, N, stuck = ah, G, REST
        else:
            s, c = tilt(st[S_THETA], alpha)
            thdd = rock_acceleration_k(s, c, ah, G, lam, kr)
            Rx, N = contact_forces_sc(s, c, st[S_THETADOT], thdd, ah, G, lam, R)
            stuck = ROCK
        if slip_margin(mu, N, Rx) >= 0.0:
            st[S_MODE] = stuck
            log_event(st, events, t, fmode, float(stuck), float(C_SLIP_STOP), 0.0, 0.0)
        else:                                              # reversed: sigma = -sign(Rx)
            st[S_SIGMA] = -1.0 if Rx > 0.0 else 1.0
            log_event(st, events, t, fmode, fmode, float(C_SLIP_REVERSAL), 0.0, 0.0)
    elif kind == K_IMPACT:
        impact_of_the_landing_edge(st, p, t, mode, ah, G, events)


@njit(cache=True)
def impact_of_the_landing_edge(st, p, t, mode, ah, G, events):
    """The impact at ``theta = 0``, ``thetadot < 0`` (model.md decisions 2 and 3): the law of
    `physics.impact`, the end of liftoff when the rebound is too small to matter, the energy lost."""
    lam = st[S_LAM]
    R, alpha, _, _, _ = pivot(p, lam)              # the old pivot's
    R_n, alpha_n, _, _, _ = pivot(p, -lam)         # the landing corner's
    st[S_IMPACTS] += 1.0
    st[S_THETA] = 0.0
    st[S_FALL_CANDIDATE] = math.nan
    energy_before = mechanical_energy(st, p)
    if p[P_ASYM] != 0.0:       # model-asymmetric.md section 4.3, e the energy coefficient
        if lam > 0.0:
            b_o, b_n, rho_o2, rho_n2 = p[P_B1], p[P_B2], 2.0 * p[P_M1], 2.0 * p[P_M2]
        else:
            b_o, b_n, rho_o2, rho_n2 = p[P_B2], p[P_B1], 2.0 * p[P_M2], 2.0 * p[P_M1]
        branch, w, xi_plus = impact_body(abs(st[S_THETADOT]), lam * st[S_XDOT], p[P_E], p[P_MU], p[P_NU], p[P_H],
                                         b_o, b_n, rho_o2, rho_n2)
    else:
        branch, w, xi_plus = impact(abs(st[S_THETADOT]), lam * st[S_XDOT], p[P_E], p[P_MU], p[P_NU], R, alpha)
    if branch == IMPACT_PAINLEVE:
        st[S_STATUS] = STATUS_PAINLEVE
        log_event(st, events, t, float(mode), float(mode), float(C_PAINLEVE), float(branch), 0.0)
        stop(st, t)
        return
    st[S_LAM] = -lam                       # the landing edge pivots from now on
    cause = C_IMPACT
    w_z = zeno_rate(THETA_END, p[P_P2_2] if lam > 0.0 else p[P_P2_1], alpha_n)     # about the new pivot
    thetadot, xdot = w, (lam * xi_plus if xi_plus != 0.0 else 0.0)     # a stopped slip is +0, not -0
    if branch != IMPACT_FLAT:
        new_mode = ROCK if branch == IMPACT_STICK else ROCKSLIP
        # End of liftoff (decision 3): a rebound whose free-rocking peak is below THETA_END, w <= w_z,
        # is dropped and the block goes on upright with the law's slip velocity. When the block
        # slides away from the landing edge (xi+ < 0) the tipping rebound carries its centre of mass
        # the other way, at h w: there the block keeps its centre of mass's velocity, xi+ + h w,
        # since keeping xi+ would add up to h |xi+| w_z of kinetic energy. With step-end switching a
        # landing is only seen at a step's end, so flights shorter than a few steps cannot be
        # resolved (they would chatter for ever): they end the liftoff too.
        too_small = w <= w_z
        if p[P_LOCATED] == 0.0 and not too_small:
            sigma_new = 1.0 if xdot >= 0.0 else -1.0
            thdd0, _ = accelerations(new_mode, -lam, sigma_new, 0.0, 0.0, ah, G, p)
            too_small = thdd0 < 0.0 and 2.0 * w <= STEP_END_FLIGHT_STEPS * p[P_STEP] * abs(thdd0)
        if too_small:
            thetadot = 0.0
            xdot = lam * (xi_plus if xi_plus >= 0.0 else xi_plus + R * math.cos(alpha) * w)
            cause = C_LIFTOFF_END
        else:
            st[S_MODE] = new_mode
    if thetadot == 0.0:
        # Upright after the impact (a flat landing, or a dropped rebound): a slip velocity on the
        # scale of a negligible rebound, |xdot| <= R w_z, goes too (decision 3). Otherwise a block with
        # nu > tan(alpha) chatters: it slips, lifts off from SLIP at once (eq. 23), falls back, lands.
        if abs(xdot) <= R_n * w_z:
            xdot = 0.0
        st[S_MODE] = REST if xdot == 0.0 else SLIP
    st[S_THETADOT] = thetadot
    st[S_XDOT] = xdot
    if xdot != 0.0:
        st[S_SIGMA] = 1.0 if xdot > 0.0 else -1.0
    loss = energy_before - mechanical_energy(st, p)
    st[S_W_IMPACT] -= loss
    log_event(st, events, t, float(mode), st[S_MODE], float(cause), float(branch), loss)


@njit(cache=True)
def settle(st, p, t, ah, av, events):
    """Apply at once every condition of the current state that already holds at time ``t``."""
    G = p[P_G] + av
    for _ in range(MAX_TRANSITIONS_PER_STEP):
        if finished(st):
            return
        mode = int(st[S_MODE])
        g = event_values(mode, st[S_LAM], st[S_SIGMA], st[S_THETA], st[S_THETADOT], st[S_XDOT], ah, G, p)
        fired = first_event(g, N_EVENTS[mode])
        if fired < 0:
            return
        apply_event(EVENT_KINDS[mode][fired], st, p, t, ah, G, events)


# ============================================================================================
# REST: exact exits of a linear input, no integration
# ============================================================================================

@njit(cache=True)
def first_negative(A, B, tau, tau_end):
    """First local time in ``[tau, tau_end]`` at which ``A + B t`` is negative (its zero crossing),
    or ``inf``. A linear margin is negative somewhere on the interval only if it is at one of its
    ends, so one that falls to exactly 0 at ``tau_end`` (a record's peak exactly at a threshold)
    does not cross: the conditions of model.md's table are strict."""
    if A + B * tau < 0.0:
        return tau
    if B < 0.0 and A + B * tau_end < 0.0:
        r = -A / B
        if r < tau:
            r = tau
        return r if r <= tau_end else tau_end
    return math.inf


@njit(cache=True)
def rest_exit(tau, tau_end, a0, sa, v0, sv, p, step_end, h):
    """When and why the block leaves REST within ``[tau, tau_end]`` of the current interval.

    The conditions are linear in time (eq. 6, eq. 11, and flight ``G < 0``). Returns
    ``(time, kind)``; ``kind = -1`` if the block rests through. Ties go to the first row of
    model.md's table (flight, then slip, then liftoff); with ``step_end`` the transition happens at
    the end of the step in which the first condition was met, and among the conditions met within
    that step the first row wins (decision 1).
    """
    g0 = p[P_G] + v0
    mu = p[P_MU]
    ta = p[P_TAN_ALPHA]        # ah > 0 lifts off about pivot 1
    tb = p[P_TAN_ALPHA2]       # ah < 0 about pivot 2
    t_flight = first_negative(g0, sv, tau, tau_end)
    t_slip = min(first_negative(mu * g0 - a0, mu * sv - sa, tau, tau_end),
                 first_negative(mu * g0 + a0, mu * sv + sa, tau, tau_end))
    t_lift = min(first_negative(ta * g0 - a0, ta * sv - sa, tau, tau_end),
                 first_negative(tb * g0 + a0, tb * sv + sa, tau, tau_end))
    best = min(t_flight, min(t_slip, t_lift))
    if best == math.inf:
        return best, -1
    if step_end and best > tau:
        # Move to the end of the step containing the first crossing; among the conditions met
        # within that step the first row of the table wins (decision 1).
        best = (math.floor(best / h) + 1.0) * h
        if best >= tau_end:
            best = tau_end
            # a crossing exactly at the interval's end is not yet a negative margin
            if min(t_flight, min(t_slip, t_lift)) >= tau_end:
                return math.inf, -1
        if t_flight < best:
            return best, K_FLIGHT
        if t_slip < best:
            return best, K_SLIP_START
        return best, K_LIFTOFF
    if t_flight <= best:
        return best, K_FLIGHT
    if t_slip <= best:
        return best, K_SLIP_START
    return best, K_LIFTOFF


@njit(cache=True)
def rest_bounds(ground):
    """The REST index of a ground array (`GROUND_ROWS`): ``float64[3, n_blocks]``, for each block of
    `REST_BLOCK` intervals (columns) the largest ``abs(ah)`` and the smallest and largest ``av`` at
    their ends, which bound the linearly interpolated motion anywhere in the block."""
    K = ground.shape[1]
    n_blocks = max(1, (K + REST_BLOCK - 1) // REST_BLOCK)
    bounds = np.empty((3, n_blocks))
    for b in range(n_blocks):
        a_max, v_low, v_high = 0.0, math.inf, -math.inf
        for k in range(b * REST_BLOCK, min(K, (b + 1) * REST_BLOCK)):
            a_max = max(a_max, max(abs(ground[0, k]), abs(ground[1, k])))
            v_low = min(v_low, min(ground[2, k], ground[3, k]))
            v_high = max(v_high, max(ground[2, k], ground[3, k]))
        bounds[0, b], bounds[1, b], bounds[2, b] = a_max, v_low, v_high
    return bounds


@njit(cache=True, inline='always')
def rest_block_holds(p, bounds, block):
    """Whether the block at rest stays at rest through the whole block ``block`` of the REST index:
    with the case's scale factors, ``G = g + av`` stays positive and ``abs(ah)`` below
    ``min(mu, tan(alpha)) G`` everywhere in it, with a relative margin `REST_SAFETY` so that the
    exact per-interval exits (`rest_exit`) could not have found a crossing there either."""
    amax = abs(p[P_KH]) * bounds[0, block]
    kv = p[P_KV]
    av_low = kv * bounds[1, block] if kv >= 0.0 else kv * bounds[2, block]
    g_low = p[P_G] + av_low
    if not g_low > REST_SAFETY * p[P_G]:
        return False
    if amax == 0.0:
        return True
    m = min(p[P_MU], min(p[P_TAN_ALPHA], p[P_TAN_ALPHA2])) * g_low
    return m - amax > REST_SAFETY * (m + amax)


# ============================================================================================
# Moving states: RK4 steps with event location
# ============================================================================================

@njit(cache=True)
def event_value_at(i, mode, lam, sigma, y0, k1, tau_a, dtau, a0, sa, v0, sv, p):
    """Event function ``i`` at ``tau_a + dtau``, reached by one RK4 step from the state ``y0``
    (first stage ``k1``)."""
    y, _ = rk4_from(mode, lam, sigma, y0, k1, tau_a, dtau, a0, sa, v0, sv, p)
    if EVENT_KINDS[mode][i] == K_IMPACT:     # the landing's event function is theta itself:
        return y[0]                          # no trigonometry (most located events are landings)
    t = tau_a + dtau
    g = event_values(mode, lam, sigma, y[0], y[1], y[3], a0 + sa * t, p[P_G] + v0 + sv * t, p)
    return g[i]


@njit(cache=True)
def locate(i, mode, lam, sigma, y0, k1, tau_a, tau_b, g_a, g_b, a0, sa, v0, sv, p):
    """Local time of the zero crossing of event function ``i`` in ``(tau_a, tau_b]`` (Illinois).

    ``g_a >= 0 > g_b``. Returns the upper end of the final bracket, where the event function is
    already negative, so the new state's conditions hold there.
    """
    lo = 0.0
    hi = tau_b - tau_a
    glo = g_a
    ghi = g_b
    side = 0
    tol = 1e-15 + LOCATE_TOLERANCE * hi
    for _ in range(200):
        if hi - lo <= tol:
            break
        if glo > 0.0 and ghi < 0.0:
            m = hi - ghi * (hi - lo) / (ghi - glo)
            if not (lo < m < hi):
                m = 0.5 * (lo + hi)
        else:
            m = 0.5 * (lo + hi)
        # keep the secant away from the ends so that the bracket always shrinks
        width = hi - lo
        if m - lo < 0.01 * width:
            m = lo + 0.01 * width
        elif hi - m < 0.01 * width:
            m = hi - 0.01 * width
        gm = event_value_at(i, mode, lam, sigma, y0, k1, tau_a, m, a0, sa, v0, sv, p)
        if gm < 0.0:
            hi = m
            ghi = gm
            if side == -1:
                glo *= 0.5
            side = -1
        else:
            lo = m
            glo = gm
            if side == 1:
                ghi *= 0.5
            side = 1
    return tau_a + hi


@njit(cache=True, inline='always')
def crossing_time(i, n, g_start, g_end, mode, lam, sigma, y0, k1, tau_a, tau_b, a0, sa, v0, sv, p):
    """The located crossing of event function ``i`` in ``(tau_a, tau_b]``, or ``inf`` if it stays
    non-negative (or is not one of the state's ``n``). An event function that starts at zero
    (theta after an impact) counts its start as the positive side."""
    if i >= n or not g_end[i] < 0.0:
        return math.inf
    ga = g_start[i] if g_start[i] > 0.0 else 0.0
    return locate(i, mode, lam, sigma, y0, k1, tau_a, tau_b, ga, g_end[i], a0, sa, v0, sv, p)


@njit(cache=True)
def advance(st, p, tau_a, tau_b, tk, a0, sa, v0, sv, events):
    """Integrate the moving state from local time ``tau_a`` to ``tau_b`` (one step), handling
    every transition inside it. Returns the local time reached: ``tau_b``, or earlier if the block
    came to REST (the caller handles REST) or the run ended.

    Near a Painleve point the ROCKSLIP accelerations grow like ``1/D``: the step is cut into
    sub-steps over which ``D`` falls by at most `SINGULAR_FRACTION`, so the approach (and a flight
    that may come first) is resolved whatever the step, no RK4 stage evaluates ``D <= 0``, and the
    Painleve point is reached when ``D`` would vanish within `PAINLEVE_TIME`."""
    located = p[P_LOCATED] != 0.0
    g = p[P_G]
    for _ in range(MAX_TRANSITIONS_PER_STEP + MAX_SUBSTEPS):
        mode = int(st[S_MODE])
        if mode == REST or finished(st):
            return tau_a
        hh = tau_b - tau_a
        if hh <= 0.0:
            return tau_b
        lam = st[S_LAM]
        sigma = st[S_SIGMA]
        tau_end = tau_b
        if mode == ROCKSLIP:
            remaining = time_to_painleve(lam, sigma, st[S_THETA], st[S_THETADOT], p)
            if remaining <= PAINLEVE_TIME:
                apply_event(K_PAINLEVE, st, p, tk + tau_a, a0 + sa * tau_a, g + v0 + sv * tau_a, events)
                return tau_a
            if hh > SINGULAR_FRACTION * remaining:
                tau_end = tau_a + SINGULAR_FRACTION * remaining
        y0 = (st[S_THETA], st[S_THETADOT], st[S_X], st[S_XDOT], st[S_W_GROUND], st[S_W_FRICTION])
        if st[S_K1_VALID] != 0.0:      # left by `glide` at this state and time
            k1 = (st[S_K1_THDD], st[S_K1_XDD], st[S_K1_PG], st[S_K1_PF])
        else:
            k1 = first_stage(mode, lam, sigma, y0, tau_a, a0, sa, v0, sv, p)
        y1, d_min = rk4_from(mode, lam, sigma, y0, k1, tau_a, tau_end - tau_a, a0, sa, v0, sv, p)
        for _ in range(60):                   # a stage past D = 0 (should not happen): shorten
            if d_min > 0.0:
                break
            tau_end = tau_a + 0.5 * (tau_end - tau_a)
            y1, d_min = rk4_from(mode, lam, sigma, y0, k1, tau_a, tau_end - tau_a, a0, sa, v0, sv, p)
        hh = tau_end - tau_a
        n = N_EVENTS[mode]
        g_end = event_values(mode, lam, sigma, y1[0], y1[1], y1[3], a0 + sa * tau_end, g + v0 + sv * tau_end, p)
        first = first_event(g_end, n)
        if first < 0:              # the rest of the (sub-)step holds no event
            accept(st, y1[0], y1[1], y1[2], y1[3], y1[4], y1[5], mode, tau_a, tau_end, tk, p, True)
            if tau_end >= tau_b:
                return tau_b
            tau_a = tau_end
            continue
        # an event inside this (sub-)step
        if located:
            # event values at the start of the step (all >= 0 by construction)
            g_start = event_values(mode, lam, sigma, y0[0], y0[1], y0[3], a0 + sa * tau_a, g + v0 + sv * tau_a, p)
            times = (crossing_time(0, n, g_start, g_end, mode, lam, sigma, y0, k1, tau_a, tau_end, a0, sa, v0, sv, p),
                     crossing_time(1, n, g_start, g_end, mode, lam, sigma, y0, k1, tau_a, tau_end, a0, sa, v0, sv, p),
                     crossing_time(2, n, g_start, g_end, mode, lam, sigma, y0, k1, tau_a, tau_end, a0, sa, v0, sv, p),
                     crossing_time(3, n, g_start, g_end, mode, lam, sigma, y0, k1, tau_a, tau_end, a0, sa, v0, sv, p),
                     crossing_time(4, n, g_start, g_end, mode, lam, sigma, y0, k1, tau_a, tau_end, a0, sa, v0, sv, p))
            # The earliest wins; crossings within the location tolerance of it are ties, which go
            # to the first row of the table (e.g. flight before the eq. 23 liftoff at G = 0).
            best = min(min(min(times[0], times[1]), min(times[2], times[3])), times[4])
            best_i = 0
            while times[best_i] > best + TIE_TOLERANCE * hh + 1e-15:
                best_i += 1
            te = times[best_i]
            kind = EVENT_KINDS[mode][best_i]
            if te < tau_end:
                y1, _ = rk4_from(mode, lam, sigma, y0, k1, tau_a, te - tau_a, a0, sa, v0, sv, p)
        else:
            te = tau_end
            kind = EVENT_KINDS[mode][first]
        accept(st, y1[0], y1[1], y1[2], y1[3], y1[4], y1[5], mode, tau_a, te, tk, p, True)
        if kind == K_IMPACT:
            if not located:
                land_on_the_ground(st, p, g + v0 + sv * te)
            st[S_THETA] = 0.0
        elif kind == K_SLIP_STOP:
            # Holding the slip at zero takes kinetic energy (that of the overshoot past the stop when
            # it is found at a step's end; next to none when located): friction's work.
            before = mechanical_energy(st, p)
            st[S_XDOT] = 0.0
            st[S_W_FRICTION] += mechanical_energy(st, p) - before
        ah_e = a0 + sa * te
        av_e = v0 + sv * te
        apply_event(kind, st, p, tk + te, ah_e, g + av_e, events)
        settle(st, p, tk + te, ah_e, av_e, events)
        tau_a = te
    return tau_a


@njit(cache=True)
def land_on_the_ground(st, p, G):
    """Step-end switching only: a landing found at the end of a step has ``theta < 0``. Bring
    the block back to ``theta = 0`` at constant energy (the rise of potential energy in ``G`` is
    taken from the rotation rate), otherwise each late landing would add energy and the impacts
    of a block coming to rest would never die out."""
    th = st[S_THETA]
    if th >= 0.0:
        return
    R, alpha, _, _, m = pivot(p, st[S_LAM])
    rise = G * R * (math.cos(alpha) - math.cos(alpha - th))        # > 0 for th < 0
    w2 = st[S_THETADOT] * st[S_THETADOT] - rise / m
    st[S_THETADOT] = -math.sqrt(w2) if w2 > 0.0 else 0.0


@njit(cache=True, inline='always')
def track(mode, th0, thd0, x0, xd0, th1, thd1, x1, xd1, hh, t_start, alpha, max_th, max_th_time, max_x, fall,
          peaks_inside):
    """The bookkeeping of one step from ``(th0, thd0, x0, xd0)`` to ``(th1, thd1, x1, xd1)``,
    pure: returns the updated ``(max theta, its time, max |x|, fall candidate)``.

    Extremes are taken at the step's end and, with ``peaks_inside`` (fixed steps; not for the
    reference solver's long steps), at a peak inside the step where the rate changes sign, from the
    parabola through the step's ends (exact to O(h^3); the ends alone are off by up to
    thetaddot h^2 / 8). The fall that ends in overturning starts when theta last passed alpha upwards.
    The slip does not change in ROCK, nor the rotation in SLIP: their checks are left out there.
    """
    if mode != SLIP:
        if th1 > max_th:
            max_th = th1
            max_th_time = t_start + hh
        if peaks_inside and thd0 > 0.0 >= thd1:
            s_peak = hh * thd0 / (thd0 - thd1)
            peak = th0 + 0.5 * thd0 * s_peak
            if peak > max_th:
                max_th = peak
                max_th_time = t_start + s_peak
    if mode != ROCK:
        if abs(x1) > max_x:
            max_x = abs(x1)
        if peaks_inside and xd0 * xd1 < 0.0:
            peak = abs(x0 + 0.5 * xd0 * hh * xd0 / (xd0 - xd1))
            if peak > max_x:
                max_x = peak
    if th0 <= alpha < th1:
        fall = t_start + hh * (alpha - th0) / (th1 - th0)
    elif th1 <= alpha:
        fall = math.nan
    return max_th, max_th_time, max_x, fall


@njit(cache=True)
def accept(st, th, thd, x, xd, wg, wf, mode, tau_a, tau_b, tk, p, peaks_inside):
    """Take the state integrated from local time ``tau_a`` to ``tau_b`` into ``st``."""
    st[S_K1_VALID] = 0.0
    # `track` as for ROCKSLIP whatever the state: both the rotation and the slip are checked (a
    # single step after an event is not worth a version per state)
    (st[S_MAX_THETA], st[S_THETA_MAX_TIME], st[S_MAX_X], st[S_FALL_CANDIDATE]) = track(
        ROCKSLIP, st[S_THETA], st[S_THETADOT], st[S_X], st[S_XDOT], th, thd, x, xd, tau_b - tau_a, tk + tau_a,
        pivot_alpha(p, st[S_LAM]), st[S_MAX_THETA], st[S_THETA_MAX_TIME], st[S_MAX_X], st[S_FALL_CANDIDATE],
        peaks_inside)
    st[S_THETA] = th
    st[S_THETADOT] = thd
    st[S_X] = x
    st[S_XDOT] = xd
    st[S_W_GROUND] = wg
    st[S_W_FRICTION] = wf
    add_time(st, mode, tau_b - tau_a)


@njit(cache=True)
def glide(st, p, mode, energy, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset, n_base, t0):
    """Full steps of the moving state ``mode`` from grid point ``j - 1`` of the interval for as
    long as no event function turns negative, with the whole state in registers; ``st`` is written
    back once. Returns the grid point reached (``n_sub + 1``: the interval is done; otherwise the
    step ending at grid point ``j`` holds an event, or approaches a Painleve point, for `advance`).
    Called with ``mode`` and ``energy`` (the energy ledger is on) literal constants (`glide_in`), so
    that each state gets a loop of its own."""
    lam = st[S_LAM]
    sigma = st[S_SIGMA]
    th, thd, x, xd = st[S_THETA], st[S_THETADOT], st[S_X], st[S_XDOT]
    wg, wf = st[S_W_GROUND], st[S_W_FRICTION]
    max_th, max_th_time, max_x, fall = st[S_MAX_THETA], st[S_THETA_MAX_TIME], st[S_MAX_X], st[S_FALL_CANDIDATE]
    alpha = pivot_alpha(p, lam)
    tau_a = (j - 1) * h
    if st[S_K1_VALID] != 0.0:
        a1, b1, pg1, pf1 = st[S_K1_THDD], st[S_K1_XDD], st[S_K1_PG], st[S_K1_PF]
    else:
        a1, b1, pg1, pf1, _, _, _, _, _ = evaluate(mode, energy, lam, sigma, th, thd, xd, tau_a, a0, sa, v0, sv, p)
    elapsed = 0.0
    while j <= n_sub:
        tau_b = j * h if j < n_sub else dt_rec
        hh = tau_b - tau_a
        if mode == ROCKSLIP and hh > SINGULAR_FRACTION * time_to_painleve(lam, sigma, th, thd, p):
            break                  # near a Painleve point: `advance` takes sub-steps
        th1, thd1, x1, xd1, wg1, wf1, d_min = rk4_step(mode, energy, lam, sigma, th, thd, x, xd, wg, wf, tau_a,
                                                       hh, a0, sa, v0, sv, p, a1, b1, pg1, pf1)
        thdd, xdd, pg, pf, s, c, D, ah, G = evaluate(mode, energy, lam, sigma, th1, thd1, xd1, tau_b, a0, sa, v0, sv, p)
        g0, g1, g2, g3, g4 = event_functions(mode, lam, sigma, th1, thd1, xd1, ah, G, s, c, thdd, D, p)
        if d_min <= 0.0 or g0 < 0.0 or g1 < 0.0 or g2 < 0.0 or g3 < 0.0 or g4 < 0.0:
            break
        max_th, max_th_time, max_x, fall = track(mode, th, thd, x, xd, th1, thd1, x1, xd1, hh, tk + tau_a, alpha,
                                                 max_th, max_th_time, max_x, fall, True)
        th, thd, x, xd, wg, wf = th1, thd1, x1, xd1, wg1, wf1
        a1, b1, pg1, pf1 = thdd, xdd, pg, pf
        elapsed += hh
        if every > 0:
            store_row(st, history, every, offset, n_base + j, t0 + (n_base + j) * h, lam, th, thd, x, xd, mode)
        tau_a = tau_b
        j += 1
    st[S_THETA], st[S_THETADOT], st[S_X], st[S_XDOT] = th, thd, x, xd
    st[S_W_GROUND], st[S_W_FRICTION] = wg, wf
    st[S_MAX_THETA], st[S_THETA_MAX_TIME], st[S_MAX_X], st[S_FALL_CANDIDATE] = max_th, max_th_time, max_x, fall
    add_time(st, mode, elapsed)
    st[S_K1_VALID] = 1.0
    st[S_K1_THDD], st[S_K1_XDD], st[S_K1_PG], st[S_K1_PF] = a1, b1, pg1, pf1
    return j


@njit(cache=True)
def glide_in(st, p, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset, n_base, t0):
    """`glide` in the block's present state: each state, with and without the energy ledger, gets
    a loop of its own (the literal arguments make numba compile a version for each)."""
    mode = int(st[S_MODE])
    if p[P_ENERGY] != 0.0:
        if mode == ROCK:
            return glide(st, p, ROCK, True, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset,
                         n_base, t0)
        if mode == SLIP:
            return glide(st, p, SLIP, True, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset,
                         n_base, t0)
        return glide(st, p, ROCKSLIP, True, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset,
                     n_base, t0)
    if mode == ROCK:
        return glide(st, p, ROCK, False, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset,
                     n_base, t0)
    if mode == SLIP:
        return glide(st, p, SLIP, False, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset,
                     n_base, t0)
    return glide(st, p, ROCKSLIP, False, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset,
                 n_base, t0)


# ============================================================================================
# The driver
# ============================================================================================

@njit(cache=True)
def run(p, ground, bounds, st, history, every, offset, events, k_end):
    """Integrate from the interval ``st[S_K]`` up to (not including) ``k_end``.

    Parameters
    ----------
    p : float64[N_PARAMS]
        Constants (``P_*``). The case's record is columns ``P_FIRST ...`` of ``ground``, scaled by
        ``P_KH`` (horizontal) and ``P_KV`` (vertical).
    ground : float64[4, M]
        The ground motion [m/s^2] interval by interval (`GROUND_ROWS`): ``ah`` and ``av`` at the
        start and at the end of each interval, linear in between; tail of zeros included. Interval
        ``k`` of the case, ``[t0 + k dt_rec, t0 + (k + 1) dt_rec]``, is column ``P_FIRST + k``. A
        record's samples give ``ground[1, k] = ground[0, k + 1]``; an analytic pulse may jump at an
        interval's boundary. Several records may share the array (a batch).
    bounds : float64[3, n_blocks]
        `rest_bounds` of ``ground`` (unscaled), to skip whole blocks at rest.
    st : float64[N_STATE]
        The integration state, updated in place (resumable).
    history : float64[6, n]
        Output (rows ``HISTORY_COLUMNS``) for every ``every``-th grid point ``n``, in column
        ``n // every - offset``; ``st[S_ROWS]`` counts the columns written. ``every = 0`` keeps none.
    events : float64[m, 8]
        Event log rows (``EVENT_COLUMNS``); ``st[S_N_EVENTS]`` counts all events, including those
        beyond the log's capacity.
    k_end : int
        Stop before this interval (at most the record's number of intervals).
    """
    # The constants as a tuple of scalars: unlike an array, it cannot alias the state arrays, so
    # the compiler keeps them in registers instead of reloading them after every store.
    p = (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], p[12], p[13], p[14],
         p[15], p[16], p[17], p[18], p[19], p[20], p[21], p[22], p[23], p[24], p[25], p[26], p[27], p[28],
         p[29], p[30], p[31])
    n_sub = int(p[P_N_SUB])
    h = p[P_STEP]
    dt_rec = p[P_DT_REC]
    t0 = p[P_T0]
    first = int(p[P_FIRST])
    kh = p[P_KH]
    kv = p[P_KV]
    step_end = p[P_LOCATED] == 0.0
    k = int(st[S_K])
    if st[S_STARTED] == 0.0:
        st[S_STARTED] = 1.0
        st[S_E_INITIAL] = mechanical_energy(st, p)
        settle(st, p, t0, kh * ground[0, first], kv * ground[2, first], events)
        note_extremes(st, t0)
        write_history(st, history, every, offset, 0, t0)
    while k < k_end and not finished(st):
        col = first + k
        if st[S_MODE] == REST:
            # whole blocks of the record in which nothing can move the block: no scan at all
            block = col // REST_BLOCK
            if rest_block_holds(p, bounds, block):
                k_stop = min(k_end, (block + 1) * REST_BLOCK - first)
                while k < k_stop:
                    st[S_T_REST] += dt_rec
                    if every > 0:
                        n_base = k * n_sub
                        for jj in range(1, n_sub + 1):
                            write_history(st, history, every, offset, n_base + jj, t0 + (n_base + jj) * h)
                    k += 1
                continue
        a0 = kh * ground[0, col]
        sa = (kh * ground[1, col] - a0) / dt_rec
        v0 = kv * ground[2, col]
        sv = (kv * ground[3, col] - v0) / dt_rec
        if k > 0 and (a0 != kh * ground[1, col - 1] or v0 != kv * ground[3, col - 1]):
            st[S_K1_VALID] = 0.0        # the ground jumps: the derivative at the step's start changes
        tk = t0 + k * dt_rec
        n_base = k * n_sub
        tau = 0.0
        j = np.int64(1)                         # next grid point of this interval (typed int64
                                                # from the start: a literal 1 makes numba compile
                                                # `glide_in` twice)
        while j <= n_sub and not finished(st):
            if st[S_MODE] == REST:
                te, kind = rest_exit(tau, dt_rec, a0, sa, v0, sv, p, step_end, h)
                if kind < 0:
                    add_time(st, REST, dt_rec - tau)
                    if every > 0:
                        for jj in range(j, n_sub + 1):
                            write_history(st, history, every, offset, n_base + jj, t0 + (n_base + jj) * h)
                    j = n_sub + 1
                    tau = dt_rec
                    break
                add_time(st, REST, te - tau)
                while j <= n_sub and j * h <= te * (1.0 + 1e-14):
                    write_history(st, history, every, offset, n_base + j, t0 + (n_base + j) * h)
                    j += 1
                tau = te
                ah_e = a0 + sa * te
                av_e = v0 + sv * te
                apply_event(kind, st, p, tk + te, ah_e, p[P_G] + av_e, events)
                settle(st, p, tk + te, ah_e, av_e, events)
                continue
            if tau == (j - 1) * h:         # on the grid: full steps while nothing happens
                j = glide_in(st, p, j, n_sub, h, dt_rec, tk, a0, sa, v0, sv, history, every, offset, n_base, t0)
                if j > n_sub:
                    break
                tau = (j - 1) * h
            tau_b = j * h if j < n_sub else dt_rec
            tau = advance(st, p, tau, tau_b, tk, a0, sa, v0, sv, events)
            if tau >= tau_b:
                write_history(st, history, every, offset, n_base + j, t0 + (n_base + j) * h)
                j += 1
        k += 1
    st[S_K] = k
    return k


# numba keys each function's cache on its own file only: drop the core's compiled code when any
# of its sources changed (`compiled.freshen`), before anything is loaded from the cache.
compiled.freshen(run)
