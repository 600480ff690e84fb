"""Model + ground motion arrays -> Result. Pure: no files, no plotting.

`simulate` sets up the compiled kernel (`kernel.run`, through `native.entry_points`: the build's
ahead-of-time machine code when it fits the sources, else numba's JIT), drives it chunk by chunk (so that an
hour-long record needs bounded memory when the history is streamed with ``on_chunk``), and turns
its state vector and logs into a `Result` whose summary is plain data (overturning, flight and the
Painleve case are outcomes, not exceptions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import layout as L
from . import native
from .layout import IMPACT_BRANCHES, OVERTURNED, REST, ROCK, ROCKSLIP, SLIP, STATE_NAMES

#: The event log of a result: time [s], the state before and after, the cause, the pivoting edge
#: (``lam``) and slip direction (``sigma``) after the event, and for an impact the branch of the impact
#: law (stick, slip, flat or painleve; empty for other events) and the kinetic energy it took [J] (>= 0).
EVENT_DTYPE = np.dtype([("time", "f8"), ("from", "S10"), ("to", "S10"), ("cause", "S14"),
                        ("edge", "i1"), ("slip_direction", "i1"), ("impact", "S8"), ("energy_loss", "f8")])


@dataclass(frozen=True)
class Model:
    """The block and its contact (docs/model.md, 'Scene and assumptions'; an asymmetric body:
    docs/model-asymmetric.md).

    Attributes
    ----------
    half_width, half_height : float
        ``b`` and ``h`` [m]: half the block's width and height. For an asymmetric body ``half_width``
        is ``b1``, the distance of pivot 1 (the corner a positive ``ah`` tips it over, ``lam = +1``)
        from the vertical through the centre of mass, and ``half_height`` the centre of mass's height.
    mu_static, mu_kinetic : float
        ``mu`` and ``nu`` [-]: static and kinetic friction coefficients (``nu <= mu``).
    restitution : float
        ``e`` [-]: coefficient of restitution of eq. 8, within [0, 1].
    gravity : float
        ``g`` [m/s^2].
    mass : float
        ``M`` [kg]; scales energies only.
    half_width_2 : float or None
        ``b2`` [m]: pivot 2's distance (``lam = -1``); None: ``b1`` (symmetric).
    radius_of_gyration : float or None
        ``sqrt(I_cm / M)`` [m] about the centre of mass; None: the uniform rectangle's,
        ``sqrt((bm^2 + h^2) / 3)`` with ``bm = (b1 + b2) / 2``. With ``b2`` None or ``b1`` and no
        radius of gyration the kernel runs the rectangle's expressions (bit for bit as ever,
        model-asymmetric.md section 7); given, the generic ones. ``e`` is then the energy coefficient
        (section 4.2).
    """

    half_width: float
    half_height: float
    mu_static: float
    mu_kinetic: float
    restitution: float
    gravity: float = 9.80665
    mass: float = 1.0
    half_width_2: float | None = None
    radius_of_gyration: float | None = None

    @property
    def asymmetric(self) -> bool:
        """Whether the generic body's expressions run: ``b2 != b1`` or an inertia given."""
        return (self.half_width_2 is not None and self.half_width_2 != self.half_width) \
            or self.radius_of_gyration is not None

    @property
    def half_widths(self) -> tuple[float, float]:
        """``(b1, b2)`` [m]."""
        return self.half_width, self.half_width if self.half_width_2 is None else self.half_width_2

    @property
    def k2(self) -> float:
        """``I_cm / M`` [m^2] (model-asymmetric.md section 1)."""
        if self.radius_of_gyration is not None:
            return self.radius_of_gyration ** 2
        b1, b2 = self.half_widths
        bm = 0.5 * (b1 + b2)
        return (bm * bm + self.half_height ** 2) / 3.0

    @property
    def pivots(self) -> tuple[dict, dict]:
        """The constants of pivot 1 (``lam = +1``) and pivot 2 (``lam = -1``), model-asymmetric.md
        section 1: ``R`` [m], ``alpha`` [rad], ``tan_alpha`` (``b_i / h``), ``rho2`` (``k2 + R_i^2``)
        [m^2], ``kr`` (``R_i / rho_i^2``) [1/m], ``p2`` (``g R_i / rho_i^2``) [1/s^2], ``b`` [m]."""
        h, k2, g = self.half_height, self.k2, self.gravity
        out = []
        for b in self.half_widths:
            R = math.sqrt(b * b + h * h)
            rho2 = k2 + R * R
            out.append({"R": R, "alpha": math.atan2(b, h), "tan_alpha": b / h, "rho2": rho2, "kr": R / rho2,
                        "p2": g * R / rho2, "b": b})
        return out[0], out[1]

    @property
    def tipping_angles(self) -> tuple[float, float]:
        """``(alpha_1, alpha_2)`` [rad]: the static tipping angles about pivots 1 and 2."""
        if not self.asymmetric:
            alpha = self.constants[1]
            return alpha, alpha
        one, two = self.pivots
        return one["alpha"], two["alpha"]

    @property
    def restitution_max(self) -> float:
        """``e_max = (h^2 + sqrt(D_1 D_2)) / (rho_1 rho_2)`` [-], with ``D_i = k2 + b_i^2``: the largest
        energy coefficient whose impacts never add energy (model-asymmetric.md section 4.2; 1 for a
        symmetric block)."""
        if not self.asymmetric:
            return 1.0
        one, two = self.pivots
        h2, k2 = self.half_height ** 2, self.k2
        D1, D2 = k2 + one["b"] ** 2, k2 + two["b"] ** 2
        return (h2 + math.sqrt(D1 * D2)) / math.sqrt(one["rho2"] * two["rho2"])

    @classmethod
    def from_block(cls, width, height, mu_static, mu_kinetic, restitution, gravity=9.80665, mass=1.0):
        """From the full ``width`` and ``height`` [m] of the block (``2 b`` and ``2 h``: the same
        order as the half sizes of `Model` itself)."""
        return cls(0.5 * width, 0.5 * height, mu_static, mu_kinetic, restitution, gravity, mass)

    @property
    def constants(self):
        """``(R, alpha, p2)``: see `physics.block_constants`."""
        return native.entry_points().block_constants(self.half_width, self.half_height, self.gravity)


