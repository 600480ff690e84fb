"""Result -> figures, in the style of the paper's Figures 6 to 10.

matplotlib's object API only: figures are `matplotlib.figure.Figure` objects rendered by the Agg
backend through `Figure.savefig` (PNG files written by `_write_png`). pyplot is never imported,
so there is no global figure state, no GUI backend and nothing to close; figures are freed with
their last reference.

`response_figure` draws, from top to bottom:

1. the response where the motion is (`motion_range`: where the ground or the block moves, the whole
   record when that is most of it): the liftoff angle (signed rotation ``phi`` [rad], left axis,
   with +-alpha drawn once the rotation comes near it) and the slip displacement (``x`` [mm], right
   axis) over the state, shaded in the background (SLIP, ROCK, ROCKSLIP; REST unshaded), with
   overturning (or the end of a computation that left the model: flight, Painleve) marked by a
   vertical line;
2. the same, magnified on the window where things happen (`zoom_window`), as in every figure of
   the paper;
3. the horizontal and vertical ground acceleration as applied [gal], over the same time as 1.

Labels never cover data: what a panel needs to say (overturning, the end of the computation, alpha
off the scale, a block at rest) goes in its title line, and the legends below the panels. Lines are
decimated for drawing (`_envelope`, a min/max envelope of at most `MAX_LINE_POINTS` points), never
in what is stored. The format follows the file name in `save_figure` (PNG, PDF, SVG...).
"""

from __future__ import annotations

import math
import os
import struct
import zlib
from pathlib import Path

import numpy as np
from matplotlib import rcParams
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .core.layout import OVERTURNED, REST, ROCK, ROCKSLIP, SLIP, STATE_NAMES
from .errors import OutputError
from .files import atomic_write, check_destination
from .units import percent_text

GAL = 0.01          # [m/s^2]
FIGSIZE = (11.0, 8.0)   # [in]
DPI = 150
#: zlib level of PNG files (`_write_png`): 3 deflates a run's figure in about 17 ms (244 KB), 6 in
#: about 45 ms (213 KB).
PNG_COMPRESSION = 3

ROTATION_COLOUR = "#1f4e9c"   # dark blue: liftoff angle, left axis
SLIP_COLOUR = "#c0392b"       # red: slip displacement, right axis
ALPHA_COLOUR = "#5b6f8f"      # +-alpha: the rotation past which gravity tips the block over
GROUND_COLOURS = {"horizontal": "#222222", "vertical": "#2e8b57"}
STATE_COLOURS = {SLIP: "#fde2b8", ROCK: "#d3ead0", ROCKSLIP: "#e2d3f0"}   # REST unshaded
OVERTURN_COLOUR = "black"
STOP_COLOUR = "#8b0000"

