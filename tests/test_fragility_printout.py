"""What `rockslide fragility` prints about each state's fits (issue 27, "Words"): why the method of
moments is left out, intervals from too few records, medians and bounds beyond the levels tested.

The stripes are written by hand so that what the printout must say follows from them alone.
"""

from __future__ import annotations

import numpy as np
import pytest

from rockslide.analyses import fragility as fr

G = 9.80665
PGA = fr.parse_im("pga")
LEVELS = np.array([0.2, 0.4, 0.6, 0.8]) * G       # [m/s^2]
STATE = fr.parse_damage("overturn")


def describe(rows, resamples=200):
    """The fit, and its printout: the state's line and its caveats, as `rockslide fragility` prints them."""
    fit = fr.fit_state(LEVELS, np.array(rows, dtype=np.int8), resamples=resamples, show=PGA.show)
    line = fr.describe_fit(STATE, fit, PGA)
    assert "\n" not in line
    return fit, "\n".join([line, *(f"warning: {c}" for c in fr.caveats(fit, PGA))])


# five records whose first exceedances are bracketed by the levels (moments defined, a fit too)
BRACKETED = [[0, 1, 1, 1], [0, 0, 1, 1], [0, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 1]]


def test_the_moments_left_out_are_said_with_the_reason():
    """A record that never exceeds leaves the moments undefined (right-censored): the printout says
    so (it used to drop them silently, only the JSON said why)."""
    fit, text = describe(BRACKETED + [[0, 0, 0, 0]])
    assert fit.median is not None and fit.moments_median is None
    assert "no method-of-moments estimate: 1 of 6 records never exceed the state up to 0.8 g" in text
    _, with_moments = describe(BRACKETED)
    assert "; moments: median" in with_moments and "no method-of-moments" not in with_moments


@pytest.mark.parametrize("records, warned", [(2, True), (4, True), (5, False), (8, False)])
def test_intervals_from_few_records_are_flagged(records, warned):
    """The percentile bootstrap of R records draws from at most C(2R-1, R) distinct resamples (35
    for 4): below `MIN_BOOTSTRAP_RECORDS` (5) the printout warns."""
    rows = (BRACKETED * 2)[:records]
    fit, text = describe(rows)
    assert fit.median_ci is not None or fit.moments_median_ci is not None
    assert fit.n_records == records
    assert (f"resample only {records} records" in text) is warned
    assert fr.MIN_BOOTSTRAP_RECORDS == 5


def test_no_interval_no_warning_about_it():
    _, text = describe(BRACKETED[:3], resamples=0)
    assert "resample only" not in text


def test_a_median_beyond_the_highest_level_is_extrapolated():
    """Few runs reach the state, all at the highest level: the fitted median lies above 0.8 g, where
    no run was made."""
    rows = [[0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 0], [0, 0, 0, 1]]
    fit, text = describe(rows)
    assert fit.median > LEVELS[-1]                   # the premise, from the fit itself
    assert fit.median_ci[1] > fit.median                # and its interval reaches further still
    assert (f"warning: median {PGA.show(fit.median)} and its upper 95% bound "
            f"{PGA.show(fit.median_ci[1])} lie beyond the highest level tested, 0.8 g: extrapolated") in text


def test_a_median_below_the_lowest_level_is_extrapolated():
    rows = [[1, 1, 1, 1], [0, 1, 1, 1], [1, 1, 1, 1], [1, 0, 1, 1], [1, 1, 1, 1], [1, 1, 0, 1]]
    fit, text = describe(rows)
    assert fit.median < LEVELS[0]
    assert f"median {PGA.show(fit.median)}" in text and "below the lowest level tested, 0.2 g: extrapolated" in text


def test_a_bound_alone_beyond_the_levels_is_flagged_as_the_medians():
    """The README's first session: the median inside the levels, its upper bound beyond them."""
    rows = [[0, 0, 1, 1], [0, 0, 0, 1], [0, 0, 0, 0], [0, 1, 1, 1], [0, 0, 0, 0], [0, 0, 1, 1]]
    fit, text = describe(rows)
    assert LEVELS[0] < fit.median < LEVELS[-1] * (1 + fr.EXTRAPOLATION_MARGIN) < fit.median_ci[1]
    assert (f"warning: the median's upper 95% bound {PGA.show(fit.median_ci[1])} lies beyond the highest "
            "level tested, 0.8 g: extrapolated") in text


def test_a_median_inside_the_levels_is_not_flagged():
    fit, text = describe(BRACKETED, resamples=0)
    assert LEVELS[0] < fit.median < LEVELS[-1]
    assert "extrapolated" not in text and "warning" not in text


def test_the_caveats_are_in_the_json_too():
    fit, _ = describe([[0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 1, 0]])
    assert any("resample only 3 records" in c for c in fr.caveats(fit, PGA))
    assert any("beyond the highest level tested" in c for c in fr.caveats(fit, PGA))
