"""Figures: every kind of response renders and saves; the panels show where the motion is and the
zoom finds whole swings; +-alpha is drawn; labels never cover data; no pyplot."""

from __future__ import annotations

import ast
import os
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox
from PIL import Image

from rockslide import plots
from rockslide.core.simulate import EVENT_DTYPE, Model, Result, Settings, Summary, simulate
from rockslide.errors import OutputError
from rockslide.io.results import read_result, write_result
from rockslide.plots import response_figure, save_figure, state_segments, zoom_window

REPO = Path(__file__).resolve().parents[1]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def pulse(amplitude, mu, *, vertical=0.3, frequency=1.5, vertical_abs=False, **settings):
    t = np.arange(0, 10, 0.01)
    ah = amplitude * np.sin(2 * np.pi * frequency * t) * np.exp(-((t - 4) / 2) ** 2)
    av = vertical * (np.abs(ah) if vertical_abs else ah)
    return simulate(Model.from_block(0.1, 0.2, mu, 0.95 * mu, 0.8), 0.01, ah, av,
                    Settings(tail=2.0, **settings))


# Each kind of response the figure must show, and how to recognise it.
KINDS = {
    "rest": (lambda: pulse(0.5, 0.52), lambda s: s.states_seen == ["REST"]),
    "slip": (lambda: pulse(3.0, 0.2), lambda s: "SLIP" in s.states_seen and "ROCK" not in s.states_seen),
    "rock": (lambda: pulse(5.7, 0.8, vertical=0.0, frequency=2.5),
             lambda s: "ROCK" in s.states_seen and not s.overturned and s.max_rotation > 0.1),
    "rockslip": (lambda: pulse(6.0, 0.52), lambda s: "ROCKSLIP" in s.states_seen and not s.overturned),
    "overturn": (lambda: pulse(5.5, 0.8, vertical=0.0), lambda s: s.overturned),
    "flight": (lambda: pulse(6.0, 0.8, vertical=-2.2, vertical_abs=True), lambda s: s.status == "flight"),
    "painleve": (lambda: pulse(3.0, 2.0, vertical=0.0, slip_rate=0.5),
                 lambda s: s.status == "painleve"),
}


@pytest.fixture(scope="module")
def responses():
    out = {}
    for kind, (make, is_kind) in KINDS.items():
        result = make()
        assert is_kind(result.summary), f"the {kind!r} case no longer gives that response: {result.summary}"
        out[kind] = result
    return out


def png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def axis(fig: Figure, label: str):
    """The axes of ``fig`` labelled ``label`` (record, record-slip, zoom, zoom-slip, ground)."""
    found = [ax for ax in fig.axes if ax.get_label() == label]
    assert len(found) == 1, (label, [ax.get_label() for ax in fig.axes])
    return found[0]


def texts(fig: Figure) -> str:
    parts = [fig._suptitle.get_text()] if fig._suptitle else []
    for ax in fig.axes:
        parts += [t.get_text() for t in ax.texts] + [ax.get_title(loc="left"), ax.get_title(loc="right")]
    return "\n".join(parts)


# --------------------------------------------------------------------------------------------------
# Every kind renders
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", list(KINDS))
def test_each_kind_renders_and_saves_a_png(tmp_path, responses, kind):
    result = responses[kind]
    fig = response_figure(result, title=f"case-{kind}")
    assert isinstance(fig, Figure)
    assert fig.get_size_inches().tolist() == [11.0, 8.0]
    path = save_figure(fig, tmp_path / "figs" / f"{kind}.png")
    data = path.read_bytes()
    assert png_size(data) == (1650, 1200)          # 11 x 8 in at 150 dpi
    assert len(data) > 20_000
    assert sorted(os.listdir(tmp_path / "figs")) == [f"{kind}.png"]
    title = fig._suptitle.get_text()
    assert f"case-{kind}" in title and result.summary.verdict in title


