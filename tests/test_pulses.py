"""Analytic pulses as ground motion: their shapes and sampling (`rockslide.pulses`), case files,
`rockslide run`, `rockslide sweep` over amplitude and period (overturning spectra) and their figure.

The closed-form checks of the response are in tests/test_pulse_closed_forms.py; the bad inputs in
tests/test_bad_input.py.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import REPO

from rockslide import pulses
from rockslide.analyses import sweep as sw
from rockslide.case import Pulse, case_to_dict, case_with, parse_case
from rockslide.cli import main
from rockslide.core import batch
from rockslide.core.simulate import ground_array, ground_series
from rockslide.engine import prepare as runner
from rockslide.io import results
from rockslide.plots import SPECTRUM_CATEGORIES, spectrum_category, spectrum_figure

EPS = pulses.INTERPOLATION_TOLERANCE


def intervals_of(pulse, max_step=1e-4):
    """``(t0, t1, a0, a1)`` of every interval of a sampled pulse at amplitude 1: start and end
    times [s] and values."""
    start, dt, h, _ = pulses.sample(pulse, None, max_step)
    k = np.arange(h.shape[1])
    return start + k * dt, start + (k + 1) * dt, h[0], h[1]


#: Each shape written out independently: (pulse, a(t) at amplitude 1 on 0 <= t <= L, L).
SHAPES = [
    (Pulse("rectangular", 1.0, duration=0.2), lambda t: np.ones_like(t), 0.2),
    (Pulse("half-sine", 1.0, duration=0.3), lambda t: np.sin(np.pi * t / 0.3), 0.3),
    (Pulse("one-sine", 1.0, period=0.4), lambda t: np.sin(2 * np.pi * t / 0.4), 0.4),
    (Pulse("cycloidal-a", 1.0, period=0.25, cycles=3), lambda t: np.sin(2 * np.pi * t / 0.25), 0.75),
    (Pulse("cycloidal-b", 1.0, period=0.5, cycles=2), lambda t: np.cos(2 * np.pi * t / 0.5), 1.0),
    (Pulse("ricker", 1.0, period=0.5),
     lambda t: (1 - 2 * (np.pi * (t - 0.5 * pulses.RICKER_CUT * 2 * 0.5) / 0.5) ** 2)
     * np.exp(-(np.pi * (t - pulses.RICKER_CUT * 0.5) / 0.5) ** 2), 2 * pulses.RICKER_CUT * 0.5),
]
IDS = [p.pulse for p, _, _ in SHAPES]


# ------------------------------------------------------------------------------------------------
# Shapes and sampling
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("pulse, exact, length", SHAPES, ids=IDS)
def test_samples_are_the_shape_with_its_ends_on_the_grid(pulse, exact, length):
    """The end values of every interval are the shape's values at the grid times (1e-13: the grid
    times differ from ``k L / N`` by rounding); zero before 0 and after ``L``; ``0`` and ``L`` are
    grid points; the step is at most the solver's."""
    t0, t1, a0, a1 = intervals_of(pulse)
    dt = t1[0] - t0[0]
    assert pulse.length == pytest.approx(length, rel=1e-15)
    assert dt <= 1e-4 and t0[0] == -dt and t1[-1] == pytest.approx(length, rel=1e-14)
    inside = (t0 >= -1e-12) & (t1 <= length * (1 + 1e-12))
    assert not inside[0] and inside[1:].all()
    assert a0[0] == a1[0] == 0.0
    np.testing.assert_allclose(a0[1:], exact(t0[1:]), rtol=0, atol=1e-13)
    np.testing.assert_allclose(a1[1:], exact(t1[1:]), rtol=0, atol=1e-13)


@pytest.mark.parametrize("pulse, exact, length", SHAPES, ids=IDS)
def test_linear_interpolation_within_the_tolerance(pulse, exact, length):
    """Between samples the core interpolates linearly: at the middle of every interval (where the
    error of a curved shape peaks) the error is at most `INTERPOLATION_TOLERANCE` of the amplitude
    (``D^2 max|a''| / 8``, the step chosen for it), and it is not needlessly small: the step is the
    largest allowed (at least a third of the bound, or the solver's step)."""
    t0, t1, a0, a1 = intervals_of(pulse)
    mid = 0.5 * (t0 + t1)[1:]
    error = np.abs(0.5 * (a0 + a1)[1:] - exact(mid)).max()
    assert error <= EPS * (1 + 1e-6)
    if pulse.curvature and pulse.max_step() < 1e-4:
        assert error > EPS / 3


