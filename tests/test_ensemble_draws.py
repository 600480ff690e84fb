"""Draws at the edges of the input space (issue 43, item 11): a lognormal of huge beta draws factors
of infinity, 0 or beyond what the model takes, an asymmetric body's member a restitution above its
e_max or a radius of gyration beyond its k_max. Those members are left out of every statistic and
said, as the members that leave the model during the computation are; only an ensemble whose every
member is outside is refused, in one line naming the key. The counts are computed here on their own
(scipy's Latin hypercube, the body's constants of `core.simulate.Model`), not read from the code."""

from __future__ import annotations

import json
import math

import h5py
import numpy as np
import pytest
import yaml
from conftest import G0, case_text, invoke, listing, one_line_error
from scipy.stats import norm, qmc

import rockslide
from rockslide.analyses import ensemble as ens
from rockslide.core.simulate import Model

N = 200
#: [m/s^2] The shipped example's peak scaled ground acceleration: 700 gal horizontal (the vertical,
#: scaled with the record's V/H ratio kept, is lower).
EXAMPLE_PEAK = 7.0
MAX_ACCELERATION = 1e6 * G0


def strict_json(text: str):
    """JSON as a strict reader takes it: NaN and Infinity refused."""
    def refuse(constant):
        raise ValueError(f"{constant} in the JSON")
    return json.loads(text, parse_constant=refuse)


def lognormal_draws(beta: float, n: int = N, seed: int = ens.SEED) -> np.ndarray:
    """The factors of a lognormal of median 1, drawn as the ensemble says it draws them: one Latin
    hypercube stratum per member (scipy's, with the seed), through the inverse CDF."""
    q = qmc.LatinHypercube(d=1, seed=seed).random(n)[:, 0]
    with np.errstate(over="ignore", under="ignore"):
        return np.exp(beta * norm.ppf(q))


def outside_intensity(factors: np.ndarray) -> np.ndarray:
    """Members whose intensity factor no model takes: not finite, not above 0, or scaling the peak
    ground acceleration beyond 1e6 g."""
    with np.errstate(over="ignore", invalid="ignore"):
        return ~np.isfinite(factors) | ~(factors > 0) | ~(factors * EXAMPLE_PEAK <= MAX_ACCELERATION)


def test_a_lognormal_of_huge_beta_leaves_its_impossible_members_out(ws):
    """beta 300: about half the draws are exp(+-hundreds), infinite, 0 or beyond 1e6 g. Exit 0; the
    members left out are exactly those; the probability is over the rest; the file holds no
    infinity (their samples NaN, their status drawn_outside) and the JSON is strict JSON."""
    (ws / "case.yaml").write_text(case_text({"ground.tail": "0 s",
                                             "uncertain.intensity": {"lognormal": {"median": 1, "beta": 300}}}))
    factors = lognormal_draws(300.0)
    expected = outside_intensity(factors)
    assert 0 < expected.sum() < N and (~np.isfinite(factors)).any() and (factors == 0).any()   # the attack holds
    done = invoke("run", "case.yaml", "--ensemble", N, "--json", "--no-plot", "--out-dir", ws)
    assert done.exit_code == 0, (done.output, done.exception)
    summary = strict_json(done.stdout)["ensemble"]
    assert summary["n_drawn_outside"] == int(expected.sum())
    assert sum(summary["drawn_outside"].values()) == int(expected.sum())
    assert all(text.startswith("uncertain.intensity: ") for text in summary["drawn_outside"])
    with h5py.File(ws / "example.h5", "r") as f:
        status = f["ensemble/status"][()]
        overturned = f["ensemble/overturned"][()].astype(bool)
        sampled = f["ensemble/sample_intensity"][()]
        assert f["ensemble/status"].attrs["flag_meanings"].split()[ens.STATUS_DRAWN_OUTSIDE] == "drawn_outside"
        infinite = []
        f.visititems(lambda name, obj: infinite.append(name) if isinstance(obj, h5py.Dataset)
                     and obj.dtype.kind == "f" and np.isinf(obj[()]).any() else None)
        stored = strict_json(f.attrs["ensemble"].replace("NaN", "null"))
    assert not infinite
    assert np.array_equal(status == ens.STATUS_DRAWN_OUTSIDE, expected)
    assert np.array_equal(np.isnan(sampled), ~np.isfinite(factors))
    # the ensemble's normal quantile (AS241) is within 1.1e-15 of scipy's (Cephes), times beta 300 and
    # |z| <= 4 in the exponent: 1.3e-12 relative at most
    assert np.allclose(sampled[np.isfinite(factors)], factors[np.isfinite(factors)], rtol=2e-12, atol=0)
    within = status == 0
    left = int(((status > 0) & ~expected).sum())             # flight or painleve, during the computation
    assert summary["n_within_model"] == int(within.sum()) == N - int(expected.sum()) - left
    assert summary["n_overturned"] == int(overturned[within].sum())
    assert summary["p_overturn"] == pytest.approx(overturned[within].mean(), abs=0)
    assert stored["n_drawn_outside"] == summary["n_drawn_outside"]
    printed = invoke("run", "case.yaml", "--ensemble", N, "--no-plot", "--out-dir", ws, "--overwrite")
    assert printed.exit_code == 0, printed.output
    lines = [line for line in printed.stdout.splitlines() if "drawn outside the model" in line]
    assert len(lines) == 1 and lines[0].startswith(f"  {int(expected.sum())} of {N} members drawn outside the "
                                                   "model (uncertain.intensity: ") and lines[0].endswith(": left out")