def test_rest_has_flat_lines_no_shading_and_no_zoom(responses):
    result = responses["rest"]
    assert zoom_window(result) is None
    fig = response_figure(result, title="rest")
    assert len(fig.axes) == 3                       # response + its slip twin + ground
    top, slip_ax = axis(fig, "record"), axis(fig, "record-slip")
    assert not any(isinstance(c, PolyCollection) for c in top.collections)
    assert np.all(top.lines[0].get_ydata() == 0.0) and np.all(slip_ax.lines[0].get_ydata() == 0.0)
    assert "stays at rest" in texts(fig)


def test_states_are_shaded(responses):
    result = responses["rockslip"]
    fig = response_figure(result, zoom=None)
    shaded = [c for c in axis(fig, "record").collections if isinstance(c, PolyCollection)]
    colours = {tuple(np.round(c.get_facecolor()[0], 3)) for c in shaded}
    assert len(shaded) == 3 and len(colours) == 3   # SLIP, ROCK, ROCKSLIP, one colour each
    seg_states = {s for _, _, s in state_segments(result)}
    assert seg_states == {0, 1, 2, 3}


@pytest.mark.parametrize("kind, label", [("overturn", "OVERTURNED"), ("flight", "FLIGHT"),
                                         ("painleve", "PAINLEVE")])
def test_the_end_is_marked(responses, kind, label):
    result = responses[kind]
    fig = response_figure(result, title=kind, time_shift=30.0)
    end = (result.summary.overturn_time if kind == "overturn" else result.summary.end_time) + 30.0
    assert label in texts(fig)
    assert f"t = {end:.3f} s" in texts(fig)
    verticals = [line for ax in fig.axes for line in ax.lines
                 if len(line.get_xdata()) == 2 and np.all(np.asarray(line.get_xdata()) == end)]
    assert len(verticals) >= 3                      # response, zoom and ground panels
    if kind != "overturn":
        assert result.summary.status in fig._suptitle.get_text()


def test_history_ends_early_but_ground_continues(responses):
    result = responses["overturn"]
    fig = response_figure(result, zoom=None, crop=None)
    top, ground = axis(fig, "record"), axis(fig, "ground")
    assert top.lines[0].get_xdata()[-1] == pytest.approx(result.summary.overturn_time, abs=1e-3)
    assert ground.lines[0].get_xdata()[-1] == result.ground_time[-1]
    assert ground.get_xlim() == top.get_xlim() == (0.0, result.ground_time[-1])


# --------------------------------------------------------------------------------------------------
# Options
# --------------------------------------------------------------------------------------------------


def test_time_shift_moves_every_time(responses):
    result = responses["rockslip"]
    plain = response_figure(result)
    shifted = response_figure(result, time_shift=30.0)
    assert len(plain.axes) == len(shifted.axes) == 5
    for a, b in zip(plain.axes, shifted.axes, strict=True):
        assert np.allclose(np.asarray(b.get_xlim()) - 30.0, a.get_xlim())
        for la, lb in zip(a.lines, b.lines, strict=True):
            if len(la.get_xdata()) > 2:             # data lines (not axhline/axvline)
                assert np.allclose(np.asarray(lb.get_xdata()) - 30.0, np.asarray(la.get_xdata()))
        if not a.get_label().endswith("-slip"):
            assert a.get_xlabel() == b.get_xlabel() == "time [s]"
    window = zoom_window(result)
    assert axis(shifted, "zoom").get_xlim() == pytest.approx((window[0] + 30.0, window[1] + 30.0))


def test_zoom_options(responses):
    result = responses["rock"]
    assert len(response_figure(result, zoom=None).axes) == 3
    fig = response_figure(result, zoom=(4.0, 5.0))
    assert axis(fig, "zoom").get_xlim() == (4.0, 5.0)
    fig = response_figure(result, time_shift=10.0, zoom=(14.0, 15.0))   # in the figure's time
    assert axis(fig, "zoom").get_xlim() == (14.0, 15.0)
    with pytest.raises(ValueError, match="zoom"):
        response_figure(result, zoom="everything")
    with pytest.raises(ValueError, match="start < end"):
        response_figure(result, zoom=(5.0, 4.0))


