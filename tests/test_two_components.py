"""Two horizontal components and the block's orientation (issue 32).

The checks of the issue: an orientation equal to the first component's azimuth is the one-component
run bit for bit; the largest peak over azimuths is the peak of the vector sum within the grid's
``1 - cos(0.5 deg)``; RotD50 equals an independent brute-force computation; turning both
components and the block by one angle changes nothing, bit for bit.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np
import pytest
from conftest import invoke, one_line_error, real_record

from rockslide.api import run, sweep
from rockslide.case import case_to_dict, parse_case, parse_mapping
from rockslide.core import intensity
from rockslide.errors import CaseError
from rockslide.io import records as rec

DT = 0.01
#: Half the azimuth grid's step [deg]: the direction of the vector's peak lies within it of a grid
#: angle, so the grid's largest peak is at least cos(0.5 deg) of the vector's (1 - 3.8e-5).
HALF_STEP = math.radians(0.5)


def _components(n: int = 1500):
    """Two horizontal components [m/s^2] that are not proportional (different frequencies and
    envelopes), so that the motion's direction turns during the record."""
    t = np.arange(n) * DT
    envelope = np.exp(-((t - 5.0) / 3.0) ** 2)
    a1 = 4.0 * envelope * np.sin(2 * math.pi * 1.3 * t) + 1.0 * envelope * np.sin(2 * math.pi * 4.1 * t)
    a2 = 3.0 * envelope * np.sin(2 * math.pi * 0.9 * t + 0.7) - 1.5 * np.exp(-((t - 7.0) / 1.0) ** 2)
    return a1, a2


@pytest.fixture
def pair(tmp_path):
    """The two components written as PEER AT2 files whose titles name azimuths 0 and 90."""
    a1, a2 = _components()
    g = 9.80665
    rec.write_at2(tmp_path / "h1.at2", a1 / g, DT, title="Synthetic 2026", component="0")
    rec.write_at2(tmp_path / "h2.at2", a2 / g, DT, title="Synthetic 2026", component="90")
    rec.write_at2(tmp_path / "up.at2", 0.1 * a1 / g, DT, title="Synthetic 2026", component="UP")
    return tmp_path


def _case(folder, *, orientation=None, azimuths=(None, None), scale=None, one=None, vertical=False):
    ground = {}
    if one is not None:
        ground["horizontal"] = one
    else:
        for k, (name, azimuth) in enumerate(zip(("h1.at2", "h2.at2"), azimuths, strict=True), start=1):
            ground[f"horizontal_{k}"] = {"file": name} if azimuth is None else {"file": name, "azimuth": azimuth}
    if vertical:
        ground["vertical"] = "up.at2"
    if scale:
        ground["scale"] = scale
    block = {"height": "1.0 m", "width": "0.25 m", "mass": "50 kg"}
    if orientation is not None:
        block["orientation"] = orientation
    data = {"name": "two", "block": block, "contact": {"mu_static": 0.7, "restitution": 0.9},
            "ground": ground, "solver": {"dt": "1 ms"}, "output": {"interval": "10 ms"}}
    return parse_mapping(data, base_dir=folder)


# --------------------------------------------------------------------------------------------------
# Direction cosines: exact at quarter turns, a function of the angle differences only
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("quarters", range(-9, 10))
def test_quarter_turns_are_exact(quarters):
    expected = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][quarters % 4]
    c, s = intensity.direction_cosines(math.radians(90.0 * quarters))
    assert (c, s) == expected
    assert math.copysign(1.0, c) == math.copysign(1.0, expected[0])     # no negative zero


@pytest.mark.parametrize("degrees", [1.0, 30.0, 45.0, 137.5, 211.0, -63.0])
def test_direction_cosines_closed_form(degrees):
    c, s = intensity.direction_cosines(math.radians(degrees))
    # the reduction to [0, 90) deg and a swap: within 2 ulp of the library's cos and sin
    assert c == pytest.approx(math.cos(math.radians(degrees)), abs=4e-16)
    assert s == pytest.approx(math.sin(math.radians(degrees)), abs=4e-16)


def test_along_at_quarter_turns_is_a_component_exactly():
    a1, a2 = _components()
    az1, az2 = math.radians(20.0), math.radians(110.0)
    assert np.array_equal(intensity.along(a1, a2, az1, az2, az1), a1)
    assert np.array_equal(intensity.along(a1, a2, az1, az2, az2), a2)
    assert np.array_equal(intensity.along(a1, a2, az1, az2, az1 + math.pi), -a1)
    assert np.array_equal(intensity.along(a1, a2, az1, az2, az2 - math.pi), -a2)


