"""Mode-initiation criteria of an asymmetric body (issue 39.4, model-asymmetric.md sections 1-3):
under ``A_h > 0`` the body turns about corner 1 (``b1``), under ``A_h < 0`` about corner 2, each
with its own ``b_i / h`` (eq. 6), ``R_i / rho_i^2`` (eq. 3) and contact forces (eqs. 19, 20, 26).

What these tests protect: the generic expressions at ``b1 = b2`` with the rectangle's inertia give
the rectangle's map and friction (to rounding, 1e-12); each side lifts off at its own corner's
slenderness times ``G`` (eq. 6, closed form); and the mode the map says a resting body starts is
the one the kernel's state machine starts under a held acceleration (an independent implementation:
`core.kernel`'s transitions from REST), for each of slip, liftoff and liftoff-slip, on both sides.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import invoke

import rockslide
from rockslide.core.criteria import initial_mode, mode_boundaries, mode_map, sufficient_friction
from rockslide.core.physics import REST, ROCK, ROCKSLIP, SLIP

G0 = 9.80665
B1, B2, H = 0.044, 0.129, 0.294
K = 0.1786


def test_the_generic_expressions_of_a_rectangle_are_the_rectangles():
    b, h = 0.05, 0.1
    k = math.sqrt((b * b + h * h) / 3.0)
    ah = np.linspace(-1.5, 1.5, 121) + 1e-7          # off the exact thresholds (ties decide by rounding)
    mu = np.linspace(0.013, 1.2, 40)
    for av in (-0.5, 0.0, 0.5):
        plain = mode_map(ah, mu, av, b, h)
        body = mode_map(ah, mu, av, b, h, half_width_2=b, radius_of_gyration=k)
        assert (plain == body).all()
    for a in (0.6, 0.9, -0.7, -1.3):
        assert sufficient_friction(a * G0, 0.0, b, h, half_width_2=b, radius_of_gyration=k) == pytest.approx(
            sufficient_friction(a * G0, 0.0, b, h), rel=1e-12)


@pytest.mark.parametrize("av", [-0.5, 0.0, 0.5])
def test_each_side_lifts_off_at_its_corners_slenderness(av):
    body = {"half_width_2": B2, "radius_of_gyration": K}
    for sign, b in ((1.0, B1), (-1.0, B2)):
        threshold = b / H * (1.0 + av)               # eq. 6: |A_h| = (b_i / h) G, in g
        below = initial_mode(sign * threshold * (1 - 1e-9) * G0, av * G0, 5.0, B1, H, G0, **body)
        above = initial_mode(sign * threshold * (1 + 1e-9) * G0, av * G0, 5.0, B1, H, G0, **body)
        assert (below, above) == (REST, ROCK), (sign, below, above)
    lines = mode_boundaries(np.linspace(-1.5, 1.5, 11), av, B1, H, **body)
    verticals = sorted(x[0] for x, y in lines if len(x) == 2 and x[0] == x[1])
    assert verticals == pytest.approx([-B2 / H * (1 + av), B1 / H * (1 + av)], rel=1e-12)


def _first_motion(amplitude_g: float, mu: float) -> int:
    """The state the kernel leaves REST for under a held acceleration (a rectangular pulse)."""
    case = {"name": "body",
            "block": {"centre_of_mass_height": f"{H} m", "half_widths": [f"{B1} m", f"{B2} m"],
                      "radius_of_gyration": f"{K} m", "mass": "50 kg"},
            "contact": {"mu_static": mu, "restitution": 0.5},
            "ground": {"horizontal": {"pulse": "rectangular", "amplitude": f"{amplitude_g} g", "duration": "0.05 s"}}}
    states = rockslide.run(case).result.history["state"]
    moving = states[states != REST]
    return int(moving[0]) if moving.size else REST


@pytest.mark.parametrize("amplitude,mu", [(0.3, 0.7), (0.3, 0.16), (0.1, 0.7), (0.12, 0.1),
                                          (-0.6, 0.9), (-0.6, 0.5), (-0.3, 0.2), (-0.3, 0.9)])
def test_the_map_starts_the_mode_the_kernel_starts(amplitude, mu):
    expected = initial_mode(amplitude * G0, 0.0, mu, B1, H, G0, half_width_2=B2, radius_of_gyration=K)
    assert _first_motion(amplitude, mu) == expected


def test_the_points_cover_every_mode():
    """The kernel comparison above is meaningful: its points start every mode, on both sides."""
    body = {"half_width_2": B2, "radius_of_gyration": K}
    modes = {initial_mode(a * G0, 0.0, mu, B1, H, G0, **body)
             for a, mu in [(0.3, 0.7), (0.3, 0.16), (0.1, 0.7), (0.12, 0.1), (-0.6, 0.9), (-0.6, 0.5), (-0.3, 0.2)]}
    assert modes == {REST, SLIP, ROCK, ROCKSLIP}


def test_the_criteria_command_draws_a_body_on_both_sides(tmp_path):
    case = tmp_path / "rock.yaml"
    case.write_text("name: rock\nblock: {centre_of_mass_height: 0.294 m, half_widths: [0.044 m, 0.129 m], "
                    "mass: 50 kg}\ncontact: {mu_static: 0.7, restitution: 0.5}\nground: {tail: 1 s}\n")
    result = invoke("criteria", case, "-o", tmp_path / "c.png", "--av", "0g")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "c.png").stat().st_size > 10_000
