"""The standard normal distribution's functions and the chi-square tail, on numpy arrays.

What the fits and the risk integral need of scipy.special (``ndtr``, ``log_ndtr``, ``ndtri``,
``chdtrc``), without importing it: scipy 1.17's scipy.special loads its array-API layer, which
makes numpy load ``numpy.f2py`` and ``numpy.testing``, 0.25-0.4 s of a fragility or risk command
that otherwise spends about 0.1 s computing (docs/performance.md). tests/test_normal.py holds each
function against scipy.special and against mpmath at 50 digits.

Each takes what numpy takes and gives a float64 array, or a numpy scalar for a scalar (as a
ufunc does).

- `normal_cdf` is Cephes' ``ndtr`` (Moshier, Cephes Math Library 2.2, 1992; scipy's own), its
  rational approximations and branches as scipy evaluates them.
- `log_normal_cdf` is scipy's ``log_ndtr`` (by way of the Faddeeva package: ``ln(erfcx(-x/sqrt 2)
  / 2) - x^2/2`` below -1, ``log1p(-erfc(x/sqrt 2) / 2)`` above), with the scaled complementary
  error function `erfcx` from Cephes' erfc approximations, which are approximations of ``erfcx``
  times ``exp(-y^2)``; no underflow however far in the lower tail. `log_normal_cdf_pair` gives
  ``ln Phi(x)`` and ``ln Phi(-x)`` together, from one evaluation of the error functions.
- `normal_quantile` is Wichura's AS241, as Python's ``statistics.NormalDist`` writes it.
- `chi2_sf` is the chi-square survival function for whole degrees of freedom, by its finite sums.
"""

from __future__ import annotations

import math

import numpy as np

SQRT_HALF = math.sqrt(0.5)
#: Cephes' erfc (ndtr.c): ``erfc(y) = exp(-y^2) P(y) / Q(y)`` for 1 <= y < 8 and ``exp(-y^2) R(y) /
#: S(y)`` above; ``erf(y) = y T(y^2) / U(y^2)`` for |y| < 1. Highest power first; the leading 1 of Q,
#: S and U written out.
_P = (2.46196981473530512524E-10, 5.64189564831068821977E-1, 7.46321056442269912687E0, 4.86371970985681366614E1,
      1.96520832956077098242E2, 5.26445194995477358631E2, 9.34528527171957607540E2, 1.02755188689515710272E3,
      5.57535335369399327526E2)
_Q = (1.0, 1.32281951154744992508E1, 8.67072140885989742329E1, 3.54937778887819891062E2, 9.75708501743205489753E2,
      1.82390916687909736289E3, 2.24633760818710981792E3, 1.65666309194161350182E3, 5.57535340817727675546E2)
_R = (5.64189583547755073984E-1, 1.27536670759978104416E0, 5.01905042251180477414E0, 6.16021097993053585195E0,
      7.40974269950448939160E0, 2.97886665372100240670E0)
_S = (1.0, 2.26052863220117276590E0, 9.39603524938001434673E0, 1.20489539808096656605E1, 1.70814450747565897222E1,
      9.60896809063285878198E0, 3.36907645100081516050E0)
_T = (9.60497373987051638749E0, 9.00260197203842689217E1, 2.23200534594684319226E3, 7.00332514112805075473E3,
      5.55923013010394962768E4)
_U = (1.0, 3.35617141647503099647E1, 5.21357949780152679795E2, 4.59432382970980127987E3, 2.26290000613890934246E4,
      4.92673942608635921086E4)
#: Above this y, `erfcx` is its asymptotic series ``(1 - 1/(2y^2) + 3/(2y^2)^2 - ...) / (y sqrt(pi))``
#: to :data:`_SERIES_TERMS` terms (the first term left out is below 1e-17 relative), where Cephes'
#: rational function, fitted up to erfc's underflow at y = 26.6, is not vouched for.
_SERIES_FROM = 26.0
_SERIES_TERMS = 8


