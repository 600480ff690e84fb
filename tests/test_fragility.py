"""`rockslide fragility`: the fits against independent computations, runs against `rockslide run`,
the result file, the JSON, bad input, and the shared real suite.

Offline: the runs use the shipped example case (`configs/example.yaml`) and the project's synthetic
suite (`records/suite-synthetic.yaml`); the test on the real 18-record suite skips with a message
naming the folder when it is absent.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np
import pytest
import yaml
from conftest import REPO, invoke, one_line_error, real_records_dir
from scipy import optimize, stats

from rockslide.analyses import fragility as fr
from rockslide.case import case_to_dict, load_suite
from rockslide.core import batch, intensity
from rockslide.core import kernel as K
from rockslide.core.normal import log_normal_cdf
from rockslide.engine import chunks
from rockslide.engine import execute as ex
from rockslide.engine import prepare as runner
from rockslide.errors import CaseError, RockslideError
from rockslide.io import results

EXAMPLE = REPO / "configs" / "example.yaml"
SUITE = REPO / "records" / "suite-synthetic.yaml"
RECORDS = REPO / "records"
G = 9.80665
SUMMARY_FIELDS = ("overturned", "overturn_time", "direction", "max_rotation", "max_slip", "residual_slip",
                  "impacts")


@pytest.fixture(scope="module", autouse=True)
def compiled():
    batch.warm_up()


# --------------------------------------------------------------------------------------------------
# The fits
# --------------------------------------------------------------------------------------------------


def binomial_stripes(seed, levels, n, median, beta):
    rng = np.random.default_rng(seed)
    return rng.binomial(n, stats.norm.cdf(np.log(levels / median) / beta)).astype(float)


def test_mle_equals_a_direct_maximisation_of_the_binomial_likelihood():
    """Baker's (2015) binomial likelihood of the stripes maximised directly with scipy's Nelder-Mead
    over (ln median, ln beta), the likelihood written with scipy.stats.binom: the same optimum as the
    probit regression's Newton iterations. Nelder-Mead stops within ~1e-9 of the optimum in its
    variables, so 1e-7."""
    levels = np.linspace(0.1, 1.5, 15)
    n = np.full(15, 20.0)
    z = binomial_stripes(3, levels, 20, 0.7, 0.35)

    def negative(x):
        p = stats.norm.cdf((np.log(levels) - x[0]) / math.exp(x[1]))
        return -np.sum(stats.binom.logpmf(z, n, p))

    direct = optimize.minimize(negative, [math.log(0.5), math.log(0.5)], method="Nelder-Mead",
                               options={"xatol": 1e-11, "fatol": 1e-13, "maxiter": 20_000})
    a, b, converged = fr.probit_mle(np.log(levels), n[None, :], z[None, :])
    assert converged[0] and direct.success
    assert math.exp(-a[0] / b[0]) == pytest.approx(math.exp(direct.x[0]), rel=1e-7)
    assert 1.0 / b[0] == pytest.approx(math.exp(direct.x[1]), rel=1e-7)
    # and fit_state gives the same from the runs themselves (20 records)
    exceeded = (np.arange(20)[:, None] < z[None, :]).astype(np.int8)
    fit = fr.fit_state(levels, exceeded, resamples=0)
    assert fit.median == pytest.approx(math.exp(direct.x[0]), rel=1e-7)
    assert fit.beta == pytest.approx(math.exp(direct.x[1]), rel=1e-7)


def test_bootstrap_intervals_cover_the_true_median_and_beta():
    """40 synthetic analyses (20 records x 10 levels, each run reaching the state with probability
    Phi(ln(x / 0.8) / 0.4)): the 95 % intervals should hold the truth in about 38 of 40. If they did
    with probability 0.95, fewer than 34 would happen with probability 0.2 %; intervals too narrow
    by half (coverage ~ 0.66) would pass with probability < 1e-4."""
    levels = np.linspace(0.2, 2.0, 10)
    p = stats.norm.cdf(np.log(levels / 0.8) / 0.4)
    held = {"median": 0, "beta": 0}
    for seed in range(40):
        exceeded = (np.random.default_rng(seed).random((20, 10)) < p).astype(np.int8)
        fit = fr.fit_state(levels, exceeded, resamples=400, seed=seed)
        held["median"] += fit.median_ci[0] <= 0.8 <= fit.median_ci[1]
        held["beta"] += fit.beta_ci[0] <= 0.4 <= fit.beta_ci[1]
        assert fit.median_ci[0] <= fit.median <= fit.median_ci[1]
    assert held["median"] >= 34 and held["beta"] >= 34, held


def test_the_bootstrap_fits_each_resample_as_a_fit_of_it_alone():
    """The bootstrap fits each distinct resample once, all at once, iterating only on those not yet
    converged; a resample's (median, beta) must be what `probit_mle` gives for its counts alone.
    6 records give at most 462 distinct resamples of 1000, so most are repeats. Each resample is
    drawn here as `_bootstrap` draws it (the same generator and seed) and fitted by itself: equal
    to the bit, since every row's arithmetic is the same whichever rows it is fitted with, where
    numpy's exp and log are the C library's. On a CPU with AVX-512 numpy's own vector code (SVML)
    can round a row's last bit differently in a larger array (2026-11-29: 7 of 198 resamples, 1 ulp
    each): within 2 ulp there, and most to the bit."""
    levels = np.linspace(0.1, 1.5, 15)
    rng = np.random.default_rng(5)
    capacity = 0.7 * np.exp(0.4 * rng.standard_normal((6, 1)) + 0.1 * rng.standard_normal((6, 15)))
    exceeded = (levels[None, :] >= capacity).astype(np.int8)
    fit = fr.fit_state(levels, exceeded, resamples=200, seed=11)
    picks = np.random.default_rng(11).integers(0, 6, size=(200, 6))
    expected = []
    for pick in picks:
        n, z = fr.stripe_counts(exceeded[pick])
        low, high = fr._separation(n[None, :], z[None, :])
        if low[0] >= 0 and high[0] > low[0]:
            a, b, converged = fr.probit_mle(np.log(levels), n[None, :], z[None, :])
            if converged[0] and b[0] > 0:
                expected.append((math.exp(-a[0] / b[0]), 1.0 / b[0]))
    assert len({tuple(p) for p in np.sort(picks, axis=1)}) < 150          # repeats: the case above
    assert fit.resamples_fitted == len(expected) > 150
    expected = np.array(expected)
    assert np.all(np.abs(fit.samples - expected) <= 2 * np.spacing(np.abs(expected)))
    assert np.count_nonzero((fit.samples != expected).any(axis=1)) <= len(expected) // 10


def plain_newton(a, b, s, n, z):
    """`fr._newton` as a textbook writes it, one data set at a time, every quantity evaluated anew
    at every point; with the number of line searches that found no better point in 60 halvings.
    The reference of the one below."""
    a, b = a.copy(), b.copy()
    converged = np.zeros(a.shape, dtype=bool)
    exhausted = 0

    def log_likelihood(ar, br, nr, zr):
        eta = ar + br * s
        return np.sum(zr * log_normal_cdf(eta) + (nr - zr) * log_normal_cdf(-eta))

    for r in range(a.size):
        nr, zr = n[r], z[r]
        ll = log_likelihood(a[r], b[r], nr, zr)
        for _ in range(fr.FIT_ITERATIONS):
            eta = a[r] + b[r] * s
            log_phi = -0.5 * eta * eta - 0.5 * math.log(2.0 * math.pi)
            up = np.exp(log_phi - log_normal_cdf(eta))
            down = np.exp(log_phi - log_normal_cdf(-eta))
            d1 = zr * up - (nr - zr) * down
            d2 = zr * up * (eta + up) + (nr - zr) * down * (down - eta)
            g0, g1 = d1.sum(), (d1 * s).sum()
            h00, h01, h11 = d2.sum(), (d2 * s).sum(), (d2 * s * s).sum()
            det = h00 * h11 - h01 * h01
            da = np.nan_to_num((h11 * g0 - h01 * g1) / det)
            db = np.nan_to_num((h00 * g1 - h01 * g0) / det)
            t = 1.0
            for _ in range(60):
                trial = log_likelihood(a[r] + t * da, b[r] + t * db, nr, zr)
                if trial >= ll - 1e-13 * abs(ll):
                    break
                t *= 0.5
            else:
                exhausted += 1
            a[r], b[r] = a[r] + t * da, b[r] + t * db
            ll = trial if np.isfinite(trial) else ll
            if abs(t * da) <= fr.FIT_TOLERANCE * (1.0 + abs(a[r])) and \
                    abs(t * db) <= fr.FIT_TOLERANCE * (1.0 + abs(b[r])):
                converged[r] = True
                break
    return a, b, converged, exhausted


def test_newton_takes_its_log_cdfs_from_the_line_search_to_the_bit():
    """`fr._newton` evaluates ``ln Phi(+-eta)`` once per point: a step takes them from the line
    search's last evaluation, which was at that point. 228 data sets fitted together: overlapping
    ones from a near start and from a steep one (where about one in 60 overshoots at some step and
    halves it), and nearly separated ones (whose estimates run away, line searches running out on
    the way); against the textbook iterations one data set at a time: the same numbers to the bit.
    Taking them from the search's first trial instead, or from the wrong data sets, fails here."""
    rng = np.random.default_rng(17)
    levels = np.linspace(0.1, 1.5, 9)
    s = np.log(levels)
    n = rng.integers(0, 6, size=(600, 9)).astype(float)
    z = rng.binomial(n.astype(int), stats.norm.cdf(np.log(levels / 0.6) / 0.4)).astype(float)
    low, high = fr._separation(n, z)
    overlap = np.flatnonzero((low >= 0) & (high > low))[:220]
    # nearly separated: no run below a level reaches the state, every run above it does, half at it
    cut, level = rng.integers(1, 8, size=(8, 1)), np.arange(9)[None, :]
    n = np.concatenate([n[overlap], np.full((8, 9), 4.0)])
    z = np.concatenate([z[overlap], np.where(level > cut, 4.0, np.where(level == cut, 2.0, 0.0))])
    kind = np.repeat([0, 1, 2], [20, 200, 8])       # 0: near start, 1: steep start, 2: separated
    start_a, start_b = np.where(kind == 1, 0.0, 0.5), np.where(kind == 1, 30.0, 2.0)
    with np.errstate(all="ignore"):
        a, b, converged = fr._newton(start_a.copy(), start_b.copy(), s, n, z)
        expected_a, expected_b, expected_converged, exhausted = plain_newton(start_a, start_b, s, n, z)
    assert exhausted > 0 and converged[kind < 2].all()                  # both kinds of path taken
    assert np.array_equal(a, expected_a) and np.array_equal(b, expected_b)
    assert np.array_equal(converged, expected_converged)


