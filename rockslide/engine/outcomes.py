"""The outcome table: every case's result variables from its final kernel state (`sweep_variables`),
the same numbers as a single run's summary (`core.simulate.summarise`), with their units and
meanings; every study's file holds them."""

from __future__ import annotations

import numpy as np

from ..core import layout as L
from ..core.layout import OVERTURNED
from ..core.simulate import may_still_overturn_params
from .plan import Plan

#: Bits of the ``modes`` variable.
MODE_BITS = {"slip": 1, "liftoff": 2, "liftoff_slip": 4}

STATUS_FLAGS = {"flag_values": np.arange(len(L.STATUS_NAMES), dtype=np.int8),
                "flag_meanings": " ".join(L.STATUS_NAMES)}


def sweep_variables(plan: Plan, states: np.ndarray) -> dict:
    """The result variables on the grid, from the final kernel states.

    Returns
    -------
    dict
        ``name -> (array shaped like the grid, attributes)``; attributes ``units`` and
        ``long_name`` (and CF ``flag_*`` for the coded ones). Same values as the summary of
        ``rockslide run`` (`simulate.summarise`, which reads one state vector the same way: a change
        there is a change here; tests/test_sweep.py compares points with runs).
    """
    shape = plan.shape
    st = states
    overturned = st[:, L.S_MODE] == OVERTURNED
    status = st[:, L.S_STATUS].astype(np.int8)
    t_slip, t_rock, t_rockslip = st[:, L.S_T_SLIP], st[:, L.S_T_ROCK], st[:, L.S_T_ROCKSLIP]
    modes = ((t_slip > 0) * MODE_BITS["slip"] + (t_rock > 0) * MODE_BITS["liftoff"]
             + (t_rockslip > 0) * MODE_BITS["liftoff_slip"]).astype(np.int8)
    end = np.where(np.isnan(st[:, L.S_END_TIME]), plan.record_end, st[:, L.S_END_TIME])
    alpha = plan.case_column(L.P_ALPHA)
    undecided = np.zeros(len(st), dtype=bool)
    # a block at rest stands, an overturned one has fallen, one outside the model is not decided
    # here: `may_still_overturn` says False for each, and only the others are asked, one at a time
    moving = np.flatnonzero((st[:, L.S_MODE] != L.REST) & ~overturned & (st[:, L.S_STATUS] == L.STATUS_OK))
    for i, row in zip(moving, moving if plan.rows is None else plan.rows[moving], strict=True):
        p = plan.params[row]
        undecided[i] = may_still_overturn_params(st[i], p)

    def grid(values, dtype):
        return np.asarray(values, dtype=dtype).reshape(shape)

    nan = np.nan
    out = {
        "overturned": (grid(overturned, np.int8),
                       {"units": "1", "long_name": "overturned (1) or standing (0)",
                        "flag_values": np.array([0, 1], dtype=np.int8),
                        "flag_meanings": "standing overturned"}),
        "overturn_time": (grid(np.where(overturned, st[:, L.S_OVERTURN_TIME], nan), np.float64),
                          {"units": "s", "long_name": "time the rotation reached pi/2 (NaN: standing)"}),
        "direction": (grid(np.where(overturned, st[:, L.S_DIRECTION], 0.0), np.int8),
                      {"units": "1", "long_name": "sign of the rotation at overturning (0: standing)",
                       "flag_values": np.array([-1, 0, 1], dtype=np.int8),
                       "flag_meanings": "negative standing positive"}),
        "fall_start_time": (grid(np.where(overturned, st[:, L.S_FALL_START], nan), np.float64),
                            {"units": "s", "long_name": "time the rotation last passed alpha before "
                             "overturning (NaN: standing)"}),
        "max_rotation": (grid(st[:, L.S_MAX_THETA], np.float64),
                         {"units": "rad", "long_name": "largest rotation |phi|"}),
        "alpha": (grid(alpha, np.float64),
                  {"units": "rad", "long_name": "alpha = atan(b/h): the rotation past which gravity "
                   "tips the block over"}),
        "max_rotation_ratio": (grid(st[:, L.S_MAX_THETA] / alpha, np.float64),
                               {"units": "1", "long_name": "largest rotation / alpha: how near "
                                "overturning (above 1: past alpha)"}),
        "max_slip": (grid(st[:, L.S_MAX_X], np.float64),
                     {"units": "m", "long_name": "largest slip displacement |x|"}),
        "residual_slip": (grid(st[:, L.S_X], np.float64),
                          {"units": "m", "long_name": "slip displacement x at the end"}),
        "impacts": (grid(st[:, L.S_IMPACTS], np.int32),
                    {"units": "1", "long_name": "number of rocking impacts"}),
        # the run stops at overturning, so the impacts counted are those before it
        "overturn_mode": (grid(np.where(overturned, np.where(st[:, L.S_IMPACTS] > 0, 2, 1), 0), np.int8),
                          {"units": "1", "long_name": "how the block overturned: without any impact "
                           "before, or after one or more impacts (0: standing)",
                           "flag_values": np.array([0, 1, 2], dtype=np.int8),
                           "flag_meanings": "standing without_impact after_impact"}),
        "undecided": (grid(undecided, np.int8),
                      {"units": "1", "long_name": "still moving at the end with the energy or tilt to "
                       "overturn afterwards: 'standing' not decided (give ground.tail)",
                       "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "decided undecided"}),
        "status": (grid(status, np.int8),
                   {"units": "1", "long_name": "ok, or where the computation left the model",
                    **STATUS_FLAGS}),
        "modes": (grid(modes, np.int8),
                  {"units": "1", "long_name": "modes that occurred (bit mask)",
                   "flag_masks": np.array(list(MODE_BITS.values()), dtype=np.int8),
                   "flag_meanings": " ".join(MODE_BITS)}),
        "end_time": (grid(end, np.float64),
                     {"units": "s", "long_name": "time the computation ended (overturning, leaving "
                      "the model, or the end of the record and tail)"}),
        "time_slip": (grid(t_slip, np.float64),
                      {"units": "s", "long_name": "time spent slipping (SLIP)"}),
        "time_liftoff": (grid(t_rock, np.float64),
                         {"units": "s", "long_name": "time spent lifted off without slip (ROCK)"}),
        "time_liftoff_slip": (grid(t_rockslip, np.float64),
                              {"units": "s", "long_name": "time spent lifted off and slipping "
                               "(ROCKSLIP)"}),
    }
    return out