#: Motion spread over more than this [s] is not magnified as a whole: the zoom shows the episode
#: around the largest rotation (or the end), see `zoom_window`.
ZOOM_LONG_SPAN = 10.0
#: Moving states less than this apart [s] belong to one episode.
EPISODE_GAP = 1.0
#: Margin around the events in the zoom [s]: ``max(ZOOM_MIN_PAD, ZOOM_PAD_FRACTION * span)``.
ZOOM_MIN_PAD = 0.25
ZOOM_PAD_FRACTION = 0.1
#: "auto" leaves the zoom out when the window covers this fraction of the shown range or more.
ZOOM_USELESS_FRACTION = 0.9
#: The ground "moves" where its acceleration exceeds this fraction of its peak (`motion_range`).
GROUND_MOVES_FRACTION = 0.02
#: Margin around the motion in `motion_range` [s]: ``max(MOTION_MIN_PAD, MOTION_PAD_FRACTION * span)``.
MOTION_MIN_PAD = 1.0
MOTION_PAD_FRACTION = 0.05
#: +-alpha is drawn on a rotation axis when the rotation shown reaches this fraction of alpha
#: (below it, alpha would squash the curve to a flat line: the panel says alpha is off the scale).
ALPHA_SHOWN_FRACTION = 0.25
#: Lines with more points than this are drawn as a min/max envelope of about that many points.
MAX_LINE_POINTS = 20_000
#: Space [pt] between the edges of a response figure and what is drawn in it (`_fit_column`).
EDGE_PAD = 4.0
#: Space [pt] between the blocks stacked in a response figure: the title, each panel with its
#: decorations, the legend (`_fit_column`).
BLOCK_GAP = 8.0


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
    end = summary.end_time if _stop_time(result) is not None else max(t_last, summary.end_time)
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

    All the motion (the moving states, and overturning or the end of a computation that stopped)
    with a margin ``pad = max(0.25 s, 10 % of its span)``, when it spans at most `ZOOM_LONG_SPAN`
    (10 s). Longer, the episode (moving states less than `EPISODE_GAP` apart) around the largest
    rotation, or the one that ends in overturning or the stop, with the same margin; and if that
    episode is itself longer than 10 s, its swings around that moment: from the second impact
    before it to the second impact after it (or the stop), so that the opposite swings on both
    sides are whole. The window is kept within the record.
    """
    t_first, t_last = _record_range(result)
    stop = _stop_time(result)
    moving = [(a, b) for a, b, s in state_segments(result) if s != REST]
    marks = moving + ([(stop, stop)] if stop is not None else [])
    if not marks:
        return None
    first, last = min(a for a, _ in marks), max(b for _, b in marks)
    if last - first > ZOOM_LONG_SPAN:
        focus = stop if stop is not None else _peak_time(result)
        first, last = _episode_around(marks, focus)
        if last - first > ZOOM_LONG_SPAN:
            impacts = np.array([float(e["time"]) for e in result.events if _text(e["cause"]) == "impact"
                                and first <= float(e["time"]) <= last])
            before, after = impacts[impacts < focus], impacts[impacts > focus]
            first = before[-2] if before.size >= 2 else first
            last = stop if stop is not None else (after[1] if after.size >= 2 else last)
    pad = max(ZOOM_MIN_PAD, ZOOM_PAD_FRACTION * (last - first))
    t0, t1 = max(first - pad, t_first), min(last + pad, t_last)
    return (float(t0), float(t1)) if t1 > t0 else None


def motion_range(result) -> tuple[float, float]:
    """The part of the record worth showing [s] (not shifted): from where the ground or the block
    first moves to where the last of them stops (the ground moves where its acceleration exceeds
    `GROUND_MOVES_FRACTION` of its peak; the block moves in any state but REST, up to overturning
    or the end of the computation, after which nothing is shown but the margin), with a margin
    ``max(1 s, 5 % of the span)``. The whole record
    when the block stays at rest on still ground, or when the motion covers most of the record
    (`ZOOM_USELESS_FRACTION`)."""
    t_first, t_last = _record_range(result)
    marks = [(a, b) for a, b, s in state_segments(result) if s != REST]
    stop = _stop_time(result)
    if stop is not None:
        marks.append((stop, stop))
    ground = np.maximum(np.abs(np.asarray(result.ground_horizontal)), np.abs(np.asarray(result.ground_vertical)))
    if ground.size and ground.max() > 0.0:
        moves = np.flatnonzero(ground > GROUND_MOVES_FRACTION * ground.max())
        times = np.asarray(result.ground_time)
        last_move = float(times[moves[-1]]) if stop is None else min(float(times[moves[-1]]), stop)
        marks.append((min(float(times[moves[0]]), last_move), last_move))
    if not marks:
        return t_first, t_last
    first, last = min(a for a, _ in marks), max(b for _, b in marks)
    pad = max(MOTION_MIN_PAD, MOTION_PAD_FRACTION * (last - first))
    t0, t1 = max(t_first, first - pad), min(t_last, last + pad)
    if t1 - t0 >= ZOOM_USELESS_FRACTION * (t_last - t_first) or t1 <= t0:
        return t_first, t_last
    return float(t0), float(t1)


def _episode_around(marks, focus: float) -> tuple[float, float]:
    """The episode (``marks`` merged where less than `EPISODE_GAP` apart) that holds ``focus``, or
    the nearest one."""
    episodes: list[list[float]] = []
    for a, b in sorted(marks):
        if episodes and a - episodes[-1][1] < EPISODE_GAP:
            episodes[-1][1] = max(episodes[-1][1], b)
        else:
            episodes.append([a, b])
    a, b = min(episodes, key=lambda ab: max(ab[0] - focus, focus - ab[1], 0.0))
    return a, b


def _stop_time(result) -> float | None:
    """When the computation ended early (overturning, flight, Painleve), else None."""
    summary = result.summary
    return summary.end_time if (summary.overturned or summary.status != "ok") else None


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


def _text(name) -> str:
    return name.decode() if isinstance(name, bytes) else str(name)


def _code(name) -> int:
    return STATE_NAMES.index(_text(name))


# --------------------------------------------------------------------------------------------------
# The figure
# --------------------------------------------------------------------------------------------------


def response_figure(result, *, title: str = "", time_shift: float = 0.0,
                    zoom: tuple | None | str = "auto", crop: tuple | None | str = "auto") -> Figure:
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
        window is almost the whole shown range); ``(t0, t1)`` in the figure's time (time_shift
        included) [s]; None = no magnified panel.
    crop : "auto", (t0, t1) or None
        The time range of the response and ground panels: ``"auto"`` = `motion_range`;
        ``(t0, t1)`` in the figure's time [s]; None = the whole record.

    Returns
    -------
    matplotlib.figure.Figure
        11 x 8 in; save it with `save_figure`. Its axes are labelled (``Axes.get_label``)
        ``"record"`` and ``"record-slip"`` (the response: rotation, and the slip twin), ``"zoom"``
        and ``"zoom-slip"`` (if magnified) and ``"ground"``. It is laid out once, when made
        (`_fit_column`, no layout engine): resized, or given other texts, it is not laid out again.
    """
    if hasattr(result, "result") and hasattr(result, "case_text"):   # a StoredResult
        title = title or result.name
        result = result.result
    shift = float(time_shift)
    t0, t1 = _choose_range(result, crop, shift)
    window = _choose_zoom(result, zoom, shift, (t0, t1))

    fig = Figure(figsize=FIGSIZE, dpi=DPI)
    FigureCanvasAgg(fig)        # measured and drawn by one renderer (`_fit_column`)
    ratios = [3.0, 3.0, 2.0] if window else [3.0, 2.0]
    axes = fig.subplots(len(ratios), 1, gridspec_kw={"height_ratios": ratios})
    top, ground = axes[0], axes[-1]
    ground.sharex(top)

    title_y = _response_panel(top, result, shift, (t0, t1), window=window, label="record")
    record = _record_range(result)
    if (t0, t1) == record:
        top.set_title("whole record", loc="left", fontsize=10, y=title_y)
    else:
        top.set_title(f"{t0 + shift:.2f} to {t1 + shift:.2f} s of the {record[0] + shift:.4g} to "
                      f"{record[1] + shift:.4g} s record", loc="left", fontsize=10, y=title_y)
    if window:
        zax = axes[1]
        title_y = _response_panel(zax, result, shift, (window[0] - shift, window[1] - shift), label="zoom")
        # round first: a pulse's ground starts a sample before 0 (-0.00 otherwise)
        zax.set_title(f"magnified: {round(window[0], 2) + 0.0:.2f} to {window[1]:.2f} s", loc="left",
                      fontsize=10, y=title_y)
    _ground_panel(ground, result, shift, (t0, t1))
    ground.set_label("ground")
    ground.set_xlim(t0 + shift, t1 + shift)
    for ax in axes:
        ax.set_xlabel("time [s]")

    suptitle = fig.suptitle(_title(result, title), fontsize=12)
    legend = fig.legend(handles=_legend_handles(result), loc="lower center", ncols=6, frameon=False,
                        fontsize=9)
    _fit_column(fig, suptitle=suptitle, legend=legend, title_size=10)
    return fig