@pytest.mark.parametrize("rows, note", [
    ([[0, 0, 0], [0, 0, 0]], "no run exceeds"),
    ([[1, 1, 1], [1, 1, 1]], "every run exceeds"),
    ([[0, 0, 1], [0, 0, 1]], "separate between"),          # none up to the second, all from the third
    ([[0, 0, 1, 1], [0, 0, 1, 1], [0, -1, 1, 1]], "separate between"),
    ([[0, 1, 1], [0, 0, 1]], "separate at"),               # mixed at the second level only
    ([[0, 0, 1], [0, 1, 1], [-1, 0, 1]], "cannot fix beta"),
    ([[-1, -1], [-1, -1]], "no run inside the model"),
    ([[1, 1, 0, 0], [1, 0, 0, 0], [1, 1, 1, 0]], "falls as the intensity rises"),
])
def test_a_fit_is_refused_where_the_data_cannot_support_it(rows, note):
    levels = np.linspace(0.2, 0.8, len(rows[0]))
    fit = fr.fit_state(levels, np.array(rows, dtype=np.int8), resamples=50)
    assert fit.median is None and fit.beta is None and note in fit.note
    assert fit.median_ci is None


def test_one_mixed_level_alone_separates():
    """All below 0.5 stay, all above exceed, 0.5 mixed: the likelihood grows as beta -> 0."""
    levels = np.array([0.3, 0.5, 0.7])
    fit = fr.fit_state(levels, np.array([[0, 0, 1], [0, 1, 1]], dtype=np.int8), resamples=0)
    assert fit.median is None and "separate at 0.5 " in fit.note


