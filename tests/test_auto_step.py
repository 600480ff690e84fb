"""``solver.dt: auto``: the step chosen from a tolerance (rockslide.engine.step), against exact solutions.

Free rocking with elastic impacts (e = 1) has its impacts at odd multiples of the quarter period T
(tests/rocking_reference.py, a quadrature to 1e-13): the tolerance on event times is checked
against that exact solution, not against the pilot's own estimate.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from rocking_reference import quarter_period

from rockslide.case import case_to_dict, case_with, parse_case
from rockslide.core import layout as L
from rockslide.engine import step as S
from rockslide.engine.prepare import prepare, simulate_prepared
from rockslide.errors import CaseError

FREE = """
name: free
block: {{height: {height} m, width: {width} m, mass: 1 kg}}
contact: {{mu_static: 10, restitution: 1.0}}
ground: {{tail: {tail} s}}
initial: {{rotation: {theta0} rad}}
solver: {{dt: auto, tolerance: {{time: 1e-9 s}}}}
"""

FREE_CASES = [(1.0, 0.2, 0.15), (1.0, 0.2, -0.05), (0.2, 0.1, 0.1), (0.2, 0.1, -0.3)]


@pytest.mark.parametrize("height,width,theta0", FREE_CASES)
def test_free_rocking_events_within_the_tolerance_of_exact_with_5x_fewer_steps(height, width, theta0):
    """Tolerance 1e-9 s: every impact within 1e-9 s of the exact T (2k + 1), at a step at least 5x
    the default 0.1 ms (so at least 5x fewer steps)."""
    case = parse_case(FREE.format(height=height, width=width, theta0=theta0, tail=20.0), source="free.yaml")
    prepared = prepare(case)
    choice = prepared.step_choice
    assert choice is not None and choice.met
    result = simulate_prepared(prepared)
    assert result.step == pytest.approx(choice.step, rel=1e-12)
    assert choice.step >= 5 * 1e-4
    _, alpha, p2 = prepared.model.constants
    T = quarter_period(abs(theta0), alpha, p2)
    times = result.events["time"]
    assert times.size >= 10 and all(c == b"impact" for c in result.events["cause"])
    exact = T * (2 * np.arange(times.size) + 1)
    assert np.max(np.abs(times - exact)) <= 1e-9
    assert choice.error_time <= S.SAFETY * 1e-9


def test_the_estimate_follows_fourth_order_and_a_looser_tolerance_takes_a_coarser_step():
    """Tolerances 1e-9 s and 1e-6 s: the looser takes a step at least as large; the estimate is of the
    error actually made (within a factor 2 of the exact error, for free rocking)."""
    text = FREE.format(height=1.0, width=0.2, theta0=0.1, tail=20.0)
    tight = prepare(parse_case(text, source="a.yaml"))
    loose = prepare(parse_case(text.replace("1e-9 s", "1e-6 s"), source="b.yaml"))
    assert loose.step_choice.step >= tight.step_choice.step
    result = simulate_prepared(tight)
    _, alpha, p2 = tight.model.constants
    T = quarter_period(0.1, alpha, p2)
    exact_error = np.max(np.abs(result.events["time"] - T * (2 * np.arange(result.events.size) + 1)))
    assert 0.5 * exact_error <= tight.step_choice.error_time <= 2.0 * exact_error


def test_step_errors_richardson_and_different_sequences():
    kinds = np.array([(b"ROCK", b"ROCK", b"impact", 1.0)], dtype=object)
    coarse = (np.array([1.0 + 16e-9]), kinds, 0.1 + 15e-6, 10)
    fine = (np.array([1.0 + 1e-9]), kinds, 0.1, 20)
    error_time, error_rotation = S.step_errors(coarse, fine, S.richardson_factor("located"))
    assert error_time == pytest.approx(16e-9, rel=1e-6)       # 16/15 of the difference 15e-9
    assert error_rotation == pytest.approx(16e-6, rel=1e-6)
    other = (np.array([1.0, 2.0]), np.concatenate([kinds, kinds]), 0.1, 20)
    assert S.step_errors(coarse, other, 16 / 15)[0] == math.inf
    assert S.richardson_factor("step-end") == 2.0


def test_apply_step_takes_whole_divisors_and_keeps_small_blocks_resolved():
    params = np.zeros((2, L.N_PARAMS))
    params[:, L.P_DT_REC] = 0.01
    params[:, L.P_G] = 9.81
    params[0, L.P_R] = 1.0            # p = 2.7 rad/s: 1 step of 10 ms has p h = 0.027
    params[1, L.P_R] = 1e-4           # p = 271 rad/s: needs h <= 0.1 / p = 0.37 ms
    S.apply_step(params, 0.004)
    assert params[0, L.P_N_SUB] == 3 and params[0, L.P_STEP] == pytest.approx(0.01 / 3)
    assert params[1, L.P_N_SUB] == 28 and params[1, L.P_STEP] * 271.2 <= 0.1


def test_case_keys_round_trip_and_bad_values():
    case = parse_case(FREE.format(height=1.0, width=0.2, theta0=0.1, tail=1.0), source="c.yaml")
    assert case.solver.auto and case.solver.tolerance_time == 1e-9 and case.solver.tolerance_rotation == 1e-4
    again = parse_case(yaml.safe_dump(case_to_dict(case)), source="d.yaml")
    assert again.solver == case.solver
    fixed = case_with(case, {"solver.dt": "0.5 ms"})
    assert not fixed.solver.auto and fixed.solver.dt == 5e-4
    with pytest.raises(CaseError, match="solver.tolerance.time"):
        case_with(case, {"solver.tolerance": {"time": "-1 s"}})
    with pytest.raises(CaseError, match="output.interval"):
        case_with(case, {"output.interval": "auto"})


def test_default_step_unchanged_and_no_pilot_without_auto():
    """Without ``dt: auto`` a run takes solver.dt as before and pilots nothing."""
    text = FREE.format(height=1.0, width=0.2, theta0=0.1, tail=1.0).replace("dt: auto, ", "")
    prepared = prepare(parse_case(text, source="e.yaml"))
    assert prepared.step_choice is None and prepared.settings.dt == 1e-4
    assert prepared.ground.dt == 1e-4          # the still ground sampled at solver.dt, as before


def test_a_sweep_at_auto_takes_its_pilots_step_and_says_so():
    """A sweep of the example with ``dt: auto``: every point at the step of the pilot of the case
    file's own case (each a whole divisor of the record's step), its file attributes stating the
    step and the estimate; its verdicts those of the sweep at 0.1 ms."""
    from conftest import REPO

    from rockslide.analyses import sweep as sw
    from rockslide.case import load_case
    from rockslide.engine.execute import execute

    records = REPO / "records"
    base = load_case(REPO / "configs" / "example.yaml")
    auto = case_with(base, {"solver.dt": "auto"})
    axes = [sw.parse_axis("mu", "0.3:0.6:0.1"), sw.parse_axis("pga", "300gal:900gal:300gal")]
    plans = {name: sw.plan_sweep(c, axes, records_dir=records) for name, c in (("fixed", base), ("auto", auto))}
    study = plans["auto"].step_study
    assert study.auto and len(study.choices) == 1 and study.choices[0].met
    params = plans["auto"].case_params()
    np.testing.assert_allclose(params[:, L.P_STEP], study.choices[0].step, rtol=1e-12)
    n = params[:, L.P_DT_REC] / params[:, L.P_STEP]
    np.testing.assert_allclose(n, np.round(n), rtol=1e-12)
    assert study.choices[0].saving >= 5
    fixed_params = plans["fixed"].case_params()
    assert np.all(fixed_params[:, L.P_STEP] <= 1e-4 * (1 + 1e-9))          # the default unchanged
    assert not plans["fixed"].step_study.auto and "would take" in plans["fixed"].step_study.note()
    attrs = sw.root_attributes(plans["auto"], "")
    assert attrs["step_mode"] == "auto" and attrs["integration_step"] == study.choices[0].step
    assert attrs["step_error_time"] <= S.SAFETY * auto.solver.tolerance_time
    verdicts = {name: sw.sweep_variables(p, execute(p, None, workers=1).states)["overturned"][0]
                for name, p in plans.items()}
    np.testing.assert_array_equal(verdicts["auto"], verdicts["fixed"])


def test_the_device_launch_order_counts_each_cases_steps():
    """With ``auto`` the cases of one study may take different steps: the device's launch order
    (`gpu.launch_order`, by expected work) puts the case of more steps per interval first, the
    record, block and intensity being the same."""
    from rockslide.core import gpu

    params = np.zeros((3, L.N_PARAMS))
    params[:, L.P_G], params[:, L.P_MU], params[:, L.P_TAN_ALPHA] = 9.81, 0.5, 0.5
    params[:, L.P_N_SUB] = (1, 100, 8)
    base = np.full((4, 50), 9.81)                     # 1 g: above every REST threshold
    order = gpu.launch_order(params, base, np.zeros(3, np.int64), np.full(3, 50), np.ones(3))
    assert list(order) == [1, 2, 0]


def test_bench_gpu_writes_its_file_from_what_it_measured(tmp_path):
    """``bench_gpu.py --cpu-only --out FOLDER`` (no GPU here) measures a tiny grid at auto and writes
    FOLDER/bench_gpu.md with its numbers; the device's columns say 'not measured'. Without ``--out``
    it writes nothing."""
    import subprocess
    import sys

    from conftest import REPO

    done = subprocess.run([sys.executable, str(REPO / "benchmarks" / "bench_gpu.py"), "--cpu-only", "--grid",
                           "rocking", "--cases", "4", "--auto", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=600, cwd=REPO)
    assert done.returncode == 0, done.stderr[-2000:]
    text = (tmp_path / "bench_gpu.md").read_text()
    assert "| GPU | not measured |" in text and "4 cases at " in text and "(auto)" in text
    assert "--cpu-only" in text
    # without --out, a run without the device leaves the device's figures in results/ alone
    kept = (REPO / "results" / "bench_gpu.md").read_bytes()
    done = subprocess.run([sys.executable, str(REPO / "benchmarks" / "bench_gpu.py"), "--cpu-only", "--grid",
                           "rocking", "--cases", "4"], capture_output=True, text=True, timeout=600, cwd=REPO)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "wrote" not in done.stdout and (REPO / "results" / "bench_gpu.md").read_bytes() == kept