def paper_figure(panels, *, title: str = "", time_shift: float = 0.0) -> Figure:
    """Several responses in the layout of the paper's Figures 6 to 10: one row per sub-figure
    ((a), (b), (c)), the response where the motion is (`motion_range`) on the left and the
    magnified window on the right.

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
        t0, t1 = motion_range(result)
        window = _choose_zoom(result, "auto", time_shift, (t0, t1))
        title_y = _response_panel(whole, result, time_shift, (t0, t1), window=window, label=f"record{row}")
        whole.set_title(f"{label} {caption}", loc="left", fontsize=10, y=title_y)
        if window is None:
            window = (t0 + time_shift, t1 + time_shift)
        title_y = _response_panel(zoomed, result, time_shift, (window[0] - time_shift, window[1] - time_shift),
                                  label=f"zoom{row}", notes=False)
        zoomed.set_title(f"magnified: {window[0]:.2f} to {window[1]:.2f} s", loc="left", fontsize=10, y=title_y)
        for ax in (whole, zoomed):
            ax.set_xlabel("time [s]")
    if title:
        fig.suptitle(title, fontsize=12)
    handles = [h for _, r, _ in panels for h in _legend_handles(r, ground=False)]
    unique = {h.get_label(): h for h in handles}
    fig.legend(handles=list(unique.values()), loc="outside lower center", ncols=7, frameon=False,
               fontsize=9)
    return fig


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


def _choose_range(result, crop, shift) -> tuple[float, float]:
    """The time range of the response and ground panels [s], not shifted."""
    if crop is None:
        return _record_range(result)
    if isinstance(crop, str):
        if crop != "auto":
            raise ValueError(f"crop must be 'auto', a (start, end) pair or None, got {crop!r}")
        return motion_range(result)
    a, b = _time_pair(crop, "crop range")
    return a - shift, b - shift


def _choose_zoom(result, zoom, shift, shown):
    """The magnified window [s] in the figure's time (shifted), or None."""
    if zoom is None:
        return None
    if isinstance(zoom, str):
        if zoom != "auto":
            raise ValueError(f"zoom must be 'auto', a (start, end) pair or None, got {zoom!r}")
        window = zoom_window(result)
        if window is None:
            return None
        if window[1] - window[0] >= ZOOM_USELESS_FRACTION * (shown[1] - shown[0]):
            return None
        return window[0] + shift, window[1] + shift
    return _time_pair(zoom, "zoom window")


def _time_pair(pair, what: str) -> tuple[float, float]:
    a, b = (float(v) for v in pair)
    if not (math.isfinite(a) and math.isfinite(b) and b > a):
        raise ValueError(f"{what} must be (start, end) with start < end, got {pair!r}")
    return a, b