@dataclass(frozen=True)
class Settings:
    """How to integrate.

    Attributes
    ----------
    dt : float
        Largest step [s] (default the paper's 0.1 ms). The step used is ``dt_record / n`` with the
        smallest whole ``n`` that makes it ``<= dt``, so that input kinks fall on step boundaries.
    events : str
        ``"located"``: events found inside the step; ``"step-end"``: the paper-like switch at the end
        of the step.
    tail : float
        Free vibration after the record [s] (ground still).
    rotation, rotation_rate, slip_rate : float
        Initial conditions: signed rotation ``phi`` [rad], its rate [rad/s], slip rate [m/s].
    history_every : int
        Keep every n-th step in the history (0: no history).
    energy : bool
        Integrate the energy ledger (work of the ground and of friction).
    chunk_steps : int
        Integration steps per kernel call at most (bounds the memory of a streamed history and the
        time before Ctrl-C is noticed: the kernel returns to Python between chunks).
    """

    dt: float = 1e-4
    events: str = "located"
    tail: float = 0.0
    rotation: float = 0.0
    rotation_rate: float = 0.0
    slip_rate: float = 0.0
    history_every: int = 1
    energy: bool = True
    chunk_steps: int = 2_000_000


@dataclass
class Summary:
    """What happened, as plain data (the fields of ``rockslide run --json``)."""

    overturned: bool                  #: whether the block overturned (theta reached pi/2)
    overturn_time: float | None       #: [s] when theta reached pi/2
    direction: int | None             #: sign of the rotation phi at overturning, +1 about the left edge
    fall_start_time: float | None     #: [s] when theta last passed alpha before overturning
    max_rotation: float               #: [rad] max ``|phi|``
    max_rotation_time: float          #: [s] when max ``|phi|`` was reached
    max_slip: float                   #: [m] max ``|x|``
    residual_slip: float              #: [m] x at the end
    impacts: int                      #: impacts of the rocking block on its base (eq. 8)
    states_seen: list[str]            #: the states it was in (REST, SLIP, ROCK, ROCKSLIP, OVERTURNED)
    time_in_state: dict[str, float]   #: [s] time spent in each state, by name
    status: str                       #: ok, flight, painleve or chatter
    end_time: float                   #: [s] when the computation ended
    energy: dict[str, float] = field(default_factory=dict)   #: [J] the energy ledger (energy_* in files)
    alpha: float = math.nan           #: [rad] atan(b/h), the rotation past which gravity tips the block over
    max_rotation_ratio: float = math.nan   #: max ``|phi|`` / alpha, how near overturning (> 1 passed alpha)
    undecided: bool = False           #: ended moving, with the energy or tilt to overturn (`may_still_overturn`)
    alpha_2: float = math.nan         #: [rad] atan(b2/h), pivot 2's tipping angle (alpha's for a rectangle)

    @property
    def verdict(self) -> str:
        """The verdict as printed (standing, overturned, undecided or outside the model, and why)."""
        if self.status == "chatter":
            return f"stopped: the state machine chattered at t = {self.end_time:.4f} s (a bug; please report it)"
        if self.status != "ok":
            return f"outside the model ({self.status} at t = {self.end_time:.4f} s)"
        if self.undecided:
            return (f"undecided: still moving at the end (t = {self.end_time:.4f} s) with the energy to "
                    "overturn; give ground.tail for its free motion")
        return "overturned" if self.overturned else "standing"


