"""`rockslide risk`: the rate of a damage state against closed forms, OpenQuake's hazard-curve
format, the files and the messages.

Closed forms (independent of the code): a power-law hazard curve ``lambda(x) = k0 x^-k`` and a
lognormal fragility give ``lambda_F = k0 theta^-k exp(k^2 beta^2 / 2)`` (the expectation of
``k0 C^-k`` for a lognormal capacity C); a step fragility at theta gives ``lambda(theta)``.
The OpenQuake files are written here in the layout the engine's manual shows ("Outputs from
Classical PSHA": one comment line, ``lon,lat,depth,poe-<IML>...``, one row per site), and one file
is the engine's own output (benchmarks/openquake_demo: OpenQuake engine 3.26.2, run once outside
the test environment, which does not have the engine).
"""

from __future__ import annotations

import json
import math
import os

import h5py
import numpy as np
import pytest
from conftest import G, fragility_file, invoke, one_line_error, openquake_csv
from scipy import optimize, stats

import rockslide
from rockslide.analyses import risk as rk
from rockslide.errors import CaseError
from rockslide.io import hazard as hz

K0, K, THETA, BETA = 1e-4, 2.5, 0.5, 0.4          # [1/yr at 1 g], [-], [g], [-]: the issue's example


def closed_form(k0=K0, k=K, theta=THETA, beta=BETA) -> float:
    """[1/yr] ``k0 theta^-k exp(k^2 beta^2 / 2)``, theta in g (k0 is the rate at 1 g)."""
    return k0 * theta ** -k * math.exp(k * k * beta * beta / 2.0)


def power_law(points: int, low=1e-3, high=1e2, k0=K0, k=K) -> rk.HazardCurve:
    x = np.geomspace(low, high, points)
    return rk.HazardCurve("power law", x * G, k0 * x ** -k)


def test_closed_form_value_of_the_issue():
    # the issue states 9.3266e-4 /yr for these numbers; the closed form written out independently
    assert closed_form() == pytest.approx(9.3266e-4, rel=1e-5)


@pytest.mark.parametrize("points", [20, 200])
def test_power_law_and_lognormal_match_the_closed_form(points):
    # the integration is exact for a log-log interpolated curve, so the only error is rounding
    # (and what lies beyond five decades: P(F|1e-3 g) ~ Phi(-15.5), lambda(100 g) = 1e-9)
    result = rk.rate(rk.Lognormal(THETA * G, BETA), power_law(points))
    assert result.rate == pytest.approx(closed_form(), rel=1e-4)
    assert result.rate == pytest.approx(closed_form(), rel=1e-9)


def test_result_does_not_depend_on_the_sampling_of_a_power_law():
    # log-log interpolation of a power law is exact: 20 and 200 levels agree to rounding, for the
    # closed form (lognormal) and for the piecewise one (tabulated fragility, steps inside intervals)
    lognormal = rk.Lognormal(THETA * G, BETA)
    levels = np.geomspace(0.03, 7.0, 37) * G
    tabulated = rk.Tabulated(levels, lognormal(levels))
    for fragility in (lognormal, tabulated):
        coarse, fine = (rk.rate(fragility, power_law(n)).rate for n in (20, 200))
        assert coarse == pytest.approx(fine, rel=1e-6)


def test_a_curved_hazard_curve_against_quadrature_of_eq_1():
    # eq. (1) as written, P(F|x) |d lambda / d ln x| integrated by scipy's adaptive quadrature over
    # each interval of a curve whose log-log slope changes from 0.5 to 6 (an OpenQuake-like shape),
    # plus the motions above the last level at P(F|x_max): independent of the by-parts closed forms
    from scipy import integrate

    x = np.array([0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0])
    lam = 0.2 * np.exp(-1.2 * np.log(x / 0.01) ** 1.35)
    fragility = rk.Lognormal(0.4 * G, 0.5)
    total = 0.0
    for x0, x1, l0, l1 in zip(x[:-1], x[1:], lam[:-1], lam[1:], strict=True):
        k = -math.log(l1 / l0) / math.log(x1 / x0)
        piece, _ = integrate.quad(lambda u, x0=x0, l0=l0, k=k: float(fragility(np.exp(u) * G))
                                  * k * l0 * math.exp(-k * (u - math.log(x0))),
                                  math.log(x0), math.log(x1), epsabs=0.0, epsrel=1e-12)
        total += piece
    total += lam[-1] * float(fragility(x[-1] * G))
    result = rk.rate(fragility, rk.HazardCurve("curved", x * G, lam))
    assert result.rate == pytest.approx(total, rel=1e-9)
    steep = rk.rate(rk.Lognormal(0.5 * G, 0.6), power_law(300, k=8.0, low=1e-4, high=1e2))
    # exp(k^2 beta^2 / 2) = 1e5 and the integrand peaks near 0.03 g: no loss of digits
    assert steep.rate == pytest.approx(closed_form(k=8.0, beta=0.6), rel=1e-9)