@pytest.mark.parametrize("turn", [37.3, 90.0, 180.0, -270.0, 1234.567])
def test_turning_everything_changes_nothing(turn):
    a1, a2 = _components()
    az1, az2, block = 10.0, 100.0, 52.0
    before = intensity.along(a1, a2, *(math.radians(x) for x in (az1, az2, block)))
    after = intensity.along(a1, a2, *(math.radians(x + turn) for x in (az1, az2, block)))
    assert np.array_equal(before, after)


def test_turning_everything_leaves_the_run_unchanged(pair):
    base = run(_case(pair, orientation="52 deg", azimuths=("10 deg", "100 deg")), history=False)
    turned = run(_case(pair, orientation="89.3 deg", azimuths=("47.3 deg", "137.3 deg")), history=False)
    assert base.result.summary == turned.result.summary
    assert np.array_equal(base.result.ground_horizontal, turned.result.ground_horizontal)
    # the components' handedness does not matter either: azimuth 2 at -90 deg from 1, the block
    # mirrored about component 1: the same motion along it
    mirrored = run(_case(pair, orientation="-32 deg", azimuths=("10 deg", "-80 deg")), history=False)
    assert np.array_equal(mirrored.result.ground_horizontal, base.result.ground_horizontal)


# --------------------------------------------------------------------------------------------------
# The one-component run, bit for bit
# --------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("scale", [None, {"factor": 1.3}, {"pga_horizontal": "300 gal"}])
def test_orientation_of_the_first_component_is_the_one_component_run(pair, scale):
    a1, a2 = _components()
    assert np.max(np.abs(a1)) > np.max(np.abs(a2))     # pga_horizontal: the same factor both ways
    one = run(_case(pair, one="h1.at2", scale=scale, vertical=True))
    two = run(_case(pair, orientation="0 deg", scale=scale, vertical=True))
    assert one.result.summary == two.result.summary
    for column in one.result.history:
        assert np.array_equal(one.result.history[column], two.result.history[column]), column
    assert np.array_equal(one.result.events, two.result.events)
    assert np.array_equal(one.result.ground_horizontal, two.result.ground_horizontal)
    assert np.array_equal(one.result.ground_vertical, two.result.ground_vertical)
    # no orientation: along the first component
    default = run(_case(pair, scale=scale, vertical=True), history=False)
    assert default.result.summary == one.result.summary


# --------------------------------------------------------------------------------------------------
# Rotated peaks: RotD100 and the vector sum, RotD50 by brute force
# --------------------------------------------------------------------------------------------------

def test_largest_peak_over_azimuths_is_the_vector_peak():
    a1, a2 = _components()
    vector = float(np.max(np.hypot(a1, a2)))
    az1, az2 = math.radians(17.0), math.radians(107.0)
    largest = max(np.max(np.abs(intensity.along(a1, a2, az1, az2, math.radians(d)))) for d in range(360))
    assert vector * math.cos(HALF_STEP) <= largest <= vector * (1 + 1e-15)
    rotd100 = float(np.max(intensity.rotd_peaks(a1, a2, DT, "pga")))
    assert vector * math.cos(HALF_STEP) <= rotd100 <= vector * (1 + 1e-15)
    assert rotd100 == pytest.approx(largest, rel=1e-15)    # the same peak: 180 deg apart is |-a|


def _brute_force(a1, a2, measure, period=None):
    """Peaks at 0..179 deg from the rotated records themselves (math.cos and math.sin, one record
    per angle; Sa from the oscillator under each rotated record, not from rotated responses)."""
    peaks = []
    for degrees in range(180):
        theta = math.radians(degrees)
        rotated = [math.cos(theta) * x + math.sin(theta) * y for x, y in zip(a1, a2, strict=True)]
        if measure == "pga":
            peaks.append(max(abs(x) for x in rotated))
        elif measure == "pgv":
            peaks.append(intensity.peak_velocity(rotated, DT))
        else:
            peaks.append(intensity.spectral_acceleration(rotated, DT, period))
    ordered = sorted(peaks)
    return 0.5 * (ordered[89] + ordered[90]), ordered[-1]


