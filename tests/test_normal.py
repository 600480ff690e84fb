"""The normal distribution's functions and the chi-square tail on numpy (`core.normal`), which the
fits, the goodness of fit, the risk integral and the ensembles use instead of scipy.special: each
against mpmath at 50 digits (an independent reference), against scipy.special (what they stand
in for) and at the edges.

The tolerances: `normal_cdf` and `log_normal_cdf` form ``exp(-x^2/2)`` from a rounded ``x^2``, so
their relative error grows like ``x^2`` ulps in the tails (Cephes, and scipy, have the same); 2 ulps
x ``(1 + x^2)`` holds with margin (measured: 1.3 for the CDF, 1.7 for its logarithm). `erfcx`, a
ratio of polynomials with no exponential from y = 1 on, is within 1.1e-15 (measured) everywhere.
The chi-square sums carry ``math.erfc`` and ``math.lgamma``'s rounding into the exponent of each
term: 3e-13 holds over dof 1-1001 (measured 2.3e-13 at dof 1001, where scipy's own error is 4.7e-13).
"""

from __future__ import annotations

import math
import statistics
import warnings

import mpmath as mp
import numpy as np
import pytest
import scipy.special as sp

from rockslide.core import normal as N

ULP = 2.0 ** -52
RNG = np.random.default_rng(20261129)


@pytest.fixture(autouse=True)
def _fifty_digits():
    with mp.workdps(50):
        yield


def _log_cdf(v: float) -> float:
    """ln Phi(v) in mpmath, through ``log1p(-Phi(-v))`` above 0 (Phi(v) rounds to 1 at 50 digits)."""
    v = mp.mpf(v)
    return float(mp.log1p(-mp.ncdf(-v)) if v >= 0 else mp.log(mp.ncdf(v)))


def test_the_normal_cdf_is_mpmaths_to_ulps_that_grow_with_x_squared():
    x = np.concatenate([RNG.uniform(-37.5, 8.3, 1500), -(10.0 ** RNG.uniform(-4, 1.5, 300)),
                        10.0 ** RNG.uniform(-4, 0.9, 300), [-1.0 / math.sqrt(0.5), 1.0 / math.sqrt(0.5), 0.0]])
    reference = np.array([float(mp.ncdf(mp.mpf(v))) for v in x])
    error = np.abs(N.normal_cdf(x) - reference) / reference
    assert np.all(error <= 2 * ULP * (1 + x * x))
    assert np.allclose(N.normal_cdf(x), sp.ndtr(x), rtol=1e-14, atol=0)


def test_the_log_normal_cdf_is_mpmaths_in_both_tails():
    """Down to x = -1e8 (ln Phi = -5e15) with no underflow, and up to x = 37, where ln Phi is
    -Phi(-x) (1e-300). Below 0 the logarithm, of the size of x^2/2, absorbs the error of the
    exponent: a few ulps at most."""
    x = np.concatenate([RNG.uniform(-40, 37, 1500), -(10.0 ** RNG.uniform(-3, 8, 500)), [-1.0, -1.0 - 1e-12]])
    reference = np.array([_log_cdf(v) for v in x])
    error = np.abs(N.log_normal_cdf(x) - reference) / np.abs(reference)
    assert np.all(error <= 2 * ULP * (1 + x * x))
    assert np.all(error[x < 0] <= 4 * ULP)
    assert np.allclose(N.log_normal_cdf(x), sp.log_ndtr(x), rtol=1e-13, atol=0)