def test_doubling_the_rates_doubles_the_rate():
    curve = rk.HazardCurve("site", np.array([0.05, 0.1, 0.2, 0.4, 0.8, 1.6]) * G,
                           np.array([3e-2, 1e-2, 2.5e-3, 6e-4, 9e-5, 1e-5]))
    for fragility in (rk.Lognormal(0.3 * G, 0.5), rk.Tabulated(np.array([0.1, 0.3, 0.9]) * G,
                                                                np.array([0.0, 0.4, 1.0]))):
        assert rk.rate(fragility, curve.scaled(2.0)).rate == pytest.approx(2.0 * rk.rate(fragility, curve).rate,
                                                                         rel=1e-12)


@pytest.mark.parametrize("theta", [0.5, 0.237, 0.05, 1.6])
def test_a_step_gives_the_hazard_at_the_step(theta):
    # a capacity known exactly: lambda_F = lambda(theta), at a level of the curve or between two
    curve = rk.HazardCurve("site", np.array([0.05, 0.1, 0.2, 0.4, 0.8, 1.6]) * G,
                           np.array([3e-2, 1e-2, 2.5e-3, 6e-4, 9e-5, 1e-5]))
    i = np.searchsorted(curve.levels / G, theta, side="right") - 1
    i = min(i, curve.levels.size - 2)
    x0, x1 = curve.levels[i] / G, curve.levels[i + 1] / G
    slope = math.log(curve.rates[i + 1] / curve.rates[i]) / math.log(x1 / x0)
    expected = curve.rates[i] * (theta / x0) ** slope        # the power law through the two points
    assert rk.rate(rk.Tabulated.step(theta * G), curve).rate == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(("level", "offset"), [(0, 0.0), (0, 1e-10), (2, -1e-10), (2, 0.0), (2, 1e-10),
                                               (5, -1e-10), (5, 0.0)])      # inside the curve's levels
def test_a_step_within_rounding_of_a_hazard_level(level, offset):
    # a step at theta = x_i (1 +- 1e-10) gives lambda(theta), which differs from lambda(x_i) by
    # k 1e-10 relative (k < 3 here): 1e-9 separates that from a jump lost or spread over an interval
    curve = rk.HazardCurve("site", np.array([0.05, 0.1, 0.2, 0.4, 0.8, 1.6]) * G,
                           np.array([3e-2, 1e-2, 2.5e-3, 6e-4, 9e-5, 1e-5]))
    theta = curve.levels[level] * (1.0 + offset)
    result = rk.rate(rk.Tabulated.step(theta), curve)
    assert result.rate == pytest.approx(curve.rates[level], rel=1e-9)
    assert result.contributions.sum() == pytest.approx(result.rate, rel=1e-12)


def test_disaggregation_sums_to_the_rate_and_peaks_near_the_median():
    curve = power_law(60, low=0.01, high=10.0)
    result = rk.rate(rk.Lognormal(THETA * G, BETA), curve)
    assert result.contributions.sum() == pytest.approx(result.rate, rel=1e-12)
    # the integrand P(F|x) k lambda(x) = k k0 Phi(z) exp(-k (mu + beta z)) peaks where
    # phi(z) = k beta Phi(z) (its derivative in z vanishes)
    z = optimize.brentq(lambda z: stats.norm.pdf(z) - K * BETA * stats.norm.cdf(z), -5.0, 5.0)
    peak = THETA * math.exp(BETA * z)
    top = int(np.argmax(result.contributions[:-1]))
    ratio = curve.levels[1] / curve.levels[0]
    assert curve.levels[top] / G / ratio <= peak <= curve.levels[top + 1] / G * ratio
    fine = np.geomspace(0.2, 1.0, 4001) * G
    assert fine[np.argmax(rk.density(rk.Lognormal(THETA * G, BETA), curve, fine))] / G == pytest.approx(peak,
                                                                                                        rel=1e-3)
    grid = np.geomspace(0.011, 9.9, 2000) * G
    dens = rk.density(rk.Lognormal(THETA * G, BETA), curve, grid)
    integral = np.sum(0.5 * (dens[1:] + dens[:-1]) * np.diff(np.log(grid)))
    assert integral == pytest.approx(result.rate, rel=1e-3)   # trapezoid on 2000 points


def test_truncated_curve_says_by_how_much_at_most():
    curve = power_law(30, low=0.01, high=0.6)          # ends where the fragility is at 0.68
    fragility = rk.Lognormal(THETA * G, BETA)
    result = rk.rate(fragility, curve)
    assert rk.truncated(result)
    lam_max = K0 * 0.6 ** -K
    assert result.missing == pytest.approx(lam_max * (1.0 - float(fragility(0.6 * G))), rel=1e-12)
    full = closed_form()
    assert result.rate <= full <= result.rate + result.missing