@pytest.mark.parametrize("measure, period", [("pga", None), ("pgv", None), ("sa", 0.5), ("sa", 0.05)])
def test_rotd50_and_rotd100_by_brute_force(measure, period):
    a1, a2 = _components(600)
    peaks = intensity.rotd_peaks(a1, a2, DT, measure, period)
    rotd50, rotd100 = _brute_force(a1, a2, measure, period)
    # rounding only: cos/sin of the angle (1 ulp apart from direction_cosines') and, for Sa, the
    # order of the sums (rotating responses instead of inputs: linearity, exact but for rounding)
    assert float(np.median(peaks)) == pytest.approx(rotd50, rel=1e-12)
    assert float(np.max(peaks)) == pytest.approx(rotd100, rel=1e-12)


def test_rotd_pga_of_a_circular_motion_is_its_radius():
    """A motion that turns at a constant radius r has every rotated peak r (within the sampling of
    the turn: 3000 samples per turn, so at most 1 - cos(0.06 deg))."""
    t = np.arange(3001) / 3000.0
    peaks = intensity.rotd_peaks(2.0 * np.cos(2 * math.pi * t), 2.0 * np.sin(2 * math.pi * t), DT, "pga")
    assert np.all(peaks <= 2.0 + 1e-15) and np.all(peaks >= 2.0 * math.cos(math.pi / 3000))


def test_rotd_with_pyrotd_if_installed():
    """Against pyrotd (an optional extra: the test skips without it)."""
    pyrotd = pytest.importorskip("pyrotd")
    a1, a2 = _components(1200)
    periods = np.array([0.2, 1.0])
    ours = [np.median(intensity.rotd_peaks(a1, a2, DT, "sa", p)) for p in periods]
    theirs = pyrotd.calc_rotated_spec_accels(DT, a1, a2, 1.0 / periods, 0.05, percentiles=[50])
    # pyrotd takes the record as band-limited (FFT) and periodic (no padding in time), rockslide as
    # linear between samples: 0.15 % and 0.4 % apart here; on the real pairs, up to 2.3 % at
    # periods <= 0.3 s (benchmarks/compare_pyrotd.py -> results/compare_pyrotd.md)
    np.testing.assert_allclose(ours, [row["spec_accel"] for row in theirs], rtol=0.01)


# --------------------------------------------------------------------------------------------------
# Azimuths from the AT2 headers, the case file, the reporting
# --------------------------------------------------------------------------------------------------

def test_azimuths_from_at2_headers(pair):
    assert rec.at2_azimuth(pair / "h1.at2") == 0.0
    assert rec.at2_azimuth(pair / "h2.at2") == math.radians(90.0)
    assert rec.at2_azimuth(pair / "up.at2") is None
    # PEER titles name north 360 as often as 0 ("Sylmar - Olive View Med FF, 360")
    rec.write_at2(pair / "north.at2", np.zeros(4), DT, title="Northridge-01 1/17/1994, Sylmar - Olive View Med FF",
                  component="360")
    assert rec.at2_azimuth(pair / "north.at2") == 0.0


def test_azimuths_of_the_peer_kobe_records():
    ns = real_record("kobe_jma_1995_ns_peer_rsn1106_kjm000.at2")
    ew = real_record("kobe_jma_1995_ew_peer_rsn1106_kjm090.at2")     # title line ends ', KJMA, 90'
    assert rec.at2_azimuth(ns) == 0.0
    assert rec.at2_azimuth(ew) == math.radians(90.0)


def test_reported_across_peak_and_ignored_share(pair, tmp_path):
    """The peak across the block and the share of the Arias intensity across it, from the closed
    forms: across theta, ``-a1 sin(theta - az1) - a2 sin(theta - az2)``; at theta = az1 the share is
    ``sum a2^2 / sum (a1^2 + a2^2)``."""
    case = _case(pair, orientation="30 deg")
    a1, a2 = (rec.load_record(pair / f"h{k}.at2").data for k in (1, 2))
    result = run(case, history=False)
    components = result.ground["components"]
    theta = math.radians(30.0)
    across = -a1 * math.sin(theta) - a2 * math.sin(theta - math.pi / 2)
    assert components["pga_across"] == pytest.approx(np.max(np.abs(across)), rel=1e-14)
    assert components["ignored_share"] == pytest.approx(np.sum(across**2) / np.sum(a1**2 + a2**2), rel=1e-12)
    at_first = run(_case(pair, orientation="0 deg"), history=False).ground["components"]
    assert at_first["ignored_share"] == pytest.approx(np.sum(a2**2) / np.sum(a1**2 + a2**2), rel=1e-12)
    assert at_first["pga_across"] == float(np.max(np.abs(a2)))


