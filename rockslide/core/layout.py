"""The numbers the compiled core and its callers agree on: state codes, the layout of the parameter,
state, event and history arrays, and their names.

Plain constants and numpy only (no numba): the outer layers and a run through the build's
ahead-of-time machine code (`native`) read results without importing the compiler. `physics` and
`kernel` import these names and compile them in as constants; they are part of the core's sources
(`native.source_stamp`).
"""

from __future__ import annotations

import math

import numpy as np

# --- states, in the order of docs/model.md's table; stored in results as int8 -------------------
REST, SLIP, ROCK, ROCKSLIP, OVERTURNED = 0, 1, 2, 3, 4
STATE_NAMES = ("REST", "SLIP", "ROCK", "ROCKSLIP", "OVERTURNED")

# --- branches of the impact law (model.md decision 2), as the event log stores them (0: not an impact)
IMPACT_NONE, IMPACT_STICK, IMPACT_SLIP, IMPACT_FLAT, IMPACT_PAINLEVE = 0, 1, 2, 3, 4
IMPACT_BRANCHES = ("", "stick", "slip", "flat", "painleve")

# --- parameter vector ``p`` (``P_STEP``: the integration step, h in docs/model.md's 'Integration';
# not the block's half height) ---------------------------------------------------------------
# ``P_R``, ``P_ALPHA``, ``P_TAN_ALPHA`` are pivot 1's (``lam = +1``, the left corner; the only pivot
# of a symmetric block), ``P_*2`` pivot 2's (``lam = -1``), equal to pivot 1's for a symmetric block
# (docs/model-asymmetric.md). Per pivot: ``P_KR*`` the rocking coefficient ``R_i / rho_i^2`` (eq. 3),
# ``P_Q*`` = ``rho_i^2 / R_i^2`` (ROCKSLIP), ``P_M*`` = ``rho_i^2 / 2`` (kinetic energy), ``P_P2_*`` =
# ``p_i^2 = g R_i / rho_i^2``. A symmetric block stores today's expressions there (``0.75 / R``,
# ``4/3``, ``(2/3) R R``, ``0.75 g / R``), so that the generic formulas give its numbers to the bit.
# ``P_ASYM`` = 1 selects the impact law of the asymmetric body (model-asymmetric.md section 4), which
# needs ``P_H`` (CM height), ``P_B1``, ``P_B2`` (the corners' distances) and ``P_K2`` (``I_cm / M``).
(P_R, P_ALPHA, P_TAN_ALPHA, P_G, P_MU, P_NU, P_E, P_STEP, P_DT_REC, P_N_SUB, P_LOCATED, P_T0,
 P_ENERGY,
 P_FIRST, P_KH, P_KV,   # the case's record: its first column of ``ground``, scale factors
 P_R2, P_ALPHA2, P_TAN_ALPHA2, P_KR1, P_KR2, P_Q1, P_Q2, P_M1, P_M2, P_P2_1, P_P2_2,
 P_ASYM, P_H, P_B1, P_B2, P_K2) = range(32)
N_PARAMS = 32   # `kernel.run` unpacks p into a 32-tuple: keep the two in step

# --- state vector ``st`` ----------------------------------------------------------------------
(S_MODE, S_LAM, S_SIGMA, S_THETA, S_THETADOT, S_X, S_XDOT,   # the mechanical state
 S_STATUS, S_K, S_STARTED, S_END_TIME,                      # bookkeeping
 S_MAX_THETA, S_MAX_X, S_IMPACTS, S_FALL_START, S_OVERTURN_TIME, S_DIRECTION,
 S_T_REST, S_T_SLIP, S_T_ROCK, S_T_ROCKSLIP,                # time spent in each state [s]
 S_N_EVENTS,
 S_W_GROUND, S_W_FRICTION, S_W_IMPACT,                      # energy ledger [J/kg]
 S_FALL_CANDIDATE, S_THETA_MAX_TIME, S_E_INITIAL,
 S_K1_VALID, S_K1_THDD, S_K1_XDD, S_K1_PG, S_K1_PF,  # first RK4 stage of the next step
 S_ROWS,                                             # history columns written by the last call
 S_LAST_EVENT_TIME, S_EVENTS_AT_ONCE) = range(36)    # transitions at one instant (chatter guard)
N_STATE = 36

# --- outcomes ---------------------------------------------------------------------------------
STATUS_OK, STATUS_FLIGHT, STATUS_PAINLEVE, STATUS_CHATTER = 0, 1, 2, 3
STATUS_NAMES = ("ok", "flight", "painleve", "chatter")

# --- event causes (the event log's ``cause`` column) -------------------------------------------
(C_SLIP_START, C_LIFTOFF, C_SLIP_STOP, C_SLIP_REVERSAL, C_IMPACT, C_LIFTOFF_END,
 C_OVERTURN, C_FLIGHT, C_PAINLEVE) = range(9)
CAUSE_NAMES = ("slip-start", "liftoff", "slip-stop", "slip-reversal", "impact",
               "liftoff-end", "overturn", "flight", "painleve")

# --- event kinds: which condition of model.md's table a crossing is ----------------------------
K_FLIGHT, K_PAINLEVE, K_SLIP_START, K_LIFTOFF, K_SLIP_STOP, K_IMPACT, K_OVERTURN = range(7)

# rows of the ground array: ah and av at the start and at the end of each record interval
GROUND_ROWS = ("ah_start", "ah_end", "av_start", "av_end")
# history columns: time, rotation phi = lam theta, rotation rate, slip, slip rate, state
HISTORY_COLUMNS = ("time", "rotation", "rotation_rate", "slip", "slip_rate", "state")
# event log columns: ``impact`` is the branch of the impact law (`IMPACT_BRANCHES`, 0: not an
# impact), ``energy_loss`` the kinetic energy the impact took [J/kg]
EVENT_COLUMNS = ("time", "from", "to", "cause", "edge", "slip_direction", "impact", "energy_loss")


def new_state():
    """A state vector at rest, before the first call of `kernel.run`."""
    st = np.zeros(N_STATE)
    st[S_LAST_EVENT_TIME] = math.nan
    st[S_LAM] = 1.0
    st[S_SIGMA] = 1.0
    st[S_FALL_START] = math.nan
    st[S_OVERTURN_TIME] = math.nan
    st[S_END_TIME] = math.nan
    st[S_FALL_CANDIDATE] = math.nan
    return st

