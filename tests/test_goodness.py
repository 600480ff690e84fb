"""Honest statistics (issue 40): goodness of fit of the lognormal, the isotonic curve, the
monotonicity test, the probit surface on two measures, what a rate rests on, and pelicun's
sequential states. Pure numerics on counts: no run of the kernel."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from rockslide.analyses import fragility as fr
from rockslide.analyses import goodness as gf
from rockslide.analyses import risk as rk

G = 9.80665
#: The statue on Kobe (issue 40): block 1.8 m x 0.45 m, friction 0.6, e 0.85, Kobe N-S + U-D, 100
#: parameter sets per level. The issue gives 0.45 ... 0.75 g; at 0.40 g no run overturned.
KOBE_LEVELS = np.array([0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75]) * G
KOBE_N = np.full(8, 100.0)
KOBE_Z = np.array([0, 19, 58, 100, 16, 12, 30, 83], dtype=float)


def kobe_fit():
    a, b, ok = fr.probit_mle(np.log(KOBE_LEVELS), KOBE_N[None], KOBE_Z[None])
    assert ok[0] and b[0] > 0
    return math.exp(-a[0] / b[0]), 1.0 / b[0]


# --------------------------------------------------------------------------------------------------
# Goodness of fit
# --------------------------------------------------------------------------------------------------


def test_deviance_is_the_likelihood_ratio_written_with_scipy_binom():
    """The deviance against scipy's binomial log-pmf at the fractions (saturated) and at p."""
    n = np.array([10.0, 20, 30, 5])
    z = np.array([0.0, 7, 30, 2])
    p = np.array([0.05, 0.4, 0.9, 0.5])
    saturated = stats.binom.logpmf(z, n, z / n).sum()
    model = stats.binom.logpmf(z, n, p).sum()
    assert gf.deviance(n, z, p) == pytest.approx(2 * (saturated - model), rel=1e-12)


def test_the_p_value_is_scipy_stats_chi2_sf():
    """`lognormal_goodness` takes the deviance's p-value from `core.normal.chi2_sf` (scipy.stats
    would take a second to import): ``scipy.stats.chi2.sf`` within 1e-12 relative, over deviances
    from 0 to far in the tail, and at 0, infinity and NaN (tests/test_normal.py holds it against
    mpmath at 50 digits); and the Kobe fit's p-value is that of its deviance and dof."""
    deviances = np.concatenate([np.random.default_rng(3).exponential(10.0, 2000), [0.0, 1e-300, 1e3, np.inf, np.nan]])
    for dof in range(1, 40):
        ours = np.array([gf.chi2_sf(d, dof) for d in deviances])
        reference = stats.chi2.sf(deviances, dof)
        assert np.allclose(ours, reference, rtol=1e-12, atol=1e-300, equal_nan=True)
    median, beta = kobe_fit()
    fit = gf.lognormal_goodness(KOBE_LEVELS, KOBE_N, KOBE_Z, median, beta)
    assert fit.p_value == pytest.approx(stats.chi2.sf(fit.deviance, fit.dof), rel=1e-12)


def test_kobe_lognormal_is_rejected_and_the_first_line_says_so():
    median, beta = kobe_fit()
    fit = gf.lognormal_goodness(KOBE_LEVELS, KOBE_N, KOBE_Z, median, beta)
    assert fit.dof == 6
    assert fit.rejected and fit.p_value < 0.01
    assert fit.not_monotone and fit.monotone_p_value < 0.01
    assert fit.sentence().startswith("lognormal REJECTED")


def test_kobe_isotonic_is_monotone_and_pools_only_the_violators():
    """Pool adjacent violators by hand: 0.58, 1.00, 0.16, 0.12, 0.30 pool to their mean 0.432 (equal
    weights); 0 and 0.19 below and 0.83 above are kept, and sit within their Wilson intervals."""
    iso = gf.isotonic(KOBE_N, KOBE_Z)
    assert (np.diff(iso) >= 0).all()
    expected = np.array([0.0, 0.19, 0.432, 0.432, 0.432, 0.432, 0.432, 0.83])
    np.testing.assert_allclose(iso, expected, atol=1e-12)
    low, high = gf.wilson_interval(KOBE_N, KOBE_Z)
    kept = [0, 1, 7]
    assert ((iso[kept] >= low[kept]) & (iso[kept] <= high[kept])).all()


