"""Arithmetic that escaped (issue 43, item 5): hazard levels near the float limit, a denormal level
and a lognormal of huge beta were an internal error or a warning line per operation; numpy's
floating-point warnings now become one error naming the input (`errors.numbers_from`, the one
place), and the inputs are bounded where they are read."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import REPO, invoke, one_line_error

from rockslide.analyses import ensemble
from rockslide.case import Distribution, load_case
from rockslide.errors import CaseError, numbers_from
from rockslide.io import hazard

LOGNORMAL = ("--median", "10cm/s", "--beta", "0.4", "--im", "pgv")


@pytest.mark.parametrize("levels", ["1e307 0.01\n1e308 0.001\n", "5e-324 0.01\n1 0.001\n2 0.0001\n",
                                    "1 1e-320\n2 1e-323\n"])
def test_levels_and_rates_beyond_floating_point_are_one_line(tmp_path, levels):
    """Levels near 1e308 overflowed into 'Out of range float values are not JSON compliant'
    (internal error); a denormal level printed 'divide by zero encountered in log' per log."""
    path = tmp_path / "h.csv"
    path.write_text("pgv [cm/s] rate\n" + levels)
    done = invoke("risk", *LOGNORMAL, "--hazard", path, "--json", "--no-plot", "--out-dir", tmp_path)
    line = one_line_error(done, "h.csv")
    assert "warning" not in done.stderr and ("between 1e-100 and 1e+100" in line or "rate at level" in line)
    assert not list(tmp_path.glob("*.risk.*"))


def test_a_level_that_overflows_in_si_is_one_line(tmp_path):
    """1e99 g is within the range in g, 9.8e99 m/s^2 beyond it in SI."""
    path = tmp_path / "h.csv"
    path.write_text("pga [g] rate\n1 0.01\n9e99 0.001\n")
    one_line_error(invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", path, "--no-plot",
                          "--out-dir", tmp_path), "h.csv", "in SI")


def test_a_lognormal_of_huge_beta_draws_without_a_warning_and_says_each_member_outside():
    """Its samples overflowed to inf and underflowed to 0, then divided by zero (internal error).
    Now they are drawn as they come, without a warning line, and each member they put outside the
    model is said (`ensemble.drawn_outside`; tests/test_ensemble_draws.py runs such ensembles)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        drawn = ensemble.sample({"size": Distribution("lognormal", 1.0, 1e300)}, 16)
    assert set(np.unique(drawn["size"])) <= {0.0, math.inf}
    case = load_case(REPO / "configs" / "example.yaml")
    outside, reasons = ensemble.drawn_outside(case, drawn, np.ones(16))
    assert outside.all() and sum(reasons.values()) == 16
    assert set(reasons) == {"uncertain.size: factor not finite", "uncertain.size: factor not above 0"}
    values = ensemble.sample({"size": Distribution("lognormal", 1.0, 0.3)}, 16)["size"]
    assert np.all(values > 0) and abs(float(np.median(np.log(values)))) < 0.3
    assert not ensemble.drawn_outside(case, {"size": values}, np.ones(16))[0].any()


def test_numbers_from_names_the_input_and_lets_underflow_pass():
    with pytest.raises(CaseError, match=r"^x.csv: line 3: its numbers go beyond .*overflow"):
        with numbers_from("x.csv", field="line 3"):
            np.float64(1e308) * np.float64(10.0)
    with pytest.raises(CaseError, match="divide by zero"):
        with numbers_from("x.csv"):
            np.log(np.zeros(3))
    with numbers_from("x.csv"):
        assert np.float64(1e-300) * np.float64(1e-300) == 0.0
        with np.errstate(divide="ignore"):                   # a place that expects it says so
            assert np.log(np.zeros(1))[0] == -math.inf


def test_a_plain_curve_of_ordinary_levels_still_reads(tmp_path):
    path = tmp_path / "h.csv"
    path.write_text("pga [g] rate\n0.1 0.01\n0.2 0.001\n")
    table = hazard.read_hazard(path)[0]
    assert list(table.levels) == [0.1, 0.2] and list(table.rates) == [0.01, 0.001]