def _case_file(case, folder, monkeypatch) -> str:
    """The case written as a case file in ``folder``, made the current folder (for the commands)."""
    import yaml

    monkeypatch.chdir(folder)
    (folder / f"{case.name}.yaml").write_text(yaml.safe_dump(case_to_dict(case)))
    return f"{case.name}.yaml"


def test_run_command_prints_and_stores_the_components(pair, monkeypatch):
    _case_file(_case(pair, orientation="30 deg"), pair, monkeypatch)
    result = invoke("run", "two.yaml", "--no-plot")
    assert result.exit_code == 0, result.output
    assert "block at 30 deg" in result.output and "ignored by the planar model" in result.output
    with h5py.File(pair / "out" / "two.h5") as f:
        assert f.attrs["ground_orientation"] == math.radians(30.0)
        assert f.attrs["ground_azimuth_2"] == math.radians(90.0)
        assert set(f["records"]) == {"horizontal", "horizontal_2"}


def test_a_sweep_file_stores_the_azimuths_read_from_the_at2_headers(pair, monkeypatch):
    """The case gives no azimuth: the sweep reads 0 and 90 deg from the files' titles and stores them
    as a run's file does (``ground_azimuth_1``, ``ground_azimuth_2`` [rad]), so that the file says
    which directions its orientations are measured from."""
    _case_file(_case(pair), pair, monkeypatch)
    result = invoke("sweep", "two.yaml", "--azimuth", "0,45", "--no-plot")
    assert result.exit_code == 0, result.output
    with h5py.File(pair / "out" / "two.sweep.h5") as f:
        assert f.attrs["ground_azimuth_1"] == 0.0 and f.attrs["ground_azimuth_2"] == math.radians(90.0)


def test_case_round_trip(pair):
    case = _case(pair, orientation="30 deg", azimuths=("0 deg", None))
    again = parse_mapping(case_to_dict(case), base_dir=pair)
    assert again.block == case.block and again.ground == case.ground


@pytest.mark.parametrize("change, field", [
    ({"orientation": 30}, "block.orientation"),                          # a bare number: 30 rad?
    ({"azimuths": (5, None)}, "ground.horizontal_1.azimuth"),
])
def test_angles_need_their_unit(pair, change, field):
    with pytest.raises(CaseError, match="unit") as info:
        _case(pair, **change)
    assert info.value.field == field


def test_bad_two_component_cases(pair):
    text = ("name: t\nblock: {height: 1 m, width: 0.25 m, mass: 50 kg%s}\ncontact: {mu_static: 0.7, "
            "restitution: 0.9}\nground: {%s}\n")
    with pytest.raises(CaseError, match="horizontal_2.*missing"):
        parse_case(text % ("", "horizontal_1: h1.at2"))
    with pytest.raises(CaseError, match="exclusive"):
        parse_case(text % ("", "horizontal: h1.at2, horizontal_1: h1.at2, horizontal_2: h2.at2"))
    with pytest.raises(CaseError, match="one horizontal component"):
        parse_case(text % (", orientation: 10 deg", "horizontal: h1.at2"))
    with pytest.raises(CaseError, match="at most 360 deg"):     # 1e300 deg has no nanodegree
        parse_case(text % (", orientation: 1e300 deg", "horizontal_1: h1.at2, horizontal_2: h2.at2"))
    with pytest.raises(CaseError, match="pulse"):
        parse_case(text % ("", "horizontal_1: {pulse: half-sine, amplitude: 1 g, duration: 0.2 s}, "
                                "horizontal_2: h2.at2"))
    with pytest.raises(CaseError, match="not 90 deg apart") as info:
        run(_case(pair, azimuths=("0 deg", "80 deg")))
    assert info.value.field == "ground.horizontal_2.azimuth"
    rec.write_at2(pair / "h3.at2", np.zeros(1500), DT, title="Synthetic", component="UP")
    case = _case(pair).with_({"ground.horizontal_2.file": "h3.at2"})
    with pytest.raises(CaseError, match="azimuth of h3.at2 is not given"):
        run(case)


# --------------------------------------------------------------------------------------------------
# The azimuth sweep
# --------------------------------------------------------------------------------------------------