def test_isotonic_is_the_constrained_maximum_likelihood():
    """Against scipy's SLSQP maximising the binomial likelihood under p_j <= p_{j+1}, unequal n."""
    rng = np.random.default_rng(5)
    n = rng.integers(3, 30, size=7).astype(float)
    z = rng.binomial(n.astype(int), [0.1, 0.5, 0.3, 0.6, 0.4, 0.9, 0.7]).astype(float)
    eps = 1e-9

    def negative(p):
        p = np.clip(p, eps, 1 - eps)
        return -np.sum(z * np.log(p) + (n - z) * np.log(1 - p))

    cons = [{"type": "ineq", "fun": lambda p, j=j: p[j + 1] - p[j]} for j in range(6)]
    from scipy import optimize
    best = optimize.minimize(negative, np.full(7, 0.5), method="SLSQP", constraints=cons, bounds=[(eps, 1 - eps)] * 7,
                             options={"ftol": 1e-14, "maxiter": 1000})
    iso = gf.isotonic(n, z)
    assert negative(iso) <= best.fun + 1e-7
    np.testing.assert_allclose(iso, best.x, atol=1e-4)


def pool_adjacent_violators(n, z):
    """Pool adjacent violators, one row, as a textbook writes it: the reference `gf.isotonic`'s
    max-min formula is held against."""
    keep = np.flatnonzero(n > 0)
    blocks = []                                   # [sum z, sum n, levels]
    for j in keep:
        blocks.append([z[j], n[j], 1])
        while len(blocks) > 1 and blocks[-2][0] * blocks[-1][1] > blocks[-1][0] * blocks[-2][1]:
            s, w, k = blocks.pop()
            blocks[-1] = [blocks[-1][0] + s, blocks[-1][1] + w, blocks[-1][2] + k]
    out = np.full(n.shape, np.nan)
    out[keep] = np.repeat([s / w for s, w, _ in blocks], [k for _, _, k in blocks])
    return out


@pytest.mark.parametrize("levels", [1, 2, 7, 15, 40])
def test_isotonic_is_pool_adjacent_violators_to_the_bit(levels):
    """3000 rows of counts (as the bootstrap makes them: whole numbers, some levels without runs),
    more rows than one chunk of pools: the same fractions as pooling adjacent violators, bit for
    bit (the pools' sums are whole numbers, exact in floating point, and each fraction one
    division)."""
    rng = np.random.default_rng(levels)
    n = rng.integers(0, 6, size=(3000, levels)).astype(float)
    n[:, rng.random(levels) < 0.2] = 0.0
    z = rng.binomial(n.astype(int), np.sort(rng.random(levels))).astype(float)
    expected = np.array([pool_adjacent_violators(nr, zr) for nr, zr in zip(n, z, strict=True)])
    assert np.array_equal(gf.isotonic(n, z), expected, equal_nan=True)
    assert np.array_equal(gf.isotonic(n.reshape(3, 1000, levels), z.reshape(3, 1000, levels)),
                          expected.reshape(3, 1000, levels), equal_nan=True)


@pytest.mark.parametrize("ends", ["zeros first", "all runs last", "both", "all runs first", "zeros last",
                                  "nothing but zeros", "nothing but all runs"])
def test_isotonic_of_rows_whose_ends_are_certain_is_pool_adjacent_violators_to_the_bit(ends):
    """`gf.isotonic` pools only the levels between leading levels without a success and trailing
    levels where every run succeeds (in every row): held against pooling adjacent violators where
    such ends exist, and where the ends are the other way round (all runs first, zeros last: those
    are violators to pool, not ends to leave out)."""
    rng = np.random.default_rng(len(ends))
    levels = 15
    n = rng.integers(0, 6, size=(2000, levels)).astype(float)
    n[:, [3, 12]] = 0.0                                  # levels without runs, inside the ends too
    p = np.sort(rng.random(levels))
    zeros, full = slice(0, 5), slice(10, levels)
    if ends in ("zeros first", "both"):
        p[zeros] = 0.0
    if ends in ("all runs last", "both"):
        p[full] = 1.0
    if ends == "all runs first":
        p[zeros] = 1.0
    if ends == "zeros last":
        p[full] = 0.0
    if ends.startswith("nothing"):
        p[:] = 0.0 if ends.endswith("zeros") else 1.0
    z = rng.binomial(n.astype(int), p).astype(float)
    expected = np.array([pool_adjacent_violators(nr, zr) for nr, zr in zip(n, z, strict=True)])
    assert np.array_equal(gf.isotonic(n, z), expected, equal_nan=True)
    assert np.array_equal(gf.isotonic(n[7], z[7]), expected[7], equal_nan=True)


