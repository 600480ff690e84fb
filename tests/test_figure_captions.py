"""Figures a reviewer accepts (issue 27): every figure says what was computed (record, scaling,
block, mu, e, dt, version), `--size` gives the stated size with fonts of at least 6 pt, +-alpha is
drawn on both sides, accelerations are shown in the unit the case was written in, coinciding
fragility curves both show, the criteria map's boundaries are the closed forms, and `rockslide plot
A B` overlays results of one kind (mixed kinds: one line, exit 2).

The expected texts and numbers come from the case files written here, never from the code drawn."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import invoke, one_line_error
from matplotlib.text import Text

import rockslide
from rockslide import plots
from rockslide.core import criteria
from rockslide.core.physics import REST, ROCK, ROCKSLIP, SLIP
from rockslide.core.simulate import Model, Settings, simulate
from rockslide.io.example import write_example

#: A journal column [in] (the brief's "about 3.5 in"): `--size column` must give exactly this width.
COLUMN_WIDTH = 3.5
#: The smallest font a printed column still reads [pt].
MIN_FONT = 6.0




def texts(fig) -> list[str]:
    """Every text of ``fig`` (titles, labels, legends, tick labels once drawn)."""
    return [t.get_text() for t in fig.findobj(Text) if t.get_text()]


def smallest_font(fig) -> float:
    fig.canvas.draw()          # tick labels exist once drawn
    return min(t.get_fontsize() for t in fig.findobj(Text) if t.get_text() and t.get_visible())


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The shipped example (its records), a variant of it written in g with a higher friction (it
    rocks towards alpha), both run, and a small fragility analysis of each."""
    folder = tmp_path_factory.mktemp("figures")
    write_example(folder / "ex")
    text = (folder / "ex" / "example.yaml").read_text()
    statue = (text.replace("name: example", "name: statue").replace("pga_horizontal: 700 gal", "pga_horizontal: 0.8 g")
              .replace("mu_static: 0.52, mu_kinetic: 0.494", "mu_static: 0.9, mu_kinetic: 0.85"))
    assert statue != text
    (folder / "ex" / "statue.yaml").write_text(statue)
    out = folder / "out"
    for name in ("example", "statue"):
        result = invoke("run", folder / "ex" / f"{name}.yaml", "--out-dir", out, "--no-plot")
        assert result.exit_code == 0, result.output
        result = invoke("fragility", folder / "ex" / f"{name}.yaml", "--suite", folder / "ex" / "suite-synthetic.yaml",
                        "--levels", "0.4g:1.6g:0.4g", "--out-dir", out, "--no-plot")
        assert result.exit_code == 0, result.output
        result = invoke("sweep", folder / "ex" / f"{name}.yaml", "--mu", "0.5,0.9", "--pga", "0.4g,0.8g",
                        "--out-dir", out, "--no-plot")
        assert result.exit_code == 0, result.output
    return out


def test_the_run_figure_names_record_scaling_block_mu_e_dt_and_version(files):
    fig = plots.response_figure(rockslide.read_result(files / "example.h5"))
    shown = "\n".join(texts(fig))
    # the example's case file: records synthetic_kt_{h,v}.at2 scaled to 700 gal, 0.1 x 0.2 m, 10 kg,
    # mu_static 0.52, restitution 0.8, solver dt 0.1 ms
    for part in ("synthetic_kt_h.at2", "synthetic_kt_v.at2", "PGA 700 gal", "0.1 × 0.2 m", "10 kg",
                 "μ = 0.52", "e = 0.8", "dt = 0.1 ms", f"rockslide {rockslide.__version__}"):
        assert part in shown.replace("\n", " "), part
    assert f"α = {math.atan2(0.1, 0.2):.4g} rad" in shown.replace("\n", " ")


def test_a_fragility_figure_names_the_suite_levels_block_mu_e_dt(files):
    fig = rockslide.plot_results([files / "example.fragility.h5"])
    shown = " ".join(texts(fig)).replace("\n", " ")
    for part in ("suite-synthetic.yaml", "6 records", "PGA 0.4 to 1.6 g", "μ = 0.52", "e = 0.8", "dt = 0.1 ms"):
        assert part in shown, part