@dataclass
class Result:
    """Time histories, event log and summary of one simulation."""

    history: dict[str, np.ndarray]    # HISTORY_COLUMNS; state as int8
    events: np.ndarray                # EVENT_DTYPE
    summary: Summary
    step: float                       # [s] the integration step used
    ground_time: np.ndarray           # [s] ground samples as applied (tail included)
    ground_horizontal: np.ndarray     # [m/s^2]
    ground_vertical: np.ndarray       # [m/s^2]

    def events_as_dicts(self) -> list[dict]:
        """The event log as plain data; impacts also give their branch and the energy lost [J]."""
        out = []
        for e in self.events:
            event = {"time": float(e["time"]), "from": e["from"].decode(), "to": e["to"].decode(),
                     "cause": e["cause"].decode()}
            if e["impact"]:
                event["impact"] = e["impact"].decode()
                event["energy_loss"] = float(e["energy_loss"])
            out.append(event)
        return out


def substeps(dt_record: float, dt: float) -> int:
    """Number of integration steps per record interval: the smallest ``n`` with
    ``dt_record / n <= dt`` (a relative tolerance of 1e-9 absorbs decimal round-off)."""
    return max(1, math.ceil(dt_record / dt * (1.0 - 1e-9)))


def set_model(p: np.ndarray, model: Model) -> np.ndarray:
    """Write ``model`` into the kernel's parameter vector ``p`` (in place; returned): the block's
    ``R``, ``alpha`` and ``tan(alpha) = b/h`` of each pivot and their derived constants (`layout`),
    gravity and the contact. The one place a `Model` becomes
    kernel parameters (`parameters`, and the members of an ensemble)."""
    if model.asymmetric:
        for lam, pv in zip((1, 2), model.pivots, strict=True):
            R, alpha, tan_alpha, kr, q, m, p2 = (pv["R"], pv["alpha"], pv["tan_alpha"], pv["kr"],
                                                 pv["rho2"] / (pv["R"] * pv["R"]), 0.5 * pv["rho2"], pv["p2"])
            if lam == 1:
                p[L.P_R], p[L.P_ALPHA], p[L.P_TAN_ALPHA], p[L.P_KR1], p[L.P_Q1], p[L.P_M1], p[L.P_P2_1] = (
                    R, alpha, tan_alpha, kr, q, m, p2)
            else:
                p[L.P_R2], p[L.P_ALPHA2], p[L.P_TAN_ALPHA2], p[L.P_KR2], p[L.P_Q2], p[L.P_M2], p[L.P_P2_2] = (
                    R, alpha, tan_alpha, kr, q, m, p2)
        p[L.P_ASYM] = 1.0
        p[L.P_H] = model.half_height
        p[L.P_B1], p[L.P_B2] = model.half_widths
        p[L.P_K2] = model.k2
    else:
        # the rectangle's expressions, so that the generic formulas give today's numbers to the bit
        R, alpha, _ = model.constants
        p[L.P_R] = p[L.P_R2] = R
        p[L.P_ALPHA] = p[L.P_ALPHA2] = alpha
        p[L.P_TAN_ALPHA] = p[L.P_TAN_ALPHA2] = model.half_width / model.half_height
        p[L.P_KR1] = p[L.P_KR2] = 0.75 / R
        p[L.P_Q1] = p[L.P_Q2] = 4.0 / 3.0
        p[L.P_M1] = p[L.P_M2] = (2.0 / 3.0) * R * R
        p[L.P_P2_1] = p[L.P_P2_2] = 0.75 * model.gravity / R
        p[L.P_ASYM] = 0.0
        p[L.P_H] = model.half_height
        p[L.P_B1] = p[L.P_B2] = model.half_width
        p[L.P_K2] = R * R / 3.0
    p[L.P_G] = model.gravity
    p[L.P_MU] = model.mu_static
    p[L.P_NU] = model.mu_kinetic
    p[L.P_E] = model.restitution
    return p


