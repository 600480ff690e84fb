"""The baseline of the speed figures: a plain compiled RK4 loop of rocking on a record.

It integrates eq. 3 (ROCK, ``lam`` the pivot's sign) with the ground linear in each record
interval, read from the same ``float64[4, K]`` array of interval end values the kernel reads
(`simulate.ground_array`), and bounces with ``e`` where ``theta`` turns negative. No event is
located, nothing is recorded, no other state exists: it is what the kernel's rocking would cost
if it did nothing but integrate. Used by ``bench.py`` and ``bench_kernel.py``.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def plain_rk4_rocking(ground, n_sub, h, dt_rec, R, alpha, g, e, theta, rate, lam):
    """``n_sub`` RK4 steps of ``h`` per interval of ``ground``; returns the final rotation."""
    c = 0.75 / R
    for k in range(ground.shape[1]):
        a0 = ground[0, k]
        sa = (ground[1, k] - a0) / dt_rec
        v0 = ground[2, k]
        sv = (ground[3, k] - v0) / dt_rec
        for j in range(n_sub):
            t = j * h
            a1 = c * (-(g + v0 + sv * t) * math.sin(alpha - theta) + lam * (a0 + sa * t) * math.cos(alpha - theta))
            t2, r2 = theta + 0.5 * h * rate, rate + 0.5 * h * a1
            tm = t + 0.5 * h
            a2 = c * (-(g + v0 + sv * tm) * math.sin(alpha - t2) + lam * (a0 + sa * tm) * math.cos(alpha - t2))
            t3, r3 = theta + 0.5 * h * r2, rate + 0.5 * h * a2
            a3 = c * (-(g + v0 + sv * tm) * math.sin(alpha - t3) + lam * (a0 + sa * tm) * math.cos(alpha - t3))
            t4, r4 = theta + h * r3, rate + h * a3
            te = t + h
            a4 = c * (-(g + v0 + sv * te) * math.sin(alpha - t4) + lam * (a0 + sa * te) * math.cos(alpha - t4))
            theta = theta + h / 6.0 * (rate + 2.0 * r2 + 2.0 * r3 + r4)
            rate = rate + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            if theta < 0.0:
                theta, rate, lam = -theta, -e * rate, -lam
    return theta