def test_a_true_lognormal_is_rejected_no_more_often_than_the_level_allows():
    """200 suites drawn from a known lognormal (10 levels, 40 runs each), fitted and tested at level
    0.05: the rejections are Binomial(200, 0.05) if the test holds its level; more than its 99.9 %
    quantile (19) would say the test rejects true lognormals too often."""
    levels = np.geomspace(0.1, 1.2, 10) * G
    n = np.full(10, 40.0)
    p_true = stats.norm.cdf(np.log(levels / (0.45 * G)) / 0.5)
    rng = np.random.default_rng(40)
    p_values = []
    for _ in range(200):
        z = rng.binomial(40, p_true).astype(float)
        a, b, ok = fr.probit_mle(np.log(levels), n[None], z[None])
        assert ok[0]
        fit = gf.lognormal_goodness(levels, n, z, math.exp(-a[0] / b[0]), 1 / b[0], resamples=0)
        p_values.append(fit.p_value)
    rejected = int((np.array(p_values) < 0.05).sum())
    assert rejected <= stats.binom.ppf(0.999, 200, 0.05)
    assert rejected >= stats.binom.ppf(0.001, 200, 0.05)       # and not vacuously conservative


def test_monotone_test_does_not_reject_rising_noise():
    """Fractions of a rising curve with noise: the bootstrap p-value of the isotonic ratio is not
    small; a large fall (1.0 then 0.1, 100 runs each) is."""
    n = np.full(6, 30.0)
    z = np.array([2.0, 6, 5, 15, 14, 27])
    _, p = gf.monotone_test(n, z, resamples=500)
    assert p > 0.05
    _, p = gf.monotone_test(np.full(3, 100.0), np.array([100.0, 10, 90]), resamples=500)
    assert p < 0.01


def test_wilson_interval_matches_its_closed_form():
    low, high = gf.wilson_interval(np.array([20.0]), np.array([5.0]))
    q = stats.norm.ppf(0.975)
    p, n = 0.25, 20
    centre = (p + q * q / (2 * n)) / (1 + q * q / n)
    half = q / (1 + q * q / n) * math.sqrt(p * (1 - p) / n + q * q / (4 * n * n))
    assert low[0] == pytest.approx(centre - half, rel=1e-12)
    assert high[0] == pytest.approx(centre + half, rel=1e-12)


# --------------------------------------------------------------------------------------------------
# Two measures
# --------------------------------------------------------------------------------------------------


def test_probit_surface_recovers_its_coefficients():
    """2 x 10^4 runs drawn from P = Phi(1.5 + 2.0 ln PGA + 0.8 ln PGV): each coefficient within 3
    standard errors (the observed information's) of the truth."""
    rng = np.random.default_rng(11)
    m = 20_000
    pga = np.exp(rng.normal(math.log(0.5), 0.4, m))
    pgv = np.exp(rng.normal(math.log(0.4), 0.5, m))
    truth = np.array([1.5, 2.0, 0.8])
    y = rng.random(m) < stats.norm.cdf(truth[0] + truth[1] * np.log(pga) + truth[2] * np.log(pgv))
    fit = gf.probit_surface(pga, pgv, y)
    assert fit.converged
    assert (np.abs(fit.coefficients - truth) <= 3 * fit.standard_errors).all()
    assert (fit.standard_errors < 0.1).all()         # the test has teeth: errors are small


def test_probit_surface_refuses_separated_runs_and_a_constant_measure():
    fit = gf.probit_surface([1.0, 2, 3, 4], [1.0, 2, 1, 2], [0, 0, 1, 1])
    assert not fit.converged and "separate" in fit.note
    for second in ([1.0, 1, 1, 1], [0.5, 1, 1.5, 2]):     # constant, or proportional to the first
        fit = gf.probit_surface([1.0, 2, 3, 4], second, [0, 1, 0, 1])
        assert not fit.converged and "not identified" in fit.note


# --------------------------------------------------------------------------------------------------
# What a rate rests on
# --------------------------------------------------------------------------------------------------