def parameters(model: Model, dt_record: float, settings: Settings, start: float = 0.0) -> np.ndarray:
    """The kernel's parameter vector ``p`` (indices ``kernel.P_*``)."""
    n_sub = substeps(dt_record, settings.dt)
    p = set_model(np.zeros(L.N_PARAMS), model)
    p[L.P_STEP] = dt_record / n_sub
    p[L.P_DT_REC] = dt_record
    p[L.P_N_SUB] = n_sub
    p[L.P_LOCATED] = 1.0 if settings.events == "located" else 0.0
    p[L.P_T0] = start
    p[L.P_ENERGY] = 1.0 if settings.energy else 0.0
    p[L.P_FIRST] = 0.0                     # a single record, as applied: no offset, no scaling
    p[L.P_KH] = 1.0
    p[L.P_KV] = 1.0
    return p


def initial_state(settings: Settings) -> np.ndarray:
    """Kernel state for the initial conditions (model.md decision 6).

    A rotation (or rotation rate) starts in ROCK about the edge of its sign; a slip rate in SLIP,
    or ROCKSLIP with a rotation too. The kernel applies the state's tests at once at t = 0.
    """
    st = L.new_state()
    phi, phidot, xdot = settings.rotation, settings.rotation_rate, settings.slip_rate
    rocking = phi != 0.0 or phidot != 0.0
    if rocking:
        lam = math.copysign(1.0, phi) if phi != 0.0 else math.copysign(1.0, phidot)
        st[L.S_LAM] = lam
        st[L.S_THETA] = abs(phi)
        st[L.S_THETADOT] = lam * phidot
    if xdot != 0.0:
        st[L.S_SIGMA] = math.copysign(1.0, xdot)
        st[L.S_XDOT] = xdot
    st[L.S_MODE] = (ROCKSLIP if xdot != 0.0 else ROCK) if rocking else (SLIP if xdot != 0.0 else REST)
    return st


def tail_samples(tail: float, dt_record: float) -> int:
    """Samples of still ground that a tail of ``tail`` seconds appends at the step ``dt_record``
    (the tail's end rounded up to the next sample)."""
    return math.ceil(tail / dt_record - 1e-9) if tail > 0 else 0


def interval_count(component, dt_record: float, tail: float) -> int:
    """Record intervals of one ground component with its tail, as `ground_array` lays them out:
    ``n - 1 + n_tail`` for samples ``(n,)``, ``n + n_tail`` for interval end values ``(2, n)``."""
    values, samples = _intervals(component)
    return _interval_count(values, samples, tail_samples(tail, dt_record))


def _intervals(component) -> tuple[np.ndarray, bool]:
    """One component as an array and whether it is samples ``(n,)`` (else interval end values
    ``(2, n)``)."""
    values = np.asarray(component, dtype=np.float64)
    if values.ndim == 1:
        return values, True
    if values.ndim != 2 or values.shape[0] != 2:
        raise ValueError(f"a ground component is samples (n,) or interval end values (2, n), got "
                         f"shape {values.shape}")
    return values, False


def _interval_count(values: np.ndarray, samples: bool, n_tail: int) -> int:
    if samples:                               # n samples and the tail's zeros: n + n_tail - 1 intervals
        return max(values.size + n_tail, 2) - 1
    return values.shape[1] + n_tail


def _fill_intervals(out: np.ndarray, row: int, values: np.ndarray, samples: bool) -> None:
    """Write one component into rows ``row`` (start) and ``row + 1`` (end) of ``out`` (zeros after
    the component: the tail)."""
    K = out.shape[1]
    if samples:                               # interval k runs from sample k to sample k + 1
        n = values.size
        out[row, :min(n, K)] = values[:min(n, K)]
        out[row + 1, :min(n - 1, K)] = values[1:min(n, K + 1)]
    else:
        out[row:row + 2, :values.shape[1]] = values