#: Wichura's (1988) algorithm AS241 (PPND16): the coefficients of the normal's inverse CDF, central
#: region (|p - 1/2| <= 0.425) then the tails for r = sqrt(-ln min(p, 1 - p)) <= 5 and > 5, each a
#: numerator and a denominator, highest power first (as Python's ``statistics.NormalDist`` has them).
_AS241 = (
    ((2.5090809287301226727e+3, 3.3430575583588128105e+4, 6.7265770927008700853e+4, 4.5921953931549871457e+4,
      1.3731693765509461125e+4, 1.9715909503065514427e+3, 1.3314166789178437745e+2, 3.3871328727963666080e+0),
     (5.2264952788528545610e+3, 2.8729085735721942674e+4, 3.9307895800092710610e+4, 2.1213794301586595867e+4,
      5.3941960214247511077e+3, 6.8718700749205790830e+2, 4.2313330701600911252e+1, 1.0)),
    ((7.7454501427834140764e-4, 2.2723844989269184583e-2, 2.4178072517745061177e-1, 1.2704582524523683826e+0,
      3.6478483247632046050e+0, 5.7694972214606914055e+0, 4.6303378461565452959e+0, 1.4234371107496835773e+0),
     (1.0507500716444168432e-9, 5.4759380849953449460e-4, 1.5198666563616457197e-2, 1.4810397642748007459e-1,
      6.8976733498510000455e-1, 1.6763848301838038494e+0, 2.0531916266377588219e+0, 1.0)),
    ((2.0103343992922881327e-7, 2.7115555687434875782e-5, 1.2426609473880784386e-3, 2.6532189526576123093e-2,
      2.9656057182850489123e-1, 1.7848265399172913358e+0, 5.4637849111641143699e+0, 6.6579046435011037772e+0),
     (2.0442631033899397856e-15, 1.4215117583164458887e-7, 1.8463183175100546818e-5, 7.8686913114561325910e-4,
      1.4875361290850614852e-2, 1.3692988092273580531e-1, 5.9983220655588793769e-1, 1.0)),
)


def _horner(coefficients, x):
    value = np.full_like(x, coefficients[0])
    for c in coefficients[1:]:
        value *= x
        value += c
    return value


def _erf_small(y):
    """erf(y) for |y| < 1 (Cephes)."""
    z = y * y
    return y * _horner(_T, z) / _horner(_U, z)


def _erfcx_series(y):
    with np.errstate(under="ignore"):             # 1/y^2 of a huge y: its terms vanish, as they should
        w = 0.5 / y / y
        series, term = np.ones_like(y), np.ones_like(y)
        for k in range(1, _SERIES_TERMS):
            term = -term * (2 * k - 1) * w
            series += term
        return series / (y * math.sqrt(math.pi))


def _exp_minus_square(y):
    with np.errstate(under="ignore"):
        return np.exp(-(y * y))


def _error_functions(y, scaled) -> tuple[np.ndarray, np.ndarray]:
    """``erfc(y)`` and ``erfcx(y) = exp(y^2) erfc(y)`` for ``y >= 0`` (NaN below 0 and at NaN), as
    Cephes evaluates them (ndtr.c), each of its rational functions evaluated once for both: for
    ``y < 1``, ``erfc = 1 - erf(y)`` and ``erfcx = exp(y^2) erfc`` (only where ``scaled``: NaN
    elsewhere); for ``1 <= y < 8``, ``erfc = exp(-y^2) P / Q`` and ``erfcx = P / Q``; for ``8 <= y``,
    ``R / S`` likewise, with ``erfc = 0`` from 27, where ``exp(-y^2)`` has underflowed, and ``erfcx``
    its asymptotic series from `_SERIES_FROM`."""
    erfc, erfcx = np.full(y.shape, np.nan), np.full(y.shape, np.nan)
    near = (y >= 0.0) & (y < 1.0)
    if near.any():
        erfc[near] = 1.0 - _erf_small(y[near])
        both = near & scaled
        erfcx[both] = np.exp(y[both] * y[both]) * erfc[both]
    for low, high, top, bottom in ((1.0, 8.0, _P, _Q), (8.0, 27.0, _R, _S)):
        inside = (y >= low) & (y < high)
        if inside.any():
            part = y[inside]
            numerator, denominator = _horner(top, part), _horner(bottom, part)
            erfc[inside] = _exp_minus_square(part) * numerator / denominator
            erfcx[inside] = numerator / denominator
    erfc[y >= 27.0] = 0.0
    series = y >= _SERIES_FROM
    if series.any():
        erfcx[series] = _erfcx_series(y[series])
    return erfc, erfcx


def erfcx(y) -> np.ndarray:
    """The scaled complementary error function ``exp(y^2) erfc(y)`` for ``y >= 0`` (float64 array;
    NaN below 0, 0 at ``inf``). Relative error about 1e-15 (tests/test_normal.py)."""
    y = np.asarray(y, dtype=np.float64)
    return _error_functions(y, np.True_)[1][()]


def normal_cdf(x) -> np.ndarray:
    """The standard normal's CDF ``Phi(x) = erfc(-x / sqrt 2) / 2`` (scipy.special.ndtr), float64:
    Cephes' ``ndtr``; relative error within 2 ulps x (1 + x^2) of mpmath (tests/test_normal.py); 0
    below -38.5, 1 above 8.3, NaN at NaN."""
    x = np.asarray(x, dtype=np.float64)
    t = x * SQRT_HALF
    z = np.abs(t)
    out = np.full(x.shape, np.nan)
    small = z < 1.0
    out[small] = 0.5 + 0.5 * _erf_small(t[small])
    rest = z >= 1.0
    half_erfc = 0.5 * _error_functions(z[rest], np.False_)[0]
    out[rest] = np.where(t[rest] > 0.0, 1.0 - half_erfc, half_erfc)
    return out[()]


