"""The axes of a study: what a sweep can vary (:data:`AXES`), and an axis read from its text
(`parse_axis`: ``start:stop:step`` or a comma list, with units as in case files, computed in decimal
so that ``0.30:0.70:0.01`` gives exactly the floats a case file would). Every plan's dimensions are
`Axis` es: a sweep's, a fragility analysis's records and levels, an ensemble's members."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation

from ..errors import CaseError
from ..units import STANDARD_GRAVITY, UNIT_REQUIRED, parse_quantity, unit_factor
from .plan import MAX_POINTS

#: Ranges include their stop when it is within this fraction of a step of the grid.
RANGE_TOLERANCE = 1e-9

@dataclass(frozen=True)
class AxisKind:
    """What a sweep axis changes.

    Attributes
    ----------
    name : str
        Dimension name in the result file (``mu``, ``pga``...).
    option : str
        The command-line option (``--mu``).
    kind : str
        Unit kind of its values (a key of `units.UNITS`).
    key : str
        The case key it sets (dotted).
    long_name, units : str
        The dimension's ``long_name`` and ``units`` attributes (SI; ``1`` for dimensionless).
    label : str
        Axis label in figures; ``display_scale`` divides the SI values for it.
    bare_unit : str
        The unit of a value written without one (default: SI); ``deg`` for ``--azimuth``.
    """

    name: str
    option: str
    kind: str
    key: str
    long_name: str
    units: str
    label: str
    display_scale: float = 1.0
    bare_unit: str = ""


#: The axes a sweep can vary, in the order of ``rockslide sweep --help``.
AXES: dict[str, AxisKind] = {a.name: a for a in (
    AxisKind("mu", "mu", "dimensionless", "contact.mu_static", "static friction coefficient",
             "1", "static friction coefficient μ"),
    AxisKind("pga", "pga", "acceleration", "ground.scale.pga_horizontal",
             "peak horizontal ground acceleration", "m/s^2", "peak horizontal acceleration [gal]",
             0.01),
    AxisKind("vertical_factor", "vertical_factor", "dimensionless", "ground.scale.vertical_factor",
             "factor on the vertical record", "1", "vertical factor"),
    AxisKind("restitution", "restitution", "dimensionless", "contact.restitution",
             "coefficient of restitution", "1", "coefficient of restitution e"),
    AxisKind("height_to_width", "height_to_width", "dimensionless", "block.width",
             "height / width h/b, the slenderness ratio (the height kept)", "1", "height / width h/b"),
    AxisKind("gravity", "gravity", "acceleration", "gravity", "gravitational acceleration",
             "m/s^2", "gravity g [m/s²]"),
    AxisKind("amplitude", "amplitude", "acceleration", "ground.horizontal.amplitude",
             "amplitude of the horizontal pulse", "m/s^2", "pulse amplitude a_p [g]", STANDARD_GRAVITY),
    AxisKind("period", "period", "time", "ground.horizontal.period", "period of the horizontal pulse",
             "s", "pulse period T_p [s]"),
    AxisKind("duration", "duration", "time", "ground.horizontal.duration",
             "duration of the horizontal pulse", "s", "pulse duration t_d [s]"),
    AxisKind("azimuth", "azimuth", "angle", "block.orientation",
             "azimuth of the block's width, clockwise from north (two horizontal components)", "rad",
             "block orientation [deg]", math.pi / 180.0, "deg"),
    AxisKind("floor_period", "floor_period", "time", "ground.floor.horizontal",
             "period of the first horizontal mode of the floor the block stands on", "s",
             "floor period T_1 [s]"),
    AxisKind("b1", "b1", "length", "block.half_widths",
             "distance b1 of the base corner a positive ground acceleration tips the body over (pivot 1)", "m",
             "b1 [mm]", 1e-3),
    AxisKind("b2", "b2", "length", "block.half_widths",
             "distance b2 of the other base corner (pivot 2)", "m", "b2 [mm]", 1e-3),
)}
#: Axes no longer offered, with what replaces them (one line, exit 2 where they are asked for).
RETIRED_AXES = {
    "slenderness": "was width / height b/h, the inverse of the field's slenderness ratio h/b "
                   "(--slenderness 4 built a block 4 times wider than high); give --height-to-width h/b "
                   "instead (the height kept): --slenderness 0.25 is --height-to-width 4",
}
#: Figure labels of retired axes, for files written before they were retired.
_RETIRED_LABELS = {"slenderness": "width / height b/h"}
#: The axes that change the horizontal pulse of a pulse case (and only there).
PULSE_AXES = ("amplitude", "period", "duration")
#: The axes that scale record files (a pulse is scaled by its amplitude).
RECORD_SCALE_AXES = ("pga", "vertical_factor")


@dataclass(frozen=True)
class Axis:
    """One axis of a sweep: its kind and its values.

    Attributes
    ----------
    name : str
        A key of :data:`AXES`.
    values : tuple of float
        SI values, in the order given.
    texts : tuple of str
        The values as written (``"125gal"``), for messages.
    spec : str
        The option's text as given.
    given_kind : AxisKind, optional
        What the axis is, for an axis that is not one of :data:`AXES` (``rockslide fragility``'s
        levels).
    """

    name: str
    values: tuple
    texts: tuple
    spec: str
    given_kind: AxisKind | None = None

    @property
    def kind(self) -> AxisKind:
        """What the axis changes (:data:`AXES`, or ``given_kind``)."""
        return self.given_kind if self.given_kind is not None else AXES[self.name]

    def __len__(self) -> int:
        return len(self.values)


# --------------------------------------------------------------------------------------------------
# Axes
# --------------------------------------------------------------------------------------------------

#: A number and its unit, matched in linear time (possessive quantifiers, as `units.parse_quantity`).
_PIECE = re.compile(r"^\s*+([-+]?+(?:\d++(?:\.\d*+)?+|\.\d++)(?:[eE][-+]?+\d++)?+)\s*+([A-Za-z/^*0-9]*+)\s*+$")


def parse_axis(name: str, spec: str, kind: AxisKind | None = None) -> Axis:
    """Read an axis option: ``start:stop:step``, a comma list, or one value.

    Parameters
    ----------
    name : str
        A key of :data:`AXES`, or any name with ``kind``.
    spec : str
        The option's text, e.g. ``"0.30:0.70:0.01"``, ``"100gal:1000gal:25gal"``, ``"0.5,0.52,0.55"``.
    kind : AxisKind, optional
        What the axis is when it is not one of :data:`AXES` (its ``option`` and unit ``kind``).

    Returns
    -------
    Axis

    Raises
    ------
    CaseError
        Naming the option: not a range or list of numbers, unknown unit, a unit on some values
        only, a step that is not positive, a stop below the start, repeated values, too many values.
    """
    given = kind
    kind = AXES[name] if given is None else given
    option = kind.option
    text = str(spec).strip()
    if not text:
        raise CaseError("expected start:stop:step or a comma list of values, got an empty text",
                        source=option)
    if ":" in text:
        pieces = text.split(":")
        if len(pieces) != 3:
            raise CaseError(f"expected start:stop:step (three values), got {text!r}", source=option)
        numbers, unit = _range_numbers(option, kind.kind, text, [_split(option, kind.kind, p) for p in pieces])
        unit = unit or kind.bare_unit
        texts = [f"{number}{unit}" for number in numbers]
        return Axis(name, tuple(_range_values(numbers, unit, texts, kind.kind, option, name == "azimuth")),
                    tuple(texts), text, given)
    else:
        parts = [_split(option, kind.kind, p) for p in text.split(",")]
        units = {unit for _, unit in parts}
        if len(units) > 1 and "" in units:
            none = "" if kind.kind in UNIT_REQUIRED else " or on none (none means SI)"
            raise CaseError(f"give a unit on every value{none}, got {text!r}", source=option)
        texts = [f"{number}{unit}" for number, unit in parts]
    if kind.bare_unit:
        texts = [t if _PIECE.match(t).group(2) else f"{t}{kind.bare_unit}" for t in texts]
    values = [parse_quantity(t, kind.kind, source=option) for t in texts]
    if name == "azimuth":
        for t, v in zip(texts, values, strict=True):
            if not abs(v) <= 2.0 * math.pi * (1.0 + 1e-12):
                raise CaseError(f"{t} is beyond +-360 deg (the azimuth of the block's width, clockwise from "
                                "north; bare numbers are degrees)", source=option)
    seen = {}
    for t, v in zip(texts, values, strict=True):
        if v in seen:
            raise CaseError(f"{t} repeats {seen[v]} (each value once)", source=option)
        seen[v] = t
    return Axis(name, tuple(values), tuple(texts), text, given)


def _split(option: str, kind: str, piece: str) -> tuple[Decimal, str]:
    """A piece of an axis option as (number, unit text)."""
    match = _PIECE.match(piece)
    if not match:
        what = "a number" if kind == "dimensionless" else "a number with an optional unit"
        example = {"dimensionless": "0.5", "time": "0.4s"}.get(kind, "800gal")
        raise CaseError(f"cannot read {piece.strip()!r} as {what} (like {example})", source=option)
    number, unit = match.group(1), match.group(2)
    if unit:
        parse_quantity(f"1 {unit}", kind, source=option)     # an unknown unit fails here
    try:
        return Decimal(number), unit
    except InvalidOperation:  # pragma: no cover - the pattern only lets numbers through
        raise CaseError(f"cannot read {piece!r} as a number", source=option) from None


def _range_values(numbers, unit: str, texts, kind: str, option: str, azimuth: bool) -> list[float]:
    """The SI values of a range's ``numbers`` (texts) in ``unit``: what `parse_quantity` gives for
    each ``"number unit"`` text (the number's float times the unit's factor), the factor found once
    (a range of 10^6 values is read in a second, not half a minute); increasing, so never repeated."""
    if not unit and kind in UNIT_REQUIRED:
        values = [parse_quantity(t, kind, source=option) for t in texts]      # 0 alone passes; refused
    else:
        factor = unit_factor(unit, kind, source=option) if unit else None
        values = [float(n) * factor for n in numbers] if factor is not None else [float(n) for n in numbers]
    for t, v in ((texts[0], values[0]), (texts[-1], values[-1])):
        if not math.isfinite(v):
            parse_quantity(t, kind, source=option)                            # says why, naming the value
        if azimuth and not abs(v) <= 2.0 * math.pi * (1.0 + 1e-12):
            raise CaseError(f"{t} is beyond +-360 deg (the azimuth of the block's width, clockwise from "
                            "north; bare numbers are degrees)", source=option)
    return values


def _range_numbers(option: str, kind: str, text: str, pieces) -> tuple[list[str], str]:
    """The values of ``start:stop:step`` as plain decimal texts, computed in decimal, and their unit."""
    (start, u0), (stop, u1), (step, u2) = pieces
    if len({u0, u1, u2}) != 1:
        none = "" if kind in UNIT_REQUIRED else ", or all without unit (SI)"
        raise CaseError(f"give start, stop and step in one unit{none}, got {text!r}", source=option)
    if step <= 0:
        raise CaseError(f"the step must be positive, got {text!r}", source=option)
    if stop < start:
        raise CaseError(f"the stop is below the start in {text!r} (expected start <= stop)",
                        source=option)
    q = (stop - start) / step
    n = int(q)
    if q - n >= 1 - Decimal(RANGE_TOLERANCE):
        n += 1
    if n + 1 > MAX_POINTS:
        raise CaseError(f"{text!r} has {n + 1} values; at most {MAX_POINTS} on one axis",
                        source=option)
    numbers = [start + i * step for i in range(n + 1)]
    if abs(numbers[-1] - stop) <= Decimal(RANGE_TOLERANCE) * step:
        numbers[-1] = stop                               # on the grid: exactly the stop
    return [_plain(x) for x in numbers], u0


def _plain(number: Decimal) -> str:
    """A decimal as short plain text (``0.37``, ``125``, ``1E-7``)."""
    if number == number.to_integral_value() and abs(number) < Decimal("1e15"):
        return str(number.quantize(Decimal(1)))
    return str(number.normalize())