def test_azimuth_sweep_points_are_runs(pair):
    case = _case(pair, scale={"pga_horizontal": "400 gal"})
    swept = sweep(case, azimuth="0,30,90,135", records_dir=pair)
    for k, degrees in enumerate((0, 30, 90, 135)):
        alone = run(case.with_({"block.orientation": f"{degrees} deg"}), history=False).result.summary
        point = swept.isel(azimuth=k)
        assert float(point["azimuth"]) == math.radians(degrees)
        assert bool(point["overturned"]) == alone.overturned
        assert float(point["max_rotation"]) == alone.max_rotation


def test_azimuth_needs_two_components(pair, monkeypatch):
    name = _case_file(_case(pair, one="h1.at2"), pair, monkeypatch)
    one_line_error(invoke("sweep", name, "--azimuth", "0:180:45"), "--azimuth", "horizontal_1")


# --------------------------------------------------------------------------------------------------
# Suites of pairs, fragility by RotD and over azimuths, ensembles over the orientation
# --------------------------------------------------------------------------------------------------

def _suite(folder, text):
    path = folder / "suite.yaml"
    path.write_text(text)
    return path


def test_suite_pairs(pair):
    from rockslide.case import load_suite

    suite = load_suite(_suite(pair, "records:\n  - {name: s, horizontal_1: h1.at2, horizontal_2: "
                                    "{file: h2.at2, azimuth: 90 deg}}\n  - h1.at2\n"))
    assert suite.entries[0].horizontal.file == "h1.at2"
    assert suite.entries[0].horizontal_2.azimuth == math.radians(90.0)
    assert suite.entries[1].horizontal_2 is None
    with pytest.raises(CaseError, match=r"records\[0\].horizontal_2: missing"):
        load_suite(_suite(pair, "records:\n  - {horizontal_1: h1.at2}\n"))
    with pytest.raises(CaseError, match="exclusive"):
        load_suite(_suite(pair, "records:\n  - {horizontal: h1.at2, horizontal_1: h1.at2, horizontal_2: h2.at2}\n"))
    # a bare azimuth is refused in a suite as in a case file (it was read as 90 rad)
    with pytest.raises(CaseError, match=r"records\[0\].horizontal_2.azimuth: an integer 90 has no unit"):
        load_suite(_suite(pair, "records:\n  - {horizontal_1: h1.at2, horizontal_2: {file: h2.at2, azimuth: 90}}\n"))


def test_fragility_by_rotd50_and_along_the_block(pair):
    from rockslide.api import fragility

    suite = _suite(pair, "records:\n  - {name: s, horizontal_1: h1.at2, horizontal_2: h2.at2}\n")
    case = _case(pair, orientation="30 deg")
    a1, a2 = (rec.load_record(pair / f"h{k}.at2").data for k in (1, 2))
    by_rotd = fragility(case, suite, im="rotd50_pga", levels="0.1g,0.3g", resamples=0)
    brute = _brute_force(a1, a2, "pga")[0]
    assert float(by_rotd["record_im"][0]) == pytest.approx(brute, rel=1e-12)
    # pga with a pair: the peak of the motion along the block (30 deg from component 1, at 0 deg)
    along = math.cos(math.radians(30.0)) * a1 + math.sin(math.radians(30.0)) * a2
    by_pga = fragility(case, suite, im="pga", levels="0.1g,0.3g", resamples=0)
    assert float(by_pga["record_im"][0]) == pytest.approx(np.max(np.abs(along)), rel=1e-14)
    with pytest.raises(CaseError, match="needs two horizontal components"):
        fragility(case, _suite(pair, "records: [h1.at2]\n"), im="rotd100_sa(0.5s)", levels="0.1g", resamples=0)


def test_fragility_over_azimuths_is_each_stated_orientation(pair):
    from rockslide.api import fragility

    suite = _suite(pair, "records:\n  - {name: s, horizontal_1: h1.at2, horizontal_2: h2.at2}\n")
    case = _case(pair)
    levels = "0.2g,0.4g,0.6g"
    pooled = fragility(case, suite, im="rotd50_pga", levels=levels, azimuth="0,60,120", resamples=0)
    assert list(pooled["record"].values) == ["s@0deg", "s@60deg", "s@120deg"]
    for k, degrees in enumerate((0, 60, 120)):
        stated = fragility(case, suite, im="rotd50_pga", levels=levels, azimuth=str(degrees), resamples=0)
        for name in ("overturned", "max_rotation"):
            assert np.array_equal(pooled[name].isel(record=k).values, stated[name].isel(record=0).values), name
        # the RotD50 does not depend on the orientation: one scale factor per level for all
        assert float(stated["record_im"][0]) == float(pooled["record_im"][k])


