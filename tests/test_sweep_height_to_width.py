"""The sweep's block-shape axis says h/b, the field's slenderness ratio (issue 27, "Words"):
``--slenderness`` was width / height, the inverse, and ``--slenderness 4`` built a block 4 times
wider than high without a word. It is retired with a one-line message naming its replacement."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from conftest import invoke, one_line_error

import rockslide
from rockslide.analyses import sweep as sw
from rockslide.case import load_case
from rockslide.core import kernel as K
from rockslide.errors import CaseError

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "configs" / "example.yaml"
RECORDS = REPO / "records"


def test_height_to_width_keeps_the_height_and_sets_the_width():
    """h/b = 4: the width is a quarter of the height, and the kernel's alpha = atan(b/h) (Housner's
    slenderness angle) is atan(1/4)."""
    case = load_case(EXAMPLE)
    axes = [sw.parse_axis("height_to_width", "2,4")]
    plan = sw.plan_sweep(case, axes, records_dir=RECORDS)
    alpha = plan.case_column(K.P_ALPHA).reshape(plan.shape)
    assert alpha[0] == pytest.approx(math.atan(1 / 2), rel=1e-14)
    assert alpha[1] == pytest.approx(math.atan(1 / 4), rel=1e-14)
    assert sw.axis_changes("height_to_width", 4.0, case, None) == {"block.width": case.block.height / 4}
    name, values, attrs = sw.coordinates(plan)[0]
    assert name == "height_to_width" and list(values) == [2.0, 4.0]
    assert "h/b" in attrs["long_name"] and attrs["height"] == case.block.height
    assert attrs["option"] == "height_to_width"
    assert "h/b" in sw.AXES["height_to_width"].label


def test_the_retired_option_says_what_it_was_and_what_replaces_it(tmp_path):
    result = invoke("sweep", EXAMPLE, "--slenderness", "4", "--records-dir", RECORDS, "--out-dir", tmp_path,
                    "--no-progress")
    one_line_error(result, "--slenderness", "width / height", "--height-to-width")
    assert not any(tmp_path.iterdir())


def test_the_api_refuses_the_retired_axis_alike():
    with pytest.raises(CaseError, match=r"slenderness.*width / height.*--height-to-width"):
        rockslide.sweep(EXAMPLE, slenderness="4", records_dir=RECORDS)


def test_the_help_offers_height_to_width_only():
    text = invoke("sweep", "--help").output
    assert "--height-to-width" in text and "h/b" in text and "--slenderness" not in text