def test_stored_result_plots_like_a_fresh_one(tmp_path, responses):
    result = responses["rockslip"]
    stored = read_result(write_result(tmp_path / "r.h5", result, name="kobe"))
    fresh_fig = response_figure(result, title="kobe")
    stored_fig = response_figure(stored)                # the name is the default title
    # the same title; the file adds its caption (what was computed: its step, the version...)
    assert stored_fig._suptitle.get_text().startswith(fresh_fig._suptitle.get_text() + "\n")
    assert "dt = " in stored_fig._suptitle.get_text().split("impacts")[-1]
    for a, b in zip(fresh_fig.axes, stored_fig.axes, strict=True):
        assert a.get_xlim() == b.get_xlim() and a.get_ylim() == b.get_ylim()
        for la, lb in zip(a.lines, b.lines, strict=True):
            assert np.array_equal(la.get_xydata(), lb.get_xydata())


def test_long_histories_are_reduced_to_an_envelope():
    t = np.linspace(0.0, 100.0, 1_000_001)
    y = np.sin(t) + (t == 50.0)                         # one spike must survive
    tt, yy = plots._envelope(t, y, max_points=2000)
    assert tt.size <= 2000 and yy.max() == y.max() and yy.min() == y.min()
    assert np.all(np.diff(tt) >= 0)


def test_a_long_history_is_drawn_decimated_and_kept_whole(responses):
    """A 150 s history at 0.1 ms (1.5 M rows, a Kobe record at the paper's step) is drawn with at
    most MAX_LINE_POINTS points per line, its extremes kept; the result itself is not changed."""
    n = 1_500_001
    t = np.linspace(0.0, 150.0, n)
    rotation = 1e-3 * np.sin(7.0 * t) * np.exp(-((t - 40.0) / 5.0) ** 2)
    history = {"time": t, "rotation": rotation, "rotation_rate": np.zeros(n), "slip": 1e-3 * np.tanh(t - 40.0),
               "slip_rate": np.zeros(n), "state": np.zeros(n, np.int8)}
    base = synthetic([(30.0, "REST", "ROCK"), (50.0, "ROCK", "REST")], duration=150.0, max_rotation_time=40.0)
    result = Result(history=history, events=base.events, summary=base.summary, step=1e-4,
                    ground_time=base.ground_time, ground_horizontal=base.ground_horizontal,
                    ground_vertical=base.ground_vertical)
    fig = response_figure(result, crop=None)
    for ax in fig.axes:
        for line in ax.lines:
            assert len(line.get_xdata()) <= plots.MAX_LINE_POINTS
    drawn = axis(fig, "record").lines[0].get_ydata()
    assert drawn.max() == rotation.max() and drawn.min() == rotation.min()
    assert result.history["rotation"] is rotation and rotation.size == n


# --------------------------------------------------------------------------------------------------
# Where the motion is, +-alpha, labels off the data
# --------------------------------------------------------------------------------------------------


def with_ground(result, moving: tuple[float, float]) -> Result:
    """``result`` with a horizontal ground acceleration of 1 m/s^2 within ``moving`` [s], still elsewhere."""
    t = result.ground_time
    ah = np.where((t >= moving[0]) & (t <= moving[1]), 1.0, 0.0)
    return Result(history=result.history, events=result.events, summary=result.summary, step=result.step,
                  ground_time=t, ground_horizontal=ah, ground_vertical=0.3 * ah)