def ground_array(horizontal, vertical, dt_record: float, tail: float = 0.0) -> np.ndarray:
    """The kernel's ground motion, ``float64[4, K]`` (rows `kernel.GROUND_ROWS`), with ``tail``
    seconds of still ground appended (model.md decision 8).

    Parameters
    ----------
    horizontal, vertical : array_like
        Each either samples ``(n,)`` [m/s^2] at ``dt_record``, linear in between (a record), or
        ``(2, n)``: the values at the start and at the end of each interval, linear in between and
        free to jump at the boundaries (an analytic pulse with steps). Same number of intervals.
    dt_record : float
        [s] the sampling step.
    tail : float
        [s] still ground appended.
    """
    n_tail = tail_samples(tail, dt_record)
    ah, ah_samples = _intervals(horizontal)
    av, av_samples = _intervals(vertical)
    K = _interval_count(ah, ah_samples, n_tail)
    if _interval_count(av, av_samples, n_tail) != K:
        raise ValueError(f"horizontal and vertical ground motion differ in length: {K} and "
                         f"{_interval_count(av, av_samples, n_tail)} intervals")
    out = np.zeros((4, K))
    _fill_intervals(out, 0, ah, ah_samples)
    _fill_intervals(out, 2, av, av_samples)
    if not np.isfinite(out).all():       # the readers refuse these; this guards direct calls
        raise ValueError("the ground motion holds a non-finite value (NaN or infinity)")
    return out


def ground_series(ground: np.ndarray, dt_record: float, start: float = 0.0):
    """The ground motion of `ground_array` as a time series ``(time, ah, av)`` [s, m/s^2, m/s^2]:
    the samples, with a time repeated where the motion jumps (its value before, then after)."""
    K = ground.shape[1]
    t = start + dt_record * np.arange(K + 1)
    jumps = np.flatnonzero((ground[1, :-1] != ground[0, 1:]) | (ground[3, :-1] != ground[2, 1:])) + 1
    h = np.concatenate([ground[0], ground[1, -1:]])
    v = np.concatenate([ground[2], ground[3, -1:]])
    if jumps.size == 0:
        return t, h, v
    # before each jump, the value at the end of the previous interval
    return (np.insert(t, jumps, t[jumps]), np.insert(h, jumps, ground[1, jumps - 1]),
            np.insert(v, jumps, ground[3, jumps - 1]))