@pytest.mark.parametrize("kind", ["run", "fragility", "criteria", "sweep", "spectrum", "ensemble", "overlay"])
def test_size_column_is_a_column_wide_with_fonts_of_6_pt_at_least(files, kind):
    rng = np.random.default_rng(1)
    if kind == "run":
        fig = plots.response_figure(rockslide.read_result(files / "statue.h5"), size="column")
    elif kind == "fragility":
        fig = rockslide.plot_results([files / "example.fragility.h5"], size="column")
    elif kind == "overlay":
        fig = rockslide.plot_results([files / "example.h5", files / "statue.h5"], size="column")
    elif kind == "criteria":
        ah, mu = np.linspace(0, 1.5, 31), np.linspace(0, 1.2, 25)
        maps = [(f"A_v = {av:+.1f} g", criteria.mode_map(ah, mu, av, 0.05, 0.1),
                 criteria.mode_boundaries(ah, av, 0.05, 0.1)) for av in (-0.5, 0.0, 0.5)]
        fig = plots.criteria_figure(ah, mu, maps, title="t", caption="block", size="column")
    elif kind == "sweep":
        shape = (4, 5)
        fig = plots.sweep_figure([("mu", np.arange(4.0)), ("pga [gal]", np.arange(5.0))],
                                 rng.integers(0, 5, shape), rng.uniform(1e-3, 1, shape), rng.normal(size=shape) * 1e-3,
                                 title="t", caption="c", size="column")
    elif kind == "spectrum":
        fig = plots.spectrum_figure([1.0, 2.0, 3.0], [1.0, 2.0], rng.integers(0, 5, (2, 3)),
                                    rng.uniform(0.01, 1, (2, 3)), title="t", caption="c", size="column")
    else:
        fig = plots.ensemble_figure(rng.uniform(0, 1, 50), rng.uniform(size=50) < 0.2, 0.5, summary_text="s",
                                    title="t", caption="c", size="column")
    width, _ = fig.get_size_inches()
    assert width == pytest.approx(COLUMN_WIDTH, abs=1e-9)
    assert smallest_font(fig) >= MIN_FONT


@pytest.mark.parametrize("size, expected", [("page", 7.0), ("slide", 10.0), ("6x4", 6.0), ((5.0, 3.0), 5.0)])
def test_named_and_explicit_sizes(files, size, expected):
    fig = rockslide.plot_results([files / "example.h5"], size=size)
    assert fig.get_size_inches()[0] == pytest.approx(expected)
    if size == "slide":
        assert tuple(fig.get_size_inches()) == pytest.approx((10.0, 5.625))      # 16:9
    assert smallest_font(fig) >= MIN_FONT


def test_a_bad_size_is_one_line_and_exit_2(files):
    one_line_error(invoke("plot", files / "example.h5", "--size", "huge"), "--size", "column", "WIDTHxHEIGHT")
    one_line_error(invoke("plot", files / "example.h5", "--size", "0.1x4"), "--size", "out of range")


def test_plot_two_runs_writes_one_figure_with_the_cases_in_its_legend(files, tmp_path):
    out = tmp_path / "both.png"
    result = invoke("plot", files / "example.h5", files / "statue.h5", "-o", out)
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    fig = rockslide.plot_results([files / "example.h5", files / "statue.h5"])
    (legend,) = fig.legends
    names = [t.get_text().split(":")[0] for t in legend.get_texts()]
    assert names[:2] == ["example", "statue"]
    assert {ax.get_label() for ax in fig.axes} == {"rotation", "slip", "ground"}
    # one line of each run on the rotation axes, with the runs' own colours
    rotation = next(ax for ax in fig.axes if ax.get_label() == "rotation")
    colours = {line.get_color() for line in rotation.get_lines() if np.ptp(line.get_ydata()) > 0}
    assert len(colours) == 2


def test_plot_two_fragility_files_overlays_their_curves_with_bands(files, tmp_path):
    out = tmp_path / "fragility.png"
    result = invoke("plot", files / "example.fragility.h5", files / "statue.fragility.h5", "-o", out)
    assert result.exit_code == 0, result.output
    assert out.is_file()
    fig = rockslide.plot_results([files / "example.fragility.h5", files / "statue.fragility.h5"])
    labels = [t.get_text() for legend in fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
              for t in legend.get_texts()]
    assert any(label.startswith("example, overturn") for label in labels)
    assert any(label.startswith("statue, overturn") for label in labels)


