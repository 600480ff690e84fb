"""Hazard curves (``rockslide risk --hazard``): OpenQuake's CSV export and plain two-column tables.

**OpenQuake engine** (``oq export hcurves``: ``hazard_curve-<kind>-<IMT>_<calc>.csv``; the
engine's manual, "Outputs from Classical PSHA")::

    #,,,,,"generated_by='OpenQuake engine 3.18.0', start_date=..., kind='mean', investigation_time=1.0, imt='PGA'"
    lon,lat,depth,poe-0.1000000,poe-0.4000000,poe-0.6000000
    0.00000,0.00000,-0.10000,4.553860E-01,5.754042E-02,6.354511E-03

One comment line (``kind``: ``mean``, ``quantile-0.15``, ``rlz-003``...; ``investigation_time``
[yr]; ``imt``: ``PGA``, ``PGV``, ``SA(0.3)``), a header whose columns after ``lon,lat,depth`` are
``poe-<IML>``, and one row per site of probabilities of exceedance in the investigation time. The
annual rate is ``-ln(1 - PoE) / T`` (the engine's Poisson assumption). OpenQuake's IMLs are in g
for PGA and SA, in cm/s for PGV.

**Plain table**: two columns, the IM level and the annual rate of exceedance [1/yr], comma,
semicolon, tab or white-space separated; ``#`` comments; an optional header whose first cell may
name the measure and its unit in brackets or parentheses (``PGA [g]``, ``sa(0.3s) [g]``, ``pgv
(cm/s)``, in a line like ``PGA [g] rate``); without a unit in the header the levels are in
OpenQuake's units (g, or cm/s for PGV).

A curve that names its measure is of the component its ground-motion models define (RotD50 for
NGA-West2): `matching` takes a RotD50 fragility for it, refuses a RotD100 one, and
`component_note` states the condition.

Every curve read is checked (`curve_problem`): two levels or more, increasing; rates positive and
not increasing; PoE strictly between 0 and 1 (with ``trim``, after leaving out PoE 1 at the low end
and 0 at the high end). A problem is one `CaseError` naming the file, the
row or column, and what would work.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .. import interrupts
from ..errors import CaseError
from ..inputs import open_regular, printable
from ..units import STANDARD_GRAVITY, unit_factor

#: OpenQuake's units of intensity measure levels, by kind of measure [their size in SI].
OPENQUAKE_UNITS = {"acceleration": ("g", STANDARD_GRAVITY), "velocity": ("cm/s", 0.01)}
#: Relative tolerance of two spectral periods that are the same period.
PERIOD_TOLERANCE = 1e-6
#: The range of intensity levels and rates a curve may hold (in its unit and in SI): the power laws
#: between levels stay within floating point (a level near 1e308 overflowed, a denormal one gave
#: the logarithm of zero).
LEVEL_RANGE = (1e-100, 1e100)
#: Largest hazard file read [bytes] (a national model's export for thousands of sites is < 100 MB).
MAX_BYTES = 200 * 2**20
#: Most levels of one hazard curve (OpenQuake's have tens; 2 million levels took 18 s and 0.7 GB).
MAX_LEVELS = 10_000

# Every pattern here matches in time linear in its text: possessive quantifiers (``*+``, ``++``)
# never give back what they took, and a key starts a word (``(?<!\w)``), so that no text is scanned
# again from each of its characters (a comment with an 80 000-character word, ``SA(`` and 20 000
# spaces, a header cell padded with 80 000 spaces each took minutes).
_IMT = re.compile(r"^\s*+(?P<name>pga|pgv|sa)\s*+(?:\((?P<period>[^()]*+)\))?+\s*+$", re.IGNORECASE)
_FIELD = re.compile(r"(?<!\w)(\w++)\s*+=\s*+('[^']*+'|\"[^\"]*+\"|[^,\s\"]++)")
#: A header cell in a white-space separated line: a word and the groups in brackets or parentheses
#: that follow it (``sa (0.3 s) [g]`` is one cell).
_SPACED_CELL = re.compile(r"[^\s,;\[\]()]++(?:\s*+(?:\[[^\[\]]*+\]|\([^()]*+\)))*+")


@dataclass(frozen=True)
class Measure:
    """An intensity measure as a hazard curve names it: ``pga``, ``pgv`` or ``sa`` with its
    ``period`` [s]."""

    name: str
    period: float | None = None

    @property
    def kind(self) -> str:
        return "velocity" if self.name == "pgv" else "acceleration"

    def __str__(self) -> str:
        return f"SA({self.period:g})" if self.name == "sa" else self.name.upper()

    def same_as(self, name: str, period: float | None) -> bool:
        """Whether this is the measure a fragility names ``name`` (``pga``, ``pgv``, ``sa(0.3 s)``)
        with ``period`` [s]."""
        if self.name == "sa":
            return period is not None and abs(self.period - period) <= PERIOD_TOLERANCE * period
        return period is None and name == self.name


@dataclass(frozen=True)
class HazardTable:
    """One hazard curve read from a file.

    Attributes
    ----------
    name : str
        Which curve: the file's ``kind`` and the site (``mean at 12.5,41.9``), or the file's name.
    measure : Measure
    levels : numpy.ndarray
        [SI: m/s^2 or m/s] the intensity levels, increasing.
    rates : numpy.ndarray
        [1/yr] the annual rates of exceedance.
    source : str
        The file.
    kind : str
        OpenQuake's ``kind`` (``mean``, ``quantile-0.15``, ``rlz-000``); "" for a plain table.
    investigation_time : float
        [yr] OpenQuake's; NaN for a plain table.
    site : tuple of float
        (lon, lat, depth) for OpenQuake's; NaNs for a plain table.
    level_units : str or None
        None when ``levels`` are SI; else the unit a plain table's levels are in ("": not said,
        OpenQuake's), converted by `matching`.
    dropped_low, dropped_high : tuple of float
        [as ``levels``] the levels `read_hazard` left out with ``trim``: at the low end where the
        PoE is 1 (an infinite rate), at the high end where it is 0.
    """

    name: str
    measure: Measure
    levels: np.ndarray
    rates: np.ndarray
    source: str
    kind: str = ""
    investigation_time: float = math.nan
    site: tuple = (math.nan, math.nan, math.nan)
    level_units: str | None = None
    dropped_low: tuple = ()
    dropped_high: tuple = ()


def parse_measure(text: str, *, source: str, field: str | None = None) -> Measure:
    """``PGA``, ``PGV``, ``SA(0.3)`` (OpenQuake) or ``sa(0.3s)`` (rockslide) as a `Measure`."""
    match = _IMT.match(str(text))
    if match is None or (match.group("name").lower() == "sa") != (match.group("period") is not None):
        raise CaseError(f"unknown intensity measure {text!r}; a hazard curve's is PGA, PGV or SA(T) with T in s",
                        source=source, field=field)
    name = match.group("name").lower()
    if name != "sa":
        return Measure(name)
    period_text = match.group("period").strip()
    period_text = period_text[:-1].strip() if period_text.endswith("s") and not period_text.endswith("ms") \
        else period_text
    try:
        period = float(period_text) if not period_text.endswith("ms") else float(period_text[:-2]) * 1e-3
    except ValueError:
        raise CaseError(f"cannot read the period of {text!r}", source=source, field=field) from None
    if not (math.isfinite(period) and period > 0):
        raise CaseError(f"the period of {text!r} must be positive", source=source, field=field)
    return Measure("sa", period)


def rate_from_poe(poe, investigation_time: float) -> np.ndarray:
    """Annual rate [1/yr] from probabilities of exceedance in ``investigation_time`` [yr] (a Poisson
    process, as OpenQuake computes them): ``-ln(1 - PoE) / T``."""
    return -np.log1p(-np.asarray(poe, dtype=np.float64)) / investigation_time


def curve_problem(levels, rates) -> str:
    """Why ``levels`` and ``rates`` are not a hazard curve, or "" when they are: two levels or more,
    positive and increasing; rates positive, finite and not increasing."""
    levels, rates = np.asarray(levels, dtype=np.float64), np.asarray(rates, dtype=np.float64)
    if levels.size < 2:
        return (f"{levels.size} intensity level(s); a hazard curve needs two or more to interpolate "
                "between")
    if not (np.isfinite(levels).all() and (levels > 0).all()):
        return "the intensity levels must be positive numbers"
    if not ((levels >= LEVEL_RANGE[0]) & (levels <= LEVEL_RANGE[1])).all():
        return (f"the intensity levels must lie between {LEVEL_RANGE[0]:g} and {LEVEL_RANGE[1]:g} (got "
                f"{levels.min():g} ... {levels.max():g}): their logarithms and powers stay finite")
    if not (np.diff(levels) > 0).all():
        i = int(np.argmax(np.diff(levels) <= 0))
        return f"the intensity levels must increase ({levels[i]:g} is followed by {levels[i + 1]:g})"
    if not (np.isfinite(rates).all() and (rates >= LEVEL_RANGE[0]) & (rates <= LEVEL_RANGE[1])).all():
        i = int(np.argmax(~(np.isfinite(rates) & (rates >= LEVEL_RANGE[0]) & (rates <= LEVEL_RANGE[1]))))
        return (f"the rate at level {levels[i]:g} is {rates[i]:g}: rates must be positive and finite (a rate "
                "of 0 has no logarithm to interpolate; leave out the levels where it is 0)")
    if (np.diff(rates) > 0).any():
        i = int(np.argmax(np.diff(rates) > 0))
        return (f"not monotonic: the rate of exceeding {levels[i + 1]:g} is larger than that of exceeding "
                f"{levels[i]:g} ({rates[i + 1]:.4g} > {rates[i]:.4g} /yr)")
    return ""


def read_hazard(path, *, units: str | None = None, trim: bool = False) -> list[HazardTable]:
    """The hazard curves of a file: OpenQuake's CSV export (one per site), or a plain table (one).

    Parameters
    ----------
    path : str or Path
    units : str, optional
        The unit of a plain table's levels when its header does not say (``g``, ``gal``, ``cm/s``);
        default OpenQuake's (g, or cm/s for PGV).
    trim : bool
        Leave out the levels at each end of a curve where its PoE has no rate to interpolate: at
        the low end those where it is 1 (an infinite rate: OpenQuake writes ``1.000000E+00`` there
        for long investigation times; in a plain table a rate ``inf``), at the high end those
        where it is 0 (below OpenQuake's precision; in a plain table a rate of 0). The rate is then
        a lower bound, and says by how much at most; the levels left out are in ``dropped_low`` and
        ``dropped_high``. A 1 or a 0 between other values is refused still.

    Raises
    ------
    CaseError
        The file is missing, unreadable, or not a hazard curve (the message names the row or
        column and why).
    """
    source = str(path)
    try:                  # a regular file only (a FIFO or a device could block), bounded before reading
        with open_regular(path, what="hazard curve file", error=CaseError, limit=MAX_BYTES) as handle:
            text = handle.read(MAX_BYTES).decode("utf-8-sig")
    except UnicodeDecodeError:
        raise CaseError("not a text file (expected a CSV hazard curve: OpenQuake's export or two columns of "
                        "level and annual rate)", source=source) from None
    except OSError as exc:
        raise CaseError(f"cannot read the file: {exc.strerror or exc}", source=source) from None
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    filled = [line.strip() for line in lines if line.strip()][:2]
    if filled and filled[0].startswith("#") and ("investigation_time" in filled[0] or "imt=" in filled[0]
                                                 or filled[-1].replace(" ", "").startswith("lon,lat,")):
        return _read_openquake(lines, source, trim)
    return _read_plain(lines, source, units, trim)


def _kept(values: np.ndarray, infinite: float) -> slice:
    """The values to keep of a curve trimmed at its ends: all but those equal to ``infinite`` (the
    value of an infinite rate: a PoE of 1) at the start and the zeros at the end."""
    finite = np.flatnonzero(values != infinite)
    first = int(finite[0]) if finite.size else values.size
    nonzero = np.flatnonzero(values != 0)
    return slice(first, max(first, int(nonzero[-1]) + 1 if nonzero.size else 0))


def _read_openquake(lines: list[str], source: str, trim: bool) -> list[HazardTable]:
    numbered = [(n, line) for n, line in enumerate(lines, 1) if line.strip()]
    (_, comment), rest = numbered[0], numbered[1:]
    fields = {key: printable(value.strip("'\"")) for key, value in _FIELD.findall(comment)}
    for key in ("investigation_time", "imt"):
        if key not in fields:
            raise CaseError(f"the comment line has no {key}=... (OpenQuake's hazard curve export states it)",
                            source=source, field="line 1")
    try:
        years = float(fields["investigation_time"])
    except ValueError:
        years = math.nan
    if not (math.isfinite(years) and years > 0):
        raise CaseError(f"investigation_time={fields['investigation_time']!r} is not a positive number of years",
                        source=source, field="line 1")
    measure = parse_measure(fields["imt"], source=source, field="imt")
    kind = fields.get("kind", "")
    if not rest:
        raise CaseError("no header line 'lon,lat,depth,poe-<level>,...' after the comment line", source=source)
    header_line, header = rest[0]
    columns = [c.strip() for c in header.split(",")]
    if columns[:2] != ["lon", "lat"]:
        raise CaseError(f"expected the header 'lon,lat,depth,poe-<level>,...', got {header.strip()[:60]!r}",
                        source=source, field=f"line {header_line}")
    first_poe = 3 if len(columns) > 2 and columns[2] == "depth" else 2
    level_columns = columns[first_poe:]
    if len(level_columns) > MAX_LEVELS:
        raise CaseError(f"{len(level_columns)} levels in each hazard curve; at most {MAX_LEVELS} (OpenQuake's have "
                        "tens)", source=source, field=f"line {header_line}")
    levels = []
    for column in level_columns:
        if not column.startswith("poe-"):
            raise CaseError(f"column {column!r} is not poe-<level>", source=source, field=f"line {header_line}")
        try:
            levels.append(float(column[4:]))
        except ValueError:
            raise CaseError(f"cannot read the level of column {column!r}", source=source,
                            field=f"line {header_line}") from None
    display_unit, scale = OPENQUAKE_UNITS[measure.kind]
    curves = []
    for line_number, line in rest[1:]:
        interrupts.check()                 # Ctrl-C ends the reading of a long file at once
        where = f"line {line_number}"
        cells = [c.strip() for c in line.split(",")]
        if len(cells) != len(columns):
            raise CaseError(f"{len(cells)} values, the header has {len(columns)} columns", source=source,
                            field=where)
        try:
            values = [float(c) for c in cells]
        except ValueError:
            raise CaseError(f"not numbers: {line.strip()[:60]!r}", source=source, field=where) from None
        poe = np.array(values[first_poe:])
        kept = _kept(poe, 1.0) if trim else slice(0, poe.size)
        bad = ~((poe[kept] > 0) & (poe[kept] < 1))
        if bad.any():
            i = kept.start + int(np.argmax(bad))
            raise CaseError(f"PoE {poe[i]:g} at {level_columns[i]}: a probability of exceedance must be "
                            "strictly between 0 and 1 (1 is an infinite rate, 0 has no logarithm to interpolate; "
                            "leave those levels out" + (", as --trim-poe does at the ends of a curve only)" if trim
                                                        else ", or with --trim-poe those at the ends of each "
                                                        "curve: PoE 1 at its lowest levels, 0 at its highest)"),
                            source=source, field=where)
        site = (values[0], values[1], values[2] if first_poe == 3 else math.nan)
        name = kind or "curve"
        scaled = np.array(levels) * scale
        dropped = {"dropped_low": tuple(scaled[:kept.start]), "dropped_high": tuple(scaled[kept.stop:])}
        curves.append(HazardTable(name=f"{name} at {site[0]:g},{site[1]:g}", measure=measure,
                                  levels=scaled[kept], rates=rate_from_poe(poe[kept], years),
                                  source=source, kind=kind, investigation_time=years, site=site, **dropped))
        problem = curve_problem(np.array(levels)[kept], curves[-1].rates)
        if problem:
            raise CaseError(f"{problem} (levels in {display_unit}){_trimmed(dropped)}", source=source, field=where)
    if not curves:
        raise CaseError("no site rows after the header", source=source)
    return curves


def _two_columns(lines, source: str, what: str) -> tuple[list, list | None, int]:
    """The rows of a table of two numbers a line (``#`` starts a comment), its header (the first line
    that is not numbers, before any row) and the header's line number; at most `MAX_LEVELS` rows.
    ``what`` says what the two columns are, for the message of a line of another width."""
    rows, header, header_line = [], None, 0
    for line_number, line in enumerate(lines, 1):
        interrupts.check()
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        cells = _cells(text)
        if len(cells) != 2:
            raise CaseError(f"{len(cells)} values; {what}", source=source, field=f"line {line_number}")
        if len(rows) >= MAX_LEVELS:
            raise CaseError(f"more than {MAX_LEVELS} levels in one table (OpenQuake's curves have tens): a "
                            "coarser table", source=source, field=f"line {line_number}")
        try:
            rows.append((float(cells[0]), float(cells[1])))
        except ValueError:
            if rows or header is not None:
                raise CaseError(f"not numbers: {text[:60]!r}", source=source, field=f"line {line_number}") from None
            header, header_line = cells, line_number
    return rows, header, header_line


def _read_plain(lines: list[str], source: str, units: str | None, trim: bool) -> list[HazardTable]:
    rows, header, header_line = _two_columns(lines, source, "a plain hazard curve has two columns: the IM level "
                                             "and its annual rate of exceedance [1/yr] (or give OpenQuake's export "
                                             "as written)")
    measure, unit = None, units
    if header is not None:
        name, header_unit = _header_cell(header[0])
        if _IMT.match(name):
            measure = parse_measure(name, source=source, field=f"line {header_line}")
        if header_unit:
            if units is not None and units.strip() != header_unit:
                raise CaseError(f"the header says the levels are in {header_unit}, --hazard-units says {units}",
                                source=source, field=f"line {header_line}")
            unit = header_unit
    table = np.array(rows, dtype=np.float64).reshape(-1, 2)
    kept = _kept(table[:, 1], math.inf) if trim else slice(0, len(table))
    levels, rates = table[kept, 0], table[kept, 1]
    dropped = {"dropped_low": tuple(table[:kept.start, 0]), "dropped_high": tuple(table[kept.stop:, 0])}
    return [_plain_table(source, measure, levels, rates, unit, dropped)]


def _cells(text: str) -> list[str]:
    """The cells of a plain table's line: separated by commas, semicolons or tabs, else by white
    space; a header's units in brackets or parentheses (``PGA [g] rate``, ``sa(0.3s) (g); rate``)
    stay with their cell."""
    if not re.search(r"[\[(]", text):
        return [c for c in re.split(r"[,;\s]+", text) if c]
    if re.search(r"[,;\t]", text):
        return [c.strip() for c in re.split(r"[,;\t]", text) if c.strip()]
    return _SPACED_CELL.findall(text)


def _is_measure(text: str) -> bool:
    match = _IMT.match(text)
    return match is not None and (match.group("name").lower() == "sa") == (match.group("period") is not None)


def _header_cell(cell: str) -> tuple[str, str | None]:
    """A header cell's name and unit (None: not given): ``PGA [g]``, ``PGA (g)``, ``sa(0.3s) [g]``,
    ``sa(0.3s)`` (its parentheses are the period, not a unit), ``level (cm/s)``."""
    split = _trailing_unit(cell)
    if split is None or (_is_measure(cell) and not _is_measure(split[0])):
        return cell.strip(), None
    return split


def _trailing_unit(cell: str) -> tuple[str, str] | None:
    """``(name, unit)`` of a cell that ends in a group in brackets or parentheses without brackets
    of its kind inside (``PGA [g]``, ``level (cm/s)``), both stripped; None otherwise. String
    searches from the end: linear in the cell."""
    text = cell.strip()
    pairs = {"]": "[", ")": "("}
    if not text or text[-1] not in pairs:
        return None
    opening = text.rfind(pairs[text[-1]])
    if opening < 0 or text[-1] in text[opening + 1:-1]:
        return None
    return text[:opening].strip(), text[opening + 1:-1].strip()


def _plain_table(source: str, measure: Measure | None, levels, rates, unit: str | None,
                 dropped: dict) -> HazardTable:
    """A plain table's curve; ``measure`` None (the header does not name one) is settled by
    `matching` with the fragility's; ``dropped``: its `HazardTable.dropped_low` and ``_high``."""
    problem = curve_problem(levels, rates)
    if problem:
        raise CaseError(problem + _trimmed(dropped), source=source)
    return HazardTable(name=Path(source).name, measure=measure, levels=np.asarray(levels), rates=np.asarray(rates),
                       source=source, level_units=unit or "", **dropped)


def _trimmed(dropped: dict) -> str:
    """`` (--trim-poe left out ...)`` for a message about a trimmed curve, or ""."""
    left_out = len(dropped["dropped_low"]) + len(dropped["dropped_high"])
    return f" (--trim-poe left out {left_out} levels at its ends)" if left_out else ""


def matching(table: HazardTable, im_name: str, period: float | None, kind: str, label: str, *,
             rotd: int | None = None) -> HazardTable:
    """``table`` with its levels in SI, once its measure is checked against a fragility's.

    A hazard curve that names its measure (OpenQuake's ``PGA``, ``SA(T)``, ``PGV``; a plain
    table's header) is of the horizontal component its ground-motion models define: RotD50 for the
    NGA-West2 models, the geometric mean for older ones. A fragility of RotD50 of the same measure
    (and period) matches it (`component_note` says on what condition); one of RotD100 does not.

    Parameters
    ----------
    im_name, period, kind
        The fragility's measure: ``pga``, ``pgv``, ``sa(0.3 s)``, ``rotd50_pga``...; its period [s]
        or None; the unit kind of its levels (``acceleration``, ``velocity``, ``dimensionless``).
    label : str
        The fragility's measure for messages (``PGA``, ``Sa(0.3 s, 5 %)``).
    rotd : int or None
        50 or 100 when the fragility's measure is RotD50 or RotD100 of ``im_name``'s.

    Raises
    ------
    CaseError
        The measures differ, the fragility's is RotD100, or it has no hazard curve (``pga_rocking``).
    """
    if kind not in OPENQUAKE_UNITS:
        raise CaseError(f"the fragility's intensity measure {label} is not one a hazard curve gives (PGA, PGV or "
                        "SA(T)): run 'rockslide fragility' with --im pga, pgv or sa(T)", source=table.source)
    base = im_name.split("_", 1)[1] if rotd is not None else im_name
    if table.measure is not None and not table.measure.same_as(base, period):
        raise CaseError(f"the hazard curve is of {table.measure}, the fragility of {label}: give a hazard curve of "
                        f"{label} (or a fragility computed with --im {_rockslide_name(table.measure, rotd)})",
                        source=table.source)
    if table.measure is not None and rotd == 100:
        raise CaseError(f"the hazard curve is of {table.measure}, the fragility of {label}: a hazard curve is of its "
                        "ground-motion models' component (RotD50 in NGA-West2, the geometric mean before), not "
                        f"RotD100; use a fragility with --im 'rotd50_{base.replace(' ', '')}'", source=table.source)
    if table.level_units is None:                  # OpenQuake's: levels already SI
        return table
    unit = table.level_units or OPENQUAKE_UNITS[kind][0]
    scale = unit_factor(unit, kind, source=table.source, field="level unit")
    measure = table.measure or _from_fragility(base, period)
    problem = curve_problem(table.levels * scale, table.rates)
    if problem:
        raise CaseError(f"in SI: {problem}", source=table.source)
    return replace(table, measure=measure, levels=table.levels * scale, level_units=None,
                   dropped_low=tuple(np.asarray(table.dropped_low) * scale),
                   dropped_high=tuple(np.asarray(table.dropped_high) * scale))


def component_note(label: str, *, rotd: int | None, along_block: bool) -> str:
    """The condition under which a fragility of ``label`` (RotD50, or of the motion along a block
    from two-component records) and a hazard curve that names its measure give a consistent rate
    (Baker and Cornell 2006: the fragility's and the hazard's components must be the same), or ""
    (a fragility of one component per record: no condition known to state)."""
    gmpe = ("the component its ground-motion models define (RotD50 for the NGA-West2 models, the geometric mean "
            "for older ones)")
    if rotd == 50:
        return (f"the fragility is of {label}, the hazard curve of {gmpe}: the rate is consistent only if that is "
                "RotD50; for a geometric-mean hazard, convert it to RotD50 first (e.g. Boore and Kishida 2017)")
    if along_block:
        return (f"the fragility is of {label} along the block (its records' two horizontal components turned to "
                f"the block's direction), the hazard curve of {gmpe}: the rate is consistent only as far as the "
                "motion along one direction is distributed like that component (its median is close, its scatter "
                "larger); a fragility with --im 'rotd50_...' matches it")
    return ""


def _from_fragility(im_name: str, period: float | None) -> Measure:
    return Measure("sa", period) if period is not None else Measure(im_name)


def _rockslide_name(measure: Measure, rotd: int | None = None) -> str:
    """``--im`` of ``measure`` (of its RotD50 when the fragility's is a RotD: a hazard curve's is)."""
    name = f"sa({measure.period:g}s)" if measure.name == "sa" else measure.name
    return f"'rotd50_{name}'" if rotd is not None else f"'{name}'" if measure.name == "sa" else name


def read_fragility_table(path) -> tuple[str, str, np.ndarray, np.ndarray]:
    """A tabulated fragility (``rockslide risk --fragility-table``): a plain table as a hazard curve
    is written, two columns, the IM level and the probability of reaching the damage state, with a
    header naming the measure and the levels' unit (``PGA [g], probability``; ``pgv (cm/s);
    probability``; ``sa(0.3s) [g] probability``).

    Returns
    -------
    measure, unit : str
        As the header gives them (``PGA``, ``g``).
    levels : numpy.ndarray
        As written (in ``unit``), not decreasing (a level given twice is a jump).
    probabilities : numpy.ndarray
        Within 0 ... 1, not decreasing.

    Raises
    ------
    CaseError
        Naming the file and the line: no header with a measure and a unit, not two columns, not
        numbers, levels that are not positive or fall, probabilities outside 0 ... 1 or falling.
    """
    source = str(path)
    try:
        with open_regular(path, what="fragility table", error=CaseError, limit=MAX_BYTES) as handle:
            text = handle.read(MAX_BYTES).decode("utf-8-sig")
    except UnicodeDecodeError:
        raise CaseError("not a text file (expected a CSV of level and probability)", source=source) from None
    except OSError as exc:
        raise CaseError(f"cannot read the file: {exc.strerror or exc}", source=source) from None
    rows, header, _ = _two_columns(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"), source,
                                   "a fragility table has two columns: the IM level and the probability of "
                                   "reaching the state")
    name, unit = _header_cell(header[0]) if header is not None else ("", None)
    if not _is_measure(name) or not unit:
        raise CaseError("expected a header naming the measure and the levels' unit, e.g. 'PGA [g], probability'",
                        source=source, field="line 1")
    table = np.array(rows, dtype=np.float64).reshape(-1, 2)
    levels, p = table[:, 0], table[:, 1]
    if levels.size < 2:
        raise CaseError("expected two levels or more", source=source)
    if not (np.isfinite(levels).all() and (levels > 0).all() and (np.diff(levels) >= 0).all()):
        raise CaseError("the levels must be positive and not decreasing", source=source)
    if not (np.isfinite(p).all() and (p >= 0).all() and (p <= 1).all() and (np.diff(p) >= 0).all()):
        raise CaseError("the probabilities must be within 0 and 1 and not decreasing (a fragility does not fall: "
                        "make it monotone first, e.g. rockslide fragility's isotonic curve)", source=source)
    return name, unit, levels, p