def test_runs_outside_the_model_are_counted_and_left_out_of_the_fit():
    """A run marked -1 counts in n_outside_model and nowhere else: the fit equals the fit of the
    same data without that run's record at that level."""
    levels = np.linspace(0.2, 2.0, 8)
    exceeded = (np.random.default_rng(5).random((12, 8)) < stats.norm.cdf(np.log(levels))).astype(np.int8)
    n, z = fr.stripe_counts(exceeded)
    marked = exceeded.copy()
    marked[3, 4] = -1
    fit = fr.fit_state(levels, marked, resamples=0)
    assert fit.n_outside_model == 1 and fit.n_runs == 96
    n2 = n.copy()
    z2 = z.copy()
    n2[4] -= 1
    z2[4] -= exceeded[3, 4]
    a, b, _ = fr.probit_mle(np.log(levels), n2[None, :], z2[None, :])
    assert fit.median == pytest.approx(math.exp(-a[0] / b[0]), rel=1e-12)
    assert fit.n_exceeded == int(z.sum() - exceeded[3, 4])


def test_moments_of_the_bracketed_capacities():
    """Baker (2015), method of moments: the mean and the (n - 1) standard deviation of the logarithms
    of the capacities, each at the geometric midpoint of the levels bracketing the record's first
    exceedance; a record that exceeds, stops, and exceeds again counts at its first level; a record
    that never exceeds, or exceeds already at the lowest level, leaves the moments undefined, as
    does a suite whose records all first exceed at one level (beta 0)."""
    levels = np.array([0.2, 0.4, 0.6, 0.8])
    exceeded = np.array([[0, 1, 0, 1], [0, 0, 1, 1], [-1, 0, 0, 1], [0, 1, 1, 1]], dtype=np.int8)
    fit = fr.fit_state(levels, exceeded, resamples=0)
    capacity = np.log(np.sqrt([0.2 * 0.4, 0.4 * 0.6, 0.6 * 0.8, 0.2 * 0.4]))
    assert fit.moments_median == pytest.approx(math.exp(capacity.mean()), rel=1e-14)
    assert fit.moments_beta == pytest.approx(np.std(capacity, ddof=1), rel=1e-14)
    censored = fr.fit_state(levels, np.vstack([exceeded, [0, 0, 0, 0]]), resamples=0)
    assert censored.moments_median is None and censored.n_censored == 1
    assert "1 of 5 records never exceed" in censored.moments_note
    low = fr.fit_state(levels, np.vstack([exceeded, [1, 1, 1, 1]]), resamples=0)
    assert low.moments_median is None and "1 of 5 records exceed the state already at the lowest" in low.moments_note
    every = fr.fit_state(levels, np.ones((3, 4), dtype=np.int8), resamples=100)    # the review's case
    assert every.median is None and every.moments_median is None and every.moments_median_ci is None
    same = fr.fit_state(levels, np.array([[0, 1, 1, 1]] * 3, dtype=np.int8), resamples=0)
    assert same.moments_median is None and "every record first exceeds the state at 0.4" in same.moments_note


def test_the_moments_are_not_biased_by_the_level_spacing():
    """The review's simulation: 18 records with lognormal capacities (median 1 g, beta 0.3), stripes
    0.25 g apart, 300 suites. The first exceeding level overestimated the median by 12 %; the
    bracket's geometric midpoint is within 2 % (the maximum-likelihood fit: within 1 %), and beta
    within 10 %."""
    rng = np.random.default_rng(1)
    levels = np.arange(0.25, 4.01, 0.25)
    medians, betas = [], []
    for _ in range(300):
        capacity = np.exp(rng.normal(0.0, 0.3, 18))
        fit = fr.fit_state(levels, (levels[None, :] >= capacity[:, None]).astype(np.int8), resamples=0)
        medians.append(math.log(fit.moments_median))
        betas.append(fit.moments_beta)
    assert abs(math.exp(np.mean(medians)) - 1.0) < 0.02
    assert abs(np.mean(betas) / 0.3 - 1.0) < 0.1


def test_reverse_separation_and_a_single_record_are_said():
    """Every run up to a level reaches the state and none above it: the probability falls, no fit
    (it used to say 'did not converge'). One record: a fit, without intervals (every resample is
    that record: a zero-width interval before)."""
    levels = np.array([0.2, 0.4, 0.6, 0.8])
    for rows, low, high in (([[1, 1, 0, 0], [1, 1, 0, 0]], "0.4", "0.6"), ([[1, 1, 0, 0], [1, 0, 0, 0]], "0.4", "0.4")):
        reverse = fr.fit_state(levels, np.array(rows, dtype=np.int8), resamples=50)
        assert reverse.median is None
        assert reverse.note == (f"the runs reach the state up to {low} and stay below it from {high} on: the "
                                "probability falls as the intensity rises, no fit")
    falling = fr.fit_state(levels, np.array([[1, 1, 0, 1], [1, 0, 0, 0], [1, 1, 1, 0]], dtype=np.int8),
                           resamples=0)
    assert falling.note == "the fitted probability falls as the intensity rises: no fit"
    one = fr.fit_state(levels, np.array([[0, 1, 0, 1]], dtype=np.int8), resamples=50)
    assert one.median is not None and one.median_ci is None and one.resamples == 0


# --------------------------------------------------------------------------------------------------
# Options
# --------------------------------------------------------------------------------------------------


def test_intensity_measures_and_levels():
    assert fr.parse_im("PGA").name == "pga" and fr.parse_im("pgv").kind == "velocity"
    sa = fr.parse_im("sa(300 ms)")
    assert sa.period == pytest.approx(0.3) and sa.name == "sa(0.3 s)" and sa.kind == "acceleration"
    assert fr.parse_im("Sa(1s)").label == "Sa(1 s, 5 %)"
    levels = fr.parse_levels("0.1g:1.5g:0.1g", fr.parse_im("pga"))
    assert len(levels) == 15 and levels.values[2] == pytest.approx(0.3 * G) and levels.texts[2] == "0.3g"
    assert fr.parse_levels("10cm/s,20cm/s", fr.parse_im("pgv")).values == (0.1, 0.2)
    assert fr.parse_levels("0.5:2:0.5", fr.parse_im("pga_rocking")).values == (0.5, 1.0, 1.5, 2.0)