@pytest.mark.parametrize("events, kwargs, moving, expected", [
    # the ground moves from 20 to 30 s of a 100 s record, the block within: that, 1 s on each side
    ([(25.0, "REST", "ROCK"), (26.0, "ROCK", "REST")], {}, (20.0, 30.0), (19.0, 31.0)),
    # the block still rocks after the ground has calmed down: up to its end, 5 % margin
    ([(25.0, "REST", "ROCK"), (50.0, "ROCK", "REST")], {}, (20.0, 30.0), (18.5, 51.5)),
    # overturned at 24 s: nothing after it but the margin
    ([(23.0, "REST", "ROCK"), (24.0, "ROCK", "OVERTURNED")], {"overturn": 24.0}, (20.0, 30.0), (19.0, 25.0)),
    # the ground moves over most of the record: all of it
    ([], {}, (2.0, 98.0), (0.0, 100.0)),
    # nothing moves: the whole record
    ([], {}, (200.0, 300.0), (0.0, 100.0)),
])
def test_motion_range(events, kwargs, moving, expected):
    result = with_ground(synthetic(events, duration=100.0, **kwargs), moving)
    assert plots.motion_range(result) == pytest.approx(expected)


def test_the_response_panels_show_where_the_motion_is(responses):
    """By default the response and ground panels span `motion_range`; crop=None the whole record;
    a given crop is in the figure's time."""
    result = with_ground(synthetic([(25.0, "REST", "ROCK"), (26.0, "ROCK", "REST")], duration=100.0),
                         (20.0, 30.0))
    fig = response_figure(result, time_shift=5.0)
    assert axis(fig, "record").get_xlim() == axis(fig, "ground").get_xlim() == pytest.approx((24.0, 36.0))
    assert "19.00 to 31.00 s of the 0 to 100 s record" not in texts(fig)
    assert "24.00 to 36.00 s of the 5 to 105 s record" in texts(fig)
    assert axis(response_figure(result, crop=None), "record").get_xlim() == (0.0, 100.0)
    assert axis(response_figure(result, crop=(40.0, 60.0)), "record").get_xlim() == (40.0, 60.0)
    with pytest.raises(ValueError, match="crop"):
        response_figure(result, crop=(60.0, 40.0))


def horizontal_lines_at(ax, y: float) -> list:
    return [line for line in ax.lines if len(line.get_ydata()) == 2
            and np.all(np.asarray(line.get_ydata()) == y)]


@pytest.mark.parametrize("kind", ["overturn", "rock"])
def test_alpha_is_drawn_where_the_rotation_comes_near_it(responses, kind):
    """alpha = atan(b/h) (0.1 m wide, 0.2 m high: atan(0.5)) on both sides (the legend says
    +-alpha) once the rotation reaches a quarter of it on one side, within the axis limits."""
    result = responses[kind]
    alpha = result.summary.alpha
    assert alpha == pytest.approx(np.arctan(0.5), rel=1e-15)
    phi = result.history["rotation"]
    assert max(phi.max(), -phi.min()) >= 0.25 * alpha
    ax = axis(response_figure(result), "record")
    for side in (1.0, -1.0):
        assert len(horizontal_lines_at(ax, side * alpha)) == 1, side
        low, high = ax.get_ylim()
        assert low < side * alpha < high


def test_alpha_far_off_the_scale_is_said_not_drawn(responses):
    result = responses["rockslip"]
    assert result.summary.max_rotation < 0.25 * result.summary.alpha
    fig = response_figure(result)
    ax = axis(fig, "record")
    assert not horizontal_lines_at(ax, result.summary.alpha) and not horizontal_lines_at(ax, -result.summary.alpha)
    assert f"±α = ±{result.summary.alpha:.4g} rad off scale" in ax.get_title(loc="right")
    assert "% of α" in fig._suptitle.get_text()


@pytest.mark.parametrize("kind", list(KINDS))
def test_labels_never_cover_data(responses, kind):
    """Every text of the figure (titles, notes, legends) lies outside every plotting area."""
    fig = response_figure(responses[kind], title=kind)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    areas = [ax.get_window_extent(renderer) for ax in fig.axes]
    texts_ = [fig._suptitle] + [t for legend in fig.legends for t in legend.get_texts()]
    for ax in fig.axes:
        texts_ += list(ax.texts) + [ax.title, ax._left_title, ax._right_title]
        if ax.get_legend():
            texts_ += ax.get_legend().get_texts()
    for text in texts_:
        if not text.get_text():
            continue
        box = text.get_window_extent(renderer)
        for area in areas:
            assert not box.overlaps(area), (kind, text.get_text())