def test_plot_of_mixed_kinds_is_one_line_and_exit_2(files, tmp_path):
    one_line_error(invoke("plot", files / "example.h5", files / "example.fragility.h5", "-o", tmp_path / "x.png"),
                   "example.fragility.h5", "one kind")
    assert not (tmp_path / "x.png").exists()


def test_both_alpha_lines_are_drawn_when_the_rotation_comes_near_one(files):
    run = rockslide.read_result(files / "statue.h5")
    alpha = math.atan2(0.1, 0.2)          # the block: 0.1 m wide, 0.2 m high
    assert run.summary.max_rotation > 0.25 * alpha       # near enough for the lines (plots.ALPHA_SHOWN_FRACTION)
    fig = plots.response_figure(run)
    record = next(ax for ax in fig.axes if ax.get_label() == "record")
    levels = {round(float(line.get_ydata()[0]), 12) for line in record.get_lines()
              if len(set(np.asarray(line.get_ydata(), float))) == 1}
    assert round(alpha, 12) in levels and round(-alpha, 12) in levels
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(text.startswith("±α") for text in legend)


def test_a_pga_written_in_g_is_shown_in_g(files):
    fig = plots.response_figure(rockslide.read_result(files / "statue.h5"))      # pga_horizontal: 0.8 g
    ground = next(ax for ax in fig.axes if ax.get_label() == "ground")
    assert ground.get_ylabel().endswith("[g]")
    horizontal = ground.get_lines()[0]
    # the record is scaled to a PGA of 0.8 g: its peak, drawn in g, is 0.8 (the envelope keeps peaks)
    assert np.max(np.abs(horizontal.get_ydata())) == pytest.approx(0.8, rel=1e-9)
    overlay = rockslide.plot_results([files / "statue.h5", files / "example.h5"])
    assert next(ax for ax in overlay.axes if ax.get_label() == "ground").get_ylabel().endswith("[g]")


def test_coinciding_fragility_curves_both_show_and_the_legend_says_so():
    grid = np.linspace(0.01, 2.0, 50)
    fitted = 0.5 * (1 + np.tanh(grid - 1))
    same = {"fraction": np.array([0.0, 0.5, 1.0]), "fitted": fitted}
    fig = plots.fragility_figure([0.5, 1.0, 1.5], grid, [{**same, "label": "overturn: a"},
                                                         {**same, "label": "rotation>0.5alpha: a"}],
                                 xlabel="PGA [g]", confidence=0.95)
    ax = fig.axes[0]
    fits = [line for line in ax.get_lines() if len(line.get_xdata()) == grid.size]
    assert len(fits) == 2
    under, over = fits
    assert under.get_linewidth() > over.get_linewidth() and over.get_linestyle() != "-"
    assert under.get_color() != over.get_color()            # the dashes show on the wider line
    labels = [" ".join(t.get_text().split()) for legend in fig.legends for t in legend.get_texts()]
    assert any("the same as overturn" in label for label in labels)
    # two curves of one colour (an overlay's file): the dashes over it are white, not its own colour
    fig = plots.fragility_figure([0.5, 1.0, 1.5], grid, [{**same, "label": "a: x", "colour": "#123456"},
                                                         {**same, "label": "b: x", "colour": "#123456"}],
                                 xlabel="PGA [g]", confidence=0.95)
    under, over = [line for line in fig.axes[0].get_lines() if len(line.get_xdata()) == grid.size]
    assert under.get_color() == "#123456" and over.get_color() == "white"


def test_the_criteria_boundaries_are_the_closed_forms_and_part_the_map():
    b, h, av = 0.05, 0.1, 0.2            # half-width, half-height [m]; A_v = 0.2 g
    tan_alpha = b / h
    ah = np.linspace(0.0, 1.5, 301)
    lines = criteria.mode_boundaries(ah, av, b, h)
    slip_x, slip_y = lines[0]
    # eq. 11 at rest: slip where mu (g + A_v) = |A_h|, up to mu = b/h where liftoff (eq. 6) comes first
    assert slip_x[-1] == pytest.approx(tan_alpha * (1 + av)) and slip_y[-1] == pytest.approx(tan_alpha)
    assert np.allclose(slip_y, slip_x / (1 + av))
    x26, y26 = lines[-1]
    assert x26.size > 1000                 # a curve, not the grid's cells
    # either side of the eq. 26 curve, the map (cell by cell) gives liftoff above and liftoff-slip below
    for x, y in zip(x26[::200], y26[::200], strict=True):
        if np.isfinite(y) and y > tan_alpha + 0.01:
            above = criteria.mode_map([x], [y * 1.001], av, b, h)[0, 0]
            below = criteria.mode_map([x], [y * 0.999], av, b, h)[0, 0]
            assert (above, below) == (ROCK, ROCKSLIP)
    # left of the liftoff line, above b/h: rest; right of it, under b/h: slip
    lift = tan_alpha * (1 + av)
    assert criteria.mode_map([lift * 0.99], [0.8], av, b, h)[0, 0] == REST
    assert criteria.mode_map([lift * 1.01], [tan_alpha * 0.99], av, b, h)[0, 0] == SLIP


