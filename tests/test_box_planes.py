"""A box in both planes (issue 39.3, model-asymmetric.md section 9): with ``block.depth`` and two
horizontal components, the depth plane is the planar model of a block ``depth`` wide across the
first, under the component across the block; the verdict is the worse, and the output names it."""

from __future__ import annotations

import math

import pytest
from conftest import invoke, one_line_error, real_record

import rockslide

NS, EW, UD = ("kobe_jma_1995_ns_peer_rsn1106_kjm000.at2", "kobe_jma_1995_ew_peer_rsn1106_kjm090.at2",
              "kobe_jma_1995_ud_peer_rsn1106_kjmup.at2")


def box(pga="0.5 g", orientation="0 deg", depth="0.40 m", two=True) -> dict:
    ground = ({"horizontal_1": {"file": str(real_record(NS)), "azimuth": "0 deg"},
               "horizontal_2": {"file": str(real_record(EW)), "azimuth": "90 deg"}} if two
              else {"horizontal": {"file": str(real_record(NS))}})
    block = {"height": "1.8 m", "width": "0.45 m", "depth": depth, "mass": "500 kg"}
    if two:
        block["orientation"] = orientation
    return {"name": "box", "block": block, "contact": {"mu_static": 0.6, "restitution": 0.85},
            "ground": {**ground, "vertical": {"file": str(real_record(UD))}, "scale": {"pga_horizontal": pga},
                       "tail": "2 s"}, "output": {"dir": "out"}}


def test_the_depth_plane_is_the_block_across_under_the_component_across():
    """Its verdict and largest rotation are those of a separate run of a block ``depth`` wide turned
    by 90 degrees (the same arithmetic: one road), and the worse plane decides."""
    result = rockslide.run(box(orientation="30 deg"), history=False)
    across = rockslide.run({**box(orientation="120 deg"), "block": {**box()["block"], "width": "0.40 m",
                                                                     "orientation": "120 deg", "depth": None}},
                           history=False)
    planes = result.planes
    assert planes["depth"]["orientation"] == pytest.approx(math.radians(120), abs=1e-12)
    assert planes["depth"]["verdict"] == across.summary.verdict
    expected = math.inf if across.summary.overturned else across.summary.max_rotation_ratio
    assert planes["depth"]["max_rotation_ratio"] == expected
    assert planes["width"]["verdict"] == result.summary.verdict
    keys = ("overturned", "max_rotation_ratio")
    worse = max(("width", "depth"), key=lambda name: tuple(planes[name][k] for k in keys))
    assert planes["worse"] == worse


def test_the_worse_plane_is_named_in_the_printout_and_the_json(tmp_path):
    (tmp_path / "box.yaml").write_text(__import__("yaml").safe_dump(box()))
    text = invoke("run", tmp_path / "box.yaml", "--no-plot", "--out-dir", tmp_path)
    assert text.exit_code == 0, text.output
    assert "both planes (an uncoupled screening" in text.stdout and "verdict of the body" in text.stdout
    result = rockslide.read_result(tmp_path / "box.h5")
    assert "planes" in result.attrs


def test_one_component_leaves_the_depth_plane_still():
    planes = rockslide.run(box(two=False), history=False).planes
    assert planes["depth"]["orientation"] is None and "no horizontal motion" in planes["depth"]["note"]
    assert planes["worse"] == "width"


def test_a_body_with_a_depth_is_refused(ws):
    (ws / "case.yaml").write_text(
        "name: b\nblock: {centre_of_mass_height: 0.3 m, half_widths: [0.05 m, 0.1 m], depth: 0.2 m, mass: 1 kg}\n"
        "contact: {mu_static: 0.6, restitution: 0.8}\nground: {tail: 1 s}\n")
    one_line_error(invoke("run", "case.yaml"), "block.depth", "a box's depth")


def test_an_ensemble_over_orientations_screens_each_member_in_both_planes():
    """Each member of an ensemble over an uncertain orientation (issue 39.3) has the verdict of a
    run of the box at its orientation in both planes: the worse plane, named, and its rotation."""
    case = {**box(pga="0.4 g"), "uncertain": {"orientation": {"uniform": ["0 deg", "180 deg"]}}}
    members = rockslide.ensemble(case, 6)
    planes = members["plane"].values
    assert set(planes) == {0, 1}                       # both planes decide some member
    for i, angle in enumerate(members["sample_orientation"].values):
        run = rockslide.run(box(pga="0.4 g", orientation=f"{float(angle)!r} rad"), history=False).planes
        worse = run[run["worse"]]
        assert ("width", "depth")[planes[i]] == run["worse"]
        assert bool(members["overturned"][i]) == worse["overturned"]
        if not worse["overturned"]:
            assert float(members["max_rotation_ratio"][i]) == pytest.approx(worse["max_rotation_ratio"], rel=1e-12)
    summary = __import__("json").loads(members.attrs["ensemble"])
    assert summary["planes"]["depth_decides"] == int((planes == 1).sum())


def test_a_sweep_of_a_box_says_it_screens_the_width_plane_only(tmp_path):
    (tmp_path / "box.yaml").write_text(__import__("yaml").safe_dump(box()))
    result = invoke("sweep", tmp_path / "box.yaml", "--pga", "0.3g,0.4g", "--no-plot", "--out-dir", tmp_path)
    assert result.exit_code == 0, result.output
    assert "block.depth: a sweep screens the width plane only" in result.stderr