def test_damage_states():
    states = fr.damage_states(["rotation > 0.5 alpha", "slip>50mm", "residual>1cm", "rotation>10deg"])
    assert [s.name for s in states] == ["overturn", "rotation>0.5alpha", "slip>50mm", "residual>1cm",
                                        "rotation>10deg"]
    assert [(s.quantity, s.threshold) for s in states[1:]] == [
        ("max_rotation_ratio", 0.5), ("max_slip", pytest.approx(0.05)), ("residual_slip", pytest.approx(0.01)),
        ("max_rotation", pytest.approx(math.radians(10)))]
    assert fr.parse_damage("rotation>alpha").threshold == 1.0


def test_exceedances_of_each_state():
    """Overturning exceeds every state; a run outside the model is -1 everywhere."""
    variables = {"overturned": (np.array([[0, 0, 1, 0]]), {}), "status": (np.array([[0, 0, 0, 1]]), {}),
                 "max_rotation": (np.array([[0.1, 0.3, 1.57, 0.0]]), {}),
                 "max_slip": (np.array([[0.06, 0.0, 0.0, 0.0]]), {}),
                 "residual_slip": (np.array([[-0.02, 0.0, 0.0, 0.0]]), {})}
    states = fr.damage_states(["rotation>0.5alpha", "slip>50mm", "residual>10mm"])
    out = fr.exceedances(variables, np.full((1, 4), 0.4636), states)
    assert out[0].tolist() == [[0, 0, 1, 1], [0, 1, 0, 0], [1, 1, 1, 1], [-1, -1, -1, -1]]


@pytest.mark.parametrize("args, parts", [
    (["--im", "pgv/pga"], ["--im", "does not change when a record is scaled"]),
    (["--im", "sa(-1s)"], ["--im", "positive time"]),
    (["--im", "sd(1s)"], ["--im", "unknown intensity measure"]),
    (["--levels", "0.5g,0.3g"], ["--levels", "increasing"]),
    (["--levels", "1g:0.5g:0.1g"], ["--levels", "stop is below the start"]),
    (["--levels", "0g,1g"], ["--levels", "positive"]),
    (["--levels", "10 furlong"], ["--levels", "unknown acceleration unit"]),
    (["--damage", "slip>50"], ["--damage", "unit", "slip>50mm"]),
    (["--damage", "sliding>5mm"], ["--damage", "cannot read"]),
    (["--damage", "slip>-5mm"], ["--damage", "positive"]),
    (["--damage", "slip>5mm", "--damage", "slip > 5mm"], ["--damage", "twice"]),
    (["--units", "g"], ["--units", "folder or a glob"]),
    (["--units", "furlong"], ["--units", "unknown acceleration unit"]),
])
def test_bad_options_are_one_line_errors(args, parts, tmp_path):
    base = {"--im": "pga", "--levels": "0.5g,1g"}
    extra = []
    for i in range(0, len(args), 2):
        if args[i] in base:
            base[args[i]] = args[i + 1]
        else:
            extra += args[i:i + 2]
    result = invoke("fragility", EXAMPLE, "--suite", SUITE, "--records-dir", RECORDS, "--out-dir", tmp_path,
                    "--no-progress", *[x for kv in base.items() for x in kv], *extra)
    one_line_error(result, *parts)
    assert not any(tmp_path.iterdir())


def write_suite(folder, text):
    path = folder / "suite.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("text, parts", [
    ("records:\n  - {name: a, horizontal: {file: missing.at2}}\n",
     ["suite.yaml", "records[0].horizontal.file", "'missing.at2' not found"]),
    ("records:\n  - {name: a, horizontal: {file: synthetic_kt_h.at2, unit: g}}\n",
     ["suite.yaml", "records[0].horizontal.unit", "did you mean 'units'"]),
    ("records:\n  - {name: a, horizontal: synthetic_kt_h.at2, vertical: {file: synthetic_kt_v.at2, "
     "units: gal}}\n", ["suite.yaml", "records[0].vertical", "units"]),
    ("records:\n  - synthetic_kt_h.at2\n  - synthetic_kt_h.at2\n", ["suite.yaml", "records[1]", "name"]),
    ("records: synthetic_kt_h.at2\n", ["suite.yaml", "records", "non-empty list"]),
    ("recods: [a]\n", ["suite.yaml", "recods", "unknown key"]),
    ("records: [a: b: c]\n", ["suite.yaml", "invalid YAML"]),
])
def test_bad_suite_entries_name_the_file_the_entry_and_the_field(text, parts, tmp_path):
    suite = write_suite(tmp_path, text)
    out = tmp_path / "out"
    result = invoke("fragility", EXAMPLE, "--suite", suite, "--levels", "0.5g", "--records-dir", RECORDS,
                    "--out-dir", out, "--no-progress")
    one_line_error(result, *parts)
    assert not out.exists()


def test_a_folder_of_records_without_units_asks_for_units(tmp_path):
    (tmp_path / "a.csv").write_text("# time, acceleration\n0.0,0.1\n0.01,-0.2\n0.02,0.05\n")
    (tmp_path / "README.md").write_text("not a record\n")
    result = invoke("fragility", EXAMPLE, "--suite", tmp_path, "--levels", "0.5g", "--out-dir", tmp_path / "o",
                    "--no-progress")
    one_line_error(result, "a.csv", "--units")


def test_the_case_may_not_fix_the_vertical_peak(tmp_path):
    case = tmp_path / "v.yaml"
    case.write_text(EXAMPLE.read_text().replace("../records/", str(RECORDS) + "/")
                    .replace("vertical_factor: 1.0", "pga_vertical: 300 gal"))
    result = invoke("fragility", case, "--suite", SUITE, "--levels", "0.5g", "--out-dir", tmp_path / "o",
                    "--no-progress")
    one_line_error(result, "ground.scale.pga_vertical")