def test_the_pair_is_the_log_cdf_at_x_and_at_minus_x_to_the_bit():
    """`N.log_normal_cdf_pair` (the probit fits' Newton steps) is `N.log_normal_cdf` at ``x`` and at
    ``-x``, bit for bit, over every branch of both and at their edges: ``|x| = 1`` and the pieces'
    bounds of ``|x| / sqrt 2`` (1, 8, 26, 27) on either side, signed zeros, infinities and NaN; no
    warning (from a branch not taken)."""
    bounds = np.array([1.0, 8.0, 26.0, 27.0]) / N.SQRT_HALF
    edges = np.concatenate([bounds, np.nextafter(bounds, 0), np.nextafter(bounds, np.inf), [1.0, np.nextafter(1.0, 0),
                            np.nextafter(1.0, 2), 0.0, 1e10, 1e300, np.inf]])
    x = np.concatenate([RNG.uniform(-60, 60, 4000), 10.0 ** RNG.uniform(-6, 10, 1000), edges])
    x = np.concatenate([x, -x, [np.nan, -0.0]]).reshape(-1, 4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # numpy's default error state: underflow is silent
        log_p, log_q = N.log_normal_cdf_pair(x)
        assert np.array_equal(log_p, N.log_normal_cdf(x), equal_nan=True)
        assert np.array_equal(log_q, N.log_normal_cdf(-x), equal_nan=True)
        assert N.log_normal_cdf_pair(-3.0) == (N.log_normal_cdf(-3.0), N.log_normal_cdf(3.0))


def test_erfcx_is_mpmaths_over_every_branch():
    """Below 1 (``exp(y^2)(1 - erf y)``), Cephes' two rational functions (1-8, 8-26) and the
    asymptotic series from 26 on, to y = 1e9."""
    y = np.concatenate([RNG.uniform(0, 40, 1500), 10.0 ** RNG.uniform(-4, 9, 500), [1.0, 8.0, 26.0, 0.0]])
    reference = np.array([float(mp.erfc(mp.mpf(v)) * mp.exp(mp.mpf(v) ** 2)) for v in y])
    assert np.all(np.abs(N.erfcx(y) - reference) <= 1.1e-15 * reference)
    assert np.allclose(N.erfcx(y), sp.erfcx(y), rtol=3e-15, atol=0)


def test_the_edges_are_scipys():
    edges = np.array([-np.inf, np.inf, np.nan, -1e300, 1e300, -40.0, 40.0, 0.0, -0.0])
    with np.errstate(all="raise"):        # no warning from a branch not taken
        cdf, log_cdf = N.normal_cdf(edges), N.log_normal_cdf(edges)
        scaled = N.erfcx(np.array([0.0, np.inf, 1e300, -1.0]))
    assert np.array_equal(cdf, sp.ndtr(edges), equal_nan=True)
    assert np.array_equal(log_cdf, sp.log_ndtr(edges), equal_nan=True)
    assert np.allclose(scaled[:3], [1.0, 0.0, 1.0 / (1e300 * math.sqrt(math.pi))], rtol=2e-16, atol=0)
    assert np.isnan(scaled[3])


def test_the_normal_quantile_is_pythons_and_scipys():
    """`normal_quantile` (AS241 on arrays): Python's ``NormalDist.inv_cdf`` (the same algorithm, in
    C) over the central region, both tails and down to the smallest double, to the bit where numpy's
    log is the C library's; scipy's ``ndtri`` (Cephes, another algorithm) within 1.1e-15 relative;
    -inf, inf at 0, 1 and NaN outside [0, 1] as ndtri; and the inverse of `normal_cdf` (within the
    two functions' errors).

    On a CPU with AVX-512 numpy computes log with its own vector code (SVML), which differs from the
    C library's in the last bit now and then: there 12 of 840 000 quantiles in the tails (30 draws
    like this one, 2026-11-29) differed from Python's by up to 3 ulp. So: all within 4 ulp, and all
    but one in 1000 to the bit (another algorithm, or a changed coefficient, misses that)."""
    p = np.concatenate([RNG.random(20_000), 10.0 ** -RNG.uniform(0, 320, 4000), 1 - 10.0 ** -RNG.uniform(0, 16, 4000),
                        [0.075, 0.925, 0.5 - 0.425, 0.5 + 0.425, np.exp(-25.0), 5e-324]])
    p = p[(p > 0) & (p < 1)]
    x = N.normal_quantile(p)
    inv_cdf = statistics.NormalDist().inv_cdf
    python = np.array([inv_cdf(v) for v in p])
    assert np.all(np.abs(x - python) <= 4 * np.spacing(np.abs(python)))
    assert np.count_nonzero(x != python) <= p.size // 1000
    reference = sp.ndtri(p)
    assert np.all(np.abs(x - reference) <= 1.1e-15 * np.abs(reference))
    edges = np.array([0.0, 1.0, -0.1, 1.1, np.nan])
    assert np.array_equal(N.normal_quantile(edges), sp.ndtri(edges), equal_nan=True)
    lower = p[(p > 1e-300) & (p < 0.999)]
    x = N.normal_quantile(lower)
    assert np.all(np.abs(N.normal_cdf(x) - lower) <= 4 * ULP * (1 + x * x) * lower)    # both errors, measured 3.2


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 7, 13, 100, 1001])
def test_the_chi_square_tail_is_mpmaths(dof):
    """``Q(dof/2, x/2)``, the regularized upper incomplete gamma function, from 1e-6 to 1e4 (where
    it is 1e-2100 for dof 1, left out: below the smallest double)."""
    x = np.concatenate([10.0 ** np.linspace(-6, 4, 121), [dof, dof + 0.5, 2.0 * dof]])
    reference = np.array([float(mp.gammainc(mp.mpf(dof) / 2, mp.mpf(v) / 2, mp.inf, regularized=True)) for v in x])
    ours = np.array([N.chi2_sf(v, dof) for v in x])
    kept = reference > 1e-300
    assert np.all(np.abs(ours - reference)[kept] <= 3e-13 * reference[kept])
    assert np.all(ours[~kept] < 1e-290)
    assert np.allclose(ours[kept], sp.chdtrc(dof, x[kept]), rtol=1e-12, atol=0)


def test_the_chi_square_tail_at_its_edges_and_for_bad_dof():
    assert [N.chi2_sf(v, 3) for v in (0.0, -1.0, math.inf)] == [1.0, 1.0, 0.0]
    assert math.isnan(N.chi2_sf(math.nan, 3))
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="dof"):
            N.chi2_sf(1.0, bad)


def test_the_fits_import_no_scipy():
    """What `core.normal` is for: fragility, goodness of fit and risk load without scipy.special
    (0.25-0.4 s on the 2-core development machine; docs/performance.md)."""
    import subprocess
    import sys

    code = ("import sys; import rockslide.analyses.fragility, rockslide.analyses.goodness, rockslide.analyses.risk; "
            "print(sorted(m for m in sys.modules if m.startswith('scipy')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "[]"