def test_an_ensemble_whose_every_member_is_outside_is_one_line_naming_the_key(ws):
    """beta 1e300: every draw overflows to infinity or underflows to 0. Exit 2, one line naming
    uncertain.intensity, and nothing written (the refusal comes before any file)."""
    data = yaml.safe_load(case_text({"uncertain.intensity": {"lognormal": {"median": 1, "beta": 1e300}}}))
    (ws / "case.yaml").write_text(yaml.safe_dump(data))
    factors = lognormal_draws(1e300)
    assert outside_intensity(factors).all()
    before = listing(ws)
    done = invoke("run", "case.yaml", "--ensemble", N, "--json", "--no-plot", "--out-dir", ws / "out")
    one_line_error(done, "uncertain.intensity", f"every one of the {N} members is drawn outside the model")
    assert listing(ws) == before


def body_case(restitution: float, k: float, uncertain: dict) -> dict:
    """The docs' asymmetric body (b1 = 0.044 m, b2 = 0.129 m, h = 0.2 m, radius of gyration ``k``)
    under a short rectangular pulse, with ``uncertain``."""
    return {"name": "body", "block": {"centre_of_mass_height": "0.2 m", "half_widths": ["0.044 m", "0.129 m"],
                                      "radius_of_gyration": f"{k!r} m", "mass": "1 kg"},
            "contact": {"mu_static": 10.0, "restitution": restitution},
            "ground": {"horizontal": {"pulse": "rectangular", "amplitude": "4 m/s^2", "duration": "0.15 s"},
                       "tail": "1 s"},
            "solver": {"dt": "1 ms"}, "uncertain": uncertain}


B1, B2, H = 0.044, 0.129, 0.2


def e_max(f: float, k: float) -> float:
    """The body's e_max with its width scaled by ``f`` (its corners scale as the width), from the
    model's own constants (`Model.restitution_max`), not the case file's check."""
    return Model(B1 * f, H, 10.0, 10.0, 0.5, half_width_2=B2 * f, radius_of_gyration=k).restitution_max


def test_an_asymmetric_bodys_members_beyond_e_max_or_k_max_are_left_out():
    """A restitution drawn around the body's e_max, and a width factor that shrinks its k_max below
    its radius of gyration: the members that break the case file's checks are left out, exactly
    those; the rest are computed and counted."""
    k = 0.995 * math.hypot(B2, H)                      # near k_max = sqrt(max(b1, b2)^2 + h^2)
    e0 = e_max(1.0, k) - 0.002
    uncertain = {"restitution": {"uniform": [e0 - 0.03, min(1.0, e0 + 0.03)]},
                 "slenderness": {"uniform": [0.95, 1.05]}}
    members = rockslide.ensemble(body_case(e0, k, uncertain), N)
    f = members.sample_slenderness.values
    e = members.sample_restitution.values
    beyond_k = k > np.sqrt((B2 * f) ** 2 + H * H)
    beyond_e = np.array([ei > e_max(fi, k) for ei, fi in zip(e, f, strict=True)])
    expected = beyond_k | beyond_e
    assert beyond_k.any() and (beyond_e & ~beyond_k).any() and not expected.all()     # the attack holds
    status = members.status.values
    assert np.array_equal(status == ens.STATUS_DRAWN_OUTSIDE, expected)
    summary = json.loads(members.attrs["ensemble"])
    assert summary["n_drawn_outside"] == int(expected.sum())
    reasons = summary["drawn_outside"]
    assert any("radius of gyration" in text for text in reasons) and any("e_max" in text for text in reasons)
    assert all(text.startswith("uncertain.") for text in reasons)
    assert np.isnan(members.max_rotation.values[expected]).all()
    assert np.isfinite(members.max_rotation.values[~expected]).all()
    within = status == 0
    assert summary["n_within_model"] == int(within.sum())
    assert members.attrs["p_overturn"] == members.overturned.values[within].mean()


def test_rounds_to_a_precision_count_only_the_members_within_the_model():
    """``precision``: the rounds grow the ensemble for the members counted; the last interval is
    as narrow as asked, over the members within the model, some members drawn outside in each."""
    A = 2.0 * G0 * 0.1 / 0.2
    case = {"name": "pulse", "block": {"height": "0.2 m", "width": "0.1 m", "mass": "1 kg"},
            "contact": {"mu_static": 10.0, "restitution": 0.8},
            "ground": {"horizontal": {"pulse": "rectangular", "amplitude": f"{A!r} m/s^2", "duration": "0.3 s"},
                       "tail": "1 s"},
            "solver": {"dt": "1 ms"}, "uncertain": {"intensity": {"lognormal": {"median": 1, "beta": 300}}}}
    members = rockslide.ensemble(case, precision=0.2)
    summary = json.loads(members.attrs["ensemble"])
    low, high = summary["interval"]
    assert high - low <= 0.2 and summary["n"] == summary["rounds"][-1]
    expected = outside_intensity(lognormal_draws(300.0, summary["n"]) * (A / EXAMPLE_PEAK))
    assert summary["n_drawn_outside"] == int(expected.sum()) > 0
    assert summary["n_within_model"] + summary["n_drawn_outside"] <= summary["n"]