def test_steps_are_exact_jumps_in_the_applied_ground():
    """A rectangular pulse jumps at 0 and at its end, and a type-B cycloidal pulse at both ends: in
    the ground written back (`ground_series`) each jump is a time given twice, the value before and
    after; a sine pulse ends at exactly 0 (no spurious jump of 1e-16)."""
    for pulse, jumps in ((Pulse("rectangular", 1.0, duration=0.2), [0.0, 0.2]),
                         (Pulse("cycloidal-b", 1.0, period=0.5), [0.0, 0.5]),
                         (Pulse("one-sine", 1.0, period=0.5), [])):
        start, dt, h, v = pulses.sample(pulse, None, 1e-4)
        t, ah, _ = ground_series(ground_array(h, v, dt, 0.1), dt, start)
        twice = np.flatnonzero(np.diff(t) == 0.0)
        np.testing.assert_allclose(t[twice], jumps, atol=1e-15)
        np.testing.assert_array_equal(ah[twice], [0.0, 1.0][:len(jumps)] if jumps else [])
        np.testing.assert_array_equal(ah[twice + 1], [1.0, 0.0][:len(jumps)] if jumps else [])


def test_two_pulses_share_one_grid():
    """A rectangular 0.2 s and a one-sine of 0.5 s: ratio 2/5, both ends on the grid; the shorter
    is zero after its end; lengths without a small common fraction are refused."""
    start, dt, h, v = pulses.sample(Pulse("rectangular", 1.0, duration=0.2),
                                    Pulse("one-sine", 1.0, period=0.5), 1e-4)
    assert h.shape == v.shape and h.shape[1] == round(0.5 / dt) + 1
    end = round(0.2 / dt)
    assert 0.2 / dt == pytest.approx(end, abs=1e-9)
    assert (h[:, 1:end + 1] == 1.0).all() and (h[:, end + 1:] == 0.0).all()
    with pytest.raises(ValueError, match="no common sampling step"):
        pulses.sample(Pulse("rectangular", 1.0, duration=0.2), Pulse("one-sine", 1.0, period=0.2 * math.sqrt(2)),
                      1e-4)


def test_one_sine_is_a_one_cycle_type_a_cycloidal_pulse():
    a = pulses.sample(Pulse("one-sine", 1.0, period=0.3), None, 1e-4)
    b = pulses.sample(Pulse("cycloidal-a", 1.0, period=0.3, cycles=1), None, 1e-4)
    np.testing.assert_array_equal(a.horizontal, b.horizontal)


def test_ricker_wavelet_peak_and_cut():
    """The Ricker wavelet peaks at the amplitude in its middle and is cut where it falls to the
    interpolation tolerance: a step of at most 1e-6 of the amplitude at both ends."""
    _, _, a0, a1 = intervals_of(Pulse("ricker", 1.0, period=0.4))
    assert np.max(np.abs(a0)) == pytest.approx(1.0, abs=EPS)
    assert 0.5 * EPS < abs(a0[1]) <= EPS and abs(a1[-1]) <= EPS


def test_small_angle_theory_is_housners_for_a_half_sine():
    """`pulses.linear_overturning_ratio` (the curve drawn over spectra) integrates the small-angle
    equation for any sampled shape. For a half-sine it must give Housner's closed form (derived in
    tests/test_pulse_closed_forms.py) to the accuracy of its 2000 samples, ``(pi / 2000)^2 / 8
    ~ 3e-7`` relative: 1e-6; for a rectangular pulse ``A / (g alpha) = 1 / (1 - exp(-p t_d))``
    (``q(t_d) = -alpha + (A / g)(1 - exp(-p t_d))``, ``p t_d = pi / beta``), exact: 1e-10."""
    from test_pulse_closed_forms import housner_half_sine_ratio

    for beta in (0.5, 1.0, 3.0, 8.0):
        ratio = pulses.linear_overturning_ratio(Pulse("half-sine", 1.0, duration=1.0), beta)
        assert ratio == pytest.approx(housner_half_sine_ratio(beta), rel=1e-6)
        ratio = pulses.linear_overturning_ratio(Pulse("rectangular", 1.0, duration=1.0), beta)
        assert ratio == pytest.approx(1.0 / (1.0 - math.exp(-math.pi / beta)), rel=1e-10)


