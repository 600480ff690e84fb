"""Fragilities exported for pelicun (`rockslide.io.pelicun`, ``fragility --export pelicun ID``).

The row and its metadata follow the columns of pelicun's fragility CSV (the FEMA P-58 2nd edition
file of SimCenter's damage and loss model library); with pelicun installed (3.x, the ``test``
extra's optional companion), pelicun itself loads them and samples the damage at a demand equal to
each median: the fraction of realisations in or beyond the state is 0.5 within pelicun's sampling
error. Without pelicun those tests skip with a message.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from conftest import REPO, invoke, one_line_error

from rockslide import api
from rockslide.analyses import risk as rk
from rockslide.errors import CaseError
from rockslide.io import pelicun as pl
from rockslide.io.datasets import study_dataset

G = 9.80665
EXAMPLE = REPO / "configs" / "example.yaml"
SUITE = REPO / "records" / "suite-synthetic.yaml"
#: Realisations of pelicun's sampling: the standard error of a fraction 0.5 is sqrt(0.25 / N) = 0.0035,
#: and the checks allow 5 of them (a false failure once in 1.7 million).
N = 20_000
TOLERANCE = 5 * math.sqrt(0.25 / N)


def fragility_dataset(im="pfa", medians=(0.8 * G, 0.35 * G), betas=(0.3, 0.45), fractions=None):
    """A fragility as `rockslide.fragility` gives it, with chosen fits (states in the order given:
    overturning first, as rockslide lists them, although its median is the higher)."""
    levels = np.array([0.1, 0.3, 0.5, 0.7, 0.9, 1.1]) * G
    if fractions is None:
        fractions = [[0.0, 0.0, 0.2, 0.4, 0.9, 1.0], [0.0, 0.4, 0.8, 0.7, 1.0, 1.0]]
    coords = [("level", levels, {"units": "m/s^2"}),
              ("damage_state", np.array(["overturn", "rotation>0.5alpha"], dtype=object), {})]
    variables = {
        "median": (("damage_state",), np.array(medians), {"units": "m/s^2"}),
        "beta": (("damage_state",), np.array(betas), {"units": "1"}),
        "definition": (("damage_state",), np.array(["overturning", "max |rotation| > 0.5 alpha"], dtype=object),
                       {}),
        "fit_note": (("damage_state",), np.array(["", ""], dtype=object), {}),
        "fraction_exceeded": (("damage_state", "level"), np.array(fractions, dtype=float), {"units": "1"}),
    }
    attrs = {"intensity_measure": im, "title": "rockslide fragility of cabinet", "fit_method": "maximum likelihood",
             "intensity_measure_long_name": "peak floor acceleration"}
    return study_dataset(coords, variables, attrs)


def test_the_row_has_pelicuns_columns_and_the_states_in_the_order_of_their_medians():
    row, left_out = pl.pelicun_row(fragility_dataset(), "RS.cabinet.5F")
    assert left_out == []
    assert list(row)[:6] == ["ID", "Incomplete", "Demand-Type", "Demand-Unit", "Demand-Offset", "Demand-Directional"]
    assert row["Demand-Type"] == "Peak Floor Acceleration" and row["Demand-Unit"] == "g"
    assert row["Demand-Directional"] == "1" and row["Demand-Offset"] == "0"
    assert float(row["LS1-Theta_0"]) == pytest.approx(0.35) and float(row["LS1-Theta_1"]) == 0.45
    assert float(row["LS2-Theta_0"]) == pytest.approx(0.8) and float(row["LS2-Theta_1"]) == 0.3
    meta = pl.pelicun_metadata(fragility_dataset(), "RS.cabinet.5F")["RS.cabinet.5F"]
    assert meta["LimitStates"]["LS1"]["DS1"]["Description"].startswith("rotation>0.5alpha")
    assert meta["LimitStates"]["LS2"]["DS2"]["Description"].startswith("overturn")


@pytest.mark.parametrize("im, demand, unit, scale", [("pfv", "Peak Floor Velocity", "cmps", 100.0),
                                                     ("pga", "Peak Ground Acceleration", "g", 1 / G),
                                                     ("sa(0.5 s)", "Spectral Acceleration|0.5", "g", 1 / G)])
def test_demand_type_and_unit_of_each_measure(im, demand, unit, scale):
    row, _ = pl.pelicun_row(fragility_dataset(im=im, medians=(0.8, 0.35)), "X.1")
    assert (row["Demand-Type"], row["Demand-Unit"]) == (demand, unit)
    assert float(row["LS1-Theta_0"]) == pytest.approx(0.35 * scale, rel=1e-15)


def test_what_cannot_be_exported_is_refused_in_one_line():
    with pytest.raises(CaseError, match="pga_rocking has no pelicun demand type"):
        pl.pelicun_row(fragility_dataset(im="pga_rocking"), "X.1")
    with pytest.raises(CaseError, match="component ID"):
        pl.pelicun_row(fragility_dataset(), "my cabinet,5")
    with pytest.raises(CaseError, match="no damage state can be exported"):
        pl.pelicun_row(fragility_dataset(medians=(math.nan, math.nan)), "X.1")
    row, left_out = pl.pelicun_row(fragility_dataset(medians=(math.nan, 0.3)), "X.1")
    assert "LS2-Family" not in row and left_out[0].startswith("overturn: no fit")


def test_monotone_stripes_pool_adjacent_violators_and_rise_strictly():
    """``[0, .4, .8, .7, 1, 1]``: the violators .8, .7 pool to .75; the leading zeros keep their last
    level, the trailing ones their first."""
    x, p = pl.monotone_stripes([1, 2, 3, 4, 5, 6, 7], [0, 0, 0.4, 0.8, 0.7, 1, 1])
    assert x.tolist() == [2, 3, 4, 6] and p.tolist() == [0.0, 0.4, 0.75, 1.0]
    x, p = pl.monotone_stripes([1, 2, 3], [0, math.nan, 1])
    assert x.tolist() == [1, 3] and p.tolist() == [0, 1]
    for fractions in ([0.1, 0.5, 1.0], [0.0, 0.5, 0.9]):
        with pytest.raises(ValueError):
            pl.monotone_stripes([1, 2, 3], fractions)


def test_files_are_written_together_and_read_back(tmp_path):
    csv_path, json_path = api.export_pelicun(fragility_dataset(), "RS.cabinet.5F", tmp_path / "cab.csv",
                                             family="multilinear_CDF")
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 1 and rows[0]["LS1-Family"] == "multilinear_CDF"
    # rotation: stripes [0, .4, .8, .7, 1, 1] at 0.1 ... 1.1 g -> the monotone [0, .4, .75, .75, 1, 1]; overturning
    # [0, 0, .2, .4, .9, 1] as it is. The points, linear in x (pelicun's CDF), follow rockslide's curve, linear in
    # ln x between the levels (risk.Tabulated), from the last 0 to the first 1, within 1e-5 (plus 1e-6 where flat)
    levels = np.array([0.1, 0.3, 0.5, 0.7, 0.9, 1.1])
    for column, curve, (first, last) in (("LS1-Theta_0", [0, 0.4, 0.75, 0.75, 1, 1], (0.1, 0.9)),
                                         ("LS2-Theta_0", [0, 0, 0.2, 0.4, 0.9, 1], (0.3, 1.1))):
        xs, ps = ([float(v) for v in part.split(",")] for part in rows[0][column].split("|"))
        assert (xs[0], xs[-1], ps[0], ps[-1]) == (first, last, 0.0, 1.0)
        assert (np.diff(xs) > 0).all() and (np.diff(ps) > 1e-8).all()
        x = np.geomspace(0.05, 1.2, 20)
        np.testing.assert_allclose(np.interp(x, xs, ps), rk.Tabulated(levels, np.array(curve, float))(x), atol=2e-5)
    assert set(json.loads(json_path.read_text())) == {"RS.cabinet.5F"}
    with pytest.raises(Exception, match="exists"):
        api.export_pelicun(fragility_dataset(), "RS.cabinet.5F", csv_path)


# --------------------------------------------------------------------------------------------------
# pelicun itself
# --------------------------------------------------------------------------------------------------


def pelicun_fraction_reached(csv_path, component_id: str, demand_in_g: float, seed: int = 7) -> np.ndarray:
    """pelicun's damage sample of one component on story 1 under PFA = ``demand_in_g`` (pelicun
    takes a story's PFA at the floor below it: location 0): the fraction of realisations in each
    damage state or beyond, states 1, 2, ..."""
    pytest.importorskip("pelicun", reason="pelicun is not installed (pip install 'pelicun>=3.3,<3.11')")
    import pandas as pd
    from pelicun.assessment import Assessment

    assessment = Assessment({"PrintLog": False, "Seed": seed, "Verbose": False})
    assessment.stories = 1
    demand = pd.DataFrame({"1-PFA-0-1": [demand_in_g] * N})
    demand.loc["Units"] = ["g"]
    assessment.demand.load_sample(demand.loc[["Units", *range(N)]])
    components = pd.DataFrame({"Units": ["ea"], "Location": ["1"], "Direction": ["1"], "Theta_0": ["1"]},
                              index=[component_id])
    assessment.asset.load_cmp_model({"marginals": components})
    assessment.asset.generate_cmp_sample(N)
    assessment.damage.load_model_parameters([str(csv_path)], {component_id})
    assessment.damage.calculate()
    states = np.asarray(assessment.damage.ds_model.ds_sample.iloc[:, 0], dtype=float)   # the state of each
    return np.array([np.mean(states >= k) for k in (1, 2)])


@pytest.mark.parametrize("state, median_g", [(0, 0.35), (1, 0.8)])
def test_pelicun_gives_one_half_at_each_median(tmp_path, state, median_g):
    csv_path, _ = api.export_pelicun(fragility_dataset(), "RS.cabinet.5F", tmp_path / "cab.csv")
    reached = pelicun_fraction_reached(csv_path, "RS.cabinet.5F", median_g)
    assert reached[state] == pytest.approx(0.5, abs=TOLERANCE)


def test_pelicun_accepts_the_multilinear_rows(tmp_path):
    """The stripes of overturning rise 0, .2, .4, .9, 1 at 0.3 ... 1.1 g: halfway between .4 at
    0.7 g and .9 at 0.9 g, pelicun's CDF is 0.5 at 0.74 g."""
    csv_path, _ = api.export_pelicun(fragility_dataset(), "RS.cabinet.5F", tmp_path / "cab.csv",
                                     family="multilinear_CDF")
    reached = pelicun_fraction_reached(csv_path, "RS.cabinet.5F", 0.74)
    assert reached[1] == pytest.approx(0.5, abs=TOLERANCE)


