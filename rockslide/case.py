"""The case file: one YAML document describing a block, its contact, the ground motion and the run.

A case file is plain data (``yaml.safe_load``; no tags that construct objects). Every quantity may
be a string with a unit (``"800 gal"``, ``"0.1 ms"``, ``"5 deg"``) or a number, taken as SI, except
an acceleration, which needs its unit (a bare ``0.8`` is refused with what it would mean in g, gal and
m/s^2; see :mod:`rockslide.units`). Everything inside rockslide is SI: [m], [kg], [s], [rad].

The schema :data:`CASE_KEYS` drives the validation (unknown keys and their nearest valid key,
required keys, types, unit kinds, defaults and bounds) and the key reference in the README. Checks
that involve two keys (``mu_kinetic <= mu_static``, ``output.interval`` a multiple of
``solver.dt``, exclusive scale keys, a record or a tail) are in :func:`_cross_checks`.

A ``null`` value is the same as leaving the key out: the default applies, or a required key is
reported missing.

Every problem raises :class:`~rockslide.errors.CaseError` with a one-line message naming the file,
the dotted key (``contact.mu_static``) or the line and column, what was given and what is expected.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import reprlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import yaml

from .errors import CaseError
from .inputs import open_regular, regular_size
from .mesh import MESH_LENGTH_UNITS, rectangle_k2
from .pulses import SHAPES, Pulse, common_intervals
from .units import SI_UNITS, STANDARD_GRAVITY, UNIT_REQUIRED, UNITS, parse_quantity, unit_factor, written_unit

__all__ = [
    "CASE_KEYS",
    "floor_text",
    "with_orientations",
    "Floor",
    "Mode",
    "Block",
    "Case",
    "Contact",
    "Ground",
    "Initial",
    "Output",
    "Pulse",
    "RecordSpec",
    "Scale",
    "Solver",
    "Suite",
    "SuiteEntry",
    "case_to_dict",
    "parse_mapping",
    "Distribution",
    "Uncertain",
    "case_with",
    "other_plane",
    "iter_case_keys",
    "load_case",
    "load_suite",
    "parse_case",
    "parse_suite",
]

# --------------------------------------------------------------------------------------------------
# The case as data
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Block:
    """A rigid block standing on its base: a rectangle, or a planar body whose centre of mass is not
    above the middle of its base (docs/asymmetric.md, docs/model-asymmetric.md).

    Parameters
    ----------
    height : float
        Full height 2h [m] (an asymmetric body: twice its centre of mass's height).
    width : float
        Full base width 2b [m] (an asymmetric body: ``b1 + b2``).
    mass : float
        Mass [kg].
    orientation : float, optional
        Azimuth of the base width [rad], clockwise from north: the direction across the rocking
        axis, along which the ground motion of two horizontal components drives the block
        (`Ground.horizontal_2`). None: along the first component.
    centre_of_mass_height : float, optional
        ``h`` [m] of a body given by `half_widths` (then ``height = 2 h``); None for a rectangle.
    half_widths : tuple of float, optional
        ``(b1, b2)`` [m]: the base corners' distances from the vertical through the centre of mass,
        ``b1`` the corner a positive ground acceleration tips the body over (pivot 1). None: a
        rectangle, ``b1 = b2 = width / 2``.
    radius_of_gyration : float, optional
        ``sqrt(I_cm / M)`` [m] about the centre of mass. None: the uniform rectangle's,
        ``sqrt((bm^2 + h^2) / 3)``, ``bm = (b1 + b2) / 2``.
    depth : float, optional
        Full base depth [m] of a box (along its rocking axis): the block is then screened in both
        planes (model-asymmetric.md section 9: the second plane is a block ``depth`` wide across the
        first, under the component across the block). None: one plane.
    mesh : str, optional
        The closed triangle mesh (OBJ, STL, PLY) the body was derived from (docs/meshes.md), as an
        absolute path: `centre_of_mass_height`, `half_widths`, `radius_of_gyration` and `mass` are
        its planar body along `orientation` (the mesh's x axis, east, when None), and the body is
        screened in both planes. None: the body is given by its sizes.
    mesh_units : str, optional
        The mesh's length unit (``m``, ``cm``, ``mm``, ``in``, ``ft``).
    density : float, optional
        [kg/m^3] of a mesh's body (its mass the density times the volume), or None (``mass`` given).
    """

    height: float
    width: float
    mass: float
    orientation: float | None = None
    centre_of_mass_height: float | None = None
    half_widths: tuple[float, float] | None = None
    radius_of_gyration: float | None = None
    depth: float | None = None
    mesh: str | None = None
    mesh_units: str | None = None
    density: float | None = None

    @property
    def both_planes(self) -> bool:
        """Whether the body is screened in both planes: a box with a `depth`, or a mesh."""
        return self.depth is not None or self.mesh is not None

    @property
    def asymmetric(self) -> bool:
        """Whether the body is not the uniform symmetric rectangle (`half_widths` differ or an
        inertia is given): its model runs the generic body's expressions."""
        return (self.half_widths is not None and self.half_widths[0] != self.half_widths[1]) \
            or self.radius_of_gyration is not None

    @property
    def corners(self) -> tuple[float, float]:
        """``(b1, b2)`` [m] (``(b, b)`` for a rectangle)."""
        return self.half_widths if self.half_widths is not None else (self.width / 2.0, self.width / 2.0)

    @property
    def tipping_angles(self) -> tuple[float, float]:
        """``(alpha_1, alpha_2) = (atan(b1/h), atan(b2/h))`` [rad]."""
        b1, b2 = self.corners
        return math.atan2(b1, self.height / 2.0), math.atan2(b2, self.height / 2.0)

    def describe(self) -> str:
        """One line: the size, mass and tipping angle(s)."""
        if not self.asymmetric and self.half_widths is None:
            return (f"block width × height {self.width:.4g} × {self.height:.4g} m, {self.mass:.4g} kg, "
                    f"α = {math.atan2(self.width, self.height):.4g} rad")
        b1, b2 = self.corners
        a1, a2 = self.tipping_angles
        gyration = "" if self.radius_of_gyration is None else f", radius of gyration {self.radius_of_gyration:.4g} m"
        what = "body" if self.mesh is None else f"body of {Path(self.mesh).name} along {self.mesh_azimuth_text}"
        return (f"{what}: centre of mass {self.height / 2.0:.4g} m high, corners b1 = {b1:.4g} m, b2 = {b2:.4g} m"
                f"{gyration}, {self.mass:.4g} kg, α1 = {a1:.4g} rad (tips over at ah > 0), α2 = {a2:.4g} rad")

    @property
    def mesh_azimuth_text(self) -> str:
        """The direction a mesh's body is taken along, in words (``azimuth 90 deg``)."""
        azimuth = self.orientation if self.orientation is not None else 0.5 * math.pi
        return f"azimuth {math.degrees(azimuth) % 360:.4g} deg"

    @property
    def half_width(self) -> float:
        """Half the base width, b [m]."""
        return self.width / 2.0

    @property
    def half_height(self) -> float:
        """Half the height, h [m] (the height of the centre of mass)."""
        return self.height / 2.0

    @property
    def b(self) -> float:
        """Alias of :attr:`half_width` [m]."""
        return self.half_width

    @property
    def h(self) -> float:
        """Alias of :attr:`half_height` [m]."""
        return self.half_height


@dataclass(frozen=True)
class Contact:
    """Block-foundation contact.

    Parameters
    ----------
    mu_static : float
        Static friction coefficient [-], >= 0.
    mu_kinetic : float
        Kinetic friction coefficient [-], 0 <= mu_kinetic <= mu_static.
    restitution : float
        Coefficient of restitution of the rocking impacts [-], within [0, 1].
    """

    mu_static: float
    mu_kinetic: float
    restitution: float


@dataclass(frozen=True)
class RecordSpec:
    """Where and how to read one accelerogram (the reading itself is :mod:`rockslide.records`).

    Parameters
    ----------
    file : str
        File name; a relative name resolves against the case file's folder first.
    format : str, optional
        File format; None lets the reader detect it.
    units : str, optional
        Acceleration unit of the values (``"g"``, ``"gal"``, ``"m/s^2"``...); None = from the file
        (AT2 and K-NET headers, a column text header such as ``Acceleration (g)``).
    time_column, column : int or str, optional
        1-based column number or header name of the time and of the acceleration values.
    dt : float, optional
        Sample interval [s] for files without a time column; with column text, the time column is
        then not read (one ``column`` of many, evenly spaced).
    skip_lines : int
        Lines to skip before the data, >= 0.
    azimuth : float, optional
        Of one of two horizontal components: the direction it is measured along [rad], clockwise
        from north; None = from the file's header (PEER AT2).
    """

    file: str
    format: str | None = None
    units: str | None = None
    time_column: int | str | None = None
    column: int | str | None = None
    dt: float | None = None
    skip_lines: int = 0
    azimuth: float | None = None


@dataclass(frozen=True)
class Scale:
    """Scaling of the ground motion.

    Parameters
    ----------
    pga_horizontal : float, optional
        Scale the horizontal record to this peak acceleration [m/s^2], > 0. Exclusive with ``factor``.
    factor : float, optional
        Multiply the records by this factor [-], > 0. Exclusive with ``pga_horizontal``.
    pga_vertical : float, optional
        Scale the vertical record to this peak acceleration [m/s^2], >= 0. Exclusive with a
        ``vertical_factor`` other than 1.
    vertical_factor : float
        Extra factor on the vertical record [-], >= 0 (0 switches the vertical motion off).
    """

    pga_horizontal: float | None = None
    factor: float | None = None
    pga_vertical: float | None = None
    vertical_factor: float = 1.0


@dataclass(frozen=True)
class Mode:
    """One mode of the building under the block (`Floor`).

    Parameters
    ----------
    period : float
        [s] natural period ``T``, > 0.
    damping : float
        [-] damping ratio ``zeta``, within [0, 1).
    participation : float
        [-] ``Gamma phi`` at the floor: the mode's participation factor times its shape there (1: the
        floor moves as the oscillator's mass).
    """

    period: float
    damping: float = 0.05
    participation: float = 1.0


@dataclass(frozen=True)
class Floor:
    """The block stands on a floor of a linear building (`core.intensity.floor_acceleration`), or on the
    ground scaled by the code's screening amplification.

    Parameters
    ----------
    horizontal, vertical : tuple of Mode
        The building's modes in each direction (none: that component is the ground's).
    z_over_h : float or None
        Screening instead of modes: the floor's horizontal motion is the ground's times ``1 + 2 z/h``
        (the height factor of ASCE 7-16 Eq. 13.3-1), ``z/h`` the floor's height over the roof's,
        within [0, 1]; the vertical is the ground's.
    """

    horizontal: tuple = ()
    vertical: tuple = ()
    z_over_h: float | None = None

    @property
    def given(self) -> bool:
        """Whether the block stands on a floor (modes or the screening factor)."""
        return bool(self.horizontal or self.vertical) or self.z_over_h is not None

    def amplification(self) -> float:
        """The screening factor ``1 + 2 z/h`` (1 without ``z_over_h``)."""
        return 1.0 if self.z_over_h is None else 1.0 + 2.0 * self.z_over_h


@dataclass(frozen=True)
class Ground:
    """The ground motion: one or two records (files or analytic pulses), their scaling and timing.

    Parameters
    ----------
    horizontal, vertical : RecordSpec, Pulse or None
        The records; without either, the ground is still and ``tail`` is a free vibration. Both are
        files or both are pulses (:class:`~rockslide.pulses.Pulse`: a pulse has its own amplitude and
        is not scaled).
    scale : Scale
        Scaling of the record files.
    tail : float
        Free-vibration time appended after the record ends [s], >= 0.
    time_shift : float
        Time shift applied to the records [s] (see :mod:`rockslide.records`).
    horizontal_2 : RecordSpec, optional
        The second horizontal component, orthogonal to ``horizontal`` (then the first; the case file
        names them ``horizontal_1`` and ``horizontal_2``): the block feels the motion along
        ``block.orientation`` (docs/two-components.md).
    floor : Floor
        The floor the block stands on; by default none (the block is on the ground).
    """

    horizontal: RecordSpec | Pulse | None
    vertical: RecordSpec | Pulse | None
    scale: Scale
    tail: float = 0.0
    time_shift: float = 0.0
    horizontal_2: RecordSpec | None = None
    floor: Floor = Floor()

    @property
    def two_components(self) -> bool:
        """Whether the ground has two horizontal components (``horizontal_1`` and ``horizontal_2``)."""
        return self.horizontal_2 is not None


@dataclass(frozen=True)
class Initial:
    """Initial state of the block.

    Parameters
    ----------
    rotation : float
        Initial rotation [rad], signed, ``|rotation| < pi/2``.
    rotation_rate : float
        Initial angular velocity [rad/s], signed.
    slip_rate : float
        Initial sliding velocity relative to the ground [m/s], signed.
    """

    rotation: float = 0.0
    rotation_rate: float = 0.0
    slip_rate: float = 0.0


@dataclass(frozen=True)
class Solver:
    """Time integration settings.

    Parameters
    ----------
    dt : float
        Time step [s], ``0 < dt <= 0.01``; with ``auto``, the default step (0.1 ms) that ``auto``
        is compared with, and the sampling step of pulses.
    events : str
        ``"located"`` (state changes located within the step) or ``"step-end"`` (at step ends).
    method : str
        ``"kernel"`` (the fast integrator) or ``"reference"`` (the slow, plain one).
    auto : bool
        ``solver.dt: auto``: the step is chosen per case from the tolerance
        (`rockslide.engine.step.choose_step`; docs/performance.md, 'Choosing the step').
    tolerance_time : float
        [s] ``solver.tolerance.time``: the error allowed on every event time with ``auto``.
    tolerance_rotation : float
        [rad] ``solver.tolerance.rotation``: the error allowed on the largest rotation with ``auto``.
    """

    dt: float = 1e-4
    events: str = "located"
    method: str = "kernel"
    auto: bool = False
    tolerance_time: float = 1e-6
    tolerance_rotation: float = 1e-4


@dataclass(frozen=True)
class Output:
    """Where and how often results are written.

    Parameters
    ----------
    dir : str
        Output folder.
    interval : float or None
        Output interval [s], a whole multiple of ``solver.dt``; None = every solver step.
    """

    dir: str = "out"
    interval: float | None = None


@dataclass(frozen=True)
class Distribution:
    """What is known of an uncertain quantity (the case's ``uncertain`` section).

    Parameters
    ----------
    kind : {"fixed", "uniform", "normal", "lognormal"}
    a, b : float
        ``fixed``: the value (``b`` unused); ``uniform``: the lowest and highest values;
        ``normal``: the mean and the standard deviation; ``lognormal``: the median and
        ``beta``, the standard deviation of the logarithm.
    """

    kind: str
    a: float
    b: float = 0.0

    @property
    def spread(self) -> bool:
        """Whether the quantity varies at all (False: one value)."""
        return self.kind != "fixed" and not (self.b == self.a if self.kind == "uniform" else self.b == 0.0)

    @property
    def nominal(self) -> float:
        """The value the nominal case stands for: the value, the mid-range, the mean or the median."""
        return 0.5 * (self.a + self.b) if self.kind == "uniform" else self.a

    def spec(self):
        """The distribution as the case file writes it."""
        if self.kind == "fixed":
            return self.a
        if self.kind == "uniform":
            return {"uniform": [self.a, self.b]}
        if self.kind == "normal":
            return {"normal": {"mean": self.a, "std": self.b}}
        return {"lognormal": {"median": self.a, "beta": self.b}}


@dataclass(frozen=True)
class Uncertain:
    """What is not known exactly: the quantities an ensemble (``rockslide run --ensemble``) varies.

    Parameters
    ----------
    intensity : Distribution or None
        A factor on the scaled ground motion (horizontal and vertical alike).
    restitution : Distribution or None
        The coefficient of restitution itself (samples outside [0, 1] are clipped to it).
    friction : Distribution or None
        A factor on ``mu_static`` and ``mu_kinetic`` together.
    size : Distribution or None
        A factor on the block's height and width together (its shape kept).
    slenderness : Distribution or None
        A factor ``f`` on the block's width b, its height h kept: the width becomes ``f b``, so
        b/h (= tan alpha) is multiplied by ``f`` and the field's slenderness ratio h/b divided by
        it (``f`` > 1: a stockier block). The name says which quantity varies, not which ratio.
    orientation : Distribution or None
        The block's orientation itself [rad] (``block.orientation``), for a case with two horizontal
        components, e.g. uniform over 0 to 180 degrees: the orientation unknown. A mesh's body is
        derived again for each member's orientation.
    b1, b2 : Distribution or None
        A factor on one corner's distance from the vertical through the centre of mass
        (``block.half_widths``; a rectangle's ``width / 2``): where a scan or a drawing leaves the
        base's edge uncertain. Either makes a rectangle an asymmetric body (its radius of gyration
        the rectangle's of each member's size).
    radius_of_gyration : Distribution or None
        A factor on the radius of gyration (given, a mesh's, or the rectangle's by default).
    """

    intensity: Distribution | None = None
    restitution: Distribution | None = None
    friction: Distribution | None = None
    size: Distribution | None = None
    slenderness: Distribution | None = None
    orientation: Distribution | None = None
    b1: Distribution | None = None
    b2: Distribution | None = None
    radius_of_gyration: Distribution | None = None

    def given(self) -> dict[str, Distribution]:
        """The quantities given, by name."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if getattr(self, f.name) is not None}


@dataclass(frozen=True)
class Case:
    """A validated case, all quantities in SI.

    Parameters
    ----------
    name : str
        Case name (used in file names): ``^[A-Za-z0-9][A-Za-z0-9._-]*$``.
    gravity : float
        Gravitational acceleration [m/s^2], > 0.
    block, contact, ground, initial, solver, output
        The case file's sections of these names, each a dataclass of SI values.
    uncertain : Uncertain
        What is not known exactly (for ensembles); empty when the file has no ``uncertain``.
    source : str
        The case file's name as used in messages.
    base_dir : Path or None
        Folder of the case file; record files resolve against it first.
    text : str
        The case file's text, stored with the results.
    units : dict
        The unit each quantity was written in, by dotted key (``{"ground.scale.pga_horizontal":
        "gal"}``), to show results in the user's units; keys given as bare numbers are absent.
    """

    name: str
    gravity: float
    block: Block
    contact: Contact
    ground: Ground
    initial: Initial
    solver: Solver
    output: Output
    uncertain: Uncertain = Uncertain()
    source: str = "<case>"
    base_dir: Path | None = None
    text: str = ""
    units: dict = dataclasses.field(default_factory=dict, compare=False)

    def with_(self, changes: Mapping[str, object] | None = None, /, **sections) -> Case:
        """A new case with some keys changed (`case_with`): dotted keys in ``changes``, or whole
        keys and sections by name, e.g. ``case.with_({"contact.mu_static": 0.5})`` or
        ``case.with_(contact={"mu_static": 0.5, "restitution": 0.8}, name="squat")``. Numbers are
        SI; strings may carry units as in a case file (``"50 mm"``, ``"0.3 g"``)."""
        flat = dict(changes or {})
        for key, value in sections.items():
            if isinstance(value, Mapping) and isinstance(CASE_KEYS.get(key), dict) \
                    and CASE_KEYS[key].get("type") == "mapping":
                flat.update({f"{key}.{sub}": v for sub, v in value.items()})
            else:
                flat[key] = value
        return case_with(self, flat)

    def to_dict(self) -> dict:
        """The case as a plain nested dict that `load_case` reads back (`case_to_dict`)."""
        return case_to_dict(self)


def floor_text(case: Case, *, brief: bool = False) -> str | None:
    """The floor the block stands on (``ground.floor``) in one line; None without a floor.

    Parameters
    ----------
    case : Case
        The case.
    brief : bool
        False: for printouts (``rockslide run``), every word; True: for a figure's caption
        (`plots.case_caption`), the same values in fewer words (``H``/``V``, ``ζ``, ``Γφ``).

    Returns
    -------
    str or None
        The modes of each direction (period ``T`` [s], damping ratio ``zeta``, participation
        ``Gamma phi``), or the screening factor ``1 + 2 z/h`` (ASCE 7-16 Eq. 13.3-1) and ``z/h``.
    """
    floor = case.ground.floor
    if not floor.given:
        return None
    if floor.z_over_h is not None:
        if brief:
            return (f"on a floor: screening, the ground H × {floor.amplification():g} "
                    f"(1 + 2 z/h, z/h = {floor.z_over_h:g})")
        return (f"floor: screening only, the horizontal ground times 1 + 2 z/h = {floor.amplification():g} "
                f"(z/h = {floor.z_over_h:g}, ASCE 7-16 Eq. 13.3-1), not a building's response")
    mode = ("T = {0.period:g} s (ζ = {0.damping:g}, Γφ = {0.participation:g})" if brief
            else "T = {0.period:g} s, zeta = {0.damping:g}, participation {0.participation:g}")
    parts = [f"{role[0].upper() if brief else role} " + ", ".join(mode.format(m) for m in getattr(floor, role))
             for role in ("horizontal", "vertical") if getattr(floor, role)]
    return ("on a floor: " + ", ".join(parts)) if brief else "floor of a linear building: " + "; ".join(parts)


# --------------------------------------------------------------------------------------------------
# The schema
# --------------------------------------------------------------------------------------------------

#: SI unit of each quantity kind, for messages and the README.
SI_UNIT: dict[str, str] = SI_UNITS

NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9._-]*$"
#: Longest case name: ``.NAME.sweep.png.<pid>.<thread>.tmp`` must stay within the 255 bytes of a
#: file name (`files.check_name`).
MAX_NAME_LENGTH = 200
_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")

# Types that are not a quantity kind (those are the keys of units.UNITS):
#   mapping      a section; its keys in "keys"
#   record       a record: a file name, a mapping with the file keys (_FILE_KEYS) or a mapping with
#                the pulse keys (_PULSE_KEYS); "keys" holds both
#   name         a string matching NAME_PATTERN
#   string       a non-empty string
#   choice       one of the strings in "choices"
#   accel_unit   a string naming an acceleration unit
#   count        an integer >= 0
#   column       an integer >= 1 (1-based column) or a non-empty string (a header name)
# Bounds: (op, limit) pairs, op one of ">", ">=", "<", "<=", "|<|" (absolute value below the limit).


def _key(type_: str, doc: str, *, required: bool = False, default=None, bounds=(), choices=(),
         keys: dict | None = None, needs_unit: bool = False) -> dict:
    spec = {"type": type_, "required": required, "default": default, "doc": doc}
    if needs_unit:                # a bare number is refused (an azimuth of 30 would be 30 rad)
        spec["needs_unit"] = True
    if type_ in SI_UNIT:
        spec["unit"] = SI_UNIT[type_]
    if bounds:
        spec["bounds"] = tuple(bounds)
    if choices:
        spec["choices"] = tuple(choices)
    if keys is not None:
        spec["keys"] = keys
    return spec


_FILE_KEYS = {
    "file": _key("string", "accelerogram file (or, instead, 'pulse'); a relative name resolves "
                 "against the case file's folder first", required=True),
    "format": _key("string", "file format (default: detected from the file)"),
    "units": _key("accel_unit", "acceleration unit of the values, e.g. 'g', 'gal', 'm/s^2' "
                  "(default: from the file)"),
    "time_column": _key("column", "1-based column number or header name of the time values"),
    "column": _key("column", "1-based column number or header name of the acceleration values"),
    "dt": _key("time", "sample interval, for files without time column or header",
               bounds=[(">", 0.0)]),
    "skip_lines": _key("count", "lines to skip before the data", default=0),
}

_PULSE_KEYS = {
    "pulse": _key("choice", "an analytic pulse instead of a file: " + ", ".join(SHAPES), required=True,
                  choices=list(SHAPES)),
    "amplitude": _key("acceleration", "the pulse's peak acceleration (signed), e.g. '0.5 g'", required=True),
    "duration": _key("time", "length of a rectangular or half-sine pulse", bounds=[(">", 0.0)]),
    "period": _key("time", "period of a one-sine, cycloidal or ricker pulse", bounds=[(">", 0.0)]),
    "cycles": _key("count", "number of cycles of a cycloidal pulse", default=1),
}

#: A record's keys: a file's, then a pulse's (one or the other is given).
_RECORD_KEYS = {**_FILE_KEYS, **_PULSE_KEYS}

#: One of two horizontal components: a file's keys and its azimuth.
_COMPONENT_KEYS = {**_FILE_KEYS, "azimuth": _key(
    "angle", "direction the component is measured along, clockwise from north, e.g. '90 deg' "
    "(default: from the file's header, PEER AT2)", bounds=[(">=", -2.0 * math.pi), ("<=", 2.0 * math.pi)],
    needs_unit=True)}


#: The keys of one mode of ``ground.floor.horizontal`` / ``vertical`` (`Mode`).
MODE_KEYS = {
    "period": _key("time", "the mode's natural period", required=True, bounds=[(">", 0.0), ("<=", 100.0)]),
    "damping": _key("dimensionless", "its damping ratio", default=0.05, bounds=[(">=", 0.0), ("<", 1.0)]),
    "participation": _key("dimensionless", "participation factor times mode shape at the floor (1: the floor "
                          "moves as the oscillator)", default=1.0, bounds=[("|<|", 100.0)]),
}
#: At most this many modes per direction.
MAX_MODES = 20


def _modes_key(direction: str) -> dict:
    spec = _key("modes", f"the building's {direction} modes under the block: one mode {{period, damping, "
                "participation}} or a list of them", default=())
    spec["items"] = MODE_KEYS
    return spec

CASE_KEYS: dict[str, dict] = {
    "name": _key("name", "case name, used in output file names: letters, digits, '.', '_', '-'",
                 required=True),
    "gravity": _key("acceleration", "gravitational acceleration", default=STANDARD_GRAVITY,
                    bounds=[(">", 0.0)]),
    "block": _key("mapping", "the rectangular rigid block", required=True, keys={
        "height": _key("length", "full height 2h (or centre_of_mass_height)", bounds=[(">", 0.0)]),
        "width": _key("length", "full base width 2b (or half_widths)", bounds=[(">", 0.0)]),
        "mass": _key("mass", "mass (of a mesh: instead of its density)", bounds=[(">", 0.0)]),
        "orientation": _key("angle", "azimuth of the base width (across the rocking axis), clockwise "
                            "from north, with two horizontal components, e.g. '30 deg' (default: "
                            "along ground.horizontal_1)", bounds=[(">=", -2.0 * math.pi), ("<=", 2.0 * math.pi)],
                            needs_unit=True),
        "centre_of_mass_height": _key("length", "height h of the centre of mass above the base, of a body "
                                      "given by half_widths (instead of height)", bounds=[(">", 0.0)]),
        "half_widths": _key("length_pair", "[b1, b2]: distances of the base corners from the vertical through "
                            "the centre of mass, b1 the corner a positive ground acceleration tips the body "
                            "over (instead of width), e.g. '[0.044 m, 0.129 m]'"),
        "depth": _key("length", "full base depth of a box, along its rocking axis: with two horizontal components "
                      "it is also screened in the other plane (a block that wide, under the component across), "
                      "the verdict the worse of the two", bounds=[(">", 0.0)]),
        "radius_of_gyration": _key("length", "sqrt(I/M) about the centre of mass (default: the uniform "
                                   "rectangle's, sqrt((bm^2 + h^2)/3), bm = (b1 + b2)/2), at most "
                                   "sqrt(max(b1, b2)^2 + h^2)"),
        "mesh": _key("string", "a closed triangle mesh (OBJ, STL, PLY) of the body, instead of its sizes: its "
                     "planar body along block.orientation (default: the mesh's x axis, east) is derived and "
                     "screened in both planes (docs/meshes.md); a relative name resolves against the case "
                     "file's folder"),
        "mesh_units": _key("choice", "length unit of the mesh's coordinates (a mesh file does not state it)",
                           choices=list(MESH_LENGTH_UNITS)),
        "density": _key("density", "density of a mesh's body: its mass is density x volume (or give mass)",
                        bounds=[(">", 0.0)]),
    }),
    "contact": _key("mapping", "block-foundation contact", required=True, keys={
        "mu_static": _key("dimensionless", "static friction coefficient", required=True,
                          bounds=[(">=", 0.0)]),
        "mu_kinetic": _key("dimensionless", "kinetic friction coefficient, <= mu_static "
                           "(default: mu_static)", bounds=[(">=", 0.0)]),
        "restitution": _key("dimensionless", "coefficient of restitution of the rocking impacts",
                            required=True, bounds=[(">=", 0.0), ("<=", 1.0)]),
    }),
    "ground": _key("mapping", "ground motion: horizontal and/or vertical records, or none for a free "
                   "vibration over tail", required=True,
                   keys={
        "horizontal": _key("record", "horizontal record: a file name, or a mapping with file or pulse",
                           keys=_RECORD_KEYS),
        "vertical": _key("record", "vertical record: a file name, or a mapping with file or pulse",
                         keys=_RECORD_KEYS),
        "horizontal_1": _key("component", "first of two orthogonal horizontal components (instead of "
                             "horizontal): a file name, or a mapping with file and azimuth",
                             keys=_COMPONENT_KEYS),
        "horizontal_2": _key("component", "second horizontal component, 90 deg from horizontal_1",
                             keys=_COMPONENT_KEYS),
        "scale": _key("mapping", "scaling of the record files", keys={
            "pga_horizontal": _key("acceleration", "scale the horizontal record to this peak "
                                   "acceleration (exclusive with factor; with two components, the "
                                   "larger of their peaks)", bounds=[(">", 0.0)]),
            "factor": _key("dimensionless", "multiply the records by this factor (exclusive with "
                           "pga_horizontal)", bounds=[(">", 0.0)]),
            "pga_vertical": _key("acceleration", "scale the vertical record to this peak "
                                 "acceleration (exclusive with vertical_factor other than 1)",
                                 bounds=[(">=", 0.0)]),
            "vertical_factor": _key("dimensionless", "extra factor on the vertical record",
                                    default=1.0, bounds=[(">=", 0.0)]),
        }),
        "tail": _key("time", "free-vibration time after the record ends", default=0.0,
                     bounds=[(">=", 0.0)]),
        "time_shift": _key("time", "seconds added to every time (record and results), e.g. to lay a "
                           "record on another's time axis", default=0.0),
        "floor": _key("mapping", "the block stands on a floor of a linear building: its modes (the floor's "
                      "absolute acceleration from the ground's), or z_over_h for the code's screening factor",
                      keys={
            "horizontal": _modes_key("horizontal"),
            "vertical": _modes_key("vertical"),
            "z_over_h": _key("dimensionless", "screening only, instead of modes: the floor's horizontal motion is "
                             "the ground's times 1 + 2 z/h (ASCE 7-16 Eq. 13.3-1), z/h = floor height / roof height",
                             bounds=[(">=", 0.0), ("<=", 1.0)]),
        }),
    }),
    "initial": _key("mapping", "initial state", keys={
        "rotation": _key("angle", "initial rotation, signed", default=0.0,
                         bounds=[("|<|", math.pi / 2.0)]),
        "rotation_rate": _key("angular_rate", "initial angular velocity, signed", default=0.0),
        "slip_rate": _key("velocity", "initial sliding velocity, signed", default=0.0),
    }),
    "solver": _key("mapping", "time integration", keys={
        "dt": _key("time", "time step, or 'auto': the largest whole divisor of the record's step "
                   "that meets solver.tolerance (docs/performance.md)", default=1e-4,
                   bounds=[(">", 0.0), ("<=", 0.01)], choices=["auto"]),
        "events": _key("choice", "where state changes happen: located within the step, or at "
                       "step ends", default="located", choices=["located", "step-end"]),
        "method": _key("choice", "integrator: kernel (compiled, fixed step) or reference (adaptive "
                       "DOP853 with located events; slow, for short inputs)", default="kernel",
                       choices=["kernel", "reference"]),
        "tolerance": _key("mapping", "with dt: auto, the error allowed on the results", keys={
            "time": _key("time", "on every event time", default=1e-6, bounds=[(">", 0.0), ("<=", 1.0)]),
            "rotation": _key("angle", "on the largest rotation", default=1e-4,
                             bounds=[(">", 0.0), ("<=", 1.0)]),
        }),
    }),
    "output": _key("mapping", "results", keys={
        "dir": _key("string", "output folder", default="out"),
        "interval": _key("time", "output interval, a whole multiple of solver.dt "
                         "(default: every step)"),
    }),
    "uncertain": _key("mapping", "what is not known exactly, varied by an ensemble (run --ensemble): each a "
                      "number (fixed) or one of {uniform: [low, high]}, {normal: {mean:, std:}}, "
                      "{lognormal: {median:, beta:}}", keys={
        "intensity": _key("distribution", "factor on the scaled ground motion, e.g. {uniform: [0.95, 1.05]}",
                          bounds=[(">", 0.0)]),
        "restitution": _key("distribution", "coefficient of restitution, e.g. {uniform: [0.80, 0.90]}",
                            bounds=[(">=", 0.0), ("<=", 1.0)]),
        "friction": _key("distribution", "factor on mu_static and mu_kinetic together", bounds=[(">", 0.0)]),
        "size": _key("distribution", "factor on height and width together, e.g. {lognormal: {median: 1, "
                     "beta: 0.3}}", bounds=[(">", 0.0)]),
        "slenderness": _key("distribution", "factor on the width b, the height kept (b/h times it, h/b "
                            "divided by it)", bounds=[(">", 0.0)]),
        "orientation": {**_key("distribution", "the block's orientation (block.orientation) with two horizontal "
                               "components, angles with their unit, e.g. {uniform: [0 deg, 180 deg]}",
                               bounds=[(">=", -2.0 * math.pi), ("<=", 2.0 * math.pi)]),
                        "quantity": "angle"},
        "b1": _key("distribution", "factor on b1, the corner a positive ground acceleration tips the body over "
                   "(block.half_widths[0], a rectangle's width/2)", bounds=[(">", 0.0)]),
        "b2": _key("distribution", "factor on b2, the other corner (block.half_widths[1])", bounds=[(">", 0.0)]),
        "radius_of_gyration": _key("distribution", "factor on the radius of gyration about the centre of mass",
                                   bounds=[(">", 0.0)]),
    }),
}

# The dataclass built from each section (by dotted path) and from each record spec.
_SECTIONS: dict[str, type] = {
    "block": Block, "contact": Contact, "ground.scale": Scale, "ground.floor": Floor, "initial": Initial,
    "solver": Solver, "output": Output, "uncertain": Uncertain,
}


def iter_case_keys(keys: Mapping[str, dict] = CASE_KEYS, prefix: str = "") -> Iterator[tuple[str, dict]]:
    """Every key of the schema, depth first, as ``(dotted path, spec)``.

    Parameters
    ----------
    keys : mapping, optional
        A (sub-)schema; the whole :data:`CASE_KEYS` by default.
    prefix : str, optional
        Dotted path of ``keys``.
    """
    for name, spec in keys.items():
        path = f"{prefix}.{name}" if prefix else name
        yield path, spec
        if "keys" in spec:
            yield from iter_case_keys(spec["keys"], path)


# --------------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------------


def load_case(path, *, base_dir: Path | None = None) -> Case:
    """Read and validate a case file, or a mapping with the keys and units of one.

    Parameters
    ----------
    path : str, os.PathLike or mapping
        The YAML case file (UTF-8), or the case as a mapping that parses exactly as the same YAML
        would (`parse_mapping`): accelerations need their unit (``"0.3 g"``), other quantities
        are SI numbers or strings with units.
    base_dir : Path, optional
        For a mapping: the folder its record files resolve against first (default: the current
        folder).

    Returns
    -------
    Case
        With ``source`` the path as given, ``base_dir`` its (absolute) folder and ``text`` its text.

    Raises
    ------
    CaseError
        Naming the file when it is missing, unreadable or invalid.
    """
    if isinstance(path, Mapping):
        _check_nesting(path)
        return parse_mapping(path, base_dir=base_dir)
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes):
        raise CaseError(f"expected a case file's path or a mapping of its keys, got {type(path).__name__}",
                        source="case")
    p = Path(path)
    text = _read_text(p, "case file")
    return parse_case(text, source=str(path), base_dir=p.absolute().parent)


def _check_nesting(mapping) -> None:
    """Refuse a mapping given for a case that holds itself, or is larger or deeper than a case file
    may be (:data:`MAX_YAML_NODES`, :data:`MAX_YAML_DEPTH`), before it is read."""
    count = [0]

    def walk(value, around: tuple) -> None:
        count[0] += 1
        if count[0] > MAX_YAML_NODES or len(around) > MAX_YAML_DEPTH:
            raise CaseError(f"the mapping holds more than {MAX_YAML_NODES} values or {MAX_YAML_DEPTH} levels; a "
                            "case is a page or two of keys", source="case")
        if isinstance(value, (Mapping, list, tuple)):
            if id(value) in around:
                raise CaseError("the mapping holds itself (a value refers back to a mapping or list around it)",
                                source="case")
            for item in value.values() if isinstance(value, Mapping) else value:
                walk(item, (*around, id(value)))

    walk(mapping, ())


def _read_text(path: Path, what: str) -> str:
    """The UTF-8 text of a YAML file (a ``what``: "case file", "suite file"), or a CaseError."""
    source = str(path)
    try:
        size = regular_size(path, what=what, error=CaseError)       # a FIFO or device: refused
        if size > MAX_CASE_BYTES:
            raise CaseError(f"the {what} has {size} bytes; expected at most {MAX_CASE_BYTES} (a {what} is "
                            "a page or two of YAML)", source=source)
        with open_regular(path, what=what, error=CaseError) as handle:
            raw = handle.read(MAX_CASE_BYTES + 1)
        if len(raw) > MAX_CASE_BYTES:             # grew since
            raise CaseError(f"the {what} has more than {MAX_CASE_BYTES} bytes; expected at most "
                            f"{MAX_CASE_BYTES} (a {what} is a page or two of YAML)", source=source)
        return raw.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")   # as read_text() reads
    except FileNotFoundError:
        raise CaseError(f"{what} not found", source=source) from None
    except IsADirectoryError:
        raise CaseError(f"is a folder, expected a {what} (YAML)", source=source) from None
    except PermissionError:
        raise CaseError(f"cannot read the {what}: permission denied", source=source) from None
    except UnicodeDecodeError as exc:
        raise CaseError(f"not UTF-8 text (byte {exc.start}); expected a YAML {what}",
                        source=source) from None
    except OSError as exc:
        raise CaseError(f"cannot read the {what}: {exc.strerror or exc}", source=source) from None


def parse_case(text: str, *, source: str = "<case>", base_dir: Path | None = None) -> Case:
    """Validate the text of a case file.

    Parameters
    ----------
    text : str
        YAML text.
    source : str, optional
        File name used in messages and stored in the case.
    base_dir : Path, optional
        Folder record files resolve against first.

    Returns
    -------
    Case

    Raises
    ------
    CaseError
        On YAML syntax errors (with line and column), object tags, unknown or missing keys, wrong
        types or units, and values out of their physical range.
    """
    if isinstance(text, Mapping):         # a case as data: parsed as the same YAML would be
        return parse_mapping(text, source=source if source != "<case>" else "<mapping>", base_dir=base_dir)
    if not isinstance(text, str):
        raise CaseError(f"expected the YAML text of a case (or a mapping), got {_show(text)}", source=source)
    if len(text) > MAX_CASE_BYTES:
        raise CaseError(f"the case text has {len(text)} characters; expected at most {MAX_CASE_BYTES} "
                        "(a case file is a page of YAML)", source=source)
    data = _load_yaml(text, source)
    return _build(data, source=source, base_dir=base_dir, text=text)


def parse_mapping(data: Mapping, *, source: str = "<mapping>", base_dir: Path | None = None) -> Case:
    """Validate a case given as a mapping, as `parse_case` validates the same YAML.

    The case's ``text`` is the mapping written as YAML (what a result file stores as the case file),
    so that a study of it is reproducible from its file alone.

    Raises
    ------
    CaseError
        As `parse_case`; a value YAML cannot hold (an object) is named by its key.
    """
    if not isinstance(data, Mapping):
        raise CaseError(f"expected a mapping with keys {', '.join(CASE_KEYS)}, got {_show(data)}", source=source)
    plain = _plain_data(data, "", source)
    text = yaml.safe_dump(plain, sort_keys=False, allow_unicode=True)
    return _build(plain, source=source, base_dir=Path.cwd() if base_dir is None else Path(base_dir), text=text)


def _plain_data(value, path: str, source: str):
    """``value`` with numpy numbers as Python numbers and paths as strings (what YAML writes)."""
    if isinstance(value, Mapping):
        return {key: _plain_data(v, f"{path}.{key}" if path else str(key), source) for key, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain_data(v, path, source) for v in value]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if hasattr(value, "item") and callable(value.item) and getattr(value, "shape", None) == ():
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise CaseError(f"expected a number, text or mapping, got {_show(value)}", source=source, field=path or None)


#: Bounds on a case file, checked before its YAML is built (a few hundred bytes of nested aliases
#: or merge keys expand to billions of nodes). The shipped example is 1 KB, 60 nodes, 4 levels deep.
MAX_CASE_BYTES = 64 * 1024
MAX_YAML_NODES = 10_000     # after expanding aliases and merge keys
MAX_YAML_DEPTH = 20


def _check_yaml_size(root, source: str) -> None:
    """Refuse a composed YAML document that expands beyond :data:`MAX_YAML_NODES` nodes or
    :data:`MAX_YAML_DEPTH` levels, or whose aliases form a cycle; linear in the composed document
    (an alias is a shared node, counted once per use without being expanded)."""
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    stack = [(root, False)]
    on_path: set[int] = set()
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        children = _yaml_children(node)
        if children_done:
            on_path.discard(key)
            size[key] = min(1 + sum(size[id(c)] for c in children), MAX_YAML_NODES + 1)
            depth[key] = 1 + max((depth[id(c)] for c in children), default=0)
            if size[key] > MAX_YAML_NODES:
                mark = node.start_mark
                raise CaseError(f"the YAML expands to more than {MAX_YAML_NODES} values (aliases and "
                                "merge keys included); a case file is a page of plain data",
                                source=source, field=f"line {mark.line + 1}, column {mark.column + 1}")
            if depth[key] > MAX_YAML_DEPTH:
                mark = node.start_mark
                raise CaseError(f"the YAML is nested more than {MAX_YAML_DEPTH} levels deep; a case file "
                                "has sections of keys", source=source,
                                field=f"line {mark.line + 1}, column {mark.column + 1}")
            continue
        if key in size:
            continue
        if key in on_path:
            mark = node.start_mark
            raise CaseError("invalid YAML: an alias refers to a node that contains it", source=source,
                            field=f"line {mark.line + 1}, column {mark.column + 1}")
        on_path.add(key)
        stack.append((node, True))
        stack.extend((c, False) for c in children if id(c) not in size)


def _yaml_children(node) -> list:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


# How PyYAML's safe constructors fail on explicit tags with bad values (``!!int abc``, ``!!float``).
_CONSTRUCTOR_FAILURES = (ValueError, TypeError, IndexError, KeyError, AttributeError, OverflowError)


class _CaseLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing a key given twice in one mapping (``safe_load`` keeps the last)."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen: dict = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.setdefault(key, key_node.start_mark)
                except TypeError:
                    continue  # an unhashable key: the base class reports it
                if first is not key_node.start_mark:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {key!r} (first given on line {first.line + 1}); "
                        "give each key once", key_node.start_mark)
        return super().construct_mapping(node, deep=deep)


def _load_yaml(text: str, source: str):
    loader = None
    try:
        loader = _CaseLoader(text)       # a SafeLoader: plain data only
        root = loader.get_single_node()
        if root is None:
            return None
        _check_yaml_size(root, source)
        return loader.construct_document(root)
    except yaml.constructor.ConstructorError as exc:
        problem = _one_line(exc.problem or "")
        if "could not determine a constructor" in problem:
            message = (f"unsupported YAML tag: {problem} (a case file is plain data: numbers, "
                       "strings, lists and mappings)")
        else:
            message = f"invalid YAML: {_yaml_problem(exc)}"
        raise CaseError(message, source=source, field=_yaml_where(exc)) from None
    except yaml.MarkedYAMLError as exc:
        hint = " (indent with spaces; YAML does not allow tabs)" if "'\\t'" in str(exc.problem) else ""
        raise CaseError(f"invalid YAML: {_yaml_problem(exc)}{hint}", source=source,
                        field=_yaml_where(exc)) from None
    except yaml.reader.ReaderError as exc:
        before = text[:exc.position] if isinstance(text, str) else ""
        line = before.count("\n") + 1
        column = len(before) - (before.rfind("\n") + 1) + 1
        char = f"#x{exc.character:04x}" if isinstance(exc.character, int) else repr(exc.character)
        raise CaseError(f"invalid YAML: character {char} not allowed ({exc.reason})",
                        source=source, field=f"line {line}, column {column}") from None
    except yaml.YAMLError as exc:
        raise CaseError(f"invalid YAML: {_one_line(str(exc))}", source=source) from None
    except RecursionError:
        raise CaseError("invalid YAML: nested too deeply", source=source) from None
    except _CONSTRUCTOR_FAILURES as exc:
        # PyYAML's constructors fail like this on explicit tags with bad values (``!!int abc``).
        node = _bad_scalar(text)
        if node is None:
            raise CaseError(f"invalid YAML: a value cannot be read ({_one_line(str(exc))})",
                            source=source) from None
        tag = node.tag.replace("tag:yaml.org,2002:", "!!")
        mark = node.start_mark
        raise CaseError(f"invalid YAML: {node.value!r} is not a valid {tag} value", source=source,
                        field=f"line {mark.line + 1}, column {mark.column + 1}") from None
    finally:
        if loader is not None:
            loader.dispose()


def _bad_scalar(text: str):
    """The first scalar node PyYAML's safe constructor fails on (outside its own error type)."""
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except (yaml.YAMLError, RecursionError):
        return None
    stack, seen = [root], set()
    while stack:
        node = stack.pop()
        if node is None or id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, yaml.ScalarNode):
            try:
                yaml.constructor.SafeConstructor().construct_object(node)
            except yaml.YAMLError:
                pass
            except _CONSTRUCTOR_FAILURES:
                return node
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(reversed(node.value))
        elif isinstance(node, yaml.MappingNode):
            stack.extend(n for pair in reversed(node.value) for n in reversed(pair))
    return None


def _yaml_where(exc: yaml.MarkedYAMLError) -> str | None:
    mark = exc.problem_mark or exc.context_mark
    if mark is None:
        return None
    return f"line {mark.line + 1}, column {mark.column + 1}"


def _yaml_problem(exc: yaml.MarkedYAMLError) -> str:
    context = exc.context
    if context and exc.context_mark is not None and exc.problem_mark is not None \
            and exc.context_mark.line != exc.problem_mark.line:
        context += f" (from line {exc.context_mark.line + 1}, column {exc.context_mark.column + 1})"
    parts = [p for p in (context, exc.problem) if p]
    return _one_line(", ".join(parts)) or "syntax error"


# --------------------------------------------------------------------------------------------------
# Validation, driven by CASE_KEYS
# --------------------------------------------------------------------------------------------------

_repr = reprlib.Repr()
_repr.maxstring = 60
_repr.maxother = 60
_repr.maxlist = _repr.maxdict = _repr.maxtuple = _repr.maxset = _repr.maxfrozenset = 4
_repr.maxlevel = 2


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _show(value) -> str:
    """A short, one-line description of a user-given value."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        kind = "a boolean"
    elif isinstance(value, Mapping):
        kind = "a mapping"
    elif isinstance(value, (list, tuple)):
        kind = "a list"
    elif isinstance(value, str):
        kind = "a string"
    elif isinstance(value, int):
        kind = "an integer"
    elif isinstance(value, float):
        kind = "a number"
    else:
        kind = f"a {type(value).__name__}"
    return f"{kind} {_one_line(_repr.repr(value))}"


def _key_text(key) -> str:
    """A user's key as it appears in a dotted path: itself if printable, else its repr."""
    return key if isinstance(key, str) and key.isprintable() and key.strip() == key else repr(key)


def _num(x: float) -> str:
    return f"{x:.10g}"


def _with_unit(x: float, unit: str) -> str:
    return f"{_num(x)} {unit}" if unit else _num(x)


class _Ctx:
    """Where the data came from, for messages; how bare numbers are read; the units written."""

    def __init__(self, source: str, si_numbers: bool = False, base_dir: Path | None = None):
        self.source = source
        self.si_numbers = si_numbers
        self.base_dir = base_dir
        self.units: dict[str, str] = {}

    def fail(self, path: str | None, message: str):
        raise CaseError(_one_line(message), source=self.source, field=path or None)


def _read_mapping(data, keys: Mapping[str, dict], path: str, ctx: _Ctx, what: str) -> dict:
    """Check a mapping against ``keys`` and return its converted values (defaults filled in)."""
    if not isinstance(data, Mapping):
        ctx.fail(path, f"expected {what} (keys: {', '.join(keys)}), got {_show(data)}")
    for key in data:
        if not isinstance(key, str) or key not in keys:
            name = _key_text(key)
            ctx.fail(f"{path}.{name}" if path else name, f"unknown key ({_suggest(name, keys)})")
    out = {}
    for name, spec in keys.items():
        sub = f"{path}.{name}" if path else name
        value = data.get(name)
        if value is None:
            if spec["required"]:
                unit = f" [{spec['unit']}]" if spec.get("unit") else ""
                problem = "is null, a value is required" if name in data else "missing required key"
                ctx.fail(sub, f"{problem} ({spec['doc']}{unit})")
            if spec["type"] == "mapping":
                value = {}
            else:
                out[name] = spec["default"]
                continue
        out[name] = _read_value(value, spec, sub, ctx)
    return out


def _suggest(name: str, keys: Mapping[str, dict]) -> str:
    import difflib

    close = difflib.get_close_matches(name, list(keys), n=1)
    if close:
        return f"did you mean {close[0]!r}?"
    elsewhere = [p for p, _ in iter_case_keys() if p.rsplit(".", 1)[-1] == name
                 and not (p.startswith(("ground.horizontal_1.", "ground.horizontal_2.")) and name in _FILE_KEYS)]
    if len(elsewhere) == 1:
        parent = elsewhere[0].rsplit(".", 1)[0]
        return f"did you mean {elsewhere[0]!r}? it belongs under {parent!r}"
    if elsewhere:
        *first, last = (repr(p) for p in elsewhere)
        return f"did you mean {', '.join(first)} or {last}? it belongs in a section"
    return f"expected one of: {', '.join(keys)}"


def _read_value(value, spec: dict, path: str, ctx: _Ctx):
    """Convert one present (non-null) value according to its spec."""
    kind = spec["type"]
    if kind == "mapping":
        return _read_mapping(value, spec["keys"], path, ctx, "a mapping")
    if kind == "record":
        return _read_record(value, path, ctx)
    if kind == "component":
        if isinstance(value, str):
            value = {"file": value}
        if isinstance(value, Mapping) and value.get("pulse") is not None:
            ctx.fail(path, "a horizontal component is a record file; an analytic pulse has one direction "
                     "(give it as ground.horizontal)")
        return _read_mapping(value, spec["keys"], path, ctx, "a file name or a mapping with file and azimuth")
    if kind == "modes":
        return _read_modes(value, spec, path, ctx)
    if kind == "length_pair":
        if not isinstance(value, list | tuple) or len(value) != 2:
            ctx.fail(path, f"expected two lengths [b1, b2], e.g. [0.044 m, 0.129 m], got {_show(value)}")
        one = {"type": "length", "unit": "m", "bounds": ((">", 0.0),)}
        return tuple(_read_quantity(v, one, f"{path}[{i}]", ctx) for i, v in enumerate(value))
    if kind in UNITS:
        if isinstance(value, str) and value.strip() in spec.get("choices", ()):
            return value.strip()       # a word a quantity key also takes (solver.dt: auto)
        return _read_quantity(value, spec, path, ctx)
    if kind == "name":
        if not isinstance(value, str) or not _NAME_RE.fullmatch(value):
            ctx.fail(path, f"expected a name made of letters, digits, '.', '_' and '-', starting with "
                     f"a letter or digit ({NAME_PATTERN}), got {_show(value)}")
        if len(value) > MAX_NAME_LENGTH:
            ctx.fail(path, f"expected at most {MAX_NAME_LENGTH} characters (the name is part of the output "
                     f"files' names), got {len(value)}: {_show(value)}")
        for command in ("sweep", "fragility"):
            if value.endswith(f".{command}"):
                ctx.fail(path, f"a name ending in '.{command}' would write the files of the {command} of case "
                         f"{value[:-len(command) - 1]!r} (NAME.{command}.h5); choose another name")
        return value
    if kind == "string":
        if not isinstance(value, str) or not value.strip():
            ctx.fail(path, f"expected a non-empty string, got {_show(value)}")
        if not (value.isprintable() or all(c.isprintable() or c in " \t" for c in value)):
            ctx.fail(path, f"expected text without control characters (such as NUL or a line break), "
                     f"got {_show(value)}")
        return value
    if kind == "choice":
        choices = spec["choices"]
        if not isinstance(value, str) or value not in choices:
            hint = ""
            if isinstance(value, str):
                import difflib

                close = difflib.get_close_matches(value, choices, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
            ctx.fail(path, f"expected one of {', '.join(repr(c) for c in choices)}, "
                     f"got {_show(value)}{hint}")
        return value
    if kind == "accel_unit":
        if not isinstance(value, str):
            ctx.fail(path, f"expected an acceleration unit such as 'g', 'gal' or 'm/s^2', "
                     f"got {_show(value)}")
        unit_factor(value, "acceleration", source=ctx.source, field=path)
        return value
    if kind == "count":
        if not isinstance(value, int) or isinstance(value, bool) or value < 0:
            ctx.fail(path, f"expected a whole number >= 0, got {_show(value)}")
        return value
    if kind == "distribution":
        return _read_distribution(value, spec, path, ctx)
    if kind == "column":
        if isinstance(value, int) and not isinstance(value, bool):
            if value < 1:
                ctx.fail(path, f"expected a column number >= 1 (1-based) or a header name, "
                         f"got {_show(value)}")
            return value
        if not isinstance(value, str) or not value.strip():
            ctx.fail(path, f"expected a column number >= 1 (1-based) or a non-empty header name, "
                     f"got {_show(value)}")
        return value
    raise AssertionError(f"schema error: unknown type {kind!r} at {path}")  # pragma: no cover


def _read_modes(value, spec: dict, path: str, ctx: _Ctx) -> tuple:
    """One mode (a mapping) or a list of at most `MAX_MODES` of them -> a tuple of `Mode`."""
    items = [value] if isinstance(value, Mapping) else value
    if not isinstance(items, list) or not items:
        ctx.fail(path, f"expected a mode {{period: 0.8 s, damping: 0.05, participation: 1.3}} or a list of "
                 f"them, got {_show(value)}")
    if len(items) > MAX_MODES:
        ctx.fail(path, f"expected at most {MAX_MODES} modes, got {len(items)}")
    one = isinstance(value, Mapping)
    return tuple(Mode(**_read_mapping(item, spec["items"], path if one else f"{path}[{i}]", ctx, "a mode"))
                 for i, item in enumerate(items))


#: The distributions of the ``uncertain`` section, with the names of their two parameters.
DISTRIBUTIONS = {"fixed": (), "uniform": ("low", "high"), "normal": ("mean", "std"),
                 "lognormal": ("median", "beta")}


def _read_distribution(value, spec: dict, path: str, ctx: _Ctx) -> Distribution:
    """A number (fixed) or ``{uniform: [low, high]}``, ``{normal: {mean:, std:}}`` (or ``[mean, std]``),
    ``{lognormal: {median:, beta:}}`` (or ``[median, beta]``); dimensionless. The values a
    distribution gives must lie within the key's bounds (a factor > 0, a restitution within [0, 1]):
    checked on the range of a uniform, on the mean of a normal (a factor's normal must stay 4
    standard deviations above 0: else lognormal), on the median of a lognormal."""
    example = ("a number, or {uniform: [0.95, 1.05]}, {normal: {mean: 1, std: 0.02}}, "
               "{lognormal: {median: 1, beta: 0.3}}")

    def number(v, where):
        if spec.get("quantity") and (isinstance(v, str) or not ctx.si_numbers and v != 0):
            if not isinstance(v, str):
                ctx.fail(path, f"{_show(v)} has no unit; write the angle with its unit, e.g. '30 deg'")
            return parse_quantity(v, spec["quantity"], source=ctx.source, field=path)
        try:
            x = float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else math.nan
        except OverflowError:                       # an integer beyond float64
            x = math.inf
        if not math.isfinite(x):
            ctx.fail(path, f"expected a finite number for {where}, got {_show(v)} ({example})")
        return x

    if not isinstance(value, Mapping):
        dist = Distribution("fixed", number(value, "the value"))
    else:
        if len(value) != 1 or next(iter(value)) not in DISTRIBUTIONS:
            ctx.fail(path, f"expected one of {', '.join(DISTRIBUTIONS)}, got {_show(value)} ({example})")
        kind, params = next(iter(value.items()))
        names = DISTRIBUTIONS[kind]
        if kind == "fixed":
            dist = Distribution("fixed", number(params, "fixed"))
        else:
            if isinstance(params, Mapping):
                unknown = [k for k in params if k not in names]
                if unknown or len(params) != 2:
                    ctx.fail(path, f"{kind} takes {names[0]} and {names[1]}, got {_show(params)}")
                pair = [params[n] for n in names]
            elif isinstance(params, (list, tuple)) and len(params) == 2:
                pair = list(params)
            else:
                ctx.fail(path, f"{kind} takes [{names[0]}, {names[1]}] or {{{names[0]}:, {names[1]}:}}, "
                         f"got {_show(params)}")
            a, b = (number(v, f"{kind}'s {n}") for v, n in zip(pair, names, strict=True))
            if kind == "uniform" and b < a:
                ctx.fail(path, f"uniform: the highest value {_num(b)} is below the lowest {_num(a)}")
            if kind in ("normal", "lognormal") and b < 0.0:
                ctx.fail(path, f"{kind}: {names[1]} must be >= 0, got {_num(b)}")
            dist = Distribution(kind, a, b)
    checked = {"fixed": [dist.a], "uniform": [dist.a, dist.b], "normal": [dist.a], "lognormal": [dist.a]}[dist.kind]
    for op, limit in spec.get("bounds", ()):
        for v in checked:
            if not _OPS[op][0](v, limit):
                ctx.fail(path, f"its values must be {op} {_num(limit)}, got {_num(v)} in {_show(value)}")
    if dist.kind == "normal" and any(op == ">" for op, _ in spec.get("bounds", ())) and dist.a - 4 * dist.b <= 0:
        ctx.fail(path, f"a normal factor with mean {_num(dist.a)} and std {_num(dist.b)} reaches 0 and below; "
                 "use a lognormal (e.g. {lognormal: {median: 1, beta: 0.1}})")
    if dist.kind == "lognormal" and not dist.a > 0.0:
        ctx.fail(path, f"lognormal: the median must be > 0, got {_num(dist.a)}")
    return dist


def _read_record(value, path: str, ctx: _Ctx) -> dict:
    """A record: a file name, a mapping with ``file`` (`_FILE_KEYS`) or one with ``pulse``
    (`_PULSE_KEYS`); a key of the other kind is named as such."""
    if isinstance(value, str):
        value = {"file": value}
    elif not isinstance(value, Mapping):
        ctx.fail(path, f"expected a file name or a mapping with file (keys: {', '.join(_FILE_KEYS)}) or "
                 f"pulse (keys: {', '.join(_PULSE_KEYS)}), got {_show(value)}")
    pulse = value.get("pulse") is not None
    keys, other = (_PULSE_KEYS, _FILE_KEYS) if pulse else (_FILE_KEYS, _PULSE_KEYS)
    for key, item in value.items():
        if key in other and item is not None:
            if pulse:
                ctx.fail(f"{path}.{key}", "is a key of a record file, not of a pulse (a pulse takes: "
                         f"{', '.join(_PULSE_KEYS)}); give either file or pulse")
            ctx.fail(f"{path}.{key}", f"is a key of a pulse; give 'pulse' too (one of: {', '.join(SHAPES)}), "
                     f"or the keys of a record file: {', '.join(_FILE_KEYS)}")
    data = _read_mapping({k: v for k, v in value.items() if k not in other}, keys, path, ctx,
                         "a pulse" if pulse else "a file name or a mapping")
    if pulse:
        _check_pulse(data, path, ctx)
    return data


def _check_pulse(data: dict, path: str, ctx: _Ctx) -> None:
    """The keys a pulse's shape takes (`pulses.SHAPES`): its duration or its period, and cycles."""
    name = data["pulse"]
    shape = SHAPES[name]
    wanted = shape.parameter
    unwanted = "period" if wanted == "duration" else "duration"
    if data[unwanted] is not None:
        ctx.fail(f"{path}.{unwanted}", f"a {name} pulse takes {wanted}, not {unwanted}")
    if data[wanted] is None:
        ctx.fail(f"{path}.{wanted}", f"missing: a {name} pulse needs its {wanted} [s]")
    if data["cycles"] < 1:
        ctx.fail(f"{path}.cycles", f"must be at least 1, got {data['cycles']}")
    if data["cycles"] != 1 and not shape.cycles:
        ctx.fail(f"{path}.cycles", f"only the cycloidal pulses (cycloidal-a, cycloidal-b) take cycles; "
                 f"a {name} pulse has none, got {data['cycles']}")


_OPS = {
    ">": (lambda x, lim: x > lim, "greater than"),
    ">=": (lambda x, lim: x >= lim, "at least"),
    "<": (lambda x, lim: x < lim, "less than"),
    "<=": (lambda x, lim: x <= lim, "at most"),
    "|<|": (lambda x, lim: abs(x) < lim, "in absolute value less than"),
}


def _read_quantity(value, spec: dict, path: str, ctx: _Ctx) -> float:
    kind = spec["type"]
    try:
        number = parse_quantity(value, kind, source=ctx.source, field=path, si_numbers=ctx.si_numbers)
    except OverflowError:
        ctx.fail(path, f"{_show(value)} is too large (expected a finite {kind})")
    if written_unit(value):
        ctx.units[path] = written_unit(value)
    elif spec.get("needs_unit") and number != 0.0 and not ctx.si_numbers:
        ctx.fail(path, f"{_show(value)} has no unit; write the angle with its unit, e.g. '30 deg'")
    unit = spec.get("unit", "")
    for op, limit in spec.get("bounds", ()):
        if not _OPS[op][0](number, limit):
            expected = " and ".join(f"{_OPS[o][1]} {_limit_text(lim, spec)}"
                                    for o, lim in spec["bounds"])
            given = _with_unit(number, unit)
            if isinstance(value, str):
                given += f" (from {value!r})"
            elif unit and number > 0:
                given += f" (a number without unit is in {unit}; write e.g. {_unit_example(kind)!r})"
            ctx.fail(path, f"must be {expected}, got {given}")
    return number


def _unit_example(kind: str) -> str:
    return {"time": "0.1 ms", "length": "200 mm", "acceleration": "800 gal", "angle": "2 deg",
            "mass": "10 kg", "angular_rate": "0.5 rad/s", "velocity": "0.1 m/s"}.get(kind, "")


def _limit_text(limit: float, spec: dict) -> str:
    if spec["type"] == "angle" and math.isclose(limit, math.pi / 2.0):
        return "pi/2 rad (90 deg)"
    if spec["type"] == "angle" and math.isclose(abs(limit), 2.0 * math.pi):
        return f"{'-' if limit < 0 else ''}360 deg"
    return _with_unit(limit, spec.get("unit", ""))


def _block_checks(raw: dict, ctx: _Ctx) -> None:
    """A block is a rectangle (``height``, ``width``) or a body (``centre_of_mass_height``,
    ``half_widths``), not both; ``radius_of_gyration`` fits a body of that size; the restitution is
    at most ``e_max`` (docs/model-asymmetric.md section 4.2). The body's form is stored with
    ``height = 2 h`` and ``width = b1 + b2``."""
    block = raw["block"]
    if block["mesh"] is not None:
        _mesh_body(block, ctx)
    else:
        for key in ("mesh_units", "density"):
            if block[key] is not None:
                ctx.fail(f"block.{key}", "is a mesh's: give it with block.mesh")
        if block["mass"] is None:
            ctx.fail("block.mass", f"missing required key ({CASE_KEYS['block']['keys']['mass']['doc']} [kg])")
    pairs = (("height", "centre_of_mass_height"), ("width", "half_widths"))
    for plain, body in pairs:
        if block[plain] is not None and block[body] is not None:
            ctx.fail(f"block.{body}", f"and block.{plain} are exclusive: give block.{plain} (a rectangle) or "
                     f"block.{body}")
        if block[plain] is None and block[body] is None:
            spec = CASE_KEYS["block"]["keys"][plain]
            ctx.fail(f"block.{plain}", f"missing required key ({spec['doc']} [m])")
    if block["centre_of_mass_height"] is not None:
        block["height"] = 2.0 * block["centre_of_mass_height"]
    if block["half_widths"] is not None:
        block["width"] = block["half_widths"][0] + block["half_widths"][1]
    b1, b2 = block["half_widths"] if block["half_widths"] is not None else (block["width"] / 2.0,) * 2
    h = block["height"] / 2.0
    k = block["radius_of_gyration"]
    failures = dict(body_failures(b1, b2, h, k, raw["contact"]["restitution"]))
    if "block.radius_of_gyration" in failures:
        ctx.fail("block.radius_of_gyration", failures["block.radius_of_gyration"])
    if block["depth"] is not None and (block["half_widths"] is not None or k is not None):
        ctx.fail("block.depth", "is a box's depth: give it with block.height and block.width (a body given by "
                 "half_widths or a radius of gyration is screened in one plane; rockslide info describes a mesh "
                 "in both)")
    if "contact.restitution" in failures:
        ctx.fail("contact.restitution", failures["contact.restitution"])


def body_failures(b1: float, b2: float, h: float, k: float | None, e: float | None) -> list[tuple[str, str]]:
    """What a body's radius of gyration and restitution break (docs/model-asymmetric.md section 4.2):
    ``k`` within ``(0, k_max]``, ``k_max = sqrt(max(b1, b2)^2 + h^2)``, and, for an asymmetric body
    (``b1 != b2`` or ``k`` given), ``e`` at most ``e_max``. A pure check, the one for a case file
    (`_block_checks`) and an ensemble's members (`analyses.ensemble`).

    Parameters
    ----------
    b1, b2 : float
        [m] The base corners' distances from the vertical through the centre of mass.
    h : float
        [m] The centre of mass's height.
    k : float or None
        [m] The radius of gyration about the centre of mass (None: the uniform rectangle's).
    e : float or None
        [-] The coefficient of restitution (None: not checked).

    Returns
    -------
    list of (str, str)
        ``(key, what is wrong)`` per failure, in the order of the keys; empty when the body is within.
    """
    out = []
    if k is not None:
        # Any body inside the bounding box [-b1, b2] x [0, 2h] with its centre of mass at (0, h) has
        # 0 < I/M <= max over the box of the squared distance from the centre of mass, b_max^2 + h^2.
        k_max = math.sqrt(max(b1, b2) ** 2 + h * h)
        if not 0.0 < k <= k_max:
            out.append(("block.radius_of_gyration", f"expected within (0, {k_max:.6g} m], the largest a body of "
                        f"that size can have (sqrt(max(b1, b2)^2 + h^2)), got {_with_unit(k, 'm')}"))
    if e is not None and (b1 != b2 or k is not None):
        k2 = k * k if k is not None else rectangle_k2(b1, b2, h)
        rho1, rho2 = math.sqrt(k2 + b1 * b1 + h * h), math.sqrt(k2 + b2 * b2 + h * h)
        e_max = (h * h + math.sqrt((k2 + b1 * b1) * (k2 + b2 * b2))) / (rho1 * rho2)
        if e > e_max:
            out.append(("contact.restitution", f"must be at most e_max = {e_max:.10g} for this body (beyond it an "
                        f"impact of a sliding base could add energy; docs/asymmetric.md), got {_num(e)}"))
    return out


def _mesh_body(block: dict, ctx: _Ctx) -> None:
    """Fill a mesh's ``block`` with its planar body along ``block.orientation`` (the mesh's x axis,
    east, when not given): ``centre_of_mass_height``, ``half_widths``, ``radius_of_gyration``,
    ``mass`` (`mesh.body_of_file`, model-asymmetric.md section 9), ``mesh`` the file's absolute path."""
    from . import mesh as meshes
    from .errors import OutputError

    for key in ("height", "width", "centre_of_mass_height", "half_widths", "radius_of_gyration", "depth"):
        if block[key] is not None:
            ctx.fail(f"block.{key}", "and block.mesh are exclusive: the mesh gives the body's sizes and inertia "
                     "(and its second plane)")
    if block["mesh_units"] is None:
        ctx.fail("block.mesh_units", f"missing: the length unit of the mesh's coordinates "
                 f"({', '.join(MESH_LENGTH_UNITS)}): a mesh file does not state it")
    if (block["density"] is None) == (block["mass"] is None):
        ctx.fail("block.density", "give the body's density (its mass is density x volume) or block.mass, "
                 "one of them" + (", not both" if block["density"] is not None else ""))
    path = Path(block["mesh"]).expanduser()
    if not path.is_absolute():
        path = (ctx.base_dir if ctx.base_dir is not None else Path.cwd()) / path
    azimuth = block["orientation"] if block["orientation"] is not None else 0.5 * math.pi
    try:
        body = meshes.body_of_file(path, units=block["mesh_units"], azimuth=azimuth, density=block["density"],
                                   mass=block["mass"])
    except (CaseError, OutputError) as exc:
        ctx.fail("block.mesh", f"{path.name}: {exc.message}")
    block.update(mesh=str(path.absolute()), centre_of_mass_height=body.h, half_widths=(body.b1, body.b2),
                 radius_of_gyration=body.radius_of_gyration, mass=body.mass)


def _cross_checks(raw: dict, ctx: _Ctx) -> None:
    """Checks that involve more than one key; ``raw`` is the converted nested dict."""
    _block_checks(raw, ctx)
    contact = raw["contact"]
    if contact["mu_kinetic"] is None:
        contact["mu_kinetic"] = contact["mu_static"]
    elif contact["mu_kinetic"] > contact["mu_static"]:
        ctx.fail("contact.mu_kinetic", f"mu_kinetic ({_num(contact['mu_kinetic'])}) must not exceed "
                 f"mu_static ({_num(contact['mu_static'])})")

    ground = raw["ground"]
    scale = ground["scale"]
    _component_checks(raw, ctx)
    if raw["block"]["mesh"] is not None and ground["horizontal_2"] is not None and raw["block"]["orientation"] is None:
        ctx.fail("block.orientation", "is needed for a mesh with two horizontal components: the azimuth, in the "
                 "ground's frame and the mesh's (x east, y north), of the direction its body is taken along")
    if raw["uncertain"]["orientation"] is not None and ground["horizontal_2"] is None:
        ctx.fail("uncertain.orientation", "given, but the ground has one horizontal component: turning the "
                 "block needs two, ground.horizontal_1 and ground.horizontal_2")
    if ground["horizontal"] is None and ground["vertical"] is None and not ground["tail"] > 0.0:
        ctx.fail("ground", "needs a record (ground.horizontal or ground.vertical: a file name or a "
                 "mapping with 'file'), or, for a free vibration without record, a ground.tail "
                 "(e.g. 'tail: 5 s') and initial conditions")
    _pulse_checks(ground, ctx)
    if scale["pga_horizontal"] is not None and scale["factor"] is not None:
        ctx.fail("ground.scale", f"pga_horizontal ({_with_unit(scale['pga_horizontal'], 'm/s^2')}) "
                 f"and factor ({_num(scale['factor'])}) are exclusive: give one of them")
    floor = ground["floor"]
    if floor["z_over_h"] is not None and (floor["horizontal"] or floor["vertical"]):
        ctx.fail("ground.floor.z_over_h", "is the code's screening factor, instead of the building's modes: give "
                 "z_over_h or modes (horizontal, vertical), not both")
    if scale["pga_vertical"] is not None and scale["vertical_factor"] != 1.0:
        ctx.fail("ground.scale", f"pga_vertical ({_with_unit(scale['pga_vertical'], 'm/s^2')}) and "
                 f"vertical_factor ({_num(scale['vertical_factor'])}) are exclusive: give one of "
                 "them (or vertical_factor 1)")
    if scale["pga_horizontal"] is not None and ground["horizontal"] is None:
        ctx.fail("ground.scale.pga_horizontal", "given, but there is no ground.horizontal record "
                 "to scale")
    if ground["vertical"] is None:
        if scale["pga_vertical"] is not None:
            ctx.fail("ground.scale.pga_vertical", "given, but there is no ground.vertical record "
                     "to scale")
        if scale["vertical_factor"] != 1.0:
            ctx.fail("ground.scale.vertical_factor", f"given ({_num(scale['vertical_factor'])}), but "
                     "there is no ground.vertical record to scale")

    dt = raw["solver"]["dt"]
    if dt == "auto":            # the step is chosen with the ground motion; rows every `interval` rounded
        dt = Solver.dt
    interval = raw["output"]["interval"]
    if interval is not None:
        ratio = interval / dt
        if not math.isfinite(ratio):
            ctx.fail("output.interval", f"{_with_unit(interval, 's')} is not a countable number of steps of "
                     f"solver.dt ({_with_unit(dt, 's')}); expected a whole multiple of solver.dt")
        if ratio < 1.0 - 1e-9:
            ctx.fail("output.interval", f"must be at least solver.dt ({_with_unit(dt, 's')}), "
                     f"got {_with_unit(interval, 's')}")
        if abs(ratio - round(ratio)) > 1e-9 * ratio:
            ctx.fail("output.interval", f"must be a whole multiple of solver.dt ({_with_unit(dt, 's')}),"
                     f" got {_with_unit(interval, 's')} ({_num(ratio)} steps)")


def _component_checks(raw: dict, ctx: _Ctx, path: str = "ground") -> None:
    """Two horizontal components come together, instead of ``horizontal``; ``horizontal_1`` then
    becomes ``horizontal`` (the first component), and ``block.orientation`` needs them. ``raw`` is
    a case (``path`` ``ground``) or a suite's entry (its path)."""
    ground = raw["ground"] if path == "ground" else raw
    one, two = ground.pop("horizontal_1"), ground["horizontal_2"]
    if one is None and two is None:
        if raw["block"]["orientation"] is not None and raw["block"].get("mesh") is None:
            ctx.fail("block.orientation", "given, but the ground has one horizontal component: give two, "
                     "ground.horizontal_1 and ground.horizontal_2 (each a file and its azimuth)")
        return
    if ground["horizontal"] is not None:
        ctx.fail(f"{path}.horizontal", f"and {path}.horizontal_1 are exclusive: give {path}.horizontal "
                 f"(one component) or {path}.horizontal_1 and {path}.horizontal_2")
    if one is None or two is None:
        given, missing = ("horizontal_1", "horizontal_2") if two is None else ("horizontal_2", "horizontal_1")
        ctx.fail(f"{path}.{missing}", f"missing: {path}.{given} is one of two horizontal components; give "
                 f"the other (or one component as {path}.horizontal)")
    ground["horizontal"] = one


def _pulse_checks(ground: dict, ctx: _Ctx) -> None:
    """Pulses and files do not mix (a pulse has no sampling step to share with a file), pulses are
    not scaled (the amplitude is the scale), and two pulses need a common sampling step."""
    roles = [r for r in ("horizontal", "vertical") if ground[r] is not None]
    pulses = {r: Pulse(**ground[r]) for r in roles if "pulse" in ground[r]}
    if not pulses:
        return
    if len(pulses) != len(roles):
        file_role = next(r for r in roles if r not in pulses)
        pulse_role = next(iter(pulses))
        ctx.fail(f"ground.{file_role}", f"is a record file while ground.{pulse_role} is a pulse: give "
                 "both as pulses or both as files")
    scale = ground["scale"]
    given = [k for k in ("pga_horizontal", "factor", "pga_vertical") if scale[k] is not None]
    if scale["vertical_factor"] != 1.0:
        given.append("vertical_factor")
    if given:
        ctx.fail(f"ground.scale.{given[0]}", "scales record files; a pulse is scaled by its amplitude "
                 f"(ground.{next(iter(pulses))}.amplitude)")
    if len(pulses) == 2:
        try:
            common_intervals([p.length for p in pulses.values()])
        except ValueError as exc:
            ctx.fail("ground.vertical", f"the horizontal and vertical pulses do not share a sampling grid: {exc}")


def _build(data, *, source: str, base_dir: Path | None, text: str, si_numbers: bool = False) -> Case:
    ctx = _Ctx(source, si_numbers, base_dir)
    if data is None:
        ctx.fail(None, f"the case file is empty (expected a mapping with keys: {', '.join(CASE_KEYS)})")
    if not isinstance(data, Mapping):
        ctx.fail(None, f"the top level must be a mapping (keys: {', '.join(CASE_KEYS)}), "
                 f"got {_show(data)}")
    raw = _read_mapping(data, CASE_KEYS, "", ctx, "a mapping")
    _cross_checks(raw, ctx)
    ground = raw["ground"]
    records = {k: None if ground[k] is None else (Pulse if "pulse" in ground[k] else RecordSpec)(**ground[k])
               for k in ("horizontal", "vertical", "horizontal_2")}
    solver = raw["solver"]
    tolerance = solver.pop("tolerance")
    auto = solver["dt"] == "auto"
    solver.update(dt=Solver.dt if auto else solver["dt"], auto=auto, tolerance_time=tolerance["time"],
                  tolerance_rotation=tolerance["rotation"])
    sections = {path: cls(**_at(raw, path)) for path, cls in _SECTIONS.items()}
    return Case(
        name=raw["name"], gravity=raw["gravity"], block=sections["block"],
        contact=sections["contact"],
        ground=Ground(scale=sections["ground.scale"], tail=ground["tail"],
                      time_shift=ground["time_shift"], floor=sections["ground.floor"], **records),
        initial=sections["initial"], solver=sections["solver"], output=sections["output"],
        uncertain=sections["uncertain"], source=source, base_dir=base_dir, text=text, units=ctx.units,
    )


def _at(tree: dict, path: str):
    for part in path.split("."):
        tree = tree[part]
    return tree


# --------------------------------------------------------------------------------------------------
# Changing and exporting
# --------------------------------------------------------------------------------------------------


def case_to_dict(case: Case, *, case_file: bool = True) -> dict:
    """The case as a plain nested dict of SI values, keys as in the case file.

    Keys whose value is None (not given, no default) are left out, so the dict suits HDF5
    attributes and JSON. ``load_case(case_to_dict(c))`` (and ``parse_case`` of it written as YAML)
    gives back ``c`` apart from ``text``, ``source``, ``base_dir`` and ``units``.

    Parameters
    ----------
    case : Case
    case_file : bool, optional
        Write accelerations as strings with their unit (``"9.80665 m/s^2"``, exact), as a case file
        needs them (the default); False: every value a number (SI).

    Returns
    -------
    dict
        Lengths [m], mass [kg], times [s], accelerations [m/s^2], angles [rad], rates [rad/s], [m/s].
    """
    def plain(obj) -> dict:
        return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)
                if getattr(obj, f.name) is not None}

    first = "horizontal_1" if case.ground.two_components else "horizontal"
    ground = {first: case.ground.horizontal, "horizontal_2": case.ground.horizontal_2,
              "vertical": case.ground.vertical}
    ground = {k: plain(v) for k, v in ground.items() if v is not None}
    ground.update(scale=plain(case.ground.scale), tail=case.ground.tail,
                  time_shift=case.ground.time_shift)
    floor = case.ground.floor
    if floor.given:
        ground["floor"] = {key: [plain(mode) for mode in modes] for key, modes in
                           (("horizontal", floor.horizontal), ("vertical", floor.vertical)) if modes}
        if floor.z_over_h is not None:
            ground["floor"]["z_over_h"] = floor.z_over_h
    out = {
        "name": case.name,
        "gravity": case.gravity,
        "block": _block_dict(case.block),
        "contact": plain(case.contact),
        "ground": ground,
        "initial": plain(case.initial),
        "solver": solver_dict(case.solver),
        "output": plain(case.output),
    }
    uncertain = {name: d.spec() for name, d in case.uncertain.given().items()}
    if uncertain:
        out["uncertain"] = uncertain
    if case_file:
        for path, spec in iter_case_keys():
            *parents, leaf = path.split(".")
            node = out
            for part in parents:
                node = node.get(part) if isinstance(node, dict) else None
            needs_unit = spec["type"] in UNIT_REQUIRED or spec.get("needs_unit")
            if spec.get("quantity") and isinstance(node, dict) and node.get(leaf) is not None:
                node[leaf] = _with_si_units(node[leaf], SI_UNIT[spec["quantity"]])
            elif needs_unit and isinstance(node, dict) and node.get(leaf) is not None:
                node[leaf] = f"{node[leaf]!r} {SI_UNIT[spec['type']]}"
    return out