def test_every_drawing_command_takes_size():
    for command in ("run", "sweep", "fragility", "criteria", "plot"):
        assert "--size" in invoke(command, "--help").stdout, command


def test_plots_without_a_caption_still_work_from_a_bare_result():
    run = simulate(Model.from_block(0.1, 0.2, 0.8, 0.76, 0.8), 0.01, np.zeros(100), np.zeros(100), Settings())
    fig = plots.response_figure(run, size="page")
    assert fig.get_size_inches()[0] == pytest.approx(7.0)


def test_two_sweeps_side_by_side_on_one_colour_scale_in_the_cases_unit(files):
    fig = rockslide.plot_results([files / "statue.sweep.h5", files / "example.sweep.h5"])
    maps = [ax for ax in fig.axes if ax.get_title(loc="left")]          # not the colour bar
    titles = [ax.get_title(loc="left") for ax in maps]
    assert titles == ["statue", "example"]
    meshes = [c for ax in maps for c in ax.collections if c.get_array() is not None]
    assert len(meshes) == 2 and len({(m.norm.vmin, m.norm.vmax) for m in meshes}) == 1     # one colour scale
    # statue's case gives its PGA in g: the shared axis is in g, the values the case's 0.4 and 0.8 g
    assert all(ax.get_xlabel().replace("\n", " ").endswith("[g]") for ax in maps)
    assert maps[1].get_xlim() == pytest.approx((0.2, 1.0))     # 0.4 g and 0.8 g, cells 0.4 g wide
    single = rockslide.plot_results([files / "statue.sweep.h5"])
    assert all(ax.get_xlabel().replace("\n", " ").endswith("[g]") for ax in single.axes if ax.get_xlabel())


def test_a_common_scale_factor_is_said_once_only_when_every_record_has_it():
    """``both ×f`` for two records scaled alike, ``all ×f`` for three; a record without a factor
    (the vertical unscaled) keeps each record's own factor in the caption."""
    from rockslide.plots import case_caption

    def records(*factors):
        roles = ("horizontal", "vertical", "horizontal_2")
        return [{"role": role, "path": f"{role}.at2", **({} if f is None else {"scale_factor": f})}
                for role, f in zip(roles, factors, strict=False)]

    assert "both ×1.5" in case_caption("", records=records(1.5, 1.5))
    three = case_caption("", records=records(1.5, 1.5, 1.5))
    assert "all ×1.5" in three and "both" not in three
    alone = case_caption("", records=records(1.5, None))
    assert "both" not in alone and "horizontal.at2 (H) ×1.5" in alone


def test_a_height_to_width_sweep_marks_the_block_as_the_base_case():
    from conftest import REPO

    from rockslide.plots import case_caption

    text = (REPO / "configs" / "example.yaml").read_text()
    assert "0.2 m (base)" in case_caption(text, varied=("height_to_width", "mu"))
    assert "0.2 m (base)" not in case_caption(text, varied=("mu",))


# --------------------------------------------------------------------------------------------------
# What a reviewer sends back: legends over the data, a colour with two meanings, an empty panel
# --------------------------------------------------------------------------------------------------