def scaled(result, rotation: float, slip: float) -> Result:
    """``result`` with its rotation and slip histories multiplied by ``rotation`` and ``slip``."""
    history = {**result.history, "rotation": result.history["rotation"] * rotation,
               "slip": result.history["slip"] * slip}
    return Result(history=history, events=result.events, summary=result.summary, step=result.step,
                  ground_time=result.ground_time, ground_horizontal=result.ground_horizontal,
                  ground_vertical=result.ground_vertical)


# The kinds of response, and two whose y axes are labelled otherwise: with offset texts (1e-8 over
# the rotation axis, 1e-5 over the slip axis), and with wide tick labels (-0.0001, 600000).
LAYOUTS = {kind: (lambda r, kind=kind: r[kind]) for kind in KINDS}
LAYOUTS["offset texts"] = lambda r: scaled(r["rockslip"], 1e-6, 1e-6)
LAYOUTS["wide tick labels"] = lambda r: scaled(r["rockslip"], 1e-2, 1e4)


# `make test-fast` draws each layout at 150 dpi only; `make test` at all three
@pytest.mark.parametrize("dpi", [pytest.param(50, marks=pytest.mark.slow), 150,
                                 pytest.param(300, marks=pytest.mark.slow)])
@pytest.mark.parametrize("layout", list(LAYOUTS))
def test_the_layout_keeps_everything_in_the_figure_and_apart(responses, layout, dpi):
    """What constrained layout did, `_fit_column` does once: every panel with its decorations
    (tick labels, axis labels, offset texts, titles), the title and the legend lie inside the
    figure, stacked without overlapping, at any dpi (the margins are fractions of the figure)."""
    fig = response_figure(LAYOUTS[layout](responses), title=layout)
    fig.set_dpi(dpi)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    rows = {}
    for ax in fig.axes:
        rows.setdefault(ax.get_subplotspec().rowspan.start, []).append(ax.get_tightbbox(renderer))
    stack = ([fig._suptitle.get_window_extent(renderer)] + [Bbox.union(rows[k]) for k in sorted(rows)]
             + [fig.legends[0].get_window_extent(renderer)])
    for box in stack:
        assert 0 <= box.x0 and box.x1 <= fig.bbox.width and 0 <= box.y0 and box.y1 <= fig.bbox.height, box
    for upper, lower in zip(stack[:-1], stack[1:], strict=True):
        assert upper.y0 > lower.y1, (upper, lower)
    if layout == "offset texts":
        assert {ax.yaxis.offsetText.get_text() for ax in fig.axes} >= {"1e\u22128", "1e\u22125"}


def test_a_saved_response_figure_is_drawn_once(tmp_path, responses, monkeypatch):
    """No layout engine: constrained layout drew the figure twice for each savefig."""
    draws = []
    draw = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: (draws.append(self), draw(self, renderer))[1])
    fig = response_figure(responses["overturn"], title="overturn")
    assert fig.get_layout_engine() is None
    save_figure(fig, tmp_path / "f.png")
    assert draws == [fig]


# --------------------------------------------------------------------------------------------------
# zoom_window on known events
# --------------------------------------------------------------------------------------------------