def _block_dict(block: Block) -> dict:
    """The block's keys as a case file gives them: a body (``half_widths``) by its centre of mass's
    height and half widths, not by the bounding rectangle its `Block` also holds."""
    out = {f.name: getattr(block, f.name) for f in dataclasses.fields(block) if getattr(block, f.name) is not None}
    if block.mesh is not None:          # the body is the mesh's: derived again when read
        for key in ("height", "width", "centre_of_mass_height", "half_widths", "radius_of_gyration"):
            out.pop(key, None)
        if block.density is not None:
            out.pop("mass")
        return out
    if block.centre_of_mass_height is not None:
        out.pop("height")
    if block.half_widths is not None:
        out.pop("width")
        out["half_widths"] = list(block.half_widths)
    return out


def solver_dict(solver: Solver) -> dict:
    """The solver section as the case file writes it (``dt: auto``, ``tolerance: {time, rotation}``)."""
    return {"dt": "auto" if solver.auto else solver.dt, "events": solver.events, "method": solver.method,
            "tolerance": {"time": solver.tolerance_time, "rotation": solver.tolerance_rotation}}


def _with_si_units(value, unit: str):
    """A distribution as the case file writes it (`Distribution.spec`) with each number as a string
    with its SI unit (``{"uniform": ["0.0 rad", "3.14 rad"]}``)."""
    if isinstance(value, dict):
        return {k: _with_si_units(v, unit) for k, v in value.items()}
    if isinstance(value, list):
        return [_with_si_units(v, unit) for v in value]
    return f"{float(value)!r} {unit}"