# --------------------------------------------------------------------------------------------------
# Runs equal `rockslide run`
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def planned(example):
    """The synthetic suite at three PGA levels, computed in one batch."""
    suite = load_suite(SUITE)
    im = fr.parse_im("pga")
    fplan = fr.plan_fragility(example, suite, im, fr.parse_levels("0.7g,1.1g,1.4g", im), records_dir=RECORDS)
    plan = fplan.plan
    states = batch.compute(plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
                           plan.factor_v)
    return fplan, fr.analyse(fplan, states, fr.damage_states(["slip>50mm"]), resamples=0)


def assert_run_equals(variables, index, summary):
    for name in SUMMARY_FIELDS:
        value = variables[name][0][index]
        expected = getattr(summary, name)
        if expected is None:
            expected = math.nan if name == "overturn_time" else 0
        if isinstance(expected, float) and math.isnan(expected):
            assert math.isnan(value), name
        else:
            assert value == float(expected), name          # bit for bit
    assert K.STATUS_NAMES[variables["status"][0][index]] == summary.status


def test_runs_equal_single_runs_of_their_case(planned):
    """Every run of the grid against `runner.run_case` of `point_case` (the record in ground, scaled
    by ground.scale.factor): the same numbers, bit for bit."""
    fplan, analysis = planned
    over = analysis.variables["overturned"][0]
    assert over.any() and not over.all()
    for r in range(fplan.shape[0]):
        for j in range(fplan.shape[1]):
            _, result = runner.run_case(fr.point_case(fplan, r, j), RECORDS, history=False)
            assert_run_equals(analysis.variables, (r, j), result.summary)


def test_scale_factors_put_each_record_at_each_level(planned):
    """k = level / PGA: the scaled record's peak is the level (to one rounding); the vertical has the
    same factor (vertical_factor 1), so the record's V/H ratio is kept."""
    fplan, analysis = planned
    factors = analysis.variables["scale_factor"][0]
    for r, case in enumerate(fplan.record_cases):
        ground = runner.load_ground(case, RECORDS)
        for j, level in enumerate(fplan.levels.values):
            assert factors[r, j] * np.max(np.abs(ground.horizontal)) == pytest.approx(level, rel=1e-15)
        assert np.array_equal(fplan.plan.factor_v.reshape(fplan.shape)[r], factors[r])


def test_sa_scaling_puts_each_record_at_its_level(example):
    """With sa(0.3 s) each scaled record's Sa is the level: Sa is linear in the record, so to a few
    roundings."""
    im = fr.parse_im("sa(0.3s)")
    fplan = fr.plan_fragility(example, load_suite(SUITE), im, fr.parse_levels("0.5g,2g", im), records_dir=RECORDS)
    for r, case in enumerate(fplan.record_cases[:2]):
        ground = runner.load_ground(case, RECORDS)
        for j, level in enumerate(fplan.levels.values):
            k = fplan.plan.factor_h[r * 2 + j]
            assert intensity.spectral_acceleration(k * ground.horizontal, ground.dt, 0.3) == \
                pytest.approx(level, rel=1e-12)


def test_a_run_through_rockslide_run_on_its_case_file(planned, tmp_path):
    """Both ways through the command line: the case a user would write (the record and
    ground.scale.factor) run by `rockslide run` gives the fragility run's numbers."""
    fplan, analysis = planned
    r, j = 1, 2
    data = case_to_dict(fr.point_case(fplan, r, j), case_file=True)
    data["name"] = "point"
    (tmp_path / "point.yaml").write_text(yaml.safe_dump(data))
    run = invoke("run", tmp_path / "point.yaml", "--out-dir", tmp_path, "--no-plot")
    assert run.exit_code == 0, run.output
    assert_run_equals(analysis.variables, (r, j), results.read_result(tmp_path / "point.h5").result.summary)


def test_runs_that_leave_the_model_are_counted_and_not_fitted(example):
    """At 2.5 g the synthetic verticals (half the horizontal peak) pass -1 g: the block would fly.
    Those runs are status flight, -1 in every state, and counted; rockslide run of such a run ends the same way."""
    im = fr.parse_im("pga")
    with pytest.warns(runner.RunWarning, match=r"would fly.*\[at record .*, level 2.5g\]; 5 of 12 runs fly"):
        fplan = fr.plan_fragility(example, load_suite(SUITE), im, fr.parse_levels("1g,2.5g", im),
                                  records_dir=RECORDS)
    plan = fplan.plan
    states = batch.compute(plan.case_params(), plan.case_states(), plan.base, plan.first, plan.count, plan.factor_h,
                           plan.factor_v)
    analysis = fr.analyse(fplan, states, fr.damage_states(), resamples=0)
    status = analysis.variables["status"][0]
    flying = status == K.STATUS_FLIGHT
    assert flying[:, 1].any() and not flying[:, 0].any()
    assert (analysis.exceeded[flying] == -1).all() and (analysis.exceeded[~flying] >= 0).all()
    assert analysis.fits[0].n_outside_model == int(flying.sum())
    record = int(np.flatnonzero(flying[:, 1])[0])
    with pytest.warns(runner.RunWarning, match="would fly"):
        summary = runner.run_case(fr.point_case(fplan, record, 1), RECORDS, history=False)[1].summary
    assert summary.status == "flight" and summary.end_time == analysis.variables["end_time"][0][record, 1]


# --------------------------------------------------------------------------------------------------
# The command, its files and its JSON
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    """`rockslide fragility --json` on the synthetic suite: (folder, JSON)."""
    out = tmp_path_factory.mktemp("fragility")
    result = invoke("fragility", EXAMPLE, "--suite", SUITE, "--levels", "0.4g:1.4g:0.2g", "--damage",
                    "rotation>0.5alpha", "--damage", "slip>50mm", "--bootstrap", "200", "--out-dir", out,
                    "--json", "--no-progress")
    assert result.exit_code == 0, (result.output, result.exception)
    return out, json.loads(result.stdout)