def simulate(model: Model, dt_record: float, horizontal, vertical, settings: Settings = Settings(),
             start: float = 0.0, on_chunk=None, progress=None) -> Result:
    """Compute the response of ``model`` to the ground motion.

    Parameters
    ----------
    model : Model
    dt_record : float
        Sampling step of the ground motion [s].
    horizontal, vertical : array_like
        Ground accelerations ``ah``, ``av`` [m/s^2] (up positive): samples linearly interpolated,
        or interval end values that may jump at the samples (see `ground_array`).
    settings : Settings
    start : float
        Time of the first sample [s].
    on_chunk : callable, optional
        ``on_chunk(rows)`` receives the history chunk by chunk (``float64[n, 6]``, columns
        ``kernel.HISTORY_COLUMNS``) instead of keeping it in the result (bounded memory).
    progress : callable, optional
        ``progress(reached, end)`` is called after each chunk with the time reached and the time of
        the last ground sample [s] (tail included). It may raise to stop the run (Ctrl-C); the
        exception propagates.

    Returns
    -------
    Result
    """
    core = native.entry_points()
    ground = ground_array(horizontal, vertical, dt_record, settings.tail)
    bounds = core.rest_bounds(ground)
    p = parameters(model, dt_record, settings, start)
    st = initial_state(settings)
    n_sub = int(p[L.P_N_SUB])
    every = int(settings.history_every)
    n_intervals = ground.shape[1]
    kept = []
    event_chunks = []
    events = np.zeros((1024, len(L.EVENT_COLUMNS)))
    k = 0
    while k < n_intervals and not core.finished(st):
        k_end = min(n_intervals, k + max(1, settings.chunk_steps // n_sub))
        # history columns on the output grid between steps k*n_sub (exclusive, except at the
        # start) and k_end*n_sub (inclusive)
        if every > 0:
            first = 0 if k == 0 else (k * n_sub) // every + 1
            history = np.empty((len(L.HISTORY_COLUMNS), max(0, (k_end * n_sub) // every - first + 1)))
        else:
            first, history = 0, np.empty((len(L.HISTORY_COLUMNS), 0))
        saved = st.copy()
        while True:
            st[L.S_N_EVENTS] = 0
            st[L.S_ROWS] = 0
            core.run(p, ground, bounds, st, history, every, first, events, k_end)
            n_events = int(st[L.S_N_EVENTS])
            if n_events <= events.shape[0]:
                break
            events = np.zeros((2 * n_events, len(L.EVENT_COLUMNS)))
            st[:] = saved
        event_chunks.append(events[:n_events].copy())
        written = history[:, :int(st[L.S_ROWS])]
        if on_chunk is not None:
            on_chunk(written.T)
        elif every > 0:
            kept.append(written)
        k = int(st[L.S_K])
        if progress is not None:
            progress(start + k * dt_record, start + n_intervals * dt_record)
    columns = kept[0] if len(kept) == 1 else (np.concatenate(kept, axis=1) if kept
                                              else np.empty((len(L.HISTORY_COLUMNS), 0)))
    ground_time, ground_h, ground_v = ground_series(ground, dt_record, start)
    return Result(
        history=history_dict(columns),
        events=event_table(np.concatenate(event_chunks) if event_chunks
                           else np.zeros((0, len(L.EVENT_COLUMNS))), model.mass),
        summary=summarise(st, model, start + n_intervals * dt_record),
        step=p[L.P_STEP],
        ground_time=ground_time,
        ground_horizontal=ground_h,
        ground_vertical=ground_v,
    )


def kernel_inputs(params, states, base, first, count, kh, kv, *, copy: bool = True):
    """A batch's arguments as the kernel takes them (`batch.compute`, `compute_batch`): ``(params,
    states, base, count)``, fresh C-contiguous float64 (int64 ``count``) arrays, each case's record
    columns (``P_FIRST``, ``P_KH``, ``P_KV``) set in ``params``. ``copy=False``: ``params`` and
    ``states`` are the caller's own, changed in place where they are already C-contiguous float64
    (`gpu.prepare`'s, gathered in launch order: 140 MB a launch not copied twice)."""
    params = np.array(params, dtype=np.float64, order="C", copy=True if copy else None)
    states = np.array(states, dtype=np.float64, order="C", copy=True if copy else None)
    n = params.shape[0]
    base = np.ascontiguousarray(base, dtype=np.float64)
    params[:, L.P_FIRST] = np.broadcast_to(first, n)
    params[:, L.P_KH] = np.broadcast_to(kh, n)
    params[:, L.P_KV] = np.broadcast_to(kv, n)
    return params, states, base, np.array(np.broadcast_to(count, n), dtype=np.int64)   # a copy: never stride 0


def compute_batch(params, states, base, first, count, kh, kv):
    """`batch.compute` through `native.entry_points`: the batch driver's loop (`batch.run_batch`:
    one `kernel.run` per case, no history, no event log) in Python over the build's machine code.

    The same kernel on the same inputs: the final states are `batch.compute`'s to the last bit
    (tests/test_startup.py). Without numba's batch driver nothing of numba is imported or loaded (a
    second or more at the start of a study). Each case releases the GIL while it runs (the build
    compiles the module so: `native.RELEASES_GIL`), so that a study's threads compute side by side
    and the one waiting for Ctrl-C runs meanwhile. Arguments and result as `batch.compute`'s.
    """
    params, out, base, count = kernel_inputs(params, states, base, first, count, kh, kv)
    if params.shape[0]:
        core = native.entry_points()
        bounds = core.rest_bounds(base)
        history = np.empty((len(L.HISTORY_COLUMNS), 0))
        events = np.empty((0, len(L.EVENT_COLUMNS)))
        for i in range(params.shape[0]):
            core.run(params[i], base, bounds, out[i], history, 0, 0, events, count[i])
    return out


def history_dict(columns: np.ndarray) -> dict[str, np.ndarray]:
    """History arrays by name from the kernel's ``float64[6, n]`` output (views, no copies)."""
    out = {name: columns[i] for i, name in enumerate(L.HISTORY_COLUMNS)}
    out["state"] = out["state"].astype(np.int8)
    return out


def event_table(rows: np.ndarray, mass: float = 1.0) -> np.ndarray:
    """`EVENT_DTYPE` records from the kernel's event rows (`kernel.EVENT_COLUMNS`); energies per unit
    mass become joules with ``mass`` [kg]."""
    table = np.zeros(rows.shape[0], dtype=EVENT_DTYPE)
    if rows.shape[0]:
        table["time"] = rows[:, 0]
        names = np.array([n.encode() for n in STATE_NAMES])
        causes = np.array([c.encode() for c in L.CAUSE_NAMES])
        branches = np.array([b.encode() for b in IMPACT_BRANCHES])
        table["from"] = names[rows[:, 1].astype(int)]
        table["to"] = names[rows[:, 2].astype(int)]
        table["cause"] = causes[rows[:, 3].astype(int)]
        table["edge"] = rows[:, 4].astype(np.int8)
        table["slip_direction"] = rows[:, 5].astype(np.int8)
        table["impact"] = branches[rows[:, 6].astype(int)]
        table["energy_loss"] = mass * rows[:, 7]
    return table


def summarise(st: np.ndarray, model: Model, record_end: float) -> Summary:
    """The summary from the kernel's final state vector. `sweep.sweep_variables` reads the same
    quantities from many state vectors at once: a change here is a change there
    (tests/test_sweep.py compares sweep points with runs)."""
    R, alpha, _ = model.constants
    p = set_model(np.zeros(L.N_PARAMS), model)
    if model.asymmetric:          # the present pivot's constants
        lam = st[L.S_LAM]
        R, alpha = (p[L.P_R], p[L.P_ALPHA]) if lam > 0 else (p[L.P_R2], p[L.P_ALPHA2])
    m = p[L.P_M1] if st[L.S_LAM] > 0 else p[L.P_M2]
    time_in = {"REST": st[L.S_T_REST], "SLIP": st[L.S_T_SLIP], "ROCK": st[L.S_T_ROCK],
               "ROCKSLIP": st[L.S_T_ROCKSLIP]}
    overturned = st[L.S_MODE] == OVERTURNED
    seen = [name for name, t in time_in.items() if t > 0.0 or (name == "REST" and st[L.S_MODE] == REST)]
    if overturned:
        seen.append("OVERTURNED")
    end_time = st[L.S_END_TIME] if not math.isnan(st[L.S_END_TIME]) else record_end
    M = model.mass
    core = native.entry_points()
    kinetic = M * core.kinetic_energy_m(st[L.S_THETA], st[L.S_THETADOT], st[L.S_XDOT], st[L.S_LAM], R, alpha, m)
    potential = M * core.potential_energy(st[L.S_THETA], model.gravity, R, alpha)
    ground, friction, impact = M * st[L.S_W_GROUND], M * st[L.S_W_FRICTION], M * st[L.S_W_IMPACT]
    energy = {
        "kinetic": kinetic, "potential": potential, "work_ground": ground,
        "friction_loss": -friction, "impact_loss": -impact,
        "initial": M * st[L.S_E_INITIAL],
        "balance_residual": kinetic + potential - M * st[L.S_E_INITIAL] - (ground + friction + impact),
    }
    fall = st[L.S_FALL_START]
    return Summary(
        undecided=may_still_overturn_params(st, p),
        overturned=bool(overturned),
        overturn_time=float(st[L.S_OVERTURN_TIME]) if overturned else None,
        direction=int(st[L.S_DIRECTION]) if overturned else None,
        fall_start_time=None if math.isnan(fall) else float(fall),
        max_rotation=float(st[L.S_MAX_THETA]),
        max_rotation_time=float(st[L.S_THETA_MAX_TIME]),
        max_slip=float(st[L.S_MAX_X]),
        residual_slip=float(st[L.S_X]),
        impacts=int(st[L.S_IMPACTS]),
        states_seen=seen,
        time_in_state={k: float(v) for k, v in time_in.items()},
        status=L.STATUS_NAMES[int(st[L.S_STATUS])],
        end_time=float(end_time),
        energy={k: float(v) for k, v in energy.items()},
        alpha=float(p[L.P_ALPHA]),
        max_rotation_ratio=float(st[L.S_MAX_THETA]) / float(p[L.P_ALPHA]),
        alpha_2=float(p[L.P_ALPHA2]),
    )


def may_still_overturn_params(st: np.ndarray, p: np.ndarray) -> bool:
    """`may_still_overturn` from a kernel parameter vector ``p``. For an asymmetric body (``P_ASYM``)
    the present pivot's rotation past its ``alpha``, a slip that can lift off about ``lam = -sigma``,
    or an energy at least the lower of the two barriers ``g (R_i - h)`` (a rebound may carry it over
    the other corner)."""
    if p[L.P_ASYM] == 0.0:
        return may_still_overturn(st, p[L.P_R], p[L.P_ALPHA], p[L.P_G], p[L.P_NU], p[L.P_TAN_ALPHA])
    mode = st[L.S_MODE]
    if st[L.S_STATUS] != L.STATUS_OK or mode == REST or mode == OVERTURNED:
        return False
    lam, theta, g = st[L.S_LAM], st[L.S_THETA], p[L.P_G]
    R, alpha, m = (p[L.P_R], p[L.P_ALPHA], p[L.P_M1]) if lam > 0 else (p[L.P_R2], p[L.P_ALPHA2], p[L.P_M2])
    if theta >= alpha:
        return True
    core = native.entry_points()
    if mode == SLIP:
        alpha_l, ta = (p[L.P_ALPHA], p[L.P_TAN_ALPHA]) if st[L.S_SIGMA] < 0 else (p[L.P_ALPHA2], p[L.P_TAN_ALPHA2])
        s, c = core.tilt(0.0, alpha_l)
        if core.slip_liftoff_margin(s, c, 0.0, g, st[L.S_SIGMA], p[L.P_NU], ta) >= 0.0:
            return False
    energy = (core.kinetic_energy_m(theta, st[L.S_THETADOT], st[L.S_XDOT], lam, R, alpha, m)
              + core.potential_energy(theta, g, R, alpha))
    barrier = min(core.potential_energy(p[L.P_ALPHA], g, p[L.P_R], p[L.P_ALPHA]),
                  core.potential_energy(p[L.P_ALPHA2], g, p[L.P_R2], p[L.P_ALPHA2]))
    return bool(energy >= barrier)


def may_still_overturn(st: np.ndarray, R: float, alpha: float, gravity: float, nu: float,
                       tan_alpha: float) -> bool:
    """Whether the computation that ended in the state vector ``st`` (status ok, not overturned)
    left the block moving with what it takes to overturn afterwards: a rotation of ``alpha`` or
    more, or a mechanical energy at least the potential energy at ``theta = alpha`` (and, when it
    ends sliding upright, a kinetic friction ``nu`` above ``tan_alpha`` = b/h, which can lift it
    off on still ground, eq. 23).

    After the computation the ground is still: nothing adds energy (friction and impacts only take
    it, model.md decisions 2 and 3), and the block overturns only past ``theta = alpha``, the
    highest point of its centre of gravity; a block sliding on still ground with
    ``nu <= tan(alpha)`` slides to a stop without lifting off. A block that ends at rest, or moving
    without any of these, stands for good; otherwise whether it stands is decided by the free
    motion that was not computed (the case's ``ground.tail``).
    """
    mode = st[L.S_MODE]
    if st[L.S_STATUS] != L.STATUS_OK or mode == REST or mode == OVERTURNED:
        return False
    theta = st[L.S_THETA]
    if theta >= alpha:
        return True
    core = native.entry_points()
    if mode == SLIP:
        s, c = core.tilt(0.0, alpha)
        if core.slip_liftoff_margin(s, c, 0.0, gravity, st[L.S_SIGMA], nu, tan_alpha) >= 0.0:
            return False
    energy = (core.kinetic_energy(theta, st[L.S_THETADOT], st[L.S_XDOT], st[L.S_LAM], R, alpha)
              + core.potential_energy(theta, gravity, R, alpha))
    return bool(energy >= core.potential_energy(alpha, gravity, R, alpha))


__all__ = ["Model", "Settings", "Summary", "Result", "simulate", "substeps", "parameters", "ground_array",
           "ground_series", "kernel_inputs", "compute_batch", "may_still_overturn", "may_still_overturn_params",
           "tail_samples", "interval_count",
           "REST", "SLIP", "ROCK", "ROCKSLIP", "OVERTURNED"]