def other_plane(case: Case, orientation: float) -> Case:
    """The case of a body's second plane in the screening of both planes (model-asymmetric.md
    section 9; `Block.both_planes`): a box turned to ``orientation`` [rad] with its depth as its
    width, or a mesh's body along ``orientation``."""
    if case.block.mesh is not None:
        return case_with(case, {"block.orientation": orientation})
    return case_with(case, {"block.width": case.block.depth, "block.depth": None, "block.orientation": orientation})


def case_with(case: Case, changes: Mapping[str, object]) -> Case:
    """A new case with some keys changed, validated like a parsed case file.

    Parameters
    ----------
    case : Case
        The case to start from (its SI values, :func:`case_to_dict`).
    changes : mapping of str to object
        Dotted keys and new values, e.g. ``{"contact.mu_static": 0.5, "block.width": "50 mm",
        "ground.scale.pga_horizontal": 8.0}``. Values are SI numbers (accelerations included: this
        is the Python API, where every number is SI) or strings with units; None removes a key (its
        default applies), which is how to switch between exclusive keys
        (``{"ground.scale.factor": None, "ground.scale.pga_horizontal": 8.0}``). A whole section or
        record may be given as a mapping (or a record as a file name).

    Returns
    -------
    Case
        Same ``source`` and ``base_dir``; ``text`` is the original text followed by a YAML comment
        block listing the changes (so the stored text remains the file as written; the effective
        values are those of :func:`case_to_dict`).

    Raises
    ------
    CaseError
        For an unknown key (with the nearest valid one) or an invalid resulting case; messages name
        the changed keys.

    Notes
    -----
    When ``contact.mu_static`` is changed and ``contact.mu_kinetic`` is not, and the case has
    ``mu_kinetic == mu_static`` (the default), ``mu_kinetic`` follows the new ``mu_static``. An
    explicitly different ``mu_kinetic`` is kept, and a ``mu_static`` below it is rejected.
    """
    if not isinstance(changes, Mapping):
        raise CaseError(f"expected a mapping of dotted keys to values, got {type(changes).__name__}", source="changes")
    ctx = _Ctx(case.source, si_numbers=True)
    data = case_to_dict(case, case_file=False)
    if ("contact.mu_static" in changes and "contact.mu_kinetic" not in changes
            and case.contact.mu_kinetic == case.contact.mu_static):
        data["contact"].pop("mu_kinetic", None)
    for key, value in changes.items():
        if not isinstance(key, str) or not key or not key.isprintable():
            ctx.fail(None, f"a change needs a dotted key like 'contact.mu_static', got {_show(key)}")
        _check_key_path(key, ctx)
        if isinstance(value, os.PathLike):
            value = os.fspath(value)
        parts = key.split(".")
        node = data
        for part in parts[:-1]:
            child = node.get(part)
            if isinstance(child, str):  # a record given as a file name
                child = {"file": child}
            if not isinstance(child, dict):
                child = {}
            node[part] = child
            node = child
        if value is None:
            node.pop(parts[-1], None)
        else:
            node[parts[-1]] = value
    summary = ", ".join(f"{k}={_one_line(_repr.repr(v))}" for k, v in changes.items())
    try:
        new = _build(data, source=case.source, base_dir=case.base_dir, text=case.text, si_numbers=True)
    except CaseError as exc:
        raise CaseError(f"{exc.message} (after changing {summary})", source=exc.source,
                        field=exc.field) from None
    text = case.text
    if text and not text.endswith("\n"):
        text += "\n"
    text += "# case_with changes:\n" + "".join(f"#   {k}: {_one_line(repr(v))}\n"
                                               for k, v in changes.items())
    return dataclasses.replace(new, text=text, units={**case.units, **new.units})