def test_service_life_return_period_and_rock_survival():
    lam = closed_form()
    assert rk.probability_in(lam, 50.0) == pytest.approx(1.0 - math.exp(-lam * 50.0), rel=1e-12)
    assert rk.return_period(lam) == pytest.approx(1.0 / lam)
    alive = rk.survival(np.array([1e-6, 1e-4, 2e-4]), 24_000.0)
    assert alive == pytest.approx(np.exp(-np.array([0.024, 2.4, 4.8])))
    # exp(-2.4) = 0.09 > 0.05: not rejected; exp(-4.8) = 0.008: rejected at 95 %
    assert rk.rejected(alive, 0.95).tolist() == [False, False, True]


def test_fragility_uncertainty_gives_an_interval_around_the_rate():
    curve = power_law(100)
    box = rk.lognormal_box((0.4 * G, 0.6 * G), (0.3, 0.5))
    low, high = rk.rate_range(box, curve)
    # for a power law the rate falls with the median and rises with beta: the corners are exact
    assert low == pytest.approx(closed_form(theta=0.6, beta=0.3), rel=1e-9)
    assert high == pytest.approx(closed_form(theta=0.4, beta=0.5), rel=1e-9)


# --------------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------------




def test_openquake_file_parses_to_poisson_rates(tmp_path):
    levels = np.array([0.1, 0.4, 0.6])
    poes = [[4.553860e-01, 5.754042e-02, 6.354511e-03], [1.522632e-01, 1.0e-03, 2.0e-05]]
    path = openquake_csv(tmp_path / "hazard_curve-mean-PGA_12.csv", levels, poes, years=1.0,
                         sites=[(0.0, 0.0), (0.1, 0.0)])
    tables = hz.read_hazard(path)
    assert [t.name for t in tables] == ["mean at 0,0", "mean at 0.1,0"]
    for table, row in zip(tables, poes, strict=True):
        assert table.levels == pytest.approx(levels * G, rel=1e-12)
        assert table.rates == pytest.approx([-math.log(1.0 - p) / 1.0 for p in row], rel=1e-12)
        assert table.measure == hz.Measure("pga") and table.kind == "mean" and table.investigation_time == 1.0


def test_openquake_curve_of_a_power_law_gives_the_closed_form(tmp_path):
    years = 50.0
    levels = np.geomspace(1e-3, 1e2, 200)
    poes = [-np.expm1(-K0 * levels ** -K * years)]
    poes[0] = np.minimum(poes[0], 0.999999)       # PoE 1 has no rate; the lowest levels are clipped
    path = openquake_csv(tmp_path / "pl.csv", levels, poes, years=years)
    ds = rockslide.risk(hazard=path, median="0.5g", beta=BETA)
    # PoEs written with 7 significant digits: rates within ~1e-6 where PoE is small, and the
    # clipped levels (PoE 1 - 1e-6, x < 0.0075 g) are where P(F|x) < 1e-30
    assert float(ds.rate[0]) == pytest.approx(closed_form(), rel=1e-4)


def test_spectral_acceleration_and_pgv_units(tmp_path):
    path = openquake_csv(tmp_path / "sa.csv", [0.1, 0.2, 0.4], [[0.3, 0.1, 0.01]], imt="SA(0.3)")
    ds = rockslide.risk(hazard=path, median="0.25g", beta=0.5, im="sa(300ms)")
    assert ds.hazard_level.values[0] == pytest.approx(np.array([0.1, 0.2, 0.4]) * G)
    path = openquake_csv(tmp_path / "pgv.csv", [5.0, 10.0, 20.0], [[0.3, 0.1, 0.01]], imt="PGV")
    ds = rockslide.risk(hazard=path, median="12cm/s", beta=0.5, im="pgv")
    assert ds.hazard_level.values[0] == pytest.approx([0.05, 0.10, 0.20])      # cm/s -> m/s


def test_zeros_at_the_top_of_a_curve_only_with_drop_zero_poe(tmp_path):
    # OpenQuake writes 0.000000E+00 where the PoE is below its precision (the manual's example)
    path = openquake_csv(tmp_path / "z.csv", [0.1, 0.2, 0.4, 0.8, 1.6], [[0.3, 0.1, 0.01, 0.0, 0.0]])
    with pytest.raises(CaseError, match="--trim-poe"):
        rockslide.risk(hazard=path, median="0.5g", beta=0.4)
    ds = rockslide.risk(hazard=path, median="0.5g", beta=0.4, drop_zero_poe=True)
    assert np.isfinite(ds.hazard_level.values[0]).sum() == 3
    assert ds.hazard_rate.values[0][:3] == pytest.approx(-np.log1p(-np.array([0.3, 0.1, 0.01])) / 50.0)
    assert float(ds.rate_missing_max[0]) > 0                       # ends at 0.4 g: P(F) < 1 there
    inside = openquake_csv(tmp_path / "in.csv", [0.1, 0.2, 0.4], [[0.3, 0.0, 0.01]])
    with pytest.raises(CaseError, match="poe-0.2000000"):
        rockslide.risk(hazard=inside, median="0.5g", beta=0.4, drop_zero_poe=True)