def test_json_has_every_state_with_fits_and_counts(analysed):
    _, payload = analysed
    states = payload["damage_states"]
    assert list(states) == ["overturn", "rotation>0.5alpha", "slip>50mm"]
    assert payload["intensity_measure"] == {"name": "pga", "units": "m/s^2",
                                            "long_name": "peak horizontal ground acceleration"}
    assert payload["levels"] == pytest.approx([0.4 * G, 0.6 * G, 0.8 * G, 1.0 * G, 1.2 * G, 1.4 * G])
    assert payload["records"][0] == "kt01-soft-long" and len(payload["records"]) == 6
    for state in states.values():
        assert {"median", "beta", "median_ci", "beta_ci", "n_runs", "n_outside_model"} <= set(state)
        assert state["n_runs"] == 36 and state["n_outside_model"] == 0
        if state["median"] is not None:
            low, high = state["median_ci"]
            assert low <= state["median"] <= high and state["beta"] > 0
        else:
            assert state["note"]
    assert states["overturn"]["median"] is not None
    assert payload["bootstrap"] == {"resamples": 200, "seed": fr.BOOTSTRAP_SEED, "confidence": 0.95}
    out, _ = analysed
    with h5py.File(out / "example.fragility.h5") as f:          # runs still moving at the end
        assert payload["n_undecided"] == int(f["undecided"][:].sum())


def test_xarray_opens_the_fragility_file(analysed):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    out, payload = analysed
    with xr.open_dataset(out / "example.fragility.h5", engine="h5netcdf") as ds:
        fitted = int(ds["resamples_fitted"].max())
        assert dict(ds.sizes) == {"record": 6, "level": 6, "damage_state": 3, "resample": fitted}
        # the resamples' fits are those the intervals are the percentiles of
        boot = ds["bootstrap_median"].sel(damage_state="overturn").values
        boot = boot[np.isfinite(boot)]
        assert boot.size == int(ds["resamples_fitted"].sel(damage_state="overturn"))
        assert np.percentile(boot, 2.5) == float(ds["median_lower"].sel(damage_state="overturn"))
        assert ds["record"].values.tolist() == payload["records"]
        assert ds["damage_state"].values.tolist() == list(payload["damage_states"])
        assert ds["level"].attrs["units"] == "m/s^2" and ds["level"].values.tolist() == payload["levels"]
        for name, units in (("overturned", "1"), ("max_rotation", "rad"), ("max_rotation_ratio", "1"),
                            ("max_slip", "m"), ("residual_slip", "m"), ("status", "1"), ("scale_factor", "1")):
            assert ds[name].dims == ("record", "level") and ds[name].attrs["units"] == units, name
        assert ds["exceeded"].dims == ("record", "level", "damage_state")
        for name in ("median", "beta", "median_lower", "median_upper", "beta_lower", "beta_upper"):
            assert ds[name].dims == ("damage_state",)
        overturn = payload["damage_states"]["overturn"]
        assert float(ds["median"].sel(damage_state="overturn")) == overturn["median"]
        assert float(ds["beta_upper"].sel(damage_state="overturn")) == overturn["beta_ci"][1]
        assert ds["median"].attrs["units"] == "m/s^2"
        # the stripes' fractions are the runs' exceedances
        fraction = (ds["exceeded"] == 1).sum("record") / (ds["exceeded"] >= 0).sum("record")
        assert np.allclose(fraction.transpose("damage_state", "level"), ds["fraction_exceeded"])
        assert (ds["overturned"] == ds["exceeded"].sel(damage_state="overturn")).all()
        rocked = ds["max_rotation"] > 0
        assert rocked.any()
        ratio = ds["max_rotation"].where(rocked) / ds["max_rotation_ratio"].where(rocked)
        assert np.allclose(ratio.fillna(math.atan(0.5)), math.atan(0.5), rtol=1e-15)
        # each scaled record's PGA is the level
        assert np.allclose(ds["scale_factor"] * ds["record_pga"], ds["level"], rtol=1e-15)
        assert ds["record_pgv_pga"].attrs["units"] == "s"
        assert ds.attrs["format"] == "rockslide-fragility" and "mu_static: 0.52" in ds.attrs["case_text"]
        assert ds.attrs["command_line"].startswith("rockslide fragility ")
        assert "--damage 'rotation>0.5alpha' --damage 'slip>50mm'" in ds.attrs["command_line"]
        assert ds["horizontal_file"].values[0] == "kt01_h.at2"


def test_png_is_written_redrawn_identically_and_the_chunks_removed(analysed, tmp_path):
    out, _ = analysed
    png = out / "example.fragility.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in out.iterdir()) == ["example.fragility.h5", "example.fragility.png"]
    again = tmp_path / "again.png"
    result = invoke("plot", out / "example.fragility.h5", "-o", again)
    assert result.exit_code == 0, result.output
    assert again.read_bytes() == png.read_bytes()