def _check_key_path(key: str, ctx: _Ctx) -> None:
    keys: Mapping[str, dict] | None = CASE_KEYS
    done: list[str] = []
    for part in key.split("."):
        if keys is None:
            ctx.fail(key, f"unknown key: {'.'.join(done)} has no sub-keys")
        if part not in keys:
            ctx.fail(".".join([*done, part]), f"unknown key ({_suggest(part, keys)})")
        done.append(part)
        keys = keys[part].get("keys")


# --------------------------------------------------------------------------------------------------
# Record suites (``rockslide fragility --suite``)
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SuiteEntry:
    """One record of a suite: a horizontal accelerogram, and optionally its vertical companion.

    Parameters
    ----------
    name : str
        The record's name in results (unique in its suite).
    horizontal : RecordSpec
        The horizontal record, read like a case's ``ground.horizontal``.
    vertical : RecordSpec or None
        Its vertical record, read like ``ground.vertical``.
    horizontal_2 : RecordSpec or None
        The second of two horizontal components (``horizontal`` is then the first: the suite file
        names them ``horizontal_1`` and ``horizontal_2``, read like a case's).
    orientation : float or None
        [rad] The block's orientation for this entry's runs (an entry of `with_orientations`).
    """

    name: str
    horizontal: RecordSpec
    vertical: RecordSpec | None = None
    horizontal_2: RecordSpec | None = None
    orientation: float | None = None


