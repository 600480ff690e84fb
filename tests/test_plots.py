"""Figures: every kind of response renders and saves; the zoom finds the events; no pyplot."""

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
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from rockslide import plots
from rockslide.core.simulate import EVENT_DTYPE, Model, Result, Settings, Summary, simulate
from rockslide.errors import OutputError
from rockslide.plots import response_figure, save_figure, state_segments, zoom_window
from rockslide.results import read_result, write_result

REPO = Path(__file__).resolve().parents[1]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def pulse(amplitude, mu, *, vertical=0.3, frequency=1.5, vertical_abs=False, **settings):
    t = np.arange(0, 10, 0.01)
    ah = amplitude * np.sin(2 * np.pi * frequency * t) * np.exp(-((t - 4) / 2) ** 2)
    av = vertical * (np.abs(ah) if vertical_abs else ah)
    return simulate(Model.from_block(0.2, 0.1, mu, 0.95 * mu, 0.8), 0.01, ah, av,
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
        parts += [t.get_text() for t in ax.texts] + [ax.get_title(loc="left")]
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
    assert png_size(data) == (1320, 960)           # 11 x 8 in at 120 dpi
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
    assert len(verticals) >= 3                      # whole record, zoom and ground panels
    if kind != "overturn":
        assert result.summary.status in fig._suptitle.get_text()


def test_history_ends_early_but_ground_continues(responses):
    result = responses["overturn"]
    fig = response_figure(result, zoom=None)
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
    assert stored_fig._suptitle.get_text() == fresh_fig._suptitle.get_text()
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


# --------------------------------------------------------------------------------------------------
# zoom_window on known events
# --------------------------------------------------------------------------------------------------


def synthetic(events, *, duration=10.0, overturn=None, status="ok", max_rotation=0.1,
              max_rotation_time=0.0) -> Result:
    table = np.zeros(len(events), dtype=EVENT_DTYPE)
    for row, (time, old, new) in zip(table, events, strict=True):
        row["time"], row["from"], row["to"], row["cause"] = time, old, new, "liftoff"
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
    # events spread over 16 s: the 5 s around the largest rotation
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (17.0, "REST", "ROCK"), (18.0, "ROCK", "REST")],
     {"duration": 30.0, "max_rotation_time": 10.0}, (7.5, 12.5)),
    # ... near the end of the record: shifted inside it
    ([(2.0, "REST", "ROCK"), (29.0, "ROCK", "REST")], {"duration": 30.0, "max_rotation_time": 29.0},
     (25.0, 30.0)),
    # overturning after a long time: the 5 s that end just after it
    ([(2.0, "REST", "ROCK"), (3.0, "ROCK", "REST"), (18.0, "REST", "ROCK"), (20.0, "ROCK", "OVERTURNED")],
     {"duration": 30.0, "overturn": 20.0, "max_rotation_time": 20.0}, (15.25, 20.25)),
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


def test_other_formats(tmp_path, responses):
    fig = response_figure(responses["rock"])
    assert save_figure(fig, tmp_path / "f.pdf").read_bytes()[:5] == b"%PDF-"
    assert b"<svg" in save_figure(fig, tmp_path / "f.svg").read_bytes()[:2000]


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
        r = simulate(Model.from_block(0.2, 0.1, 0.52, 0.494, 0.8), 0.01, ah, 0.3 * ah, Settings(tail=2.0))
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
