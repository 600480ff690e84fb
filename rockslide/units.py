"""Quantities with units: SI inside, conversions once at the edge.

Case files and command-line options may give a quantity as a plain number (SI) or as a string with
a unit (``"800 gal"``, ``"0.1 ms"``, ``"5 deg"``). The unit ``g`` is the standard gravity
9.80665 m/s^2 (as in PEER and K-NET files), whatever gravity a case uses for its physics.
"""

from __future__ import annotations

import math
import re

from .errors import CaseError

STANDARD_GRAVITY = 9.80665  # [m/s^2]

UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "mass": {"kg": 1.0},
    "time": {"s": 1.0, "ms": 1e-3},
    "acceleration": {
        "m/s^2": 1.0, "m/s2": 1.0, "m/s**2": 1.0,
        "cm/s^2": 1e-2, "cm/s2": 1e-2, "cm/s**2": 1e-2, "gal": 1e-2,
        "mm/s^2": 1e-3, "mm/s2": 1e-3,
        "g": STANDARD_GRAVITY,
    },
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "angular_rate": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
    "velocity": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3},
    "dimensionless": {"": 1.0},
}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/^*0-9]*)\s*$")


def unit_factor(unit: str, kind: str, *, source: str | None = None, field: str | None = None) -> float:
    """Factor converting ``unit`` to SI for a quantity of ``kind``; CaseError if unknown."""
    table = UNITS[kind]
    key = unit.strip()
    if key in table:
        return table[key]
    lowered = key.lower()
    for name, factor in table.items():
        if name.lower() == lowered:
            return factor
    if kind == "dimensionless":
        raise CaseError(f"unknown dimensionless unit {unit!r} (expected a plain number, without unit)",
                        source=source, field=field)
    expected = ", ".join(u for u in table if u)
    raise CaseError(f"unknown {kind} unit {unit!r} (expected one of: {expected})",
                    source=source, field=field)


def parse_quantity(value, kind: str, *, source: str | None = None, field: str | None = None) -> float:
    """Convert a number (taken as SI) or a ``"number unit"`` string to an SI float.

    Parameters
    ----------
    value : int, float or str
        ``0.2``, ``"200 mm"``, ``"800 gal"``, ``"0.1 ms"``...
    kind : str
        One of the keys of ``UNITS``.

    Raises
    ------
    CaseError
        Naming ``source`` and ``field`` when the value is not a finite number with a known unit.
    """
    if isinstance(value, bool):
        raise CaseError(f"expected {_article(kind)} {kind} (a number or a string like "
                        f"{_example(kind)!r}), got {value!r}", source=source, field=field)
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str):
        match = _QUANTITY.match(value)
        if not match and kind == "dimensionless":
            raise CaseError(f"cannot read {value!r} as a number (expected a plain number, like "
                            f"{_example(kind)!r})", source=source, field=field)
        if not match:
            raise CaseError(f"cannot read {value!r} as {_article(kind)} {kind} (expected a number and "
                            f"a unit, like {_example(kind)!r})", source=source, field=field)
        number = float(match.group(1)) * unit_factor(match.group(2), kind, source=source, field=field) \
            if match.group(2) else float(match.group(1))
    else:
        raise CaseError(f"expected {_article(kind)} {kind} (a number or a string like {_example(kind)!r}), "
                        f"got {type(value).__name__}", source=source, field=field)
    if not math.isfinite(number):
        raise CaseError(f"{value!r} is not a finite number", source=source, field=field)
    return number


def _example(kind: str) -> str:
    return {
        "length": "200 mm", "mass": "10 kg", "time": "0.1 ms", "acceleration": "800 gal",
        "angle": "2 deg", "angular_rate": "0.5 rad/s", "velocity": "0.1 m/s", "dimensionless": "0.5",
    }[kind]


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"