def synthetic(events, *, duration=10.0, overturn=None, status="ok", max_rotation=0.1,
              max_rotation_time=0.0) -> Result:
    """A result with the event log ``events`` (``(time, from, to)``, cause liftoff, or ``(time,
    from, to, cause)``) and no history."""
    table = np.zeros(len(events), dtype=EVENT_DTYPE)
    for row, (time, old, new, *cause) in zip(table, events, strict=True):
        row["time"], row["from"], row["to"], row["cause"] = time, old, new, (cause or ["liftoff"])[0]
    end = overturn if overturn is not None else duration
    summary = Summary(overturned=overturn is not None, overturn_time=overturn,
                      direction=1 if overturn is not None else None, fall_start_time=None,
                      max_rotation=max_rotation, max_rotation_time=max_rotation_time, max_slip=0.0,
                      residual_slip=0.0, impacts=0, states_seen=["REST", "ROCK"], time_in_state={},
                      status=status, end_time=end)
    ground_time = np.arange(0.0, duration + 1e-9, 0.01)
    empty = {k: np.zeros(0) for k in ("time", "rotation", "rotation_rate", "slip", "slip_rate")}
    empty["state"] = np.zeros(0, np.int8)
    return Result(history=empty, events=table, summary=summary, step=1e-4, ground_time=ground_time,
                  ground_horizontal=np.zeros_like(ground_time), ground_vertical=np.zeros_like(ground_time))


@pytest.mark.parametrize("events, kwargs, expected", [
    # one rocking episode: a 0.25 s margin on each side
    ([(3.0, "REST", "ROCK"), (3.5, "ROCK", "ROCK"), (4.0, "ROCK", "REST")], {}, (2.75, 4.25)),
    # several episodes over 3 s: a 10 % margin
    ([(3.0, "REST", "SLIP"), (3.4, "SLIP", "REST"), (5.0, "REST", "ROCK"), (6.0, "ROCK", "REST")], {},
     (2.7, 6.3)),
    # kept within the record
    ([(0.1, "REST", "SLIP"), (0.6, "SLIP", "REST")], {}, (0.0, 0.85)),
    ([(9.5, "REST", "ROCK")], {}, (9.25, 10.0)),
    # events spread over 16 s: the episode of the largest rotation, with its margin
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (17.0, "REST", "ROCK"), (18.0, "ROCK", "REST")],
     {"duration": 30.0, "max_rotation_time": 17.5}, (16.75, 18.25)),
    # ... episodes less than 1 s apart are one
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (15.0, "REST", "SLIP"), (16.0, "SLIP", "REST"),
      (16.5, "REST", "ROCK"), (18.0, "ROCK", "REST")],
     {"duration": 30.0, "max_rotation_time": 17.5}, (14.7, 18.3)),
    # a long rocking episode (slow swings, impacts every 2.2 s): the swing of the largest rotation and
    # the opposite swings before and after it, whole (from the second impact before the peak to
    # the second after it), where a fixed 5 s window (12 to 17 s) would cut both
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (5.0, "REST", "ROCK")]
     + [(5.0 + 2.2 * k, "ROCK", "ROCK", "impact") for k in range(1, 10)] + [(26.0, "ROCK", "REST")],
     {"duration": 30.0, "max_rotation_time": 14.5}, (5 + 2.2 * 3 - 0.66, 5 + 2.2 * 6 + 0.66)),
    # overturning after a long time: the episode that ends in it
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (18.0, "REST", "ROCK"), (20.0, "ROCK", "OVERTURNED")],
     {"duration": 30.0, "overturn": 20.0, "max_rotation_time": 20.0}, (17.75, 20.25)),
    # ... after a long rocking episode: from the second impact before it
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (5.0, "REST", "ROCK")]
     + [(5.0 + 2.0 * k, "ROCK", "ROCK", "impact") for k in range(1, 11)] + [(26.0, "ROCK", "OVERTURNED")],
     {"duration": 30.0, "overturn": 26.0, "max_rotation_time": 26.0}, (22.7, 26.3)),
    # overturning soon
    ([(3.0, "REST", "ROCK"), (4.0, "ROCK", "OVERTURNED")], {"overturn": 4.0}, (2.75, 4.25)),
])
def test_zoom_window_on_known_events(events, kwargs, expected):
    assert zoom_window(synthetic(events, **kwargs)) == pytest.approx(expected)


def test_zoom_window_without_events_is_none():
    assert zoom_window(synthetic([])) is None