def test_share_of_the_rate_below_an_intensity_is_its_closed_form():
    """Power-law hazard lambda = k0 x^-k, lognormal fragility: the rate from intensities below X is
    the partial integral of P(F|x) |d lambda| over (0, X]; by parts, k0 theta^-k exp(k^2 beta^2 / 2)
    Phi(ln(X/theta)/beta + k beta) - P(F|X) lambda(X). The hazard curve starts at 1e-7 g, where
    P(F) < 1e-40."""
    k0, k, theta, beta = 1e-4, 2.5, 0.5 * G, 0.4
    levels = np.geomspace(1e-7, 50.0, 40) * G
    curve = rk.HazardCurve("power", levels, k0 * levels ** -k)
    fragility = rk.Lognormal(theta, beta)
    total = rk.rate(fragility, curve).rate
    for x in (0.2 * G, 0.37 * G, 0.5 * G, 0.81 * G):
        closed = (k0 * theta ** -k * math.exp(0.5 * (k * beta) ** 2) * stats.norm.cdf(math.log(x / theta) / beta
                                                                                    + k * beta)
                  - fragility(x) * k0 * x ** -k)
        assert rk.rate_below(fragility, curve, x) == pytest.approx(closed, rel=1e-6)
        # and by quadrature of eq. (1), independently
        quad = integrate.quad(lambda u: fragility(math.exp(u)) * k * k0 * math.exp(-k * u), math.log(levels[0]),
                              math.log(x), limit=200, epsabs=0, epsrel=1e-10)[0]
        assert rk.rate_below(fragility, curve, x) == pytest.approx(quad, rel=1e-6)
    assert rk.rate_below(fragility, curve, levels[-1] * 2) == pytest.approx(total, rel=1e-12)


# --------------------------------------------------------------------------------------------------
# pelicun: sequential states, and pelicun's own probabilities
# --------------------------------------------------------------------------------------------------


def crossing_dataset(medians, betas, fractions, isotonic=None):
    from rockslide.io.datasets import study_dataset

    levels = np.array([0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0]) * G
    coords = [("level", levels, {"units": "m/s^2"}),
              ("damage_state", np.array(["overturn", "rotation>0.5alpha"], dtype=object), {})]
    variables = {
        "median": (("damage_state",), np.asarray(medians, float) * G, {"units": "m/s^2"}),
        "beta": (("damage_state",), np.asarray(betas, float), {"units": "1"}),
        "definition": (("damage_state",), np.array(["overturning", "max |rotation| > 0.5 alpha"], dtype=object), {}),
        "fit_note": (("damage_state",), np.array(["", ""], dtype=object), {}),
        "fraction_exceeded": (("damage_state", "level"), np.array(fractions, dtype=float), {"units": "1"}),
    }
    if isotonic is not None:
        variables["isotonic"] = (("damage_state", "level"), np.array(isotonic, dtype=float), {"units": "1"})
    return study_dataset(coords, variables, {"intensity_measure": "pga", "title": "t", "fit_method": "ml"})


def test_crossing_lognormals_are_never_exported_as_they_are():
    """Medians 0.3 g and 0.584 g with betas 0.2 and 0.6 cross at exp((0.6 ln 0.3 - 0.2 ln 0.584) / 0.4)
    = 0.215 g: refused, naming both states and the crossing."""
    from rockslide.errors import CaseError
    from rockslide.io import pelicun as pl

    fractions = [[0, 0, 0.3, 0.6, 0.9, 1, 1], [0, 0.1, 0.4, 0.7, 0.95, 1, 1]]
    expected = math.exp((0.6 * math.log(0.3) - 0.2 * math.log(0.584)) / 0.4)
    assert expected == pytest.approx(0.215, abs=5e-4)
    with pytest.raises(CaseError, match=r"rotation>0.5alpha and overturn cross at 0\.215 g"):
        pl.pelicun_row(crossing_dataset([0.584, 0.3], [0.6, 0.2], fractions), "X.1")
    # the multilinear curves are made sequential: the higher state lowered to the lower where above
    crossing = [[0, 0.2, 0.3, 0.6, 0.9, 1, 1], [0, 0.1, 0.4, 0.7, 0.95, 1, 1]]
    row, notes = pl.pelicun_row(crossing_dataset([math.nan, math.nan], [math.nan, math.nan], crossing, crossing),
                                "X.1", family="multilinear_CDF")
    assert any("lowered" in n and "overturn" in n for n in notes)
    x1, p1 = ([float(v) for v in part.split(",")] for part in row["LS1-Theta_0"].split("|"))
    x2, p2 = ([float(v) for v in part.split(",")] for part in row["LS2-Theta_0"].split("|"))
    grid = np.geomspace(0.05, 1.2, 200)
    assert (np.interp(grid, x2, p2) <= np.interp(grid, x1, p1) + 1e-5).all()