def test_an_interrupted_analysis_resumes_from_its_chunks(example, tmp_path):
    """Chunks stored by an earlier (interrupted) run of the same definition are reused; the result
    equals an uninterrupted run's."""
    im = fr.parse_im("pga")
    fplan = fr.plan_fragility(example, load_suite(SUITE), im, fr.parse_levels("0.6g,1.2g", im),
                              records_dir=RECORDS, chunk_size=2)
    store = chunks.ChunkStore.beside(tmp_path / "a" / "example.fragility.h5", fplan.plan.key)
    ex.compute(fplan.plan, store, [0, 1, 2])
    args = ["fragility", EXAMPLE, "--suite", SUITE, "--levels", "0.6g,1.2g", "--chunk-size", "2", "--no-plot",
            "--no-progress", "--bootstrap", "50"]
    resumed = invoke(*args, "--out-dir", tmp_path / "a")
    assert resumed.exit_code == 0, resumed.output
    assert "reused 3 of 6 chunks (6 runs)" in resumed.stdout
    fresh = invoke(*args, "--out-dir", tmp_path / "b")
    assert fresh.exit_code == 0 and "reused" not in fresh.stdout
    a = results.read_dataset(tmp_path / "a" / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    b = results.read_dataset(tmp_path / "b" / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    for name, (_, values, _) in a.variables.items():
        assert np.array_equal(values, b.variables[name][1], equal_nan=values.dtype.kind == "f"), name


def test_an_existing_result_is_refused(analysed):
    out, _ = analysed
    before = (out / "example.fragility.h5").read_bytes()
    result = invoke("fragility", EXAMPLE, "--suite", SUITE, "--levels", "0.5g", "--out-dir", out)
    one_line_error(result, "example.fragility.h5 exists", "--overwrite")
    assert (out / "example.fragility.h5").read_bytes() == before


def test_folder_and_glob_suites(example, tmp_path):
    """A folder's files and a glob's are horizontal records named by their file name."""
    for name in ("kt03_h", "kt01_h"):
        (tmp_path / f"{name}.at2").write_bytes((RECORDS / "suite-synthetic" / f"{name}.at2").read_bytes())
    (tmp_path / "notes.md").write_text("documentation, not a record\n")
    folder = fr.suite_from(tmp_path)
    assert [e.name for e in folder.entries] == ["kt01_h", "kt03_h"] and folder.entries[0].vertical is None
    assert [e.name for e in fr.suite_from(str(tmp_path / "kt03*.at2")).entries] == ["kt03_h"]
    with pytest.raises(CaseError, match="no file matches"):
        fr.suite_from(str(tmp_path / "nothing*.csv"))
    with pytest.raises(RockslideError, match="not found"):
        fr.suite_from(tmp_path / "missing")


# --------------------------------------------------------------------------------------------------
# The shared suite of 18 real records
# --------------------------------------------------------------------------------------------------


def test_the_shared_suite_of_real_records(example, tmp_path):
    """The 18 PEER-processed records (two-column CSV in g, one with Windows line ends) as a folder
    suite: read in name order, their PGAs within the 0.19-1.30 g that their provenance lists, and a
    run (of a 0.005 s record) equal to its single run."""
    folder = real_records_dir()
    if folder is None or not (folder / "suite-slammer").is_dir():
        pytest.skip("needs the shared record suite: suite-slammer not found in $ROCKSLIDE_RECORDS or "
                    "../shared/records")
    suite = fr.suite_from(folder / "suite-slammer", units="g")
    im = fr.parse_im("pgv")
    fplan = fr.plan_fragility(example, suite, im, fr.parse_levels("30cm/s,60cm/s", im))
    assert len(fplan.names) == 18 and fplan.names == sorted(fplan.names)
    pga = fplan.measures["pga"] / G
    assert pga.min() == pytest.approx(0.19, abs=0.01) and pga.max() == pytest.approx(1.30, abs=0.01)
    assert (fplan.measures["pgv_pga"] > 0.02).all() and (fplan.measures["pgv_pga"] < 0.5).all()
    r = fplan.names.index("Kobe_1995_TAK-090")
    plan = fplan.plan
    rows = slice(2 * r, 2 * r + 2)
    states = batch.compute(plan.params[rows], plan.states[rows], plan.base, plan.first[rows], plan.count[rows],
                           plan.factor_h[rows], plan.factor_v[rows])
    _, result = runner.run_case(fr.point_case(fplan, r, 1), history=False)
    assert states[1, K.S_MAX_THETA] == result.summary.max_rotation
    assert states[1, K.S_X] == result.summary.residual_slip


def test_the_synthetic_suite_is_what_synthetic_py_makes(tmp_path):
    """`records/suite-synthetic/` holds exactly what `synthetic.suite_pair` and `records.write_at2`
    make (so `records/make_example_records.py` regenerates it byte for byte), and the suite file
    lists every pair."""
    from rockslide.io.records import write_at2
    from rockslide.io.synthetic import SUITE as MADE
    from rockslide.io.synthetic import suite_pair

    suite = load_suite(SUITE)
    assert [e.horizontal.file for e in suite.entries] == [f"suite-synthetic/{n}_h.at2" for n in MADE]
    assert [e.vertical.file for e in suite.entries] == [f"suite-synthetic/{n}_v.at2" for n in MADE]
    for name, (seed, *_) in MADE.items():
        horizontal, vertical = suite_pair(name)
        for part, values, s in (("h", horizontal, seed), ("v", vertical, seed + 100)):
            made = write_at2(tmp_path / f"{name}_{part}.at2", values, 0.01,
                             title=f"rockslide synthetic suite record {name}, seed {s}",
                             component="horizontal" if part == "h" else "vertical")
            assert made.read_bytes() == (RECORDS / "suite-synthetic" / f"{name}_{part}.at2").read_bytes()


def test_a_record_sampled_more_coarsely_than_the_step_allows_is_named(tmp_path):
    """A case step coarser than a record's sampling: the error names the case's key and the record."""
    case = tmp_path / "coarse.yaml"
    case.write_text(EXAMPLE.read_text().replace("../records/", str(RECORDS) + "/").replace("dt: 0.1 ms", "dt: 10 ms"))
    result = invoke("fragility", case, "--suite", SUITE, "--levels", "0.5g", "--out-dir", tmp_path / "o",
                    "--no-progress")
    assert result.exit_code == 0, result.output          # 10 ms = the records' step: allowed
    (tmp_path / "fine.csv").write_text("".join(f"{0.005 * i:.3f},{0.1 * (-1) ** i}\n" for i in range(40)))
    suite = write_suite(tmp_path, "records:\n  - {name: fine, horizontal: {file: fine.csv, units: g}}\n")
    result = invoke("fragility", case, "--suite", suite, "--levels", "0.5g", "--out-dir", tmp_path / "p",
                    "--no-progress")
    one_line_error(result, "coarse.yaml", "solver.dt", "suite.yaml: records[0] (fine)")


# --------------------------------------------------------------------------------------------------
# Fragility with uncertain parameters (--samples)
# --------------------------------------------------------------------------------------------------

UNCERTAIN = {"size": {"lognormal": {"median": 1.0, "beta": 0.3}}, "restitution": {"uniform": [0.7, 0.9]},
             "friction": {"uniform": [0.9, 1.1]}}


def _sampled(example, samples, levels="0.3g:1.5g:0.4g"):
    case = example.with_(uncertain=UNCERTAIN)
    im = fr.parse_im("pga")
    fplan = fr.plan_fragility(case, load_suite(SUITE), im, fr.parse_levels(levels, im), records_dir=RECORDS,
                              samples=samples, seed=5)
    p = fplan.plan
    states = batch.compute(p.params, p.states, p.base, p.first, p.count, p.factor_h, p.factor_v)
    return fplan, states


def test_parameter_samples_keep_the_cases_own_values_as_sample_zero(example):
    """Sample 0 of every record and level is the run without samples, bit for bit; the fits with
    samples use the drawn sets only, and the fits of sample 0 are those of the plain analysis."""
    plain, plain_states = _sampled(example, 0)
    sampled, sampled_states = _sampled(example, 4)
    assert sampled.plan.shape == (*plain.plan.shape, 5)
    zero = sampled_states.reshape(*plain.plan.shape, 5, -1)[:, :, 0, :]
    assert np.array_equal(zero.reshape(plain_states.shape), plain_states, equal_nan=True)
    a = fr.analyse(plain, plain_states, fr.damage_states(), resamples=50)
    b = fr.analyse(sampled, sampled_states, fr.damage_states(), resamples=50)
    assert np.array_equal(b.exceeded[:, :, 0, :], a.exceeded)
    assert b.nominal_fits[0].median == a.fits[0].median and b.nominal_fits[0].beta == a.fits[0].beta
    assert b.fitted.shape == (6 * 4, 4, 1) and b.fits[0].n_runs == 6 * 4 * 4


def test_each_sampled_run_is_the_run_of_its_block(example):
    """A drawn run computes what ``rockslide run`` computes for the record's case at that level
    with the drawn block (height and width times the size factor), friction and restitution."""
    fplan, states = _sampled(example, 3)
    values = fplan.parameter_values
    assert values["size"].shape == (6, 4) and (values["size"][:, 0] == 1.0).all()
    assert (values["restitution"][:, 0] == example.contact.restitution).all()
    record, level, k = 2, 1, 3
    case = fr.point_case(fplan, record, level)
    f, size, e = values["friction"][record, k], values["size"][record, k], values["restitution"][record, k]
    drawn = case.with_({"block.height": example.block.height * size, "block.width": example.block.width * size,
                        "contact.mu_static": example.contact.mu_static * f,
                        "contact.mu_kinetic": example.contact.mu_kinetic * f, "contact.restitution": e})
    summary = runner.run_case(drawn, RECORDS, history=False)[1].summary
    row = states.reshape(6, 4, 4, -1)[record, level, k]
    assert row[K.S_MAX_THETA] == summary.max_rotation and row[K.S_MAX_X] == summary.max_slip


def test_parameter_samples_are_in_the_file_the_json_and_the_figure(tmp_path, example):
    data = case_to_dict(example)
    data["uncertain"] = UNCERTAIN
    for role in ("horizontal", "vertical"):
        data["ground"][role]["file"] = str(RECORDS / data["ground"][role]["file"].split("/")[-1])
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(data))
    args = ["fragility", tmp_path / "case.yaml", "--suite", SUITE, "--levels", "0.3g:1.5g:0.4g", "--samples", "3",
            "--bootstrap", "20", "--out-dir", tmp_path, "--no-progress"]
    done = invoke(*args, "--json")
    assert done.exit_code == 0, done.output
    payload = json.loads(done.stdout)
    assert payload["parameter_samples"]["n"] == 3 and payload["n_runs"] == 6 * 4 * 4
    assert "without_parameter_uncertainty" in payload["damage_states"]["overturn"]
    stored = results.read_dataset(tmp_path / "example.fragility.h5", format=results.FRAGILITY_FORMAT)
    assert stored.variables["parameter_size"][0] == ("record", "sample")
    assert stored.variables["overturned"][0] == ("record", "level", "sample")
    assert stored.attrs["parameter_samples"] == 3
    assert invoke("plot", tmp_path / "example.fragility.h5", "-o", tmp_path / "again.png").exit_code == 0


def test_parameter_samples_draw_from_the_stated_defaults_and_refuse_intensity(example):
    """Without an uncertain section --samples draws from ensemble.DEFAULTS less the intensity (issue 40:
    it refused to run, although --ensemble has stated defaults)."""
    from rockslide.analyses import ensemble as ens

    im = fr.parse_im("pga")
    fplan = fr.plan_fragility(example, load_suite(SUITE), im, fr.parse_levels("1g", im), records_dir=RECORDS,
                              samples=2)
    assert set(fplan.distributions) == {"friction", "size", "slenderness", "restitution"}
    assert fplan.distributions["friction"] == ens.DEFAULTS["friction"]
    e = example.contact.restitution
    assert fplan.distributions["restitution"].spec() == ens.distributions(example)[0]["restitution"].spec()
    assert fplan.parameter_values["restitution"][:, 1:].min() >= e - 0.05 - 1e-12
    with pytest.raises(CaseError, match="uncertain.intensity: does not apply"):
        fr.plan_fragility(example.with_(uncertain={"intensity": {"uniform": [0.9, 1.1]}}), load_suite(SUITE), im,
                          fr.parse_levels("1g", im), records_dir=RECORDS, samples=2)


def test_pga_rocking_of_a_body_is_normalised_by_its_weaker_corner(example):
    """``pga_rocking`` = PGA / (g tan alpha): for an asymmetric body tan alpha is its weaker corner's
    ``min(b1, b2) / h``, the smaller of its two static tipping accelerations (a rectangle: b/h)."""
    body = example.with_({"block.width": None, "block.height": None, "block.centre_of_mass_height": 0.1,
                          "block.half_widths": [0.06, 0.02]})
    im = fr.parse_im("pga_rocking")
    fplan = fr.plan_fragility(body, load_suite(SUITE), im, fr.parse_levels("1,2", im), records_dir=RECORDS)
    for r, case in enumerate(fplan.record_cases[:2]):
        peak = np.max(np.abs(runner.load_ground(case, RECORDS).horizontal))
        for j, level in enumerate(fplan.levels.values):
            k = fplan.plan.factor_h[r * 2 + j]
            assert k * peak / (body.gravity * 0.02 / 0.1) == pytest.approx(level, rel=1e-12)