def test_zoom_window_of_a_stopped_computation():
    result = synthetic([(3.0, "REST", "ROCK"), (3.2, "ROCK", "ROCKSLIP"), (3.3, "ROCKSLIP", "ROCKSLIP")],
                       status="flight")
    result.summary.end_time = 3.3
    assert zoom_window(result) == pytest.approx((2.75, 3.55))


def test_state_segments_merge_impacts():
    result = synthetic([(3.0, "REST", "ROCK"), (3.5, "ROCK", "ROCK"), (4.0, "ROCK", "REST")])
    assert state_segments(result) == [(0.0, 3.0, 0), (3.0, 4.0, 2), (4.0, 10.0, 0)]


# --------------------------------------------------------------------------------------------------
# Saving
# --------------------------------------------------------------------------------------------------


def test_save_figure_refuses_to_overwrite(tmp_path, responses, monkeypatch):
    monkeypatch.chdir(tmp_path)
    fig = response_figure(responses["slip"])
    save_figure(fig, "out/f.png")
    before = (tmp_path / "out" / "f.png").read_bytes()
    with pytest.raises(OutputError) as info:
        save_figure(fig, "out/f.png")
    assert str(info.value) == "out/f.png exists (use --overwrite to replace it)"
    assert (tmp_path / "out" / "f.png").read_bytes() == before
    save_figure(response_figure(responses["rock"]), "out/f.png", overwrite=True)
    assert (tmp_path / "out" / "f.png").read_bytes() != before
    assert os.listdir(tmp_path / "out") == ["f.png"]