def _pelicun_uq():
    """pelicun's random variables. pelicun 3.10 imports ``scipy.stats._mvn`` (a private module scipy
    1.17 removed) for the multivariate normal CDF only, which a fragility's curves never call: a
    stand-in module lets the rest of pelicun load."""
    import sys
    import types

    pytest.importorskip("pelicun", reason="pelicun is not installed (pip install pelicun)")
    try:
        import scipy.stats._mvn  # noqa: F401
    except ModuleNotFoundError:
        sys.modules["scipy.stats._mvn"] = types.SimpleNamespace(mvndst=None)
    try:
        from pelicun import uq
    except ImportError as exc:
        pytest.skip(f"pelicun does not import here: {exc}")
    return uq


def _pelicun_cdf(uq, family, theta_0, theta_1, x):
    """A limit state's CDF as pelicun's damage model builds it from the CSV's columns
    (``DamageModel``: a multilinear Theta_0 split at '|' and ',')."""
    if family == "multilinear_CDF":
        xs, ps = (np.array(part.split(","), dtype=float) for part in theta_0.split("|"))
        theta = np.column_stack((xs, ps))
    else:
        theta = np.array([float(theta_0), float(theta_1)])
    rv = uq.rv_class_map(family)(name="FRG-X", theta=theta, truncation_limits=np.array([np.nan, np.nan]))
    return rv.cdf(np.asarray(x, dtype=float))


def test_pelicun_loads_the_export_and_gives_rockslides_probabilities(tmp_path):
    """The exported CSV read back as a CSV; pelicun's own random variables of each limit state, at 20
    intensities, equal rockslide's curves (the lognormal; the isotonic, linear in ln x, as risk
    integrates it) to 1e-4."""
    import csv

    from rockslide import api

    uq = _pelicun_uq()
    fractions = [[0, 0, 0.3, 0.6, 0.9, 1, 1], [0, 0.1, 0.4, 0.7, 0.95, 1, 1]]
    ds = crossing_dataset([0.35, 0.3], [0.3, 0.3], fractions, fractions)
    levels = np.array([0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0])
    x = np.geomspace(0.08, 1.3, 20)
    for family, curves in (("lognormal", [rk.Lognormal(0.3, 0.3), rk.Lognormal(0.35, 0.3)]),
                           ("multilinear_CDF", [rk.Tabulated(levels, np.array(fractions[1], float)),
                                               rk.Tabulated(levels, np.array(fractions[0], float))])):
        path, _ = api.export_pelicun(ds, "RS.x", tmp_path / f"{family}.csv", family=family)
        with open(path, newline="") as f:
            row = next(csv.DictReader(f))
        for k, curve in enumerate(curves, start=1):
            got = _pelicun_cdf(uq, row[f"LS{k}-Family"], row[f"LS{k}-Theta_0"], row[f"LS{k}-Theta_1"], x)
            np.testing.assert_allclose(got, curve(x), atol=1e-4)


# --------------------------------------------------------------------------------------------------
# Ensembles to a stated precision
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("k, n, width", [(30, 100, 0.05), (0, 100, 0.02), (100, 100, 0.05), (50, 100, 0.1)])
def test_members_needed_is_the_fewest_with_that_width(k, n, width):
    from rockslide.analyses import ensemble as ens

    m = ens.members_needed(k, n, width)
    p = min(max(k / n, 0.5 / n), 1 - 0.5 / n)
    low, high = ens.wilson_interval(p * m, m)
    assert high - low <= width
    low, high = ens.wilson_interval(p * (m - 1), m - 1)
    assert high - low > width
    if k == 50:     # the normal approximation's 4 z^2 p (1 - p) / w^2 = 384, and Wilson's is close to it
        assert abs(m - 4 * stats.norm.ppf(0.975) ** 2 * 0.25 / width ** 2) < 5


def test_an_ensemble_to_a_precision_says_how_many_it_took():
    """The example case's neighbourhood until the 95 % interval is within 0.15 wide."""
    from conftest import REPO

    from rockslide import api

    ds = api.ensemble(REPO / "configs" / "example.yaml", "precision:0.15", seed=3)
    import json
    summary = json.loads(ds.attrs["ensemble"])
    assert summary["interval"][1] - summary["interval"][0] <= 0.15
    assert summary["n"] == summary["rounds"][-1] == ds.sizes["member"]
    assert summary["precision"] == 0.15
    if len(summary["rounds"]) > 1:        # the round before was not precise enough
        assert summary["rounds"][-2] < summary["n"]