def test_ensemble_over_the_orientation(pair):
    from rockslide.api import ensemble

    case = _case(pair, orientation="30 deg", scale={"pga_horizontal": "400 gal"})
    case = case.with_({"uncertain.orientation": {"uniform": ["0 deg", "180 deg"]}})
    members = ensemble(case, 6, seed=3, records_dir=pair)
    drawn = members["sample_orientation"].values
    assert np.all((drawn >= 0.0) & (drawn <= math.pi)) and len(set(drawn)) == 6
    for k in (0, 5):
        alone = run(case.with_({"block.orientation": float(drawn[k])}), history=False).result.summary
        assert float(members["max_rotation"][k]) == alone.max_rotation


def test_uncertain_orientation_checks(pair):
    base = _case(pair).with_({"uncertain.orientation": {"uniform": ["0 deg", "90 deg"]}})
    assert base.uncertain.orientation.b == math.radians(90.0)
    assert parse_mapping(case_to_dict(base), base_dir=pair).uncertain == base.uncertain
    with pytest.raises(CaseError, match="one horizontal component"):
        _case(pair, one="h1.at2").with_({"uncertain.orientation": {"uniform": ["0 deg", "90 deg"]}})
    data = case_to_dict(_case(pair))
    data["uncertain"] = {"orientation": {"uniform": [0, 90]}}
    with pytest.raises(CaseError, match="no unit"):
        parse_mapping(data, base_dir=pair)


def test_worst_azimuth_rule():
    """Most overturning first, then the largest rotation where it stands, then the earliest fall."""
    from types import SimpleNamespace

    from rockslide.analyses import sweep as sw

    plan = SimpleNamespace(axes=[sw.parse_axis("azimuth", "0,45,90"), sw.parse_axis("mu", "0.5,0.6")])
    over = np.array([[0, 0], [1, 0], [1, 0]])
    ratio = np.array([[0.9, 0.8], [9.0, 0.5], [9.0, 0.7]])
    when = np.where(over == 1, 5.0, np.nan)
    variables = {"overturned": (over, {}), "max_rotation_ratio": (ratio, {}), "overturn_time": (when, {})}
    worst = sw.worst_azimuth(plan, variables)
    assert worst["azimuth"] == math.radians(90.0) and worst["overturned"] == 0.5    # 0.7 > 0.5 of alpha
    assert worst["text"].startswith("worst azimuth 90 deg: overturned at 50 %")
    when[1, 0] = 4.0                                       # all fall: the earliest is the worst
    variables["overturned"] = (np.ones((3, 2), dtype=int), {})
    variables["overturn_time"] = (np.array([[6.0, 6.0], [4.0, 6.0], [5.0, 6.0]]), {})
    assert sw.worst_azimuth(plan, variables)["azimuth"] == math.radians(45.0)


def test_sweep_command_prints_the_worst_azimuth(pair, monkeypatch):
    name = _case_file(_case(pair, scale={"pga_horizontal": "300 gal"}), pair, monkeypatch)
    result = invoke("sweep", name, "--azimuth", "0:90:45", "--no-plot")
    assert result.exit_code == 0, result.output
    assert "worst azimuth" in result.output


# --------------------------------------------------------------------------------------------------
# Two components on a floor: the floor filters the motion along the block
# --------------------------------------------------------------------------------------------------

