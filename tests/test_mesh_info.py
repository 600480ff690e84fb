"""A scanned object's planar body reaches a case file (issue 39.2): ``rockslide info rock.obj`` prints
what the mesh gives, with the case-file keys of each plane, and those keys give the body of
model-asymmetric.md section 1 (the example's rock is built to be that body)."""

from __future__ import annotations

import math

import pytest
from conftest import invoke, one_line_error

from rockslide import api
from rockslide.io.example import ROCK_FILE, rock_obj

G = 9.80665


@pytest.fixture
def rock(tmp_path):
    path = tmp_path / ROCK_FILE
    path.write_text(rock_obj())
    return path


def test_the_example_rock_is_the_contracts_rock(rock):
    details = api.describe_mesh(rock, units="m", density="2650 kg/m^3")
    along, across = details["bodies"]
    assert (along["b1"], along["b2"], along["h"]) == pytest.approx((0.044, 0.129, 0.294), abs=1e-12)
    assert across["b1"] == pytest.approx(across["b2"], abs=1e-12)
    volume = 0.173 * 0.588 * 0.2                               # a prism: base area x depth
    assert along["mass"] == pytest.approx(2650 * volume, rel=1e-12)


def test_its_case_keys_give_the_same_body(rock):
    """The printed keys, put in a case, give the body's tipping ratios b_i / h (model-asymmetric.md
    section 1: 0.1496598639 and 0.4387755102)."""
    block = api.describe_mesh(rock, units="m", density=2650)["bodies"][0]["block"]
    case = api.load_case({"name": "rock", "block": block, "contact": {"mu_static": 0.9, "restitution": 0.8},
                          "ground": {"tail": "1 s"}})
    from rockslide.engine.prepare import model_for

    model = model_for(case)
    assert math.tan(model.tipping_angles[0]) == pytest.approx(0.1496598639, rel=1e-6)
    assert math.tan(model.tipping_angles[1]) == pytest.approx(0.4387755102, rel=1e-6)


def test_info_of_a_mesh_on_the_command_line(rock, tmp_path):
    result = invoke("info", rock, "--units", "cm", "--density", "2.65g/cm^3", "-o", tmp_path / "rock.png")
    assert result.exit_code == 0, result.output
    assert "b1 = 0.00044 m" in result.stdout and "half_widths: [0.00044 m, 0.00129 m]" in result.stdout
    assert (tmp_path / "rock.png").stat().st_size > 10_000
    one_line_error(invoke("info", rock), "--units", "length unit")
    one_line_error(invoke("info", rock, "--units", "m", "--density", "heavy"), "--density")