def test_poe_of_1_at_the_low_levels_and_0_at_the_high_trimmed(tmp_path):
    # OpenQuake writes 1.000000E+00 at the lowest levels for long investigation times (an infinite
    # rate): --trim-poe (and its former name --drop-zero-poe) leaves out both ends and says so
    poes = [[1.0, 1.0, 0.999, 0.9, 0.3, 0.05, 0.0, 0.0], [1.0, 0.9999, 0.999, 0.9, 0.3, 0.05, 1e-3, 0.0]]
    levels = [0.005, 0.01, 0.05, 0.1, 0.4, 0.8, 1.6, 3.2]
    path = openquake_csv(tmp_path / "long.csv", levels, poes, years=10_000.0, sites=[(0.0, 0.0), (0.1, 0.0)])
    one_line_error(invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", path, "--out-dir", tmp_path),
                   "poe-0.0050000", "--trim-poe")
    for option in ("--trim-poe", "--drop-zero-poe"):
        result = invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", path, "--out-dir", tmp_path,
                        option, "--overwrite", "--no-plot")
        assert result.exit_code == 0, result.output
        assert "left out 2 levels (0.005 g ... 0.01 g) at the low end with PoE 1" in result.stdout
        assert "2 levels (1.6 g ... 3.2 g) at the high end with PoE 0" in result.stdout
        assert "left out 1 level (0.005 g) at the low end with PoE 1 (an infinite rate) and 1 level (3.2 g) at " \
               "the high end" in result.stdout
    ds = rockslide.risk(hazard=path, median="0.5g", beta=0.4, trim_poe=True)
    assert ds.hazard_level.values[0][:4] == pytest.approx(np.array(levels[2:6]) * G)
    assert ds.hazard_rate.values[0][:4] == pytest.approx(-np.log1p(-np.array(poes[0][2:6])) / 10_000.0, rel=1e-12)
    assert np.isnan(ds.hazard_level.values[0][4:]).all()
    # a 1 after a PoE below 1, or a 0 before a positive PoE, is still refused
    for row, column in (([0.999, 1.0, 0.9, 0.3], "poe-0.0100000"), ([1.0, 0.99, 0.0, 0.3], "poe-0.1000000")):
        bad = openquake_csv(tmp_path / "bad.csv", [0.005, 0.01, 0.1, 0.4], [row], years=10_000.0)
        with pytest.raises(CaseError, match=column):
            rockslide.risk(hazard=bad, median="0.5g", beta=0.4, trim_poe=True)
    only_ends = openquake_csv(tmp_path / "ends.csv", [0.005, 0.01, 0.1, 0.4], [[1.0, 1.0, 0.5, 0.0]])
    with pytest.raises(CaseError, match="--trim-poe left out 3 levels"):
        rockslide.risk(hazard=only_ends, median="0.5g", beta=0.4, trim_poe=True)


def test_plain_table_with_and_without_header(tmp_path):
    plain = tmp_path / "site.csv"
    plain.write_text("# a site\nPGA [gal], rate\n50, 1e-2\n100, 2e-3\n200, 3e-4\n")
    headed = rockslide.risk(hazard=plain, median="0.15g", beta=0.4)
    assert headed.hazard_level.values[0] == pytest.approx([0.5, 1.0, 2.0])
    bare = tmp_path / "bare.txt"
    bare.write_text("0.05 1e-2\n0.1 2e-3\n0.2 3e-4\n")
    plain_g = rockslide.risk(hazard=bare, median="0.15g", beta=0.4)      # OpenQuake's unit: g
    assert plain_g.hazard_level.values[0] == pytest.approx(np.array([0.05, 0.1, 0.2]) * G)


@pytest.mark.parametrize("header", ["PGA [gal] rate", "PGA [gal], rate", "PGA [gal];rate", "PGA [gal]\trate",
                                    "PGA (gal) rate", "PGA (gal), rate [1/yr]", "PGA(gal)\trate (1/yr)",
                                    "pga  [gal]   rate", "PGA [gal] ; rate"])
def test_a_header_with_units_in_any_separator(tmp_path, header):
    # 'PGA [g] rate' gave "line 1: 1 values"; the unit is read (gal: levels / 100 in m/s^2)
    plain = tmp_path / "site.txt"
    data = "\n".join(f"{x}{';' if ';' in header else ' '}{r}" for x, r in ((50, 1e-2), (100, 2e-3), (200, 3e-4)))
    plain.write_text(f"{header}\n{data}\n")
    ds = rockslide.risk(hazard=plain, median="0.15g", beta=0.4)
    assert ds.hazard_level.values[0] == pytest.approx([0.5, 1.0, 2.0])


