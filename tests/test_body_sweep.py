"""The asymmetric body travels the one road (issue 39.4): a sweep over ``b1`` or ``b2`` gives, at
each point, the numbers of a run of the case with those ``half_widths`` (the same assembler and
kernel), and the sweep's axes name the corners."""

from __future__ import annotations

import pytest
from conftest import REPO

import rockslide

EXAMPLE = REPO / "configs" / "example.yaml"


@pytest.mark.parametrize("axis", ["b1", "b2"])
def test_a_sweep_point_over_a_corner_is_the_run_of_that_body(axis):
    case = rockslide.load_case(EXAMPLE)
    values = [0.03, 0.07]
    grid = rockslide.sweep(case, records_dir=REPO / "records", pga=["500gal", "900gal"], **{axis: values})
    h = case.block.height / 2.0
    for i, pga in enumerate(("500gal", "900gal")):
        for j, value in enumerate(values):
            corners = [value, 0.05] if axis == "b1" else [0.05, value]
            body = case.with_({"block.width": None, "block.height": None, "block.centre_of_mass_height": h,
                               "block.half_widths": corners, "ground.scale.pga_horizontal": pga})
            run = rockslide.run(body, records_dir=REPO / "records", history=False).summary
            point = grid.isel(pga=i, **{axis: j})
            assert bool(point.overturned) == run.overturned
            assert float(point.max_rotation) == run.max_rotation
            assert int(point.impacts) == run.impacts
    assert grid[axis].attrs["units"] == "m"