def _title(result, name: str) -> str:
    s = result.summary
    head = f"{name}: {s.verdict}" if name else s.verdict
    facts = [f"max |φ| = {s.max_rotation:.4g} rad", f"max |x| = {1e3 * s.max_slip:.4g} mm",
             f"residual x = {1e3 * s.residual_slip:.4g} mm", f"impacts: {s.impacts}"]
    if math.isfinite(s.alpha) and not s.overturned:
        facts.insert(1, f"{percent_text(s.max_rotation_ratio)} of α = {s.alpha:.4g} rad")
    if s.overturned and s.overturn_time is not None:
        facts.insert(0, f"overturned at t = {s.overturn_time:.3f} s")
    return head + "\n" + ",  ".join(facts)


def _response_panel(ax, result, shift, span, *, label, window=None, notes=True):
    """Rotation (left axis, with +-alpha) and slip in mm (right axis) over the shaded states, for
    ``span``. What the panel has to say goes in its title line, on the right, never over the data
    (unless not ``notes``: a narrow panel beside one that says it).

    The axes are labelled ``label`` (rotation) and ``label + "-slip"`` (the twin, slip). Returns
    the height for the panel's titles (`_title_height`).
    """
    a, b = span
    _shade_states(ax, result, shift, span)
    history = result.history or {}
    t = np.asarray(history.get("time", np.zeros(0)))
    shown = _within(t, span)
    t = t[shown]
    phi = np.asarray(history.get("rotation", np.zeros(0)))[shown]
    x_mm = 1e3 * np.asarray(history.get("slip", np.zeros(0)))[shown]

    slip_ax = ax.twinx()
    ax.set_label(label)
    slip_ax.set_label(f"{label}-slip")
    said = []
    if t.size:
        ax.plot(*_envelope(t + shift, phi), color=ROTATION_COLOUR, lw=1.0, zorder=3)
        slip_ax.plot(*_envelope(t + shift, x_mm), color=SLIP_COLOUR, lw=1.0, zorder=3)
    else:
        said.append("no time history stored")
    ax.axhline(0.0, color="0.6", lw=0.5, zorder=1)
    alpha = result.summary.alpha
    sides = []
    if math.isfinite(alpha) and phi.size:
        reach = {1.0: float(phi.max(initial=0.0)), -1.0: -float(phi.min(initial=0.0))}
        sides = [side for side, r in reach.items() if r >= ALPHA_SHOWN_FRACTION * alpha]
    rot_lim, slip_lim = _aligned_limits(np.append(phi, [side * alpha for side in sides]), x_mm)
    for side in sides:
        ax.axhline(side * alpha, color=ALPHA_COLOUR, ls="--", lw=0.9, zorder=2)
    if math.isfinite(alpha) and phi.size and not sides:
        said.append(f"±α = ±{alpha:.4g} rad off scale")
    ax.set_ylim(*rot_lim)
    slip_ax.set_ylim(*slip_lim)
    ax.set_xlim(a + shift, b + shift)
    ax.set_ylabel("liftoff angle φ [rad]", color=ROTATION_COLOUR)
    slip_ax.set_ylabel("slip x [mm]", color=SLIP_COLOUR)
    ax.tick_params(axis="y", colors=ROTATION_COLOUR)
    slip_ax.tick_params(axis="y", colors=SLIP_COLOUR)
    ax.grid(True, axis="x", color="0.88", lw=0.6)

    if result.summary.states_seen == ["REST"] and result.summary.status == "ok":
        said.append("the block stays at rest")
    end = _mark_end(ax, result, shift, span, hatch=True)
    colour = "0.3"
    if end is not None:
        said.insert(0, end[0])
        colour = end[1]
    title_y = _title_height(ax, slip_ax)
    if said and notes:
        ax.set_title("; ".join(said), loc="right", fontsize=9, color=colour, y=title_y)
    if window is not None:
        slip_ax.axvspan(window[0], window[1], fill=False, ls=":", lw=1.0, ec="0.35", zorder=4)
    return title_y