def test_a_header_naming_the_period_and_the_unit(tmp_path):
    plain = tmp_path / "sa.txt"
    plain.write_text("sa(0.3s) (gal) rate\n50 1e-2\n100 2e-3\n")
    assert rockslide.risk(hazard=plain, median="0.1g", beta=0.4, im="sa(0.3s)").hazard_level.values[0] == \
        pytest.approx([0.5, 1.0])
    plain.write_text("SA (0.3 s) rate\n0.05 1e-2\n0.1 2e-3\n")            # no unit: OpenQuake's, g
    assert rockslide.risk(hazard=plain, median="0.1g", beta=0.4, im="sa(0.3s)").hazard_level.values[0] == \
        pytest.approx([0.05 * G, 0.1 * G])
    with pytest.raises(CaseError, match="SA\\(1\\)"):
        plain.write_text("sa(1s) [g] rate\n0.05 1e-2\n0.1 2e-3\n")
        rockslide.risk(hazard=plain, median="0.1g", beta=0.4, im="sa(0.3s)")




def test_fragility_file_fit_stripes_and_interval(tmp_path):
    frag = fragility_file(tmp_path / "block.fragility.h5")
    hazard = {"power law": (np.geomspace(1e-3, 1e2, 200) * G, K0 * np.geomspace(1e-3, 1e2, 200) ** -K)}
    fit = rockslide.risk(frag, hazard)
    assert float(fit.rate[0]) == pytest.approx(closed_form(), rel=1e-6)
    # for a power law the box's corners bound the rate (see above)
    assert float(fit.rate_lower[0]) == pytest.approx(closed_form(theta=0.625, beta=0.32), rel=1e-9)
    assert float(fit.rate_upper[0]) == pytest.approx(closed_form(theta=0.4, beta=0.5), rel=1e-9)
    other = rockslide.risk(frag, hazard, damage="rotation>0.5alpha")
    assert float(other.rate[0]) == pytest.approx(closed_form(theta=0.25), rel=1e-6)
    stripes = rockslide.risk(frag, hazard, stripes=True)
    # the stripes by hand: P = 0 below 0.2 g, linear in ln x between, 1 from 1 g; lambda_F = E[lambda(C)]
    # with C's distribution the stripes: sum of jumps and of the linear pieces, integrated here by
    # the trapezoid rule on 20001 points per piece (independent of the code's closed form)
    x = np.array([0.2, 0.4, 0.6, 0.8, 1.0])
    p = np.array([0.0, 0.3, 0.7, 0.9, 1.0])
    expected = 0.0
    for a, b, pa, pb in zip(x[:-1], x[1:], p[:-1], p[1:], strict=True):
        u = np.linspace(math.log(a), math.log(b), 20001)
        lam = K0 * np.exp(u) ** -K
        expected += (pb - pa) / (u[-1] - u[0]) * np.sum(0.5 * (lam[1:] + lam[:-1]) * np.diff(u))
    assert float(stripes.rate[0]) == pytest.approx(expected, rel=1e-6)


def test_bootstrap_resamples_give_a_percentile_interval(tmp_path):
    rng = np.random.default_rng(5)
    medians, betas = 0.5 * np.exp(rng.normal(0.0, 0.1, 400)), rng.uniform(0.3, 0.5, 400)
    frag = fragility_file(tmp_path / "boot.fragility.h5", bootstrap=(medians * G, betas))
    x = np.geomspace(1e-3, 1e2, 200)
    ds = rockslide.risk(frag, {"power law": (x * G, K0 * x ** -K)})
    each = [closed_form(theta=m, beta=b) for m, b in zip(medians, betas, strict=True)]
    low, high = np.percentile(each, [2.5, 97.5])
    assert float(ds.rate_lower[0]) == pytest.approx(low, rel=1e-6)
    assert float(ds.rate_upper[0]) == pytest.approx(high, rel=1e-6)
    assert "400 bootstrap resamples" in ds.attrs["fragility_uncertainty"]
    aged = rockslide.risk(frag, {"power law": (x * G, K0 * x ** -K)}, age="1ka")
    assert [float(aged.survival_lower[0]), float(aged.survival_upper[0])] == pytest.approx(
        [math.exp(-high * 1000.0), math.exp(-low * 1000.0)], rel=1e-6)