@dataclass(frozen=True)
class Suite:
    """A validated suite of records.

    Parameters
    ----------
    entries : tuple of SuiteEntry
        In the order of the file.
    source : str
        The suite file's name as used in messages.
    base_dir : Path or None
        The folder record files resolve against first.
    text : str
        The suite file's text.
    orientations : int
        Consecutive entries that are one record at several block orientations (`with_orientations`;
        1 otherwise): the bootstrap of a fit resamples records, each with all its orientations.
    """

    entries: tuple
    source: str = "<suite>"
    base_dir: Path | None = None
    text: str = ""
    orientations: int = 1


#: The keys of one entry of a suite file's ``records`` list (the README's suite reference).
SUITE_ENTRY_KEYS: dict[str, dict] = {
    "name": _key("string", "the record's name in results (default: the horizontal file's name "
                 "without its extension)"),
    "horizontal": _key("record", "horizontal record: a file name or a mapping, keys as "
                       "ground.horizontal (or two components, horizontal_1 and horizontal_2)",
                       keys=_RECORD_KEYS),
    "horizontal_1": _key("component", "first of two horizontal components: a file name or a mapping "
                         "with file and azimuth, keys as ground.horizontal_1", keys=_COMPONENT_KEYS),
    "horizontal_2": _key("component", "second horizontal component, 90 deg from horizontal_1",
                         keys=_COMPONENT_KEYS),
    "vertical": _key("record", "vertical record, scaled by the same factor: a file name or a "
                     "mapping, keys as ground.vertical", keys=_RECORD_KEYS),
}