def _fit_column(fig: Figure, *, suptitle, legend, title_size: float) -> None:
    """Place the panels of ``fig``, one column of them (each with its twins), between
    ``suptitle`` at the top and ``legend`` at the bottom, with their titles (one line of
    ``title_size`` [pt]) and their axes' decorations inside the figure.

    This does what constrained layout did for the response figure, once, from the sizes of a few
    strings: constrained layout draws the figure twice for each `Figure.savefig`, and measures
    every artist on the way. Above each panel go its title line and, where an axis of the panel
    may show one (`_may_show_offset`), an offset text such as ``1e-5``; below it, its x tick
    labels and label. The panels share the height left; their heights set the y ticks, whose
    labels (and the y labels) then set the side margins. The margins are fractions of the figure,
    which hold at any dpi (text keeps its size in points).
    """
    renderer = fig.canvas.get_renderer()
    points = fig.dpi / 72.0                       # [px/pt]
    width, height = fig.bbox.width, fig.bbox.height
    pad, gap = EDGE_PAD * points, BLOCK_GAP * points

    def line(size) -> tuple[float, float]:
        """Height and descent of a line of text [px] (a Text is at least as high as "lp")."""
        return renderer.get_text_width_height_descent("lp", FontProperties(size=size), ismath=False)[1:]

    def tick_labels_from_axes(name) -> float:
        """From the axes to its tick labels [px]: the ticks' length where they point out, and the pad."""
        out = {"in": 0.0, "inout": 0.5, "out": 1.0}[rcParams[f"{name}tick.direction"]]
        return (rcParams[f"{name}tick.major.pad"] + out * rcParams[f"{name}tick.major.size"]) * points

    rows: dict[int, list] = {}
    for ax in fig.axes:
        rows.setdefault(ax.get_subplotspec().rowspan.start, []).append(ax)
    rows = [rows[k] for k in sorted(rows)]
    title_h, title_d = line(title_size)
    title = rcParams["axes.titlepad"] * points + title_h - title_d          # up to the title's top
    offset = rows[0][0].yaxis.OFFSETTEXTPAD * points + line(rcParams["ytick.labelsize"])[0]
    above = [title + (offset if any(_may_show_offset(ax) for ax in row) else 0.0) for row in rows]
    tick_labels = tick_labels_from_axes("x") + line(rcParams["xtick.labelsize"])[0]
    below = [tick_labels + max((ax.xaxis.labelpad * points + ax.xaxis.label.get_window_extent(renderer).height
                                for ax in row if ax.xaxis.get_visible() and ax.get_xlabel()), default=0.0)
             for row in rows]

    suptitle.set_y(1.0 - pad / height)
    top = pad + suptitle.get_window_extent(renderer).height + gap + above[0]
    bottom = legend.get_window_extent(renderer).y1 + gap + below[-1]
    between = max((b + gap + a for b, a in zip(below[:-1], above[1:], strict=True)), default=0.0)
    panel = (height - top - bottom - (len(rows) - 1) * between) / len(rows)
    fig.subplots_adjust(top=1.0 - top / height, bottom=bottom / height, hspace=between / panel)

    labels = {"left": set(), "right": set()}       # the y tick labels on each side
    sides = {"left": 0.0, "right": 0.0}            # from the axes to the y label's far side [px]
    for ax in fig.axes:
        axis = ax.yaxis
        side = axis.get_label_position()
        lo, hi = sorted(axis.get_view_interval())
        slack = 1e-10 * (hi - lo)
        locs = [v for v in axis.get_majorticklocs() if lo - slack <= v <= hi + slack]
        labels[side].update(axis.get_major_formatter().format_ticks(locs) if locs else ())
        if axis.get_label_text():
            sides[side] = max(sides[side], axis.labelpad * points + axis.label.get_window_extent(renderer).width)
    font = FontProperties(size=rcParams["ytick.labelsize"])
    margins = {side: pad + sides[side] + tick_labels_from_axes("y")
               + max((renderer.get_text_width_height_descent(text, font, ismath=False)[0] for text in texts),
                     default=0.0)
               for side, texts in labels.items()}
    fig.subplots_adjust(left=margins["left"] / width, right=1.0 - margins["right"] / width)


def _title_height(*axes) -> float | None:
    """1.0, the top of the axes (where matplotlib puts titles unless something is in the way), when
    no y axis of ``axes`` (a panel and its twin) can show an offset text such as ``1e-5`` over it;
    else None: matplotlib places the titles itself.

    matplotlib looks for what a title might overlap at every draw, measuring every tick label of
    the axes and its twins: a fifth of a figure's drawing time. On these panels only an offset
    text can be in the way (no tick labels at the top). A y range ``[lo, hi]`` that holds 0 has a
    tick at 0 (no additive offset), and at least two ticks: its largest tick is between
    ``(hi - lo) / 4`` and ``hi - lo``. Its power of ten is shown beside the axis when the largest
    tick is below ``10**(m + 1)`` or at least ``10**M`` (``axes.formatter.limits`` = (m, M)), which
    cannot happen when ``10**(m + 2) <= hi - lo < 10**M`` (1e-3 to 1e6 by default).
    """
    if rcParams["axes.titley"] is not None:          # the user's style places titles
        return None
    return None if any(_may_show_offset(ax) for ax in axes) else 1.0


def _may_show_offset(ax) -> bool:
    """Whether the y axis of ``ax`` may show an offset text (`_title_height`): False where it
    cannot."""
    low, high = rcParams["axes.formatter.limits"]
    lo, hi = ax.get_ylim()
    return not (lo <= 0.0 <= hi and 10.0 ** (low + 2) <= hi - lo < 10.0 ** high)


def _within(times: np.ndarray, span) -> slice:
    """The samples of sorted ``times`` within ``span``, and one more on each side (so that a line
    reaches the panel's edges)."""
    i0 = max(int(np.searchsorted(times, span[0], side="left")) - 1, 0)
    i1 = min(int(np.searchsorted(times, span[1], side="right")) + 1, times.size)
    return slice(i0, i1)


