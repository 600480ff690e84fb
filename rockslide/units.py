"""Quantities with units: SI inside, conversions once at the edge.

Case files and command-line options give a quantity as a string with a unit (``"800 gal"``,
``"0.1 ms"``, ``"5 deg"``) or as a plain number, which is SI (``0.2`` for a length is 0.2 m). The one
exception is an acceleration: engineers write 0.8 meaning g and 800 meaning gal as often as SI, so a
bare number for an acceleration (:data:`UNIT_REQUIRED`) is refused with a message that says what it
would mean in each unit; only 0, which means the same in every unit, may go without one. Programs
that hand over SI values they computed (``case.case_with``, ``case.case_to_dict``) say so with
``si_numbers=True``. The unit ``g`` is the standard gravity 9.80665 m/s^2 (as in PEER and K-NET
files), whatever gravity a case uses for its physics.
"""

from __future__ import annotations

import math
import re

from .errors import CaseError

STANDARD_GRAVITY = 9.80665  # [m/s^2]

#: The SI unit of each kind, as written in messages.
SI_UNITS = {"length": "m", "mass": "kg", "time": "s", "acceleration": "m/s^2", "angle": "rad",
            "angular_rate": "rad/s", "velocity": "m/s", "density": "kg/m^3", "dimensionless": ""}

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
    "density": {"kg/m^3": 1.0, "kg/m3": 1.0, "g/cm^3": 1000.0, "g/cm3": 1000.0},
    "dimensionless": {"": 1.0},
}

#: Quantity kinds that need a unit: a bare number is refused (a bare 0 is accepted).
UNIT_REQUIRED = frozenset({"acceleration"})
#: The units a message proposes for a bare number, by kind.
PROPOSED_UNITS = {"acceleration": (("g",), ("gal", "cm/s^2"), ("m/s^2",))}

#: A number and its unit. Possessive quantifiers (``*+``, ``++``): each part is matched once, never
#: split again in other ways, so that refusing ``1111...1!`` is linear in its length (backtracking
#: made 2000 digits and a ``!`` take a minute).
_QUANTITY = re.compile(r"^\s*+([-+]?+(?:\d++(?:\.\d*+)?+|\.\d++)(?:[eE][-+]?+\d++)?+)\s*+([A-Za-z/^*0-9]*+)\s*+$")


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


def parse_quantity(value, kind: str, *, source: str | None = None, field: str | None = None,
                   si_numbers: bool = False) -> float:
    """Convert a number (taken as SI) or a ``"number unit"`` string to an SI float.

    Parameters
    ----------
    value : int, float or str
        ``0.2``, ``"200 mm"``, ``"800 gal"``, ``"0.1 ms"``...
    kind : str
        One of the keys of ``UNITS``.
    si_numbers : bool
        Take a bare number as SI for every kind, those of :data:`UNIT_REQUIRED` included: for values
        a program computed in SI, never for what a person typed.

    Raises
    ------
    CaseError
        Naming ``source`` and ``field`` when the value is not a finite number with a known unit, or
        is a bare number other than 0 for a kind of :data:`UNIT_REQUIRED` (the message says what
        it would mean in each unit).
    """
    if isinstance(value, bool):
        raise CaseError(f"expected {_article(kind)} {kind} (a number or a string like "
                        f"{_example(kind)!r}), got {value!r}", source=source, field=field)
    bare = isinstance(value, (int, float))
    if bare:
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
        bare = not match.group(2)
    else:
        raise CaseError(f"expected {_article(kind)} {kind} (a number or a string like {_example(kind)!r}), "
                        f"got {type(value).__name__}", source=source, field=field)
    if not math.isfinite(number):
        raise CaseError(f"{value!r} is not a finite number", source=source, field=field)
    if bare and kind in UNIT_REQUIRED and number != 0.0 and not si_numbers:
        raise CaseError(bare_number_message(value, kind), source=source, field=field)
    return number