def test_command_writes_file_figure_and_json(tmp_path):
    levels = np.geomspace(0.1, 3.0, 40)
    csv = openquake_csv(tmp_path / "hazard_curve-mean-PGA_1.csv", levels,
                        [-np.expm1(-K0 * levels ** -K * 50.0), -np.expm1(-2 * K0 * levels ** -K * 50.0)],
                        sites=[(10.0, 45.0), (10.5, 45.0)])
    frag = fragility_file(tmp_path / "block.fragility.h5")
    result = invoke("risk", frag, "--hazard", csv, "--age", "24ka", "--json")
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    rates = [c["rate"] for c in payload["curves"]]
    assert rates[1] == pytest.approx(2 * rates[0], rel=1e-5)        # PoEs written with 7 digits
    assert all(c["rejected"] for c in payload["curves"])              # survival ~ exp(-22): rejected
    assert sorted(p.name for p in tmp_path.iterdir()) == ["block.fragility.h5", "block.risk.h5", "block.risk.png",
                                                          "hazard_curve-mean-PGA_1.csv"]
    with h5py.File(tmp_path / "block.risk.h5") as f:
        assert f.attrs["format"] == "rockslide-risk"
    stored = rockslide.read_result(tmp_path / "block.risk.h5")
    assert stored.rate.values == pytest.approx(rates, rel=1e-12)
    assert stored.survival.values == pytest.approx(np.exp(-np.array(rates) * 24_000.0), rel=1e-9)
    again = invoke("risk", frag, "--hazard", csv)
    one_line_error(again, "block.risk.h5 exists", "--overwrite")
    text = invoke("risk", frag, "--hazard", csv, "--overwrite", "--no-plot")
    assert text.exit_code == 0 and "return period" in text.stdout
    assert not (tmp_path / "block.risk.png").exists()
    redrawn = invoke("plot", tmp_path / "block.risk.h5", "-o", tmp_path / "again.png")
    assert redrawn.exit_code == 0 and (tmp_path / "again.png").stat().st_size > 10_000
    # the API draws it as the command does; two risk files are not overlaid: one line
    assert rockslide.plot_results([tmp_path / "block.risk.h5"]).axes
    two = invoke("plot", tmp_path / "block.risk.h5", tmp_path / "block.risk.h5", "-o", tmp_path / "two.png")
    one_line_error(two, "drawn one at a time")
    # the figure says what it draws; the fragility by its file's name, not its folder
    fig = rockslide.plot_results([tmp_path / "block.risk.h5"])
    title = fig._suptitle.get_text().replace("\n", " ")
    assert title.startswith("Annual rate of 'overturn': 2 hazard curves") and "block.fragility.h5" in title
    assert str(tmp_path) not in title and "/" not in title
    assert [ax for ax in fig.axes if ax.get_legend()] == [] and fig.legends      # the legend off the curves
    described = invoke("info", tmp_path / "block.risk.h5", "--json")
    assert described.exit_code == 0
    assert [c["rate"] for c in json.loads(described.stdout)["rates"].values()] == pytest.approx(rates, rel=1e-12)


def test_truncation_warning_on_the_command_line(tmp_path):
    plain = tmp_path / "short.csv"
    plain.write_text("PGA [g], rate\n0.05, 1e-2\n0.1, 2e-3\n0.3, 3e-4\n")
    result = invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", plain, "--out-dir", tmp_path)
    assert result.exit_code == 0, result.output
    assert "lower bound" in result.stderr and "at most" in result.stderr


# --------------------------------------------------------------------------------------------------
# Bad input: one line, exit 2
# --------------------------------------------------------------------------------------------------