def _shade_states(ax, result, shift, span):
    a, b = span
    trans = ax.get_xaxis_transform()
    for state, colour in STATE_COLOURS.items():
        boxes = [[(s + shift, 0.0), (s + shift, 1.0), (e + shift, 1.0), (e + shift, 0.0)]
                 for s, e, code in state_segments(result) if code == state and e > a and s < b]
        if boxes:
            ax.add_collection(PolyCollection(boxes, transform=trans, facecolors=colour,
                                             edgecolors="none", zorder=0), autolim=False)


def _mark_end(ax, result, shift, span, *, hatch):
    """A vertical line where the block overturned or the computation stopped (hatched after it if
    ``hatch``: nothing is computed there). Returns ``(text, colour)`` for the panel's title if the
    line is in ``span``, else None."""
    s = result.summary
    if s.overturned and s.overturn_time is not None:
        t, colour, ls = s.overturn_time, OVERTURN_COLOUR, "-"
        text = f"OVERTURNED at t = {s.overturn_time + shift:.3f} s"
    elif s.status != "ok":
        t, colour, ls = s.end_time, STOP_COLOUR, "--"
        what = {"painleve": "PAINLEVE case", "flight": "FLIGHT"}.get(s.status, s.status.upper())
        text = f"{what}: outside the model, computation stopped at t = {s.end_time + shift:.3f} s"
    else:
        return None
    a, b = span
    if not (a <= t <= b):
        return None
    ax.axvline(t + shift, color=colour, ls=ls, lw=1.4, zorder=5)
    if hatch:
        ax.axvspan(t + shift, b + shift, facecolor="none", edgecolor="0.85", hatch="//", lw=0.0,
                   zorder=0)
    return text, colour


def _ground_panel(ax, result, shift, span):
    t = np.asarray(result.ground_time)
    shown = _within(t, span)
    for key, values in (("horizontal", result.ground_horizontal), ("vertical", result.ground_vertical)):
        ax.plot(*_envelope(t[shown] + shift, np.asarray(values)[shown] / GAL), color=GROUND_COLOURS[key],
                lw=0.8, label=key, alpha=0.9 if key == "horizontal" else 0.8)
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_ylabel("ground acc. [gal]")
    ax.grid(True, axis="x", color="0.88", lw=0.6)
    _mark_end(ax, result, shift, span, hatch=False)
    peak = max(float(np.max(np.abs(result.ground_horizontal), initial=0.0)),
               float(np.max(np.abs(result.ground_vertical), initial=0.0))) / GAL
    if peak == 0.0:
        ax.set_ylim(-1.0, 1.0)
    title_y = _title_height(ax)
    ax.set_title("ground acceleration as applied", loc="left", fontsize=10, y=title_y)
    if peak == 0.0:
        ax.set_title("still ground (no record)", loc="right", fontsize=9, color="0.3", y=title_y)