def with_orientations(suite: Suite, orientations) -> Suite:
    """The suite with each entry of two horizontal components repeated at each block orientation
    [rad] (``NAME@30deg``): the runs of a fragility over orientations (``--azimuth``)."""
    entries = []
    for entry in suite.entries:
        if entry.horizontal_2 is None:
            raise CaseError(f"the record {entry.name} has one horizontal component; turning the block needs "
                            "two (horizontal_1 and horizontal_2 in the suite file)", source="azimuth")
        entries.extend(dataclasses.replace(entry, name=f"{entry.name}@{math.degrees(o):g}deg", orientation=o)
                       for o in orientations)
    return dataclasses.replace(suite, entries=tuple(entries), orientations=suite.orientations * len(orientations))


def load_suite(path) -> Suite:
    """Read and validate a suite file (YAML).

    A suite file is a mapping with one key, ``records``: a list whose items are a horizontal
    record's file name, or a mapping with :data:`SUITE_ENTRY_KEYS` (each record validated like a
    case's ``ground.horizontal``).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Suite
        With ``base_dir`` the file's (absolute) folder.

    Raises
    ------
    CaseError
        Naming the file, the entry (``records[3].horizontal.units``) and what is wrong: a missing
        or unreadable file, YAML errors, unknown keys, no records, names given twice.
    """
    p = Path(path)
    text = _read_text(p, "suite file")
    return parse_suite(text, source=str(path), base_dir=p.absolute().parent)