# --------------------------------------------------------------------------------------------------
# The command
# --------------------------------------------------------------------------------------------------


def test_fragility_exports_a_row_beside_its_file(tmp_path):
    out = tmp_path / "out"
    result = invoke("fragility", EXAMPLE, "--suite", SUITE,
                    "--levels", "0.2g:1.6g:0.2g", "--bootstrap", "0", "--no-plot", "--no-progress",
                    "--out-dir", out, "--export", "pelicun", "RS.example")
    assert result.exit_code == 0, (result.output, result.exception)
    with open(out / "example.fragility.pelicun.csv", newline="") as f:
        row = next(csv.DictReader(f))
    stored = api.read_result(out / "example.fragility.h5")
    assert row["ID"] == "RS.example" and row["Demand-Type"] == "Peak Ground Acceleration"
    assert float(row["LS1-Theta_0"]) == float(stored["median"].values[0]) / G
    assert "RS.example" in json.loads((out / "example.fragility.pelicun.json").read_text())


@pytest.mark.parametrize("args, part", [(["--export", "pelicun", "a b"], "component ID"),
                                        (["--im", "pga_rocking", "--export", "pelicun", "X"], "no pelicun demand")])
def test_bad_exports_are_one_line_before_any_run(tmp_path, args, part):
    result = invoke("fragility", EXAMPLE, "--suite", SUITE,
                    "--levels", "0.2:1:0.2" if "pga_rocking" in args else "0.2g:1g:0.2g", "--out-dir", tmp_path,
                    *args)
    one_line_error(result, part)