# ------------------------------------------------------------------------------------------------
# Case files and `rockslide run`
# ------------------------------------------------------------------------------------------------

PULSE_CASE = """\
name: pulse
block:   {height: 0.2 m, width: 0.1 m, mass: 10 kg}
contact: {mu_static: 0.8, restitution: 0.8}
ground:
  horizontal: {pulse: rectangular, amplitude: 0.6 g, duration: 0.2 s}
  vertical:   {pulse: one-sine, amplitude: 0.2 g, period: 0.5 s}
  tail: 1 s
"""


def test_case_with_pulses_reads_and_round_trips():
    case = parse_case(PULSE_CASE)
    assert case.ground.horizontal == Pulse("rectangular", 0.6 * 9.80665, duration=0.2)
    assert case.ground.vertical == Pulse("one-sine", 0.2 * 9.80665, period=0.5)
    again = parse_case(__import__("yaml").safe_dump(case_to_dict(case, case_file=True)))
    assert again.ground == case.ground
    changed = case_with(case, {"ground.horizontal.amplitude": "1 g", "ground.horizontal.duration": "0.1 s"})
    assert changed.ground.horizontal == Pulse("rectangular", 9.80665, duration=0.1)


@pytest.mark.parametrize("case_text", [PULSE_CASE, (REPO / "configs" / "example.yaml").read_text()],
                         ids=["pulses", "records"])
def test_the_announced_work_is_the_steps_the_run_takes(case_text):
    """`runner.work` (behind the "up to about" note and the free-space check) counts the RK4 steps
    a run takes: the intervals of the applied ground, tail included, times the substeps. A pulse's
    ground is interval end values (2, n), whose size once counted twice the intervals."""
    case = parse_case(case_text, base_dir=REPO / "configs")
    prepared = runner.prepare(case)
    ground = ground_array(prepared.ground.horizontal, prepared.ground.vertical, prepared.ground.dt,
                          prepared.settings.tail)
    assert runner.work(prepared).steps == ground.shape[1] * round(prepared.ground.dt / prepared.settings.dt)


def test_run_writes_the_pulses_with_their_jumps(tmp_path):
    """`rockslide run` on a case file with pulses: the ground written back is the pulses at their
    amplitudes, the rectangular steps at 0 and 0.2 s given as repeated times, the case's pulse keys
    stored; the summary is that of the core on the same ground (`runner.run_case`)."""
    (tmp_path / "pulse.yaml").write_text(PULSE_CASE)
    done = CliRunner().invoke(main, ["run", str(tmp_path / "pulse.yaml"), "--out-dir", str(tmp_path), "--json"])
    assert done.exit_code == 0, done.output
    with h5py.File(tmp_path / "pulse.h5") as f:
        t, ah, av = f["ground/time"][:], f["ground/horizontal"][:], f["ground/vertical"][:]
        stored = dict(f["case"].attrs)
    twice = np.flatnonzero(np.diff(t) == 0.0)
    np.testing.assert_allclose(t[twice], [0.0, 0.2], atol=1e-15)
    np.testing.assert_array_equal(ah[twice], [0.0, 0.6 * 9.80665])
    np.testing.assert_array_equal(ah[twice + 1], [0.6 * 9.80665, 0.0])
    assert av.max() == pytest.approx(0.2 * 9.80665, rel=EPS) and t[-1] == pytest.approx(1.5, abs=1e-4)
    assert stored["ground.horizontal.pulse"] == "rectangular" and stored["ground.vertical.period"] == 0.5
    _, result = runner.run_case(parse_case(PULSE_CASE), history=False)
    summary = results.read_result(tmp_path / "pulse.h5").result.summary
    assert (summary.max_rotation, summary.impacts) == (result.summary.max_rotation, result.summary.impacts)
    assert (tmp_path / "pulse.png").is_file()


# ------------------------------------------------------------------------------------------------
# Sweeps: overturning spectra
# ------------------------------------------------------------------------------------------------