def parse_suite(text: str, *, source: str = "<suite>", base_dir: Path | None = None) -> Suite:
    """Validate the text of a suite file (`load_suite`)."""
    data = _load_yaml(text, source)
    ctx = _Ctx(source)
    example = "records: [{name: kobe, horizontal: {file: kobe.at2}}, ...]"
    if not isinstance(data, Mapping):
        ctx.fail(None, f"expected a mapping with the key 'records' (e.g. {example}), got {_show(data)}")
    for key in data:
        if key != "records":
            ctx.fail(_key_text(key), f"unknown key (a suite file has one key, 'records': e.g. {example})")
    items = data.get("records")
    if not isinstance(items, list) or not items:
        ctx.fail("records", f"expected a non-empty list of records (e.g. {example}), got {_show(items)}")
    entries, seen = [], {}
    for i, item in enumerate(items):
        path = f"records[{i}]"
        if isinstance(item, str):
            item = {"horizontal": item}
        raw = _read_mapping(item, SUITE_ENTRY_KEYS, path, ctx, "a file name or a mapping")
        if raw["horizontal"] is None and raw["horizontal_1"] is None and raw["horizontal_2"] is None:
            ctx.fail(f"{path}.horizontal", "missing required key (horizontal record, or two components "
                     "horizontal_1 and horizontal_2)")
        raw["block"] = {"orientation": None}
        _component_checks(raw, ctx, path)
        horizontal = RecordSpec(**raw["horizontal"])
        second = None if raw["horizontal_2"] is None else RecordSpec(**raw["horizontal_2"])
        vertical = None if raw["vertical"] is None else RecordSpec(**raw["vertical"])
        name = raw["name"] if raw["name"] is not None else _file_stem(horizontal.file)
        if name in seen:
            ctx.fail(f"{path}.name" if raw["name"] is not None else path,
                     f"the name {name!r} is also records[{seen[name]}]'s; give each record its own "
                     "'name'")
        seen[name] = i
        entries.append(SuiteEntry(name=name, horizontal=horizontal, vertical=vertical, horizontal_2=second))
    return Suite(entries=tuple(entries), source=source, base_dir=base_dir, text=text)


def _file_stem(name: str) -> str:
    """A file's name without its folder and last extension (POSIX or Windows style)."""
    base = str(name).replace("\\", "/").rstrip("/").rsplit("/", 1)[-1]
    return base.rsplit(".", 1)[0] if "." in base.strip(".") else base
