"""Floor motions (`rockslide.core.intensity.floor_acceleration`) against closed forms.

The floor of a linear building is the absolute acceleration of its modes on the ground record,
stepped with the exact recurrence of `core.intensity` (Nigam & Jennings 1969). The checks here come
from the equation of motion, not from the code: the harmonic steady state's transmissibility, the
stiff limit, and the undamped identity PFA = Sa.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np
import pytest
import yaml
from conftest import REPO, invoke, one_line_error

from rockslide.analyses import fragility as fr
from rockslide.case import case_with, load_case
from rockslide.core import intensity as im
from rockslide.core import kernel as K
from rockslide.engine import prepare as runner


def transmissibility(r: float, zeta: float) -> float:
    """|a_abs / a_g| in the harmonic steady state: sqrt((1 + (2 z r)^2) / ((1 - r^2)^2 + (2 z r)^2))."""
    return math.sqrt((1 + (2 * zeta * r) ** 2) / ((1 - r * r) ** 2 + (2 * zeta * r) ** 2))


@pytest.mark.parametrize("r, expected", [(0.5, 1.332042), (1.0, 10.049876), (2.0, 0.339182)])
def test_harmonic_steady_state_amplitude(r, expected):
    """Ground ``sin(W t)`` under a floor of period 0.2 s at 5 %: after the transient has decayed
    (``exp(-zeta w t)`` < 1e-6 at t = 9 s) the floor's amplitude over the ground's is the
    transmissibility (the values are the issue's, computed independently). The sampled sine is
    piecewise linear: its fundamental is ``sinc^2(W dt / 2)`` ~ 1 - (W dt)^2 / 12 of the sine, 8e-7
    at W dt = 0.003, well inside the 1e-4 asked."""
    assert transmissibility(r, 0.05) == pytest.approx(expected, rel=1e-6)
    period, zeta = 0.2, 0.05
    forcing = r * 2 * math.pi / period
    dt = 0.003 / forcing
    t = dt * np.arange(int(16.0 / dt))
    floor, step = im.floor_acceleration(np.sin(forcing * t), dt, [(period, zeta, 1.0)])
    times = step * np.arange(floor.size)
    late = times > 12.0
    basis = np.stack([np.sin(forcing * times[late]), np.cos(forcing * times[late])], axis=1)
    coefficients, *_ = np.linalg.lstsq(basis, floor[late], rcond=None)
    assert math.hypot(*coefficients) == pytest.approx(expected, rel=1e-4)


def ground_record(n=2001, dt=0.01, seed=3):
    """A broadband record (filtered noise under a Hann window, so it starts and ends at 0), smooth
    enough that a stiff floor follows it."""
    rng = np.random.default_rng(seed)
    kernel = np.hanning(25)
    return np.hanning(n) * np.convolve(rng.normal(size=n), kernel / kernel.sum(), mode="same"), dt


def test_a_stiff_building_returns_the_ground_motion():
    """T -> 0: the floor's absolute acceleration tends to the ground's, with a lag ``2 zeta / w``
    (1.6e-5 s at T = 1 ms): its relative effect is ~ (2 zeta / w) max|a'| / max|a| < 1e-3 here."""
    a, dt = ground_record()
    floor, step = im.floor_acceleration(a, dt, [(0.001, 0.05, 1.0)])
    m = round(dt / step)
    assert step == pytest.approx(dt / m, rel=1e-15) and m == im.substeps_for(dt, 0.001)
    assert np.max(np.abs(floor[::m] - a)) <= 1e-3 * np.max(np.abs(a))


def test_no_mode_and_zero_participation_are_the_ground():
    a, dt = ground_record()
    floor, step = im.floor_acceleration(a, dt, [])
    assert step == dt and np.array_equal(floor, a)
    floor, step = im.floor_acceleration(a, dt, [(0.5, 0.05, 0.0)])
    assert np.max(np.abs(floor[::round(dt / step)] - a)) <= 1e-14 * np.max(np.abs(a))


@pytest.mark.parametrize("period", [0.1, 0.5, 2.0])
def test_pfa_of_an_undamped_floor_is_sa(period):
    """zeta = 0: the absolute acceleration is ``-w^2 u`` exactly, so PFA = Sa (the spectrum's own
    pseudo-acceleration) to round-off."""
    a, dt = ground_record()
    floor, _ = im.floor_acceleration(a, dt, [(period, 0.0, 1.0)])
    assert np.max(np.abs(floor)) == pytest.approx(im.spectral_acceleration(a, dt, period, 0.0), rel=1e-12)


@pytest.mark.parametrize("period", [0.1, 0.5, 2.0])
def test_pfa_is_the_absolute_acceleration_spectrum(period):
    """One mode of unit participation: PFA = max|a + u''| of the spectrum's oscillator, seen at the
    same steps; at 5 % it differs from Sa by O(zeta) (bounded by 2 zeta w max|u'| / Sa < 25 %)."""
    a, dt = ground_record()
    floor, _ = im.floor_acceleration(a, dt, [(period, 0.05, 1.0)])
    pfa = np.max(np.abs(floor))
    assert pfa == pytest.approx(im.spectral_absolute_acceleration(a, dt, period, 0.05), rel=1e-12)
    assert pfa == pytest.approx(im.spectral_acceleration(a, dt, period, 0.05), rel=0.25)


def test_modes_superpose():
    """``a_f = a_g + sum p_i u_i''``: two modes at once are the sum of their contributions, each
    seen at the finer steps of the faster mode (exact at any step, so no interpolation error)."""
    a, dt = ground_record()
    both, step = im.floor_acceleration(a, dt, [(1.0, 0.05, 1.3), (0.2, 0.03, -0.4)])
    first, step1 = im.floor_acceleration(a, dt, [(1.0, 0.05, 1.3)])
    second, step2 = im.floor_acceleration(a, dt, [(0.2, 0.03, -0.4)])
    assert step == step2 < step1
    m = round(dt / step)
    ground = both[::m] - (first[::round(dt / step1)] - a) - (second[::m] - a)
    assert np.max(np.abs(ground - a)) <= 1e-12 * np.max(np.abs(both))


# --------------------------------------------------------------------------------------------------
# A case on a floor: ground.floor through the engine, the result file and the command
# --------------------------------------------------------------------------------------------------

EXAMPLE = REPO / "configs" / "example.yaml"
MODES = {"horizontal": [{"period": "0.6 s", "participation": 1.3}, {"period": 0.2, "damping": 0.03,
                                                                    "participation": -0.4}],
         "vertical": {"period": "0.08 s"}}


def test_the_block_stands_on_the_floor_and_the_base_is_the_ground():
    case = load_case(EXAMPLE)
    plain = runner.prepare(case)
    on_floor = runner.prepare(case_with(case, {"ground.floor": MODES}))
    base, floor = on_floor.base, on_floor.ground
    assert plain.base is None
    np.testing.assert_array_equal(base.horizontal, plain.ground.horizontal)      # scaled as without a floor
    m = im.substeps_for(base.dt, 0.08)                                           # the fastest mode decides
    assert floor.dt == pytest.approx(base.dt / m, rel=1e-15)
    n_tail = math.ceil(case.ground.tail / base.dt - 1e-9)       # the floor moves on over the case's tail
    assert floor.horizontal.size == (base.horizontal.size + n_tail - 1) * m + 1
    still = np.zeros(n_tail)
    expected, _ = im.floor_acceleration(np.concatenate([base.horizontal, still]), base.dt,
                                        [(0.6, 0.05, 1.3), (0.2, 0.03, -0.4)], m)
    np.testing.assert_array_equal(floor.horizontal, expected)
    vertical, _ = im.floor_acceleration(np.concatenate([base.vertical, still]), base.dt, [(0.08, 0.05, 1.0)], m)
    np.testing.assert_array_equal(floor.vertical, vertical)


def test_the_floor_moves_on_over_the_tail():
    """A building still moves when the ground stops: with ``ground.tail`` the floor's motion runs
    on over the tail as its modes' free vibration (the floor of the record padded with still
    ground, computed independently here), and the run adds no still samples after it, so that it
    ends, as without a floor, a tail after the record. A long, lightly damped mode on a record cut
    short keeps moving: without this the block met a step in the floor's motion at the record's end."""
    from rockslide.analyses import sweep as sw

    case = case_with(load_case(EXAMPLE), {"ground.floor.horizontal": {"period": "2 s", "damping": 0.02},
                                          "ground.tail": "3 s"})
    prepared = runner.prepare(case)
    base, floor = prepared.base, prepared.ground
    n_tail = math.ceil(3.0 / base.dt - 1e-9)
    m = round(base.dt / floor.dt)
    still = np.concatenate([base.horizontal, np.zeros(n_tail)])
    expected, _ = im.floor_acceleration(still, base.dt, [(2.0, 0.02, 1.0)], m)
    np.testing.assert_array_equal(floor.horizontal, expected)
    assert prepared.settings.tail == 0.0
    over_tail = floor.horizontal[(base.horizontal.size - 1) * m + 1:]
    assert np.max(np.abs(over_tail)) > 0.05 * np.max(np.abs(floor.horizontal))      # it still moves
    result = runner.simulate_prepared(prepared)
    end = base.start + (base.horizontal.size - 1 + n_tail) * base.dt
    assert result.ground_time[-1] == pytest.approx(end, abs=1e-9)   # a tail after the record, as without floor
    plan = sw.plan_sweep(case, [sw.parse_axis("mu", "0.52")], records_dir=REPO / "records")
    n = floor.horizontal.size - 1
    assert int(plan.count[0]) == n                                  # the sweep's input: the same, no second tail
    np.testing.assert_allclose(plan.factor_h[0] * plan.base[0, :n], floor.horizontal[:n], rtol=0,
                               atol=1e-12 * np.max(np.abs(floor.horizontal)))


def test_screening_multiplies_the_ground_by_one_plus_two_z_over_h():
    case = load_case(EXAMPLE)
    screened = runner.prepare(case_with(case, {"ground.floor.z_over_h": 0.75}))
    np.testing.assert_array_equal(screened.ground.horizontal, 2.5 * screened.base.horizontal)
    assert "screening only" in runner.floor_text(screened.case)


def test_the_result_file_keeps_the_ground_and_the_floor(tmp_path):
    case = tmp_path / "cabinet.yaml"
    text = EXAMPLE.read_text().replace("../records/", str(REPO / "records") + "/")
    case.write_text(text.replace("  tail: 2 s", "  tail: 2 s\n  floor: {horizontal: {period: 0.5 s}}"))
    result = invoke("run", case, "--out-dir", tmp_path, "--no-plot")
    assert result.exit_code == 0, result.output
    assert "floor of a linear building: horizontal T = 0.5 s" in result.output and "PFA" in result.output
    as_json = invoke("run", case, "--out-dir", tmp_path, "--no-plot", "--overwrite", "--json")
    floor_json = json.loads(as_json.stdout)["floor"]
    plain = runner.prepare(load_case(EXAMPLE)).ground
    with h5py.File(tmp_path / "example.h5") as f:
        np.testing.assert_array_equal(f["base/horizontal"][()], plain.horizontal)
        assert f["base/horizontal"].attrs["units"] == "m/s^2"
        floor = f["ground/horizontal"][()]
    n = plain.horizontal.size
    assert np.max(np.abs(floor[:n])) > np.max(np.abs(plain.horizontal))   # a 0.5 s floor amplifies this record
    assert floor_json["pfa"] == im.peak_acceleration(floor) and floor_json["pga_base"] == im.peak_acceleration(
        plain.horizontal)
    assert floor_json["pfv"] == pytest.approx(im.peak_velocity(floor, 0.01 / im.substeps_for(0.01, 0.5)), rel=1e-9)


@pytest.mark.parametrize("floor, part", [
    ({"z_over_h": 0.5, "horizontal": {"period": 1.0}}, "give z_over_h or modes"),
    ({"horizontal": {"period": "0 s"}}, "ground.floor.horizontal.period"),
    ({"horizontal": [{"period": 1.0}, {"periode": 1.0}]}, "ground.floor.horizontal[1].periode"),
    ({"z_over_h": 1.5}, "ground.floor.z_over_h"),
])
def test_bad_floors_are_one_line(tmp_path, floor, part):
    data = yaml.safe_load(EXAMPLE.read_text())
    data["ground"]["floor"] = floor
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    one_line_error(invoke("run", path, "--out-dir", tmp_path), part)


def test_a_pulse_under_a_floor_is_refused(tmp_path):
    path = tmp_path / "pulse.yaml"
    path.write_text((REPO / "rockslide" / "spectrum-one-sine.yaml").read_text().replace(
        "ground:", "ground:\n  floor: {horizontal: {period: 0.5 s}}", 1))
    one_line_error(invoke("run", path, "--out-dir", tmp_path), "ground.floor", "analytic pulse")


def test_fragility_levels_of_pfa_are_the_peaks_of_each_runs_floor():
    """``--im pfa``: each record's floor motion is scaled so that its peak is the level; `rockslide run`
    of a run's case (`point_case`: the ground scaled, then filtered) has that PFA to round-off (the
    filter is linear), while its PGA is the ground's."""
    case = case_with(load_case(EXAMPLE), {"ground.floor": {"horizontal": {"period": 0.4, "participation": 1.2}}})
    im_pfa = fr.parse_im("pfa")
    fplan = fr.plan_fragility(case, fr.suite_from(str(REPO / "records" / "suite-synthetic.yaml")), im_pfa,
                              fr.parse_levels("0.5g,1g", im_pfa), records_dir=REPO / "records")
    for record in (0, 3):
        for level, value in enumerate((0.5 * 9.80665, 9.80665)):
            prepared = runner.prepare(fr.point_case(fplan, record, level))
            assert im.peak_acceleration(prepared.ground.horizontal) == pytest.approx(value, rel=1e-12)
            assert im.peak_acceleration(prepared.base.horizontal) < value      # the 0.4 s floor amplifies
        assert fplan.measures["im"][record] > fplan.measures["pga"][record]


def test_pfa_of_a_case_without_floor_is_its_record_peak():
    """A floor record read as it is (a COSMOS file of a building's floor): PFA is its PGA."""
    fplan = fr.plan_fragility(load_case(EXAMPLE), fr.suite_from(str(REPO / "records" / "suite-synthetic.yaml")),
                              fr.parse_im("pfa"), fr.parse_levels("0.5g", fr.parse_im("pfa")),
                              records_dir=REPO / "records")
    np.testing.assert_array_equal(fplan.measures["im"], fplan.measures["pga"])


def test_a_sweep_runs_the_block_on_the_floor():
    """`rockslide sweep` of a case on a floor: its kernel input is the floor's motion (`floor_ground`)
    scaled, as `rockslide run` of each point has it (to round-off: the filter is linear)."""
    from rockslide.analyses import sweep as sw

    case = case_with(load_case(EXAMPLE), {"ground.floor": {"horizontal": {"period": 0.4, "participation": 1.2}}})
    plan = sw.plan_sweep(case, [sw.parse_axis("pga", "200gal,400gal")], records_dir=REPO / "records")
    for i, pga in enumerate((2.0, 4.0)):
        point = runner.prepare(case_with(case, {"ground.scale.pga_horizontal": pga})).ground
        n = point.horizontal.size - 1                      # base row 0: each interval's starting value
        assert plan.case_column(K.P_STEP)[i] <= point.dt
        np.testing.assert_allclose(plan.factor_h[i] * plan.base[0, :n], point.horizontal[:n], rtol=0,
                                   atol=1e-12 * np.max(np.abs(point.horizontal)))


def test_a_floor_period_axis_runs_each_point_on_its_own_floor():
    """``--floor-period``: the case's first mode takes each period (its other modes kept); each point's
    kernel input is its own floor's motion, at its own step, as `rockslide run` of the point has it."""
    from rockslide.analyses import sweep as sw

    case = case_with(load_case(EXAMPLE), {"ground.floor": MODES})
    plan = sw.plan_sweep(case, [sw.parse_axis("floor_period", "0.3s,1.2s")], records_dir=REPO / "records")
    assert len(set(plan.first)) == 2
    for i, period in enumerate((0.3, 1.2)):
        point = case_with(case, {"ground.floor.horizontal": [{**MODES["horizontal"][0], "period": period},
                                                             MODES["horizontal"][1]]})
        ground = runner.prepare(point).ground
        n = ground.horizontal.size - 1
        assert plan.case_column(K.P_STEP)[i] <= ground.dt
        np.testing.assert_allclose(plan.factor_h[i] * plan.base[0, plan.first[i]:plan.first[i] + n],
                                   ground.horizontal[:n], rtol=0, atol=1e-12 * np.max(np.abs(ground.horizontal)))
    one = sw.plan_sweep(load_case(EXAMPLE), [sw.parse_axis("floor_period", "0.5s")], records_dir=REPO / "records")
    single = runner.prepare(case_with(load_case(EXAMPLE), {"ground.floor.horizontal": {"period": 0.5}})).ground
    n = single.horizontal.size - 1                       # a case without floor gets one of one mode
    np.testing.assert_allclose(one.factor_h[0] * one.base[0, :n], single.horizontal[:n], rtol=0,
                               atol=1e-12 * np.max(np.abs(single.horizontal)))


# --------------------------------------------------------------------------------------------------
# Figures of a block on a floor: the caption says the floor, the overlay says which run is on one
# --------------------------------------------------------------------------------------------------

def _figure_texts(fig) -> str:
    from matplotlib.text import Text

    fig.canvas.draw()
    return " ".join(t.get_text() for t in fig.findobj(Text) if t.get_text()).replace("\n", " ")


def test_floor_text_is_one_implementation_in_case_py():
    """`rockslide run`'s printout (engine.prepare) and the figures' captions use case.py's."""
    from rockslide import case as case_module

    assert runner.floor_text is case_module.floor_text
    on_floor = case_with(load_case(EXAMPLE), {"ground.floor": MODES})
    # the values of MODES above; zeta 0.05 and participation 1 are Mode's defaults
    assert case_module.floor_text(on_floor, brief=True) == (
        "on a floor: H T = 0.6 s (ζ = 0.05, Γφ = 1.3), T = 0.2 s (ζ = 0.03, Γφ = -0.4), "
        "V T = 0.08 s (ζ = 0.05, Γφ = 1)")
    screened = case_with(load_case(EXAMPLE), {"ground.floor.z_over_h": 0.75})
    assert "× 2.5 (1 + 2 z/h, z/h = 0.75)" in case_module.floor_text(screened, brief=True)
    assert case_module.floor_text(load_case(EXAMPLE)) is None


def test_a_floor_run_and_a_ground_run_overlaid_say_which_is_which(tmp_path):
    """``rockslide plot ground.h5 floor.h5``: the floor's modes in the caption, ``NAME (floor)`` in
    the legend, and the acceleration panel labelled for both (it drew the floor as "ground")."""
    from rockslide import plots
    from rockslide.api import plot_results, read_result

    text = EXAMPLE.read_text().replace("../records/", str(REPO / "records") + "/")
    (tmp_path / "ground.yaml").write_text(text.replace("name: example", "name: on-ground"))
    (tmp_path / "floor.yaml").write_text(text.replace("name: example", "name: on-floor").replace(
        "  tail: 2 s", "  tail: 2 s\n  floor: {horizontal: {period: 0.5 s, damping: 0.04}}"))
    for name in ("ground", "floor"):
        result = invoke("run", tmp_path / f"{name}.yaml", "--out-dir", tmp_path, "--no-plot")
        assert result.exit_code == 0, result.output
    floor_caption = plots.run_caption(read_result(tmp_path / "on-floor.h5"))
    assert "on a floor: H T = 0.5 s (ζ = 0.04, Γφ = 1)" in floor_caption          # the case written above
    assert "floor" not in plots.run_caption(read_result(tmp_path / "on-ground.h5"))
    fig = plot_results([tmp_path / "on-ground.h5", tmp_path / "on-floor.h5"], size="column")
    (legend,) = fig.legends
    names = [t.get_text().split(":")[0] for t in legend.get_texts()]
    assert names[:2] == ["on-ground", "on-floor (floor)"]
    panel = next(ax for ax in fig.axes if ax.get_label() == "ground")
    assert panel.get_ylabel().startswith("floor / ground [")          # column: the brief label
    assert "on a floor: H T = 0.5 s" in _figure_texts(fig)
    only_floor = plot_results([tmp_path / "on-floor.h5", tmp_path / "on-floor.h5"], names=["a", "b"])
    assert next(ax for ax in only_floor.axes if ax.get_label() == "ground").get_ylabel().startswith("floor acc.")
    # one run read back: its floor in colour over the ground under the building in grey (it drew it as "ground")
    alone = plot_results([tmp_path / "on-floor.h5"])
    assert next(ax for ax in alone.axes if ax.get_label() == "ground").get_ylabel().startswith("floor")
    lines = [line.get_label() for ax in alone.axes for line in ax.get_lines()]
    assert "ground horizontal (under the building)" in lines