def _legend_handles(result, *, ground: bool = True) -> list:
    handles = [Line2D([], [], color=ROTATION_COLOUR, lw=1.5, label="liftoff angle φ"),
               Line2D([], [], color=SLIP_COLOUR, lw=1.5, label="slip x")]
    if math.isfinite(result.summary.alpha):
        handles.append(Line2D([], [], color=ALPHA_COLOUR, ls="--", lw=0.9, label="±α (tips over past it)"))
    if ground:
        handles += [Line2D([], [], color=GROUND_COLOURS[key], lw=1.0, label=f"ground {key}")
                    for key in ("horizontal", "vertical")]
    handles += [Patch(facecolor="white", edgecolor="0.6", lw=0.5, label="REST"),
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
# Fragility curves
# --------------------------------------------------------------------------------------------------

FRAGILITY_COLOURS = ("#3a3a3a", "#1f4e9c", "#c0392b", "#2e8b57", "#8e44ad", "#d35400", "#16a085")


def fragility_figure(levels, grid, curves, *, xlabel: str, confidence: float, title: str = "") -> Figure:
    """Fragility curves: the observed fraction of each stripe, the fitted curve and its band.

    Parameters
    ----------
    levels : array_like
        The stripes' intensity levels, in the unit shown.
    grid : array_like
        Intensities the curves are drawn at, in the unit shown.
    curves : list of dict
        One per damage state: ``label`` (legend text), ``fraction`` (observed fraction per level,
        NaN where no run counts), and optionally ``fitted`` (the maximum-likelihood curve on
        ``grid``), ``band`` (``[2, grid]``: lower and upper bound of the confidence band),
        ``moments`` (the method-of-moments curve on ``grid``).
    xlabel : str
        The intensity measure and its unit.
    confidence : float
        Level of the band, for the legend.
    title : str
    """
    fig = Figure(figsize=(9.0, 6.0), dpi=DPI, layout="constrained")
    ax = fig.subplots()
    levels, grid = np.asarray(levels, dtype=float), np.asarray(grid, dtype=float)
    for i, curve in enumerate(curves):
        colour = FRAGILITY_COLOURS[i % len(FRAGILITY_COLOURS)]
        if curve.get("band") is not None:
            ax.fill_between(grid, curve["band"][0], curve["band"][1], color=colour, alpha=0.15, lw=0)
        if curve.get("fitted") is not None:
            ax.plot(grid, curve["fitted"], color=colour, lw=2.0)
        if curve.get("moments") is not None:
            ax.plot(grid, curve["moments"], color=colour, lw=1.0, ls="--")
        ax.plot(levels, curve["fraction"], "o", color=colour, ms=6, mfc="white" if curve.get("fitted") is None
                else colour, label=curve["label"])
    handles, labels = ax.get_legend_handles_labels()
    for key, handle, label in (
            ("fitted", Line2D([], [], color="0.3", lw=2.0), "maximum-likelihood lognormal fit"),
            ("moments", Line2D([], [], color="0.3", lw=1.0, ls="--"), "method of moments (first exceedances)"),
            ("band", Patch(facecolor="0.3", alpha=0.15), f"{100 * confidence:g} % bootstrap band over records")):
        if any(curve.get(key) is not None for curve in curves):
            handles.append(handle)
            labels.append(label)
    ax.legend(handles, labels, loc="upper left", fontsize=8, frameon=False)
    ax.set_xlim(0.0, float(grid[-1]))
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("probability of reaching the damage state")
    ax.grid(True, color="0.9")
    if title:
        ax.set_title(title, fontsize=11)
    return fig


# --------------------------------------------------------------------------------------------------
# Overturning spectra
# --------------------------------------------------------------------------------------------------

#: The regions of an overturning spectrum, codes 0 to 5 (`spectrum_category`).
SPECTRUM_CATEGORIES = ("no liftoff", "sliding", "rocking", "overturning with impact",
                       "overturning without impact", "outside the model")
SPECTRUM_COLOURS = ("#ffffff", "#f5c07a", "#9fd39a", "#8c6bb1", "#3a3a3a", "#d9534f")
THEORY_COLOURS = ("#1f4e9c", "#e6550d", "#000000")


def spectrum_category(overturned, status, modes, impacts) -> np.ndarray:
    """The region of each point of an overturning spectrum (codes index `SPECTRUM_CATEGORIES`).

    Precedence: outside the model (``status != 0``); overturned, without or with an impact before
    (``impacts``: the run stops at overturning); rocking if the block lifted off (``modes`` bits 2
    or 4, slipping or not); sliding if it slipped upright only (bit 1); else no liftoff.
    """
    modes = np.asarray(modes).astype(np.int64)
    out = np.zeros(modes.shape, dtype=np.int8)
    out[(modes & 1) != 0] = 1
    out[(modes & 6) != 0] = 2
    over = np.asarray(overturned).astype(bool)
    after_impact = np.asarray(impacts) > 0
    out[over & after_impact] = 3
    out[over & ~after_impact] = 4
    out[np.asarray(status) != 0] = 5
    return out


def spectrum_figure(frequency, amplitude, category, rotation, curves=(), *, xlabel: str = "ω_p / p",
                    ylabel: str = "a_p / (g tan α)", title: str = "") -> Figure:
    """An overturning spectrum: the regions of `spectrum_category` in the plane of pulse frequency
    over ``p`` (across) and amplitude over ``g tan(alpha)`` (up), and the largest rotation of the
    standing blocks over ``alpha``, with theoretical curves drawn over both.

    Parameters
    ----------
    frequency : float array (nx,)
        ``w_p / p`` of each column (any order).
    amplitude : float array (ny,)
        ``a_p / (g tan(alpha))`` of each row (any order).
    category : int array (ny, nx)
        `spectrum_category` codes.
    rotation : float array (ny, nx)
        Largest rotation over ``alpha`` [-].
    curves : sequence of (label, x, y)
        Theory: ``x`` None draws the horizontal line ``y``; else the curve through ``(x, y)`` (NaN
        where the theory has no value).
    xlabel, ylabel, title : str

    Returns
    -------
    matplotlib.figure.Figure
        Axes labelled ``"regions"`` and ``"rotation"``.
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm

    x = np.asarray(frequency, dtype=float)
    y = np.asarray(amplitude, dtype=float)
    category = np.asarray(category)
    rotation = np.asarray(rotation, dtype=float)
    if category.shape != (y.size, x.size) or rotation.shape != category.shape:
        raise ValueError(f"expected maps of shape ({y.size}, {x.size}), got {category.shape} and "
                         f"{rotation.shape}")
    xo, yo = np.argsort(x), np.argsort(y)
    x_edges, y_edges = _cell_edges(x[xo]), _cell_edges(y[yo])
    category = category[np.ix_(yo, xo)]
    rotation = rotation[np.ix_(yo, xo)]
    standing = category < 3
    cmap = ListedColormap(SPECTRUM_COLOURS)
    norm = BoundaryNorm(np.arange(len(SPECTRUM_CATEGORIES) + 1) - 0.5, cmap.N)
    shown = np.ma.masked_where(~(standing & (rotation > 0)), rotation)
    low = float(shown.min()) if shown.count() else 1e-3
    rot_norm = LogNorm(vmin=max(1e-4, min(low, 0.5)), vmax=1.0)

    fig = Figure(figsize=(14.0, 6.2), dpi=DPI, layout="constrained")
    regions, rotated = fig.subplots(1, 2)
    regions.pcolormesh(x_edges, y_edges, category, cmap=cmap, norm=norm, shading="flat")
    regions.set_label("regions")
    mesh = rotated.pcolormesh(x_edges, y_edges, shown, cmap=_with_bad("viridis"), norm=rot_norm,
                              shading="flat")
    rotated.set_label("rotation")
    fig.colorbar(mesh, ax=rotated, label="largest rotation / α (standing blocks)")
    _outline(rotated, x_edges, y_edges, ~standing)
    handles = [Patch(facecolor=c, edgecolor="0.4", label=n)
               for n, c in zip(SPECTRUM_CATEGORIES, SPECTRUM_COLOURS, strict=True)]
    for (label, cx, cy), colour in zip(curves, THEORY_COLOURS, strict=False):
        for ax in (regions, rotated):
            if cx is None:
                ax.axhline(cy, color=colour, lw=1.6, ls="--")
            else:
                ax.plot(cx, cy, color=colour, lw=2.0)
        handles.append(Line2D([], [], color=colour, lw=2.0, ls="--" if cx is None else "-", label=label))
    for ax, name in ((regions, "regions"), (rotated, "largest rotation of the standing blocks")):
        ax.set_xlim(x_edges[0], x_edges[-1])
        ax.set_ylim(y_edges[0], y_edges[-1])
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(name, loc="left", fontsize=10)
    fig.legend(handles=handles, loc="outside lower center", ncols=4, frameon=False, fontsize=9)
    if title:
        fig.suptitle(title, fontsize=12)
    return fig


# --------------------------------------------------------------------------------------------------
# Saving
# --------------------------------------------------------------------------------------------------


def save_figure(fig: Figure, path, *, overwrite: bool = False, dpi: float | None = None, staging=None) -> Path:
    """Save ``fig`` to ``path`` atomically (a temporary file in the same folder, then a rename).

    The format follows the file name (``.png``, ``.pdf``, ``.svg``...). An existing file is kept
    unless ``overwrite``; the folder is created if missing. ``dpi`` sets the resolution of raster
    formats (default `DPI`). With ``staging`` (`files.Staging`) the file is published with the rest
    of a result's files instead of at once.

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
    dpi = DPI if dpi is None else dpi
    with atomic_write(path, overwrite=overwrite, what="figure", staging=staging) as handle:
        if fmt == "png":
            canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
            fig.savefig(os.devnull, format="rgba", dpi=dpi)      # drawn on canvas, as savefig draws a PNG
            _write_png(handle, np.asarray(canvas.buffer_rgba()), dpi=dpi)
        else:
            fig.savefig(handle, format=fmt, dpi=dpi)
    return path


def _write_png(handle, rgba: np.ndarray, *, dpi: float) -> None:
    """Write the image ``rgba`` (``[height, width, 4]`` bytes, rows from the top) to the binary
    file ``handle`` as a PNG: RGB where it is opaque, else RGBA, 8 bits, its rows unfiltered and
    deflated at `PNG_COMPRESSION`, with its resolution (``dpi``).

    matplotlib writes PNGs with Pillow, which tries the five PNG filters on every row to keep
    the likeliest to compress well: on figures (flat colours, thin lines) that is two thirds of
    its time and gains nothing. zlib alone, on the rows as they are, writes a run's figure in half
    the time, 6 % smaller (30 ms and 244 KB against 58 ms and 259 KB).
    """
    height, width, _ = rgba.shape
    channels = 3 if rgba[..., 3].min() == 255 else 4

    def chunk(kind: bytes, data: bytes) -> None:
        handle.write(struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data)))

    handle.write(b"\x89PNG\r\n\x1a\n")
    chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2 if channels == 3 else 6, 0, 0, 0))
    per_metre = round(dpi / 0.0254)
    chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1))
    deflate = zlib.compressobj(PNG_COMPRESSION)
    block = 256                                          # rows at a time: a bounded copy at any dpi
    rows = np.zeros((block, 1 + width * channels), np.uint8)    # each row: filter type 0, pixels
    pixels = np.reshape(rows[:, 1:], (block, width, channels), copy=False)
    parts = []
    for start in range(0, height, block):
        n = min(block, height - start)
        pixels[:n] = rgba[start:start + n, :, :channels]
        parts.append(deflate.compress(rows[:n]))
    parts.append(deflate.flush())
    chunk(b"IDAT", b"".join(parts))
    chunk(b"IEND", b"")


__all__ = ["response_figure", "save_figure", "zoom_window", "state_segments", "sweep_figure",
           "sweep_category", "SWEEP_CATEGORIES", "fragility_figure", "spectrum_figure", "spectrum_category",
           "SPECTRUM_CATEGORIES"]