def test_bad_input_is_one_line(tmp_path):
    lognormal = ("--median", "0.5g", "--beta", "0.4", "--out-dir", tmp_path)
    sa = openquake_csv(tmp_path / "sa.csv", [0.1, 0.2], [[0.3, 0.1]], imt="SA(0.3)")
    one_line_error(invoke("risk", *lognormal, "--hazard", sa), "SA(0.3)", "PGA", "sa.csv")
    gal = tmp_path / "gal.csv"
    gal.write_text("PGA [cm/s], rate\n5, 1e-2\n10, 1e-3\n")
    one_line_error(invoke("risk", *lognormal, "--hazard", gal), "cm/s", "gal.csv")
    rising = openquake_csv(tmp_path / "rising.csv", [0.1, 0.2, 0.4], [[0.3, 0.1, 0.2]])
    one_line_error(invoke("risk", *lognormal, "--hazard", rising), "not monotonic", "line 3")
    for poe in (0.0, 1.0):
        bad = openquake_csv(tmp_path / f"poe{poe:g}.csv", [0.1, 0.2, 0.4], [[0.3, poe, 0.01]])
        one_line_error(invoke("risk", *lognormal, "--hazard", bad), "poe-0.2000000", "strictly between 0 and 1")
    single = openquake_csv(tmp_path / "one.csv", [0.1], [[0.3]])
    one_line_error(invoke("risk", *lognormal, "--hazard", single), "two or more")
    one_point = tmp_path / "one.txt"
    one_point.write_text("0.1 1e-3\n")
    one_line_error(invoke("risk", *lognormal, "--hazard", one_point), "two or more")
    no_time = tmp_path / "notime.csv"
    no_time.write_text("#,,,,,\"kind='mean', imt='PGA'\"\nlon,lat,depth,poe-0.1,poe-0.2\n0,0,0,0.1,0.01\n")
    one_line_error(invoke("risk", *lognormal, "--hazard", no_time), "investigation_time")
    good = openquake_csv(tmp_path / "good.csv", [0.1, 0.2], [[0.3, 0.1]])
    one_line_error(invoke("risk", "--median", "0.5", "--beta", "0.4", "--hazard", good), "--median", "g")
    one_line_error(invoke("risk", "--hazard", good), "--median", "--beta")
    one_line_error(invoke("risk", *lognormal, "--hazard", good, "--age", "old"), "--age")
    one_line_error(invoke("risk", *lognormal, "--hazard", tmp_path / "missing.csv"), "missing.csv", "not found")
    if hasattr(os, "mkfifo"):                  # a FIFO is refused before it is opened (it was "a folder")
        os.mkfifo(tmp_path / "pipe.csv")
        one_line_error(invoke("risk", *lognormal, "--hazard", tmp_path / "pipe.csv"), "pipe.csv", "FIFO")
    frag = fragility_file(tmp_path / "b.fragility.h5")
    one_line_error(invoke("risk", frag, "--hazard", good, "--damage", "slip>1mm"), "slip>1mm", "overturn")
    rocking = fragility_file(tmp_path / "r.fragility.h5", im="pga_rocking", median=0.9)
    one_line_error(invoke("risk", rocking, "--hazard", good), "PGA / (g tan", "--im")
    with pytest.raises(CaseError, match="not monotonic"):
        rockslide.risk(hazard={"up": ([1.0, 2.0], [1e-3, 2e-3])}, median="0.5g", beta=0.4)


def test_a_file_the_openquake_engine_wrote():
    """benchmarks/openquake_demo: OpenQuake engine 3.26.2's own export (see its README); the rates
    are recomputed here from the file's text with the csv module."""
    import csv

    from conftest import REPO

    path = REPO / "benchmarks" / "openquake_demo" / "hazard_curve-mean-PGA_1.csv"
    rows = list(csv.reader(path.read_text().splitlines()))
    header, sites = rows[1], rows[2:]
    levels = [float(name.removeprefix("poe-")) for name in header[3:]]
    tables = hz.read_hazard(path)
    assert len(tables) == len(sites) == 2
    for table, site in zip(tables, sites, strict=True):
        assert table.kind == "mean" and table.investigation_time == 50.0 and table.measure == hz.Measure("pga")
        assert table.levels == pytest.approx(np.array(levels) * G, rel=1e-15)
        assert table.rates == pytest.approx([-math.log(1.0 - float(p)) / 50.0 for p in site[3:]], rel=1e-12)
    ds = rockslide.risk(hazard=path, median="0.3g", beta=0.4)
    assert ds.rate.values[0] > 0 and ds.contribution.values[0].sum() == pytest.approx(ds.rate.values[0])


@pytest.mark.parametrize("beta", ["1e-300", "1e300", "nan", "0", "-0.4", "6"])
def test_a_beta_out_of_bounds_is_one_line(tmp_path, beta):
    # 1e-300 printed 'nan /yr' with exit 0 and 1e300 warned of an overflow: both are refused
    good = openquake_csv(tmp_path / "good.csv", [0.1, 0.2], [[0.3, 0.1]])
    result = invoke("risk", "--median", "0.5g", "--beta", beta, "--hazard", good, "--out-dir", tmp_path)
    one_line_error(result, "--beta", "0.001 ... 5")
    assert not list(tmp_path.glob("*.risk.*"))


@pytest.mark.parametrize("beta", [1e-300, 1e300, math.nan])
def test_a_fragility_files_beta_out_of_bounds_names_file_and_state(tmp_path, beta):
    good = openquake_csv(tmp_path / "good.csv", [0.1, 0.2], [[0.3, 0.1]])
    frag = fragility_file(tmp_path / "odd.fragility.h5", beta=beta, interval=False)
    one_line_error(invoke("risk", frag, "--hazard", good), "odd.fragility.h5", "beta", "'overturn'", "0.001 ... 5")


def test_bootstrap_resamples_with_a_beta_out_of_bounds_are_left_out(tmp_path):
    # the percentile interval over the resamples that remain, as computed by hand from the closed form
    medians, betas = np.array([0.45, 0.5, 0.55, 0.5]), np.array([0.35, 1e-300, 0.45, 0.4])
    frag = fragility_file(tmp_path / "boot.fragility.h5", bootstrap=(medians * G, betas))
    x = np.geomspace(1e-3, 1e2, 200)
    ds = rockslide.risk(frag, {"power law": (x * G, K0 * x ** -K)})
    kept = [closed_form(theta=m, beta=b) for m, b in zip(medians, betas, strict=True) if b > 1e-3]
    low, high = np.percentile(kept, [2.5, 97.5])
    assert [float(ds.rate_lower[0]), float(ds.rate_upper[0])] == pytest.approx([low, high], rel=1e-6)
    assert "3 bootstrap resamples" in ds.attrs["fragility_uncertainty"]
    assert "1 with beta outside 0.001 ... 5 left out" in ds.attrs["fragility_uncertainty"]