def test_ensemble_members_option_reads_auto_and_precision():
    from rockslide.analyses import ensemble as ens
    from rockslide.errors import CaseError

    assert ens.parse_members("auto") == (None, ens.AUTO_PRECISION)
    assert ens.parse_members("precision:0.05") == (None, 0.05)
    assert ens.parse_members("200") == (200, None)
    with pytest.raises(CaseError, match="^ensemble: "):
        ens.parse_members("precision:2")


# --------------------------------------------------------------------------------------------------
# In the fit, its printout and the command
# --------------------------------------------------------------------------------------------------


def test_kobe_fit_state_says_the_rejection_first_and_keeps_the_isotonic_curve():
    """fit_state on the issue's counts (100 realisations of one record, the realisations of a level
    arranged so that the counts are the issue's): the state's printout line starts with the rejection."""
    exceeded = (np.arange(100)[:, None] < KOBE_Z[None, :]).astype(np.int8)
    fit = fr.fit_state(KOBE_LEVELS, exceeded, resamples=0, per_record=100)
    line = fr.describe_fit(fr.OVERTURN, fit, fr.INTENSITY_MEASURES["pga"])
    assert line.startswith("overturn: lognormal REJECTED by the per-level fractions")
    assert "--model isotonic" in line
    np.testing.assert_allclose(fit.isotonic, gf.isotonic(KOBE_N, KOBE_Z))
    assert any("fall as the level rises by more than sampling noise" in t for t in fr.goodness_lines(fit))


def test_two_measures_on_the_command_line(tmp_path):
    """--im pga,pgv: the surface in the JSON and its figure beside the curves; --im pga,pgv/pga too."""
    import json

    from conftest import REPO, invoke

    for im in ("pga,pgv", "pga,pgv/pga"):
        out = tmp_path / im.replace("/", "_")
        result = invoke("fragility", REPO / "configs" / "example.yaml", "--suite", REPO / "records" /
                        "suite-synthetic.yaml", "--levels", "0.2g:1.6g:0.2g", "--im", im, "--bootstrap", "20",
                        "--out-dir", out, "--no-progress", "--json")
        assert result.exit_code == 0, result.output
        payload = json.loads(result.stdout)
        surface = payload["surface"]["states"]["overturn"]
        assert payload["surface"]["scales_with_record"] == (im == "pga,pgv")
        assert surface["coefficients"] is None or set(surface["coefficients"]) == {"a", "b", "c"}
        assert (out / "example.fragility.surface.png").exists() == (surface["coefficients"] is not None)
    from rockslide.errors import CaseError
    with pytest.raises(CaseError, match="^im: "):
        fr.split_measures("pga,sa(1s)")


def test_fragility_table_gives_the_tabulated_rate(tmp_path):
    """risk --fragility-table: the CSV's levels in its header's unit, integrated as risk.Tabulated."""
    from rockslide import api

    table = tmp_path / "statue.csv"
    table.write_text("PGA [g], probability\n0.4, 0\n0.45, 0.14\n0.5, 0.43\n0.75, 0.43\n0.8, 1\n")
    levels = np.geomspace(0.05, 3.0, 30) * G
    hazard = {"site": (levels, 1e-4 * (levels / G) ** -2.5)}
    ds = api.risk(hazard=hazard, fragility_table=table)
    expected = rk.rate(rk.Tabulated(np.array([0.4, 0.45, 0.5, 0.75, 0.8]) * G,
                                    np.array([0, 0.14, 0.43, 0.43, 1.0])), rk.HazardCurve("s", *hazard["site"])).rate
    assert float(ds.rate[0]) == pytest.approx(expected, rel=1e-12)
    assert float(ds.share_above_tested[0]) > 0          # above 0.8 g: the curve held at 1
    from rockslide.errors import CaseError
    table.write_text("PGA [g], probability\n0.4, 0.5\n0.5, 0.3\n")
    with pytest.raises(CaseError, match="not decreasing"):
        api.risk(hazard=hazard, fragility_table=table)


def test_a_dropped_vertical_is_said_in_the_caption():
    caption = fr.caption("name: x\n", suite="s.yaml", records=2, im=fr.INTENSITY_MEASURES["pga"],
                         levels=[1.0, 2.0], step=1e-4, vertical_note="the suite has no vertical records")
    assert "HORIZONTAL ONLY" in caption
