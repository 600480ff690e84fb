"""A body's figures show both of its tipping angles (issue 39.5): a run's rotation panel draws
``+alpha_1`` and ``-alpha_2`` (rotation about pivot 1 is positive), a rectangle ``+-alpha``; the
summary, its JSON and its result file carry ``alpha_2``."""

from __future__ import annotations

import math

import pytest
from conftest import REPO

import rockslide
from rockslide.plots import ALPHA_COLOUR, response_figure


def alpha_lines(figure) -> list[float]:
    rotation = next(ax for ax in figure.axes if ax.get_label() and not ax.get_label().endswith("-slip"))
    return sorted(line.get_ydata()[0] for line in rotation.get_lines()
                  if line.get_linestyle() == "--" and line.get_color() == ALPHA_COLOUR)


@pytest.mark.parametrize("corners", [(0.044, 0.129), (0.03, 0.03)])
def test_the_rotation_panel_draws_each_pivots_angle(corners, tmp_path):
    b1, b2 = corners
    case = rockslide.load_case(REPO / "configs" / "example.yaml").with_(
        {"block.width": None, "block.height": None, "block.centre_of_mass_height": 0.1,
         "block.half_widths": list(corners), "ground.scale.pga_horizontal": "1 g"})
    run = rockslide.run(case, records_dir=REPO / "records")
    assert run.summary.alpha == pytest.approx(math.atan2(b1, 0.1), rel=1e-12)
    assert run.summary.alpha_2 == pytest.approx(math.atan2(b2, 0.1), rel=1e-12)
    lines = alpha_lines(response_figure(run.result, title="body"))
    assert lines == pytest.approx([-math.atan2(b2, 0.1), math.atan2(b1, 0.1)], rel=1e-12)
    rockslide.run(case, records_dir=REPO / "records", outputs=rockslide.api.OutputSet(tmp_path, "body", plot=False))
    assert rockslide.read_result(tmp_path / "body.h5").summary.alpha_2 == run.summary.alpha_2