def test_a_floor_filters_the_motion_along_the_block(pair):
    """With ``ground.floor`` and two components, the block stands on the floor's response to the
    motion along its direction: the floor is linear, so that is the floor's response to component
    1 times cos(30 deg) plus component 2's times sin(30 deg) (to round-off), and the base kept in
    the result is the motion along the block."""
    from rockslide.engine import prepare as runner

    floor = {"horizontal": {"period": "0.4 s", "damping": 0.05}}
    case = _case(pair, orientation="30 deg").with_({"ground.floor": floor})
    prepared = runner.prepare(case, records_dir=pair, history=False)
    a1, a2 = _components()
    dt = prepared.base.dt
    f1, step = intensity.floor_acceleration(a1, dt, [(0.4, 0.05, 1.0)], round(dt / prepared.ground.dt))
    f2, _ = intensity.floor_acceleration(a2, dt, [(0.4, 0.05, 1.0)], round(dt / prepared.ground.dt))
    expected = math.cos(math.radians(30)) * f1 + math.sin(math.radians(30)) * f2
    assert prepared.ground.dt == step
    # the AT2 files hold the components to 7 significant digits (write_at2): compare at that scale
    assert np.max(np.abs(prepared.ground.horizontal - expected)) <= 1e-6 * np.max(np.abs(expected))
    along = math.cos(math.radians(30)) * a1 + math.sin(math.radians(30)) * a2
    assert np.max(np.abs(prepared.base.horizontal - along)) <= 1e-6 * np.max(np.abs(along))
    # and a sweep over azimuths runs each orientation on its own floor motion
    swept = sweep(case, azimuth="0,30", records_dir=pair)
    alone = run(case, history=False).result.summary
    assert float(swept.isel(azimuth=1)["max_rotation"]) == pytest.approx(alone.max_rotation, rel=1e-9)


def test_the_bootstrap_over_orientations_resamples_records_not_orientations(pair):
    """Turning the block (--azimuth) repeats each record at every orientation; the bootstrap must
    resample records, each with all its orientations. At -340 and 20 deg the two orientations are
    one, so every record's two rows are the same: resampling whole records gives exactly the fit
    and intervals of the records at one orientation (the likelihood is that of one row, squared),
    while resampling rows one by one (as if 8 records) would narrow the intervals."""
    from rockslide.api import fragility

    t = np.arange(1500) * DT
    envelope = np.exp(-((t - 5.0) / 2.0) ** 2)
    for k, hz in enumerate((1.5, 2.5, 4.0, 6.0), start=1):     # records of different frequencies
        rec.write_at2(pair / f"p{k}_1.at2", envelope * np.sin(2 * math.pi * hz * t), DT, title="S", component="0")
        rec.write_at2(pair / f"p{k}_2.at2", 0.6 * envelope * np.cos(2 * math.pi * 0.7 * hz * t), DT, title="S",
                      component="90")
    suite = _suite(pair, "records:\n" + "".join(
        f"  - {{name: r{k}, horizontal_1: p{k}_1.at2, horizontal_2: p{k}_2.at2}}\n" for k in (1, 2, 3, 4)))
    case = _case(pair, orientation="20 deg")
    levels = "0.2g:3g:0.1g"
    once = fragility(case, suite, im="pga", levels=levels, azimuth="20", resamples=300)
    twice = fragility(case, suite, im="pga", levels=levels, azimuth="-340,20", resamples=300)
    assert twice.sizes["record"] == 8 and once.sizes["record"] == 4
    assert np.isfinite(once["median_lower"].values).all()           # a fit, with an interval
    for name in ("median", "beta", "median_lower", "median_upper", "beta_lower", "beta_upper"):
        assert np.allclose(twice[name].values, once[name].values, rtol=1e-9, equal_nan=True), name


# --------------------------------------------------------------------------------------------------
# Figures and tables of two components: the orientation in the caption, the azimuth in degrees
# --------------------------------------------------------------------------------------------------

def test_two_orientations_plotted_have_different_captions(pair, monkeypatch):
    """``rockslide plot r0/two.h5 r60/two.h5``: the same case but the block at 0 and 60 deg; the
    captions gave neither. The components' azimuths, 0 and 90 deg, come from the AT2 headers
    written by `pair` (the case does not give them): they are the ones the runs stored."""
    from matplotlib.text import Text

    from rockslide import plots
    from rockslide.api import plot_results, read_result

    for degrees in (0, 60):
        _case_file(_case(pair, orientation=f"{degrees} deg"), pair, monkeypatch)
        result = invoke("run", "two.yaml", "--no-plot", "--out-dir", f"r{degrees}")
        assert result.exit_code == 0, result.output
    captions = [plots.run_caption(read_result(pair / f"r{d}" / "two.h5")) for d in (0, 60)]
    assert "block at 0 deg (components 0 and 90 deg)" in captions[0]
    assert "block at 60 deg (components 0 and 90 deg)" in captions[1]
    for caption in captions:
        assert "h1.at2 (H1), h2.at2 (H2)" in caption
    fig = plot_results([pair / "r0" / "two.h5", pair / "r60" / "two.h5"], size="column")
    shown = " ".join(t.get_text() for t in fig.findobj(Text)).replace("\n", " ")
    assert "block at 0 deg" in shown and "block at 60 deg" in shown
    assert invoke("plot", pair / "r0" / "two.h5", pair / "r60" / "two.h5", "-o", pair / "both.png").exit_code == 0