#: The shipped spectrum case (make spectrum), named "spectrum".
SPECTRUM_CASE = (REPO / "configs" / "spectrum-one-sine.yaml").read_text().replace(
    "name: spectrum-one-sine", "name: spectrum")


@pytest.fixture(scope="module")
def spectrum(tmp_path_factory):
    """A small overturning spectrum through the command line: 4 amplitudes x 3 periods (three
    records of different sampling steps in one batch)."""
    folder = tmp_path_factory.mktemp("spectrum")
    (folder / "spectrum.yaml").write_text(SPECTRUM_CASE)
    done = CliRunner().invoke(main, ["sweep", str(folder / "spectrum.yaml"), "--amplitude", "0.5g,1g,1.5g,2.2g",
                                     "--period", "0.12,0.6,1.5", "--out-dir", str(folder), "--no-progress"])
    assert done.exit_code == 0, done.output
    return folder


def test_spectrum_points_equal_rockslide_run(spectrum):
    """Every point of the grid equals `rockslide run` of the case with its amplitude and period,
    to the last bit: the amplitude is the scale factor of the pulse sampled at amplitude 1, as run
    multiplies it. The sweep records how each overturning came about."""
    stored = results.read_sweep(spectrum / "spectrum.sweep.h5")
    (_, amplitudes, _), (_, periods, _) = stored.coords
    case = parse_case(SPECTRUM_CASE)
    modes = set()
    for i, a in enumerate(amplitudes):
        for j, period in enumerate(periods):
            point = case_with(case, {"ground.horizontal.amplitude": f"{float(a)!r} m/s^2",
                                     "ground.horizontal.period": f"{float(period)!r} s"})
            summary = runner.run_case(point, history=False)[1].summary
            value = {name: stored.variables[name][0][i, j] for name in stored.variables}
            assert value["overturned"] == summary.overturned
            assert value["max_rotation"] == summary.max_rotation and value["impacts"] == summary.impacts
            assert value["end_time"] == summary.end_time
            expected = 0 if not summary.overturned else (1 if summary.impacts == 0 else 2)
            assert value["overturn_mode"] == expected
            modes.add(expected)
    assert modes == {0, 1, 2}


def test_spectrum_file_and_figure(spectrum):
    """The file carries the spectrum's scales (p, g tan(alpha), ...) and the figure is the
    dimensionless spectrum; `rockslide plot` draws it again from the file alone."""
    stored = results.read_sweep(spectrum / "spectrum.sweep.h5")
    p = math.sqrt(0.75 * 9.80665 / math.hypot(0.125, 0.5))
    assert stored.attrs["spectrum_rocking_frequency"] == pytest.approx(p, rel=1e-15)
    assert stored.attrs["spectrum_liftoff_acceleration"] == pytest.approx(0.25 * 9.80665, rel=1e-15)
    assert stored.attrs["spectrum_pulse"] == "one-sine"
    figure = sw.stored_figure(stored)
    regions = next(ax for ax in figure.axes if ax.get_label() == "regions")
    assert "ω_p / p" in regions.get_xlabel() and "a_p / (g tan α)" in regions.get_ylabel()
    lines = [line.get_label() for line in figure.legends[0].get_lines()]
    assert any("small-angle theory" in label for label in lines)
    done = CliRunner().invoke(main, ["plot", str(spectrum / "spectrum.sweep.h5"), "-o", str(spectrum / "again.png")])
    assert done.exit_code == 0 and (spectrum / "again.png").stat().st_size > 10_000


def test_duration_sweep_of_a_rectangular_pulse(tmp_path):
    """``--duration`` on a rectangular pulse: the points straddling the critical duration of
    tests/test_pulse_closed_forms.py fall on both sides of it."""
    from test_pulse_closed_forms import critical_duration

    text = SPECTRUM_CASE.replace("{pulse: one-sine, amplitude: 1.0 g, period: 0.5 s}",
                                 "{pulse: rectangular, amplitude: 0.5 g, duration: 0.2 s}")
    assert "rectangular" in text
    case = parse_case(text, source="rect.yaml")
    R, alpha = math.hypot(0.125, 0.5), math.atan(0.25)
    td = critical_duration(0.5 * 9.80665, alpha, R)
    axes = [sw.parse_axis("duration", f"{0.999 * td!r},{1.001 * td!r}")]
    plan = sw.plan_sweep(case, axes)
    states = batch.compute(plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
                           plan.factor_v)
    variables = sw.sweep_variables(plan, states)
    np.testing.assert_array_equal(variables["overturn_mode"][0], [0, 1])