def bare_number_message(value, kind: str) -> str:
    """Why a bare number is refused for ``kind``, and what it would mean in each unit.

    ``bare_number_message(0.8, "acceleration")`` gives "0.8 has no unit (an acceleration needs
    one): '0.8 g' is 7.845 m/s^2, '0.8 gal' or '0.8 cm/s^2' is 0.0008158 g, '0.8 m/s^2' is
    0.08158 g".
    """
    text = str(value).strip()
    number = float(text)
    readings = []
    for units in PROPOSED_UNITS[kind]:
        value_si = number * UNITS[kind][units[0]]
        meaning = f"{value_si:.4g} {SI_UNITS[kind]}" if units == ("g",) else f"{value_si / STANDARD_GRAVITY:.4g} g"
        readings.append(" or ".join(f"'{text} {u}'" for u in units) + f" is {meaning}")
    return f"{text} has no unit ({_article(kind)} {kind} needs one): {', '.join(readings)}"


def acceleration_text(value: float, unit: str | None = None) -> str:
    """An acceleration [m/s^2] in ``unit`` (default gal) and in g: ``"700 gal (0.714 g)"``, or for
    ``unit = "g"`` in g and gal: ``"0.714 g (700 gal)"``."""
    unit = unit or "gal"
    factor = unit_factor(unit, "acceleration")
    if factor == STANDARD_GRAVITY:
        return f"{value / factor:.4g} {unit} ({value / 0.01:.4g} gal)"
    return f"{value / factor:.4g} {unit} ({value / STANDARD_GRAVITY:.3g} g)"


def percent_text(ratio: float) -> str:
    """A ratio as a percentage with two significant digits at least: ``0.94`` -> ``"94 %"``,
    ``0.0053`` -> ``"0.53 %"``."""
    percent = 100.0 * ratio
    return f"{percent:.0f} %" if abs(percent) >= 9.95 else f"{percent:.2g} %"


#: Named figure sizes [in] (`parse_figure_size`): the width of a journal column and of a page (the
#: height follows the figure), and a 16:9 slide.
FIGURE_SIZES = {"column": (3.5, None), "page": (7.0, None), "slide": (10.0, 5.625)}
#: Figures are 1 to 50 in on each side.
FIGURE_SIDE_RANGE = (1.0, 50.0)


def parse_figure_size(value, *, source: str = "size"):
    """A figure size as given (``--size``, ``size=``): None (each figure's default), one of
    `FIGURE_SIZES` (``"column"``, ``"page"``, ``"slide"``), ``"WxH"`` in inches (``"6x4"``) or a
    ``(width, height)`` pair [in]. Returns None, the name, or ``(width, height)`` [in]; CaseError
    otherwise."""
    if value is None:
        return None
    if isinstance(value, str):
        key = value.strip().lower()
        if key in FIGURE_SIZES:
            return key
        parts = key.replace("in", "").split("x")
        pair = None
        if len(parts) == 2:
            try:
                pair = tuple(float(p) for p in parts)
            except ValueError:
                pair = None
        if pair is None:
            raise CaseError(f"unknown figure size {value!r}; expected column (3.5 in wide), page (7 in), "
                            "slide (10 x 5.6 in) or WIDTHxHEIGHT in inches (e.g. 6x4)", source=source)
    else:
        try:
            pair = tuple(float(v) for v in value)
        except (TypeError, ValueError):
            pair = ()
        if len(pair) != 2:
            raise CaseError(f"expected a (width, height) pair in inches or a size name, got {value!r}",
                            source=source)
    low, high = FIGURE_SIDE_RANGE
    if not all(math.isfinite(v) and low <= v <= high for v in pair):
        raise CaseError(f"figure size {pair[0]:g} x {pair[1]:g} in is out of range; each side must be "
                        f"{low:g} to {high:g} in (e.g. 6x4)", source=source)
    return pair


def written_unit(value) -> str | None:
    """The unit of a ``"number unit"`` string as written (``"800 gal"`` -> ``"gal"``), None if
    there is none (a bare number, or text that is not a quantity)."""
    match = _QUANTITY.match(value) if isinstance(value, str) else None
    return match.group(2) if match and match.group(2) else None


def _example(kind: str) -> str:
    return {
        "length": "200 mm", "mass": "10 kg", "time": "0.1 ms", "acceleration": "800 gal",
        "angle": "2 deg", "angular_rate": "0.5 rad/s", "velocity": "0.1 m/s", "density": "2650 kg/m^3",
        "dimensionless": "0.5",
    }[kind]


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"