def test_orientation_in_the_caption_of_a_case():
    """From the case alone: its azimuths where it gives them, else none; no orientation: the first
    component's."""
    from rockslide import plots

    def text(block, azimuths):
        one, two = ({"file": f"h{k}.at2", **({"azimuth": a} if a else {})} for k, a in enumerate(azimuths, 1))
        return ("name: t\nblock: {height: 1 m, width: 0.25 m, mass: 50 kg" + block + "}\n"
                "contact: {mu_static: 0.7, restitution: 0.9}\n"
                f"ground: {{horizontal_1: {one}, horizontal_2: {two}}}\n".replace("'", ""))

    assert "block at 30 deg (components 10 and 100 deg)" in plots.case_caption(
        text(", orientation: 30 deg", ("10 deg", "100 deg")))
    assert "block at 10 deg (components 10 and 100 deg)" in plots.case_caption(text("", ("10 deg", "100 deg")))
    assert "block at 30 deg;" in plots.case_caption(text(", orientation: 30 deg", (None, None)))
    assert "block along component 1" in plots.case_caption(text("", (None, None)))
    assert "ground h1.at2 (H1), h2.at2 (H2)" in plots.case_caption(text("", (None, None)))
    assert "block at" not in plots.case_caption(text("", (None, None)).replace(
        "horizontal_1: {file: h1.at2}, horizontal_2: {file: h2.at2}", "horizontal: h1.at2"))


def test_azimuth_sweep_csv_in_degrees_and_its_caption_names_both_components(pair, monkeypatch):
    """``--csv`` writes the azimuth in degrees, as given (it wrote radians under a plotted degree
    axis); the stored sweep's caption names the second component's file (it read only
    record_horizontal and record_vertical)."""
    import csv

    from rockslide.analyses import sweep as sw
    from rockslide.io import results

    _case_file(_case(pair, scale={"pga_horizontal": "400 gal"}), pair, monkeypatch)
    result = invoke("sweep", "two.yaml", "--azimuth", "0,30,135", "--mu", "0.5,0.7", "--csv", "--no-plot",
                    "--no-progress", "--out-dir", "out")
    assert result.exit_code == 0, result.output
    with open(pair / "out" / "two.sweep.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert "azimuth [deg]" in rows[0] and "azimuth [rad]" not in rows[0]
    stored = results.read_dataset(pair / "out" / "two.sweep.h5", format=results.SWEEP_FORMAT)
    azimuths = dict((name, values) for name, values, _ in stored.coords)["azimuth"]
    column = np.array([float(row["azimuth [deg]"]) for row in rows]).reshape(3, 2)[:, 0]
    # the values given on the command line; 1e-12 deg: one rounding of deg -> rad and one back
    np.testing.assert_allclose(column, [0.0, 30.0, 135.0], rtol=0, atol=1e-12)
    # and the file's values converted: the same two roundings, 1e-15 rad
    np.testing.assert_allclose(np.radians(column), azimuths, rtol=0, atol=1e-15)
    for variable in ("max_rotation", "overturned"):
        header = next(key for key in rows[0] if key.split(" [")[0] == variable)
        parsed = np.array([float(row[header]) for row in rows]).reshape(3, 2)
        assert np.array_equal(parsed, stored.variables[variable][1].astype(float)), variable
    caption = sw.stored_caption(results.read_sweep(pair / "out" / "two.sweep.h5"))
    assert "h1.at2 (H1)" in caption and "h2.at2 (H2)" in caption
    assert "block orientation varied" in caption and "block at" not in caption


def test_info_shows_an_at2_components_azimuth(pair):
    """``rockslide info`` of a PEER AT2 file names the azimuth its title line gives (none for UP)."""
    shown = invoke("info", pair / "h2.at2")
    assert shown.exit_code == 0 and "azimuth   90 deg" in shown.stdout
    vertical = invoke("info", pair / "up.at2")
    assert vertical.exit_code == 0 and "azimuth" not in vertical.stdout
    details = json.loads(invoke("info", pair / "h2.at2", "--json").stdout)
    assert details["azimuth"] == math.radians(90.0)