@pytest.mark.parametrize("case, axis, message", [
    ("configs/example.yaml", ["--amplitude", "1g"],
     "--amplitude: applies to a case whose ground.horizontal is a pulse"),
    ("spectrum", ["--pga", "500gal"], "--pga: scales record files; a pulse is scaled by its amplitude"),
    ("spectrum", ["--duration", "0.2"], "--duration: ground.horizontal.duration: a one-sine pulse takes period"),
])
def test_pulse_axes_on_the_wrong_case(tmp_path, case, axis, message):
    path = REPO / case if case.endswith(".yaml") else tmp_path / "spectrum.yaml"
    if not case.endswith(".yaml"):
        path.write_text(SPECTRUM_CASE)
    done = CliRunner().invoke(main, ["sweep", str(path), *axis, "--out-dir", str(tmp_path), "--no-progress",
                                     "--records-dir", str(REPO / "records")])
    assert done.exit_code == 2 and message in done.stderr, done.stderr


def test_spectrum_categories_and_figure_shapes():
    """Precedence of the regions: outside the model, overturned (without / after impact), rocking
    (lifted off, slipping or not), sliding (upright slip only), no liftoff."""
    overturned = np.array([0, 0, 0, 0, 1, 1, 1])
    status = np.array([0, 0, 0, 0, 0, 0, 1])
    modes = np.array([0, 1, 2, 5, 2, 2, 2])
    impacts = np.array([0, 0, 3, 1, 0, 2, 0])
    codes = spectrum_category(overturned, status, modes, impacts)
    assert [SPECTRUM_CATEGORIES[c] for c in codes] == [
        "no liftoff", "sliding", "rocking", "rocking", "overturning without impact", "overturning with impact",
        "outside the model"]
    with pytest.raises(ValueError, match="expected maps of shape"):
        spectrum_figure([1.0, 2.0], [1.0], np.zeros((2, 2)), np.zeros((2, 2)))


# ------------------------------------------------------------------------------------------------
# A computation that ends while the block still moves: "undecided", not "standing"
# ------------------------------------------------------------------------------------------------

#: The helper's case of the new-user review: a 1 m x 0.25 m block, a 0.6 g rectangular pulse of
#: 0.2 s and no tail. At 0.2 s it rocks at about 1 rad/s; with a tail it overturns at 0.99 s.
UNDECIDED_CASE = """\
name: pn
block:   {height: 1.0 m, width: 0.25 m, mass: 100 kg}
contact: {mu_static: 0.7, restitution: 0.912}
ground:
  horizontal: {pulse: rectangular, amplitude: AMPLITUDE, duration: 0.2 s}
  tail: TAIL
"""


def test_a_block_moving_at_the_end_with_the_energy_to_overturn_is_undecided(tmp_path):
    """Without a tail the run ends at the pulse's end with the block rocking: the verdict is
    'undecided' (in the printout, --json and the file), because the same case with a tail
    overturns; a weaker pulse that leaves less energy than the potential energy at alpha,
    g R (1 - cos alpha) per kg, is 'standing' although the block still moves, and stands with a
    tail too."""
    def run(amplitude, tail, out):
        text = UNDECIDED_CASE.replace("AMPLITUDE", amplitude).replace("TAIL", tail)
        (tmp_path / f"{out}.yaml").write_text(text)
        done = CliRunner().invoke(main, ["run", str(tmp_path / f"{out}.yaml"), "--out-dir", str(tmp_path / out),
                                         "--no-plot", "--json"])
        assert done.exit_code == 0, done.output
        return json.loads(done.stdout), results.read_result(tmp_path / out / "pn.h5").result.summary

    short, stored = run("0.6 g", "0 s", "short")
    assert short["undecided"] and stored.undecided and not short["overturned"]
    assert short["verdict"].startswith("undecided: still moving at the end (t = 0.2000 s)")
    R, alpha = math.hypot(0.125, 0.5), math.atan(0.25)
    barrier = 100 * 9.80665 * R * (1 - math.cos(alpha))              # [J]
    assert short["energy"]["kinetic"] + short["energy"]["potential"] > barrier
    assert run("0.6 g", "5 s", "long")[0]["overturned"]

    weak, _ = run("0.3 g", "0 s", "weak")              # lifts off (0.3 g > g tan(alpha) = 0.25 g)
    assert weak["states_seen"][-1] == "ROCK" and weak["end_time"] == pytest.approx(0.2)
    assert weak["energy"]["kinetic"] > 0 and weak["energy"]["kinetic"] + weak["energy"]["potential"] < barrier
    assert not weak["undecided"] and weak["verdict"] == "standing"
    assert not run("0.3 g", "5 s", "weak-long")[0]["overturned"]