def legends_clear_of_the_data(fig) -> None:
    """No legend inside an axes, and every legend of the figure outside every axes' box (drawn at
    the figure's final size, as its PNG is)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    assert [ax for ax in fig.axes if ax.get_legend() is not None] == []
    assert fig.legends
    for legend in fig.legends:
        box = legend.get_window_extent(renderer)
        for ax in fig.axes:
            assert not box.overlaps(ax.get_window_extent(renderer)), (legend, ax)


@pytest.mark.parametrize("size", [None, "column", "page"])
def test_the_ensemble_legend_is_off_the_curve_and_says_what_alpha_is(size):
    # standing members past alpha (1.28 alpha, as a statue on Kobe reaches): a legend that says
    # members "tip past alpha" would contradict them
    ratios = np.array([0.1, 0.4, 0.9, 1.05, 1.28] * 4 + [np.nan] * 5)
    overturned = np.isnan(ratios)
    fig = plots.ensemble_figure(np.nan_to_num(ratios), overturned, 1.28, summary_text="overturns in 20 % [8, 41] of 25",
                                title="t", caption="c", size=size)
    legends_clear_of_the_data(fig)
    labels = [" ".join(t.get_text().split()) for t in fig.legends[0].get_texts()]
    alpha = [label for label in labels if label.startswith("α")]
    assert len(alpha) == 1 and "tip" not in alpha[0] and "no longer pulls the block back" in alpha[0]


@pytest.mark.parametrize("size", [None, "column"])
def test_the_fragility_legend_is_below_the_curves(size):
    grid = np.linspace(0.0, 1.5, 61)
    curve = {"label": "overturn: median 0.3 g", "fraction": np.array([0.5, 0.9, 1.0]),
             "fitted": np.clip(grid / 0.6, 0, 1),
             "band": np.array([np.clip(grid / 0.7, 0, 1), np.clip(grid / 0.5, 0, 1)]),
             "moments": np.clip(grid / 0.55, 0, 1)}
    legends_clear_of_the_data(plots.fragility_figure([0.25, 0.5, 1.0], grid, [curve], xlabel="PGA [g]",
                                                     confidence=0.95, size=size))


def sweep_maps(fig):
    """The three map axes of a one-row sweep figure (titled; not the colour bars)."""
    return [ax for ax in fig.axes if ax.get_title(loc="left")]


def test_sweep_maps_give_each_colour_one_meaning():
    from matplotlib.colors import to_rgb

    category = np.array([[0, 1, 2], [3, 4, 5]])
    slip = np.array([[0.0, 0.02, -0.03], [0.01, 0.5, 0.0]])         # [m]: an overturned one slid far
    rotation = np.array([[0.0, 0.0, 0.1], [0.2, 1.5, 0.0]])
    fig = plots.sweep_figure([("mu", np.array([0.3, 0.5])), ("pga [g]", np.array([0.1, 0.2, 0.3]))],
                             category, rotation, slip, title="t", caption="c")
    legends_clear_of_the_data(fig)
    modes, rotated, slipped = sweep_maps(fig)
    legend = {" ".join(t.get_text().split()): to_rgb(h.get_facecolor())
              for t, h in zip(fig.legends[0].get_texts(), fig.legends[0].legend_handles, strict=True)}
    assert legend["no liftoff (max rotation)"] == to_rgb(plots.NO_DATA_COLOUR)
    # the slip map's colours are none of the legend's, from a tenth of its scale up (below: near white)
    mesh = slipped.collections[0]
    shades = mesh.cmap(np.linspace(0.1, 1.0, 231))[:, :3]
    for name, colour in legend.items():
        assert np.min(np.linalg.norm(shades - np.array(colour), axis=1)) > 0.1, name
    # the overturned point and the one outside the model are painted in their legend colours there
    painted = slipped.collections[1]
    assert sorted(painted.get_array().compressed().tolist()) == [4, 5]
    assert {tuple(np.round(c[:3], 6)) for c in painted.get_facecolors()} >= {
        tuple(np.round(legend["overturned"], 6)), tuple(np.round(legend["outside the model"], 6))}
    assert not slipped.texts                      # something slid: no note
    shown = mesh.get_array()
    assert shown.max() == pytest.approx(30.0)      # |residual slip| [mm] of the standing blocks only


def test_a_sweep_where_nothing_slid_says_so_instead_of_an_empty_map():
    category = np.array([[0, 2], [4, 4]])
    fig = plots.sweep_figure([("mu", np.array([0.3, 0.5])), ("pga [g]", np.array([0.1, 0.2]))], category,
                             np.array([[0.0, 0.1], [1.5, 1.5]]), np.zeros((2, 2)), title="t")
    assert [t.get_text() for t in sweep_maps(fig)[2].texts] == ["residual slip below 0.001 mm everywhere"]
