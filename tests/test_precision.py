"""`rockslide work-precision`: speed against error on a user's case (rockslide.analyses.precision).

The errors are measured against the reference solver (DOP853 at rtol 1e-12, an independent
integrator of the same state machine): on a short smooth case RK4 with located events converges at
fourth order, so halving the step divides the error by about 16 until round-off (~1e-12 s).
"""

from __future__ import annotations

import json
import math

import numpy as np
from conftest import REPO, invoke

from rockslide import api
from rockslide.analyses import precision
from rockslide.case import parse_case

EXAMPLE = REPO / "configs" / "example.yaml"


FREE = """
name: free
block: {height: 1.0 m, width: 0.2 m, mass: 1 kg}
contact: {mu_static: 10, restitution: 0.9}
ground: {tail: 6 s}
initial: {rotation: 0.1 rad}
solver: {dt: auto}
"""


def test_errors_against_the_reference_solver_fall_at_fourth_order():
    """Free rocking with impacts (e = 0.9) over 6 s, the still ground sampled at 10 ms: errors against
    the reference solver fall by 8x or more per halving above round-off, and the verdict holds."""
    table = api.work_precision(parse_case(FREE, source="free.yaml"), reference="auto")
    assert "reference solver" in table.reference
    rows = table.rows
    steps = np.array([r["step"] for r in rows])
    assert np.all(np.diff(steps) < 0) and any(math.isclose(s, 1e-4, rel_tol=1e-9) for s in steps)
    assert all(r["verdict_ok"] and r["same_events"] for r in rows)
    errors = [r["errors"]["event times"] for r in rows]
    pairs = [(a, b) for a, b in zip(errors, errors[1:], strict=False) if b > 1e-11]
    assert len(pairs) >= 2 and all(a / b > 8 for a, b in pairs), errors
    assert max(r["errors"]["event times"] for r in rows if r["step"] <= 1e-4 * (1 + 1e-9)) < 1e-10
    assert "step [ms]" in table.text()


def test_the_command_prints_and_draws(tmp_path):
    result = invoke("work-precision", EXAMPLE, "--records-dir", REPO / "records", "--reference",
                    "finest", "--json", "--out", tmp_path / "wp.png")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout.splitlines()[0])
    assert data["rows"] and "kernel at" in data["reference"]
    assert (tmp_path / "wp.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_figure_has_a_panel_per_case():
    table = [{"case": c, "mode": "located", "cpu": t, "errors": {"x": e}}
             for c in ("a", "b") for t, e in ((0.1, 1e-3), (0.2, 1e-7))]
    from rockslide.plots import work_precision_figure
    fig = work_precision_figure(table)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 2 and visible[0].get_lines()
    assert precision.REFERENCE_MAX_INTERVALS > 0