def test_a_sweep_counts_its_undecided_cases(tmp_path):
    """The sweep file's ``undecided`` is the run's for every point: amplitudes around the two of
    the test above, no tail."""
    text = UNDECIDED_CASE.replace("AMPLITUDE", "0.6 g").replace("TAIL", "0 s")
    case = parse_case(text, source="pn.yaml")
    plan = sw.plan_sweep(case, [sw.parse_axis("amplitude", "0.3g,0.45g,0.6g,0.8g")])
    states = batch.compute(plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
                           plan.factor_v)
    variables = sw.sweep_variables(plan, states)
    for i, amplitude in enumerate(["0.3 g", "0.45 g", "0.6 g", "0.8 g"]):
        _, result = runner.run_case(parse_case(UNDECIDED_CASE.replace("AMPLITUDE", amplitude).replace(
            "TAIL", "0 s")), history=False)
        assert variables["undecided"][0][i] == result.summary.undecided, amplitude
    assert variables["undecided"][0][0] == 0 and variables["undecided"][0][2] == 1     # the test above's two
    done = CliRunner().invoke(main, ["sweep", str(_write(tmp_path, "pn.yaml", text)), "--amplitude", "0.6g",
                                     "--out-dir", str(tmp_path), "--no-plot", "--no-progress"])
    assert done.exit_code == 0, done.output
    assert "1 undecided: still moving at the end with the energy to overturn" in done.output


def _write(folder, name, text):
    (folder / name).write_text(text)
    return folder / name


def test_the_printout_gives_the_peaks_of_a_pulse(tmp_path):
    """'ground as applied' names the pulse's peaks (0.6 g = 588.4 gal), not 'still'."""
    text = UNDECIDED_CASE.replace("AMPLITUDE", "0.6 g").replace("TAIL", "1 s")
    done = CliRunner().invoke(main, ["run", str(_write(tmp_path, "pn.yaml", text)), "--out-dir", str(tmp_path),
                                     "--no-plot"])
    assert done.exit_code == 0, done.output
    assert "  ground as applied: peaks 588.4 gal (0.6 g) H, 0 gal (0 g) V (analytic pulses, not scaled)" in done.output


def test_a_block_sliding_at_the_end_that_friction_cannot_tip_is_standing(tmp_path):
    """A squat block (1 m wide, 0.5 m high: tan(alpha) = 2) driven by a 1 g rectangular pulse with
    mu = 0.3 slides at about (1 - 0.3) g x 0.5 s = 3.4 m/s when the pulse ends: 5.9 J/kg of kinetic
    energy, more than the 3.0 J/kg it takes to lift the centre of gravity over the edge, but on
    still ground friction (nu = 0.3 < tan(alpha), eq. 23) cannot lift it off: it slides to a
    stop. 'standing', as the same case with a tail shows."""
    text = """\
name: squat
block:   {height: 0.5 m, width: 1.0 m, mass: 1 kg}
contact: {mu_static: 0.3, restitution: 0.8}
ground:
  horizontal: {pulse: rectangular, amplitude: 1 g, duration: 0.5 s}
  tail: TAIL
"""
    _, short = runner.run_case(parse_case(text.replace("TAIL", "0 s")), history=False)
    s = short.summary
    R, alpha = math.hypot(0.5, 0.25), math.atan(2.0)
    assert s.states_seen == ["REST", "SLIP"] and s.energy["kinetic"] > 9.80665 * R * (1 - math.cos(alpha))
    assert not s.undecided and s.verdict == "standing"
    _, long = runner.run_case(parse_case(text.replace("TAIL", "3 s")), history=False)
    assert not long.summary.overturned and long.summary.time_in_state["ROCK"] == 0.0