# --------------------------------------------------------------------------------------------------
# Components: a hazard curve is of its ground-motion models' component (RotD50 for NGA-West2)
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("imt", "plain", "rotd50"), [("PGA", "pga", "rotd50_pga"),
                                                      ("SA(0.3)", "sa(0.3s)", "rotd50_sa(0.3s)"),
                                                      ("PGV", "pgv", "rotd50_pgv")])
def test_rotd50_matches_a_hazard_curve_with_one_note_and_rotd100_does_not(tmp_path, imt, plain, rotd50):
    # RotD50 PGA against OpenQuake's PGA was refused while RotD50 SA(0.3) against SA(0.3) was accepted
    # (and RotD100 too): one rule for all, the same rate as the plain measure's, one note for 2 files
    levels, median = ([5.0, 10.0, 20.0], "12cm/s") if imt == "PGV" else ([0.1, 0.4, 0.6], "0.5g")
    files = [openquake_csv(tmp_path / f"{kind}.csv", levels, [[0.45, 0.05, 0.006]] * 2, imt=imt, kind=kind,
                           sites=[(0.0, 0.0), (1.0, 0.0)]) for kind in ("mean", "rlz-001")]
    hazard = [a for f in files for a in ("--hazard", f)]
    common = ("--median", median, "--beta", "0.4", *hazard, "--out-dir", tmp_path, "--no-plot", "--json")
    given = invoke("risk", *common, "--im", plain, "--name", "plain")
    rotd = invoke("risk", *common, "--im", rotd50, "--name", "rotd")
    assert given.exit_code == 0 and rotd.exit_code == 0, (given.output, rotd.output)
    assert [c["rate"] for c in json.loads(rotd.stdout)["curves"]] == [c["rate"] for c in
                                                                      json.loads(given.stdout)["curves"]]
    assert json.loads(given.stdout)["notes"] == []
    notes = json.loads(rotd.stdout)["notes"]
    assert len(notes) == 1 and "RotD50" in notes[0] and "NGA-West2" in notes[0]
    text = invoke("risk", *common[:-1], "--im", rotd50, "--name", "text", "--overwrite")
    assert text.exit_code == 0 and text.stdout.count("note:") == 1 and "RotD50" not in text.stderr
    assert rockslide.read_result(tmp_path / "text.risk.h5").attrs["notes"] == notes[0]
    refused = invoke("risk", *common, "--im", rotd50.replace("50", "100"), "--name", "r100")
    one_line_error(refused, "RotD100", "not RotD100", f"--im '{rotd50}'", "mean.csv")


def test_a_fragility_file_of_rotd50_gets_the_note(tmp_path):
    frag = fragility_file(tmp_path / "rotd.fragility.h5", im="rotd50_pga")
    path = openquake_csv(tmp_path / "h.csv", [0.1, 0.4, 0.6], [[0.45, 0.05, 0.006]])
    ds = rockslide.risk(frag, path)
    assert "RotD50 PGA" in ds.attrs["notes"]
    refused = fragility_file(tmp_path / "rotd100.fragility.h5", im="rotd100_pga")
    with pytest.raises(CaseError, match="RotD100"):
        rockslide.risk(refused, path)
    # arrays or a table without a header say nothing of the component: no note
    x = np.array([0.1, 0.4, 0.6]) * G
    assert rockslide.risk(frag, {"site": (x, [1e-2, 1e-3, 1e-4])}).attrs["notes"] == ""


TWO = ("records:\n  - name: a\n    horizontal_1: {file: a1.at2, azimuth: 0deg}\n"
       "    horizontal_2: {file: a2.at2, azimuth: 90deg}\n")


@pytest.mark.parametrize(("suite_text", "along"), [(TWO, True), ("records: [a.at2, b.at2]\n", False),
                                                   (None, False), ("records: [", False)])
def test_plain_pga_along_the_block_gets_a_note_only_when_the_file_says_so(tmp_path, suite_text, along):
    # a two-component suite's PGA is of the motion along the block; one component, no suite in
    # the file, or one that does not parse: unclear, accepted as before without a note
    frag = fragility_file(tmp_path / "b.fragility.h5", suite_text=suite_text)
    path = openquake_csv(tmp_path / "h.csv", [0.1, 0.4, 0.6], [[0.45, 0.05, 0.006]])
    notes = rockslide.risk(frag, path).attrs["notes"]
    assert ("along the block" in notes and "RotD50" in notes) if along else notes == ""
