"""Result -> figures, in the style of the paper's Figures 6 to 10.

matplotlib's object API only: figures are `matplotlib.figure.Figure` objects rendered by the Agg
backend through `Figure.savefig`. pyplot is never imported, so there is no global figure state, no
GUI backend and nothing to close; figures are freed with their last reference.

`response_figure` draws, from top to bottom:

1. the whole record: the liftoff angle (signed rotation ``phi`` [rad], left axis) and the slip
   displacement (``x`` [mm], right axis) over the state, shaded in the background (SLIP, ROCK,
   ROCKSLIP; REST unshaded), with overturning (or the end of a computation that left the model:
   flight, Painleve) marked by a vertical line and a label;
2. the same, magnified on the window where things happen (`zoom_window`), as in every figure of
   the paper;
3. the horizontal and vertical ground acceleration as applied [gal].
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .core.physics import OVERTURNED, REST, ROCK, ROCKSLIP, SLIP, STATE_NAMES
from .errors import OutputError
from .files import atomic_write, check_destination

GAL = 0.01          # [m/s^2]
FIGSIZE = (11.0, 8.0)   # [in]
DPI = 120

ROTATION_COLOUR = "#1f4e9c"   # dark blue: liftoff angle, left axis
SLIP_COLOUR = "#c0392b"       # red: slip displacement, right axis
GROUND_COLOURS = {"horizontal": "#222222", "vertical": "#2e8b57"}
STATE_COLOURS = {SLIP: "#fde2b8", ROCK: "#d3ead0", ROCKSLIP: "#e2d3f0"}   # REST unshaded
OVERTURN_COLOUR = "black"
STOP_COLOUR = "#8b0000"

#: Events spread over more than this [s] are not magnified as a whole: the zoom shows
#: `ZOOM_LONG_WINDOW` seconds around the largest rotation instead.
ZOOM_LONG_SPAN = 10.0
ZOOM_LONG_WINDOW = 5.0
#: Margin around the events in the zoom [s]: ``max(ZOOM_MIN_PAD, ZOOM_PAD_FRACTION * span)``.
ZOOM_MIN_PAD = 0.25
ZOOM_PAD_FRACTION = 0.1
#: "auto" leaves the zoom out when the window covers this fraction of the record or more.
ZOOM_USELESS_FRACTION = 0.9
#: Lines with more points than this are drawn as a min/max envelope of about that many points.
MAX_LINE_POINTS = 20_000


# --------------------------------------------------------------------------------------------------
# Where things happen
# --------------------------------------------------------------------------------------------------


def state_segments(result) -> list[tuple[float, float, int]]:
    """The states the block went through, as ``(start, end, state)`` [s] (not shifted).

    Built from the event log (exact times; the history may be coarser or absent). Consecutive
    events into the same state (impacts) are merged. The last segment ends where the computation
    ended (``summary.end_time``), or at the end of the record if the block stood to the end.
    OVERTURNED is terminal and not returned as a segment.
    """
    t_first, t_last = _record_range(result)
    events = result.events
    history = result.history
    if len(events):
        state = _code(events[0]["from"])
    elif history and len(history.get("state", ())):
        state = int(history["state"][0])
    else:
        state = REST
    summary = result.summary
    stopped = summary.overturned or summary.status != "ok"
    end = summary.end_time if stopped else max(t_last, summary.end_time)
    segments = []
    start = t_first
    for event in events:
        new = _code(event["to"])
        if new == state:
            continue
        t = float(event["time"])
        segments.append((start, t, state))
        start, state = t, new
    if state != OVERTURNED:
        segments.append((start, max(start, end), state))
    return segments


def zoom_window(result) -> tuple[float, float] | None:
    """The time window where things happen [s] (not shifted), or None if the block only rests.

    From ``pad`` before the first non-REST state to ``pad`` after the last one ends (overturning or
    the end of the computation included), with ``pad = max(0.25 s, 10 % of that span)``. If the span
    is longer than `ZOOM_LONG_SPAN` (10 s), the window is the `ZOOM_LONG_WINDOW` (5 s) around the
    largest rotation (or the fastest slip if the block never lifted off); for an overturned block or
    a computation that stopped, the 5 s that end just after it. The window is kept within the record.
    """
    t_first, t_last = _record_range(result)
    summary = result.summary
    moving = [(a, b) for a, b, s in state_segments(result) if s != REST]
    stop = summary.end_time if (summary.overturned or summary.status != "ok") else None
    if not moving and stop is None:
        return None
    starts = [a for a, _ in moving] + ([stop] if stop is not None else [])
    ends = [b for _, b in moving] + ([stop] if stop is not None else [])
    first, last = min(starts), max(ends)
    span = last - first
    if span > ZOOM_LONG_SPAN:
        if stop is not None:
            t1 = stop + ZOOM_MIN_PAD
            t0 = t1 - ZOOM_LONG_WINDOW
        else:
            centre = _peak_time(result)
            t0, t1 = centre - 0.5 * ZOOM_LONG_WINDOW, centre + 0.5 * ZOOM_LONG_WINDOW
        shift = max(0.0, t_first - t0) - max(0.0, t1 - t_last)
        t0, t1 = t0 + shift, t1 + shift
    else:
        pad = max(ZOOM_MIN_PAD, ZOOM_PAD_FRACTION * span)
        t0, t1 = first - pad, last + pad
    t0, t1 = max(t0, t_first), min(t1, t_last)
    if t1 <= t0:
        t0, t1 = max(t_first, t0 - ZOOM_MIN_PAD), min(t_last, t1 + ZOOM_MIN_PAD)
    return (float(t0), float(t1)) if t1 > t0 else None


def _peak_time(result) -> float:
    summary = result.summary
    if summary.max_rotation > 0.0:
        return float(summary.max_rotation_time)
    history = result.history
    if history and len(history.get("slip_rate", ())):
        return float(history["time"][int(np.argmax(np.abs(history["slip_rate"])))])
    moving = [(a, b) for a, b, s in state_segments(result) if s != REST]
    a, b = max(moving, key=lambda ab: ab[1] - ab[0])
    return 0.5 * (a + b)


def _record_range(result) -> tuple[float, float]:
    ground = np.asarray(result.ground_time)
    history = result.history or {}
    times = [ground[[0, -1]]] if ground.size else []
    if len(history.get("time", ())):
        times.append(np.asarray(history["time"])[[0, -1]])
    if not times:
        return 0.0, float(result.summary.end_time)
    both = np.concatenate(times)
    return float(both.min()), float(both.max())


def _code(name) -> int:
    return STATE_NAMES.index(name.decode() if isinstance(name, bytes) else str(name))


# --------------------------------------------------------------------------------------------------
# The figure
# --------------------------------------------------------------------------------------------------


def response_figure(result, *, title: str = "", time_shift: float = 0.0,
                    zoom: tuple | None | str = "auto") -> Figure:
    """The response of one simulation in the paper's style (module docstring).

    Parameters
    ----------
    result : Result or StoredResult
        A fresh or a stored result (a `StoredResult` gives its name as the default title).
    title : str
        Case name shown in the title, before the verdict.
    time_shift : float
        Added to every time on the figure [s], e.g. to lay it beside the paper's time axis.
    zoom : "auto", (t0, t1) or None
        The magnified window: ``"auto"`` = `zoom_window` (left out when nothing happens or the
        window is almost the whole record); ``(t0, t1)`` in the figure's time (time_shift
        included) [s]; None = no magnified panel.

    Returns
    -------
    matplotlib.figure.Figure
        11 x 8 in; save it with `save_figure`. Its axes are labelled (``Axes.get_label``)
        ``"record"`` and ``"record-slip"`` (whole record: rotation, and the slip twin), ``"zoom"`` and
        ``"zoom-slip"`` (if magnified) and ``"ground"``.
    """
    if hasattr(result, "result") and hasattr(result, "case_text"):   # a StoredResult
        title = title or result.name
        result = result.result
    shift = float(time_shift)
    window = _choose_zoom(result, zoom, shift)

    fig = Figure(figsize=FIGSIZE, dpi=DPI, layout="constrained")
    ratios = [3.0, 3.0, 2.0] if window else [3.0, 2.0]
    axes = fig.subplots(len(ratios), 1, gridspec_kw={"height_ratios": ratios})
    top, ground = axes[0], axes[-1]
    ground.sharex(top)
    t0, t1 = _record_range(result)

    _response_panel(top, result, shift, (t0, t1), window=window, label="record")
    top.set_title("whole record", loc="left", fontsize=10)
    if window:
        zax = axes[1]
        _response_panel(zax, result, shift, (window[0] - shift, window[1] - shift), label="zoom")
        zax.set_title(f"magnified: {window[0]:.2f} to {window[1]:.2f} s", loc="left", fontsize=10)
    _ground_panel(ground, result, shift, (t0, t1))
    ground.set_label("ground")
    ground.set_xlim(t0 + shift, t1 + shift)
    for ax in axes:
        ax.set_xlabel("time [s]")

    fig.suptitle(_title(result, title), fontsize=12)
    fig.legend(handles=_legend_handles(result), loc="outside lower center", ncols=7, frameon=False,
               fontsize=9)
    return fig


def paper_figure(panels, *, title: str = "", time_shift: float = 0.0) -> Figure:
    """Several responses in the layout of the paper's Figures 6 to 10: one row per sub-figure
    ((a), (b), (c)), the whole record on the left and the magnified window on the right.

    Parameters
    ----------
    panels : list of (label, result, caption)
        ``label`` like ``"(a)"``; ``caption`` a short text (conditions, verdict).
    title : str
        Figure title.
    time_shift : float
        Added to every time [s] (the paper's time axis).
    """
    fig = Figure(figsize=(12.0, 3.1 * len(panels) + 0.8), dpi=DPI, layout="constrained")
    axes = fig.subplots(len(panels), 2, squeeze=False, gridspec_kw={"width_ratios": [1.6, 1.0]})
    for row, (label, result, caption) in enumerate(panels):
        whole, zoomed = axes[row]
        t0, t1 = _active_range(result)
        window = _choose_zoom(result, "auto", time_shift)
        _response_panel(whole, result, time_shift, (t0, t1), window=window, label=f"record{row}")
        whole.set_title(f"{label} {caption}", loc="left", fontsize=10)
        if window is None:
            window = (t0 + time_shift, t1 + time_shift)
        _response_panel(zoomed, result, time_shift, (window[0] - time_shift, window[1] - time_shift),
                        label=f"zoom{row}")
        zoomed.set_title(f"magnified: {window[0]:.2f} to {window[1]:.2f} s", loc="left", fontsize=10)
        for ax in (whole, zoomed):
            ax.set_xlabel("time [s]")
    if title:
        fig.suptitle(title, fontsize=12)
    handles = [h for _, r, _ in panels for h in _legend_handles(r)]
    unique = {h.get_label(): h for h in handles}
    fig.legend(handles=list(unique.values()), loc="outside lower center", ncols=7, frameon=False,
               fontsize=9)
    return fig


def _active_range(result, fraction: float = 0.02, pad: float = 2.0) -> tuple[float, float]:
    """The part of the record where the ground moves (above ``fraction`` of its peak), padded, and
    extended to the end of the computation if that comes later (zero-padded records otherwise
    leave most of a panel empty)."""
    t0, t1 = _record_range(result)
    ground = np.maximum(np.abs(result.ground_horizontal), np.abs(result.ground_vertical))
    if ground.size == 0 or ground.max() == 0.0:
        return t0, t1
    moving = np.flatnonzero(ground > fraction * ground.max())
    times = result.ground_time
    start = max(t0, times[moving[0]] - pad)
    end = min(t1, max(times[moving[-1]] + pad, result.summary.end_time if result.summary.status != "ok"
                      or result.summary.overturned else -math.inf))
    return start, end


CRITERIA_COLOURS = {REST: "#ffffff", SLIP: STATE_COLOURS[SLIP], ROCK: STATE_COLOURS[ROCK],
                    ROCKSLIP: STATE_COLOURS[ROCKSLIP]}


def criteria_figure(ah_over_g, mu_values, maps, *, title: str = "") -> Figure:
    """Mode-initiation maps (the paper's Figure 5): one panel per vertical acceleration.

    Parameters
    ----------
    ah_over_g, mu_values : 1-D arrays
        The grid: horizontal acceleration [g] (x axis) and static friction (y axis).
    maps : list of (caption, codes)
        ``codes`` from `criteria.mode_map` (rows mu, columns ah): REST, SLIP, ROCK (liftoff) or
        ROCKSLIP (liftoff-slip).
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap

    fig = Figure(figsize=(4.2 * len(maps), 4.6), dpi=DPI, layout="constrained")
    axes = fig.subplots(1, len(maps), squeeze=False, sharey=True)[0]
    order = [REST, SLIP, ROCK, ROCKSLIP]
    cmap = ListedColormap([CRITERIA_COLOURS[c] for c in order])
    norm = BoundaryNorm(np.arange(len(order) + 1) - 0.5, cmap.N)
    for ax, (caption, codes) in zip(axes, maps, strict=True):
        index = np.vectorize(order.index)(codes)
        ax.pcolormesh(ah_over_g, mu_values, index, cmap=cmap, norm=norm, shading="nearest")
        ax.contour(ah_over_g, mu_values, index, levels=np.arange(len(order)) + 0.5, colors="0.3",
                   linewidths=0.8)
        ax.set_title(caption, fontsize=10)
        ax.set_xlabel("horizontal acceleration |A_h| [g]")
    axes[0].set_ylabel("static friction coefficient μ")
    names = {REST: "rest", SLIP: "slip", ROCK: "liftoff", ROCKSLIP: "liftoff-slip"}
    fig.legend(handles=[Patch(facecolor=CRITERIA_COLOURS[c], edgecolor="0.3", label=names[c]) for c in order],
               loc="outside lower center", ncols=4, frameon=False)
    if title:
        fig.suptitle(title, fontsize=12)
    return fig


def _choose_zoom(result, zoom, shift):
    if zoom is None:
        return None
    if isinstance(zoom, str):
        if zoom != "auto":
            raise ValueError(f"zoom must be 'auto', a (start, end) pair or None, got {zoom!r}")
        window = zoom_window(result)
        if window is None:
            return None
        t0, t1 = _record_range(result)
        if window[1] - window[0] >= ZOOM_USELESS_FRACTION * (t1 - t0):
            return None
        return window[0] + shift, window[1] + shift
    a, b = (float(v) for v in zoom)
    if not (math.isfinite(a) and math.isfinite(b) and b > a):
        raise ValueError(f"zoom window must be (start, end) with start < end, got {zoom!r}")
    return a, b


def _title(result, name: str) -> str:
    s = result.summary
    head = f"{name}: {s.verdict}" if name else s.verdict
    facts = [f"max |φ| = {s.max_rotation:.4g} rad", f"max |x| = {1e3 * s.max_slip:.4g} mm",
             f"residual x = {1e3 * s.residual_slip:.4g} mm", f"impacts: {s.impacts}"]
    if s.overturned and s.overturn_time is not None:
        facts.insert(0, f"overturned at t = {s.overturn_time:.3f} s")
    return head + "\n" + ",  ".join(facts)


def _response_panel(ax, result, shift, span, *, label, window=None):
    """Rotation (left axis) and slip in mm (right axis) over the shaded states, for ``span``.

    The axes are labelled ``label`` (rotation) and ``label + "-slip"`` (the twin, slip).
    """
    a, b = span
    _shade_states(ax, result, shift, span)
    history = result.history or {}
    t = np.asarray(history.get("time", np.zeros(0)))
    i0 = max(int(np.searchsorted(t, a, side="left")) - 1, 0)
    i1 = min(int(np.searchsorted(t, b, side="right")) + 1, t.size)
    t = t[i0:i1]
    phi = np.asarray(history.get("rotation", np.zeros(0)))[i0:i1]
    x_mm = 1e3 * np.asarray(history.get("slip", np.zeros(0)))[i0:i1]

    slip_ax = ax.twinx()
    ax.set_label(label)
    slip_ax.set_label(f"{label}-slip")
    if t.size:
        ax.plot(*_envelope(t + shift, phi), color=ROTATION_COLOUR, lw=1.0, zorder=3)
        slip_ax.plot(*_envelope(t + shift, x_mm), color=SLIP_COLOUR, lw=1.0, zorder=3)
    else:
        ax.text(0.5, 0.5, "no time history stored", transform=ax.transAxes, ha="center",
                va="center", color="0.4")
    ax.axhline(0.0, color="0.6", lw=0.5, zorder=1)
    rot_lim, slip_lim = _aligned_limits(phi, x_mm)
    ax.set_ylim(*rot_lim)
    slip_ax.set_ylim(*slip_lim)
    ax.set_xlim(a + shift, b + shift)
    ax.set_ylabel("liftoff angle φ [rad]", color=ROTATION_COLOUR)
    slip_ax.set_ylabel("slip x [mm]", color=SLIP_COLOUR)
    ax.tick_params(axis="y", colors=ROTATION_COLOUR)
    slip_ax.tick_params(axis="y", colors=SLIP_COLOUR)
    ax.grid(True, axis="x", color="0.88", lw=0.6)

    if result.summary.states_seen == ["REST"] and result.summary.status == "ok":
        ax.text(0.01, 0.94, "the block stays at rest", transform=ax.transAxes, va="top",
                fontsize=9, color="0.3")
    # the twin (slip) axes is drawn over the main one: marks go there to stay on top
    _mark_end(slip_ax, result, shift, span, label=True)
    if window is not None:
        slip_ax.axvspan(window[0], window[1], fill=False, ls=":", lw=1.0, ec="0.35", zorder=4)


def _shade_states(ax, result, shift, span):
    a, b = span
    trans = ax.get_xaxis_transform()
    for state, colour in STATE_COLOURS.items():
        boxes = [[(s + shift, 0.0), (s + shift, 1.0), (e + shift, 1.0), (e + shift, 0.0)]
                 for s, e, code in state_segments(result) if code == state and e > a and s < b]
        if boxes:
            ax.add_collection(PolyCollection(boxes, transform=trans, facecolors=colour,
                                             edgecolors="none", zorder=0), autolim=False)


def _mark_end(ax, result, shift, span, *, label):
    """A vertical line (and a label) where the block overturned or the computation stopped."""
    s = result.summary
    if s.overturned and s.overturn_time is not None:
        t, colour, ls = s.overturn_time, OVERTURN_COLOUR, "-"
        text = f"OVERTURNED\nt = {s.overturn_time + shift:.3f} s"
    elif s.status != "ok":
        t, colour, ls = s.end_time, STOP_COLOUR, "--"
        what = {"painleve": "PAINLEVE case", "flight": "FLIGHT"}.get(s.status, s.status.upper())
        text = f"{what}: outside the model\ncomputation stopped, t = {s.end_time + shift:.3f} s"
    else:
        return
    a, b = span
    if not (a <= t <= b):
        return
    ax.axvline(t + shift, color=colour, ls=ls, lw=1.4, zorder=5)
    if label:   # nothing is computed after this time: hatch it
        ax.axvspan(t + shift, b + shift, facecolor="none", edgecolor="0.85", hatch="//", lw=0.0,
                   zorder=0)
    if label:
        right_half = (t - a) > 0.6 * (b - a)
        ax.text(t + shift, 0.97, f" {text} " if not right_half else f"{text} ",
                transform=ax.get_xaxis_transform(), ha="right" if right_half else "left",
                va="top", fontsize=9, color=colour, zorder=6,
                bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.8})


def _ground_panel(ax, result, shift, span):
    t = np.asarray(result.ground_time) + shift
    for key, values in (("horizontal", result.ground_horizontal), ("vertical", result.ground_vertical)):
        ax.plot(*_envelope(t, np.asarray(values) / GAL), color=GROUND_COLOURS[key], lw=0.8,
                label=f"{key}", alpha=0.9 if key == "horizontal" else 0.8)
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_ylabel("ground acc. [gal]")
    ax.set_title("ground acceleration as applied", loc="left", fontsize=10)
    ax.legend(loc="upper right", fontsize=8, ncols=2, frameon=False)
    ax.grid(True, axis="x", color="0.88", lw=0.6)
    _mark_end(ax, result, shift, span, label=False)
    peak = max(float(np.max(np.abs(result.ground_horizontal), initial=0.0)),
               float(np.max(np.abs(result.ground_vertical), initial=0.0))) / GAL
    if peak == 0.0:
        ax.set_ylim(-1.0, 1.0)


def _legend_handles(result) -> list:
    handles = [Line2D([], [], color=ROTATION_COLOUR, lw=1.5, label="liftoff angle φ"),
               Line2D([], [], color=SLIP_COLOUR, lw=1.5, label="slip x"),
               Patch(facecolor="white", edgecolor="0.6", lw=0.5, label="REST"),
               Patch(facecolor=STATE_COLOURS[SLIP], label="SLIP"),
               Patch(facecolor=STATE_COLOURS[ROCK], label="ROCK (liftoff)"),
               Patch(facecolor=STATE_COLOURS[ROCKSLIP], label="ROCKSLIP (liftoff-slip)")]
    s = result.summary
    if s.overturned:
        handles.append(Line2D([], [], color=OVERTURN_COLOUR, lw=1.4, label="OVERTURNED"))
    elif s.status != "ok":
        handles.append(Line2D([], [], color=STOP_COLOUR, ls="--", lw=1.4, label=f"{s.status}: stopped"))
    return handles


def _aligned_limits(phi: np.ndarray, x_mm: np.ndarray):
    """Limits of the rotation and slip axes with their zeros at the same height."""
    ranges = []
    for values, default in ((phi, 0.01), (x_mm, 1.0)):
        values = values[np.isfinite(values)] if values.size else values
        lo = min(0.0, float(values.min())) if values.size else 0.0
        hi = max(0.0, float(values.max())) if values.size else 0.0
        ranges.append((lo, hi, default))
    moving = [(lo, hi) for lo, hi, _ in ranges if hi - lo > 0.0]
    if moving:
        below = max(-lo / (hi - lo) for lo, hi in moving)
        above = max(hi / (hi - lo) for lo, hi in moving)
        zero = below / (below + above)   # height of zero on both axes, in [0, 1]
    else:
        zero = 0.5
    zero = min(max(zero, 0.1), 0.9) if 0.0 < zero < 1.0 else zero
    limits = []
    for lo, hi, default in ranges:
        if hi - lo <= 0.0:   # a flat line at zero: a small default range
            size = 2.0 * default
        else:
            size = 1.08 * max(-lo / zero if zero > 0 else 0.0, hi / (1.0 - zero) if zero < 1 else 0.0)
        limits.append((-zero * size, (1.0 - zero) * size))
    return limits


def _envelope(t: np.ndarray, y: np.ndarray, max_points: int = MAX_LINE_POINTS):
    """``(t, y)`` reduced to a min/max envelope when there are more than ``max_points`` points."""
    n = t.size
    if n <= max_points:
        return t, y
    bins = max_points // 2
    edges = np.linspace(0, n, bins + 1).astype(np.int64)[:-1]
    lo, hi = np.minimum.reduceat(y, edges), np.maximum.reduceat(y, edges)
    ends = np.append(edges[1:], n) - 1
    tt = np.column_stack([t[edges], t[ends]]).ravel()
    yy = np.column_stack([lo, hi]).ravel()
    return tt, yy


# --------------------------------------------------------------------------------------------------
# Sweeps
# --------------------------------------------------------------------------------------------------

#: The categories of a sweep's overturning map, codes 0 to 5 (`sweep_category`).
SWEEP_CATEGORIES = ("rest", "slip", "liftoff", "liftoff-slip", "overturned", "outside the model")
SWEEP_COLOURS = ("#ffffff", "#f5c07a", "#9fd39a", "#c3a6e0", "#3a3a3a", "#d9534f")
#: A map's third axis is shown in at most this many rows.
SWEEP_MAX_ROWS = 4
NO_DATA_COLOUR = "#e6e6e6"


def sweep_category(overturned, status, modes) -> np.ndarray:
    """The category of each point of a sweep (codes index `SWEEP_CATEGORIES`).

    Precedence: outside the model (``status != 0``), overturned, then the most involved mode that
    occurred (``modes`` bits: 4 liftoff-slip, 2 liftoff, 1 slip), else rest.
    """
    modes = np.asarray(modes).astype(np.int64)
    out = np.zeros(modes.shape, dtype=np.int8)
    out[(modes & 1) != 0] = 1
    out[(modes & 2) != 0] = 2
    out[(modes & 4) != 0] = 3
    out[np.asarray(overturned).astype(bool)] = 4
    out[np.asarray(status) != 0] = 5
    return out


def sweep_figure(axes, category, max_rotation, residual_slip, *, title: str = "") -> Figure:
    """Maps of a sweep: overturning and the modes that occurred, max rotation, residual slip.

    Parameters
    ----------
    axes : list of (label, values)
        The sweep's axes in dimension order, values as they should be shown (e.g. in gal).
    category : int array, shaped like the grid
        `sweep_category` codes.
    max_rotation : float array [rad]
    residual_slip : float array [m]
    title : str

    Returns
    -------
    matplotlib.figure.Figure
        One axis: three panels over it. Two or more axes: three maps over the first two axes (the
        first up the page, the second across it, as ``xarray`` draws them); a third axis gives
        one row of maps for each of up to `SWEEP_MAX_ROWS` of its values (spread evenly, ends
        included); further axes are held at their first value. What is shown is said under the
        title. Overturned points are outlined on every map; the rotation map is logarithmic and
        leaves points that never lifted off grey; the residual slip map leaves overturned points
        and points outside the model grey.
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm, TwoSlopeNorm

    category = np.asarray(category)
    rotation = np.asarray(max_rotation, dtype=float)
    slip_mm = np.asarray(residual_slip, dtype=float) * 1000.0
    if category.ndim != len(axes) or category.ndim == 0:
        raise ValueError(f"expected arrays with one dimension per axis ({len(axes)}), got "
                         f"{category.shape}")
    cmap_cat = ListedColormap(SWEEP_COLOURS)
    norm_cat = BoundaryNorm(np.arange(len(SWEEP_CATEGORIES) + 1) - 0.5, cmap_cat.N)
    standing = category < 4
    positive = rotation[rotation > 0]
    rot_norm = LogNorm(vmin=max(1e-6, min(float(positive.min()) if positive.size else 1e-3, 1.0)),
                       vmax=0.5 * math.pi)
    slip_shown = np.abs(slip_mm[standing]) if standing.any() else np.zeros(0)
    limit = max(float(slip_shown.max()) if slip_shown.size else 0.0, 1e-3)
    slip_norm = TwoSlopeNorm(vcenter=0.0, vmin=-limit, vmax=limit)
    rot_cmap = _with_bad("viridis")
    slip_cmap = _with_bad("RdBu_r")
    legend = [Patch(facecolor=c, edgecolor="0.4", label=n) for n, c in zip(SWEEP_CATEGORIES, SWEEP_COLOURS,
                                                                           strict=True)]

    if category.ndim == 1:
        label, x = axes[0]
        x = np.asarray(x, dtype=float)
        fig = Figure(figsize=(9.0, 7.5), dpi=DPI, layout="constrained")
        top, mid, low = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [0.6, 2, 2]})
        top.pcolormesh(x, [0.0, 1.0], np.vstack([category, category]), cmap=cmap_cat,
                       norm=norm_cat, shading="nearest")
        top.set_yticks([])
        top.set_title("overturning and modes", loc="left", fontsize=10)
        shown = np.where(rotation > 0, rotation, np.nan)
        mid.semilogy(x, shown, "o-", color=ROTATION_COLOUR, ms=3)
        mid.axhline(0.5 * math.pi, color="0.5", lw=0.8, ls="--")
        mid.set_ylabel("max rotation [rad]")
        low.plot(x, np.where(standing, slip_mm, np.nan), "o-", color=SLIP_COLOUR, ms=3)
        low.axhline(0.0, color="0.5", lw=0.8)
        low.set_ylabel("residual slip [mm] (standing)")
        low.set_xlabel(label)
        fig.legend(handles=legend, loc="outside lower center", ncols=6, frameon=False, fontsize=9)
        if title:
            fig.suptitle(title, fontsize=12)
        return fig

    rows, note = _sweep_rows(axes)
    fig = Figure(figsize=(15.0, 3.9 * len(rows) + 1.2), dpi=DPI, layout="constrained")
    grid = fig.subplots(len(rows), 3, squeeze=False)
    (ylabel, yv), (xlabel, xv) = axes[0], axes[1]
    y_order, x_order = np.argsort(np.asarray(yv, dtype=float)), np.argsort(np.asarray(xv, dtype=float))
    y_edges = _cell_edges(np.asarray(yv, dtype=float)[y_order])
    x_edges = _cell_edges(np.asarray(xv, dtype=float)[x_order])

    def sorted_2d(values, index):
        return values[index][np.ix_(y_order, x_order)]

    for r, (index, caption) in enumerate(rows):
        cat = sorted_2d(category, index)
        rot = sorted_2d(rotation, index)
        panels = (
            (cat, dict(cmap=cmap_cat, norm=norm_cat), "overturning and modes", None),
            (np.ma.masked_where(~(rot > 0), rot), dict(cmap=rot_cmap, norm=rot_norm), "max rotation",
             "max rotation [rad]"),
            (np.ma.masked_where(~sorted_2d(standing, index), sorted_2d(slip_mm, index)),
             dict(cmap=slip_cmap, norm=slip_norm), "residual slip (standing blocks)",
             "residual slip [mm]"),
        )
        for c, (values, style, name, bar) in enumerate(panels):
            ax = grid[r, c]
            mesh = ax.pcolormesh(x_edges, y_edges, values, shading="flat", **style)
            _outline(ax, x_edges, y_edges, cat == 4)
            if bar:
                fig.colorbar(mesh, ax=ax, label=bar)
            ax.set_title(f"{name}{caption}", loc="left", fontsize=10)
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
    fig.legend(handles=legend, loc="outside lower center", ncols=6, frameon=False, fontsize=9)
    if title or note:
        fig.suptitle("\n".join(t for t in (title, note) if t), fontsize=12)
    return fig


def _cell_edges(centres: np.ndarray) -> np.ndarray:
    """Edges of cells around sorted centres: midway between them, half a spacing beyond the ends."""
    if centres.size == 1:
        half = 0.05 * max(abs(float(centres[0])), 1.0)
        return np.array([centres[0] - half, centres[0] + half])
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]])


def _outline(ax, x_edges, y_edges, mask) -> None:
    """Draw the border of the region ``mask`` (rows y, columns x) along cell edges."""
    from matplotlib.collections import LineCollection

    mask = np.asarray(mask, dtype=bool)
    padded = np.pad(mask, 1, constant_values=False)
    segments = []
    rows, cols = np.nonzero(padded[1:-1, 1:] != padded[1:-1, :-1])       # vertical edges
    segments += [((x_edges[i], y_edges[j]), (x_edges[i], y_edges[j + 1])) for j, i in zip(rows, cols,
                                                                                           strict=True)]
    rows, cols = np.nonzero(padded[1:, 1:-1] != padded[:-1, 1:-1])       # horizontal edges
    segments += [((x_edges[i], y_edges[j]), (x_edges[i + 1], y_edges[j])) for j, i in zip(rows, cols,
                                                                                           strict=True)]
    if segments:
        ax.add_collection(LineCollection(segments, colors="black", linewidths=1.2))


def _with_bad(name: str):
    from matplotlib import colormaps

    return colormaps[name].with_extremes(bad=NO_DATA_COLOUR)


def _sweep_rows(axes) -> tuple[list, str]:
    """The 2-D slices drawn (index tuples and row captions) and a note on what is not shown."""
    fixed = [f"{label} = {_short(values[0])}" for label, values in axes[3:]]
    if len(axes) == 2:
        return [((slice(None), slice(None)), "")], ""
    label, values = axes[2]
    n = len(values)
    picks = sorted(set(np.linspace(0, n - 1, min(n, SWEEP_MAX_ROWS)).round().astype(int).tolist()))
    rest = (0,) * (len(axes) - 3)
    rows = [((slice(None), slice(None), k, *rest), f": {label} = {_short(values[k])}") for k in picks]
    parts = [f"rows: {len(picks)} of the {n} values of {label}"] if len(picks) < n else []
    if fixed:
        parts.append("at the first value of the other axes: " + ", ".join(fixed))
    return rows, "; ".join(parts)


def _short(value) -> str:
    return f"{float(value):.6g}"


# --------------------------------------------------------------------------------------------------
# Saving
# --------------------------------------------------------------------------------------------------


def save_figure(fig: Figure, path, *, overwrite: bool = False, dpi: float = DPI, staging=None) -> Path:
    """Save ``fig`` to ``path`` atomically (a temporary file in the same folder, then a rename).

    The format follows the file name (``.png``, ``.pdf``, ``.svg``...). An existing file is kept
    unless ``overwrite``; the folder is created if missing. With ``staging`` (`files.Staging`) the
    file is published with the rest of a result's files instead of at once.

    Raises
    ------
    OutputError
        The file exists, the folder cannot be created or written, or the format is unknown.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    supported = fig.canvas.get_supported_filetypes()
    if fmt not in supported:
        raise OutputError(f"unknown figure format {path.suffix or '(none)'!r}; expected one of "
                          + ", ".join(f".{k}" for k in sorted(supported)), source=str(path))
    check_destination(path, overwrite=overwrite, example="out/case.png")
    with atomic_write(path, overwrite=overwrite, what="figure", staging=staging) as handle:
        fig.savefig(handle, format=fmt, dpi=dpi)
    return path


__all__ = ["response_figure", "save_figure", "zoom_window", "state_segments", "sweep_figure",
           "sweep_category", "SWEEP_CATEGORIES"]