def test_save_figure_is_atomic(tmp_path, responses, monkeypatch):
    fig = response_figure(responses["slip"])
    target = save_figure(fig, tmp_path / "f.png")
    before = target.read_bytes()

    def broken(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(fig, "savefig", broken)
    with pytest.raises(KeyboardInterrupt):
        save_figure(fig, target, overwrite=True)
    assert target.read_bytes() == before
    assert os.listdir(tmp_path) == ["f.png"]


def test_save_figure_errors(tmp_path, responses):
    fig = response_figure(responses["rest"])
    with pytest.raises(OutputError, match="unknown figure format"):
        save_figure(fig, tmp_path / "f.xyz")
    blocker = tmp_path / "plainfile"
    blocker.write_text("")
    with pytest.raises(OutputError, match="plainfile"):
        save_figure(fig, blocker / "f.png")
    assert sorted(os.listdir(tmp_path)) == ["plainfile"]


def test_titles_are_placed_without_a_search_only_where_nothing_can_be_in_their_way():
    """`plots._title_height` spares matplotlib's search for what a panel's titles might overlap
    (1.0) only for y ranges it labels without an offset text (``1e-5`` over the axis, where the
    titles are): checked against matplotlib's own tick labels for ranges holding zero from 1e-8 to
    1e8, on a short and a tall axis; the usual ranges are spared, tiny and huge ones are not."""
    spared = set()
    for height in (1.0, 6.0):                          # [in]: few ticks, many ticks
        ax = Figure(figsize=(6.0, height + 1.0), dpi=plots.DPI).subplots()
        for span in 10.0 ** (np.arange(-32, 33) / 4.0):
            for zero in (0.0, 0.25, 0.5, 0.9, 1.0):   # where zero is in the range
                ax.set_ylim(-zero * span, (1.0 - zero) * span)
                ax.yaxis.get_majorticklabels()        # ticks and their formatter, as a draw sets them
                offset = ax.yaxis.get_major_formatter().get_offset()
                if plots._title_height(ax) == 1.0:
                    assert offset == "", (span, zero, height)
                    spared.add(span)
                else:
                    assert plots._title_height(ax) is None
    assert min(spared) <= 1e-3 * 1.0001 and 1e5 <= max(spared) < 1e6


@pytest.mark.parametrize("kind", ["rest", "rockslip", "overturn"])
def test_titles_placed_without_a_search_are_where_matplotlib_puts_them(tmp_path, responses, kind, monkeypatch):
    """The figure is the same, byte for byte, when matplotlib searches for the titles' places."""
    answers = []
    title_height = plots._title_height

    def recorded(*axes):
        answers.append(title_height(*axes))
        return answers[-1]

    monkeypatch.setattr(plots, "_title_height", recorded)
    fast = save_figure(response_figure(responses[kind], title=kind), tmp_path / "fast.png")
    assert 1.0 in answers                              # some titles were placed without the search
    monkeypatch.setattr(plots, "_title_height", lambda *axes: None)
    searched = save_figure(response_figure(responses[kind], title=kind), tmp_path / "searched.png")
    assert fast.read_bytes() == searched.read_bytes()


@pytest.mark.parametrize("dpi, facecolor", [(150, "white"), (67, "white"), (100, "none")])
def test_png_holds_the_figure_as_drawn(tmp_path, responses, dpi, facecolor):
    """`plots._write_png` writes the pixels matplotlib draws, RGB where they are opaque (RGBA
    otherwise), and the resolution."""
    fig = response_figure(responses["rock"])
    fig.set_facecolor(facecolor)
    path = save_figure(fig, tmp_path / "f.png", dpi=dpi)
    fig.set_dpi(dpi)
    fig.canvas.draw()
    drawn = np.asarray(fig.canvas.buffer_rgba())
    with Image.open(path) as image:
        assert image.mode == ("RGB" if facecolor == "white" else "RGBA")
        assert image.info["dpi"] == pytest.approx((dpi, dpi), abs=0.05)     # pixels per metre, whole
        read = np.asarray(image.convert("RGBA"))
    assert drawn[..., 3].min() == (255 if facecolor == "white" else 0)
    assert np.array_equal(read, drawn)


def test_other_formats(tmp_path, responses, caplog):
    """PDF, SVG and PostScript; PostScript without matplotlib's log line that it draws the
    translucent state bands opaque (a user asked for .eps and got a warning about it)."""
    fig = response_figure(responses["rock"])
    assert save_figure(fig, tmp_path / "f.pdf").read_bytes()[:5] == b"%PDF-"
    assert b"<svg" in save_figure(fig, tmp_path / "f.svg").read_bytes()[:2000]
    with caplog.at_level("WARNING"):
        assert save_figure(fig, tmp_path / "f.eps").read_bytes()[:10] == b"%!PS-Adobe"
        assert save_figure(fig, tmp_path / "f.ps").read_bytes()[:10] == b"%!PS-Adobe"
    assert not [r for r in caplog.records if "transparency" in r.getMessage()]


# --------------------------------------------------------------------------------------------------
# No pyplot
# --------------------------------------------------------------------------------------------------


def test_plots_module_never_imports_pyplot():
    source = Path(plots.__file__).read_text(encoding="utf-8")
    imported = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            imported.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module or "")
            imported.update(f"{node.module}.{alias.name}" for alias in node.names)
    assert not any("pyplot" in name for name in imported)
    assert "pyplot" not in source.replace("pyplot is never imported", "")


def test_rendering_does_not_load_pyplot(tmp_path):
    script = textwrap.dedent("""
        import sys
        import numpy as np
        from rockslide.plots import response_figure, save_figure
        from rockslide.core.simulate import Model, Settings, simulate
        t = np.arange(0, 10, 0.01)
        ah = 6.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-((t - 4) / 2) ** 2)
        r = simulate(Model.from_block(0.1, 0.2, 0.52, 0.494, 0.8), 0.01, ah, 0.3 * ah, Settings(tail=2.0))
        save_figure(response_figure(r, title="x"), sys.argv[1])
        loaded = sorted(m for m in sys.modules if m.startswith("matplotlib.backends.backend_"))
        print("pyplot" if "matplotlib.pyplot" in sys.modules else "no pyplot", loaded)
    """)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))}
    env.pop("MPLBACKEND", None)
    out = subprocess.run([sys.executable, "-c", script, str(tmp_path / "x.png")], env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("no pyplot"), out.stdout
    assert "backend_agg" in out.stdout
    assert (tmp_path / "x.png").read_bytes()[:8] == PNG_SIGNATURE