def _log_cdf(x, t, y, erfc, erfcx) -> np.ndarray:
    """`log_normal_cdf` at ``x`` from ``t = x / sqrt 2``, ``y = |t|`` and the error functions at
    ``y`` (`_error_functions`, ``erfcx`` needed where ``x < -1``)."""
    with np.errstate(divide="ignore", over="ignore"):      # at elements of the other branch, unused
        lower = np.log(0.5 * erfcx) - y * y
        upper = np.log1p(-0.5 * np.where(t < 0.0, 2.0 - erfc, erfc))   # erfc(t) below 0 as 2 - erfc(-t)
    return np.where(x < -1.0, lower, np.where(x >= -1.0, upper, np.nan))


def log_normal_cdf(x) -> np.ndarray:
    """``ln Phi(x)`` (scipy.special.log_ndtr), float64, accurate in both tails: ``ln(erfcx(-t) / 2) -
    t^2`` with ``t = x / sqrt 2`` for x < -1 (no underflow: -5e19 at x = -1e10), ``log1p(-erfc(t) /
    2)`` above (about ``-Phi(-x)`` in the upper tail). ``-inf`` at ``-inf``, 0 at ``inf``."""
    x = np.asarray(x, dtype=np.float64)
    t = x * SQRT_HALF
    y = np.abs(t)
    return _log_cdf(x, t, y, *_error_functions(y, x < -1.0))[()]


def log_normal_cdf_pair(x) -> tuple[np.ndarray, np.ndarray]:
    """``(ln Phi(x), ln Phi(-x))``: `log_normal_cdf` at ``x`` and at ``-x``, the same numbers to the
    bit, from one evaluation of the error functions at ``|x| / sqrt 2`` (what the probit fits' Newton
    steps take at every ``eta``)."""
    x = np.asarray(x, dtype=np.float64)
    t = x * SQRT_HALF
    y = np.abs(t)
    erfc, erfcx = _error_functions(y, np.abs(x) > 1.0)
    return _log_cdf(x, t, y, erfc, erfcx)[()], _log_cdf(-x, -t, y, erfc, erfcx)[()]


def normal_quantile(p) -> np.ndarray:
    """The standard normal's inverse CDF (quantile) at ``p``, by Wichura's algorithm AS241 (Applied
    Statistics 37, 477-484, 1988; relative error about 1e-16), the expressions of Python's
    ``statistics.NormalDist.inv_cdf`` evaluated on arrays: ``-inf`` at 0, ``inf`` at 1, NaN outside
    [0, 1]. Python's own values to the bit, and within 1.1e-15 (relative) of scipy's
    ``special.ndtri`` (tests/test_normal.py)."""
    p = np.asarray(p, dtype=np.float64)
    q = p - 0.5
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = 0.180625 - q * q
        central = _horner(_AS241[0][0], r) * q / _horner(_AS241[0][1], r)
        t = np.sqrt(-np.log(np.where(q <= 0.0, p, 1.0 - p)))
        near, far = t - 1.6, t - 5.0
        tail = np.where(t <= 5.0, _horner(_AS241[1][0], near) / _horner(_AS241[1][1], near),
                        _horner(_AS241[2][0], far) / _horner(_AS241[2][1], far))
    x = np.where(np.abs(q) <= 0.425, central, np.where(q < 0.0, -tail, tail))
    x = np.where(p == 0.0, -np.inf, np.where(p == 1.0, np.inf, x))
    return np.where((p >= 0.0) & (p <= 1.0), x, np.nan)[()]


def chi2_sf(x: float, dof: int) -> float:
    """The chi-square distribution's survival function ``P(X > x)`` for ``dof`` whole degrees of
    freedom (scipy.special.chdtrc, scipy.stats.chi2.sf), by the finite sums of the regularized upper
    incomplete gamma function ``Q(dof/2, x/2)``: with ``y = x/2``, ``e^-y sum_{j<k} y^j / j!`` for
    ``dof = 2k``, and ``erfc(sqrt y) + e^-y sum_{j<k} y^(j+1/2) / Gamma(j+3/2)`` for ``dof = 2k + 1``;
    each term formed in logarithms (no overflow). Relative error below 1e-13 against scipy
    (tests/test_normal.py). 1 at ``x <= 0``."""
    if isinstance(dof, bool) or int(dof) != dof or dof < 1:
        raise ValueError(f"dof must be a whole number >= 1, got {dof!r}")
    dof, x = int(dof), float(x)
    if math.isnan(x):
        return math.nan
    if x <= 0.0:
        return 1.0
    if math.isinf(x):
        return 0.0
    y = 0.5 * x
    log_y = math.log(y)
    if dof % 2 == 0:
        return math.fsum(math.exp(-y + j * log_y - math.lgamma(j + 1.0)) for j in range(dof // 2))
    tail = math.fsum(math.exp(-y + (j + 0.5) * log_y - math.lgamma(j + 1.5)) for j in range(dof // 2))
    return math.erfc(math.sqrt(y)) + tail
