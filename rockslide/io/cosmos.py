"""COSMOS strong-motion files (version 1.20), as CESMD distributes building records: ``.V2`` / ``.V2c``.

The format (COSMOS Strong Motion Data Format, ver. 1.20, COSMOS Strong Motion Programs Board,
15 August 2001; its tables of codes are kept up to date by CESMD) is text, one channel after
another, each:

1. **Text header**: line 1 names the data (``Corrected acceleration`` for a V2 record) and says
   ``(Format v01.20 with 13 text lines)``; line 5 has the network and station code after ``Code:``
   (``CE-24601``; columns 26-27 and 29-34) and the station's name after them (from column 41);
   line 9 names the channel, its orientation and its ``Location:`` in the structure; line 13 the
   values that mean "unknown" (columns 65-71, e.g. ``-999``).
2. **Integer header**: a line ``  100 Integer-header values follow on  10 lines, Format= (10I8)``
   and the values in that Fortran format. Used here (1-based, as the format numbers them):
   ``Int(1)`` the processing stage (2: V2), ``Int(2)`` the kind of series (1: acceleration),
   ``Int(3)`` its physical unit (Table 2: 2 g, 4 cm/s/s, 10 gal), ``Int(19)`` the
   station or structure type (Table 6: 5 base of building, 10 building, 11 bridge ...), ``Int(54)``
   the sensor's orientation (degrees clockwise from north, or a code of Table 11: 400 up, 500
   radial, 600 longitudinal, 601 tangential ...) and ``Int(56)`` the sensor's location index at
   the station.
3. **Real header**: ``  100 Real-header values follow on  17 lines, Format= (6F13.6)``, then the
   values. ``Real(62)`` is the sampling interval **in milliseconds** and ``Real(63)`` the series'
   length [s] (number of points times the interval).
4. **Comments**: ``    1 Comment line(s) follow, each starting with a "|":`` and those lines.
5. **Data**: ``   8000 acceleration pts, approx   40 secs, units=cm/sec2 (04), Format=(8F10.5)``,
   the values in that format, then ``End-of-data for Chan  1 acceleration``. A V2 channel goes
   on with its velocity and displacement series; only the acceleration is read.

One channel per file is read (CESMD's ``.V2c`` files hold one each); a file with more channels is
refused with the count. Pure text parsing: the caller (`records.load_record`) converts the unit and
reports errors through ``fail(message, where)``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from .. import interrupts
from ..inputs import printable

__all__ = ["PHYSICAL_UNITS", "STRUCTURE_TYPES", "ORIENTATIONS", "Series", "looks_like_cosmos", "parse"]

#: Table 2: the unit of a series, by code -> rockslide's name of that unit (accelerations only).
PHYSICAL_UNITS = {2: "g", 4: "cm/s^2", 10: "gal"}
#: Table 6 (station or structure type), the codes a building's or a free-field record carries.
STRUCTURE_TYPES = {1: "small fiberglass shelter", 2: "small prefabricated metal building",
                   3: "sensors buried or set in ground", 4: "reference station", 5: "base of building",
                   6: "free field, unspecified", 7: "ocean-bottom sensors", 8: "near-surface vault",
                   9: "underground observatory or large vault", 10: "building", 11: "bridge", 12: "dam",
                   13: "wharf", 14: "tunnel or mine adit", 15: "other lifeline structure", 20: "other structure",
                   50: "geotechnical array", 51: "other array"}
#: Table 11: orientations that are not an azimuth.
ORIENTATIONS = {400: "up", 401: "down", 402: "vertical, sense not indicated", 500: "radial, inward",
                501: "transverse, 90 deg clockwise from radial", 600: "longitudinal (relative to structure)",
                601: "tangential (relative to structure)", 700: "H1 (horizontal, azimuth unknown)",
                701: "H2 (horizontal, azimuth unknown)", 2000: "other (described in comments)"}

# Numbers of at most 9 digits (a longer one is no count of lines or values, and int() of thousands of
# digits raises); header lines are matched on their first `MAX_LINE` characters only.
_FORMAT_LINE = re.compile(r"\(Format v(?P<version>[\d.]{1,20}) with\s+(?P<lines>\d{1,9}) text lines\)", re.IGNORECASE)
_COUNT_LINE = re.compile(r"^\s*(?P<count>\d{1,9})\s+(?P<what>Integer|Real)-header values follow on\s+"
                         r"(?P<lines>\d{1,9}) lines,\s*Format\s*=\s*\((?P<format>[^)]*)\)", re.IGNORECASE)
_COMMENT_LINE = re.compile(r"^\s*(?P<count>\d{1,9})\s+Comment line", re.IGNORECASE)
_DATA_LINE = re.compile(r"^\s*(?P<count>\d{1,9})\s+(?P<what>[A-Za-z]+)\s+pts,.*?units\s*=\s*(?P<unit>[^,(]*?)\s*"
                        r"\((?P<code>\d{1,9})\)\s*,\s*Format\s*=\s*\((?P<format>[^)]*)\)", re.IGNORECASE)
_STATION = re.compile(r"Code:\s*(\w{1,2})\s*-\s*(\S+)\s+(.*)$")
_FORTRAN = re.compile(r"^\s*(?P<repeat>\d{1,9})\s*(?P<kind>[IFEDG])\s*(?P<width>\d{1,9})(?:\.\d+)?\s*$", re.IGNORECASE)
#: Characters of a header line that are read (a COSMOS line has 80).
MAX_LINE = 1000
#: Most characters one line of a block may take (values per line times their width).
MAX_LINE_WIDTH = 1000
#: ``Int(k)`` and ``Real(k)`` used (1-based).
_STAGE, _SERIES, _UNIT, _STRUCTURE, _ORIENTATION, _LOCATION = 1, 2, 3, 19, 54, 56
_DT_MS, _LENGTH = 62, 63


@dataclass
class Series:
    """The acceleration of one COSMOS channel, as the file gives it.

    Attributes
    ----------
    values : numpy.ndarray
        Samples in ``units``.
    dt : float
        [s] sampling interval (``Real(62)`` / 1000).
    units : str
        rockslide's name of the file's unit (`PHYSICAL_UNITS`).
    lines : numpy.ndarray
        1-based line of each sample.
    header : dict
        ``network``, ``station``, ``channel`` (the channel's number), ``location`` (``Int(56)``),
        and ``cosmos``: ``station_name``, ``structure_type`` (code and words), ``orientation``
        (degrees or the words of Table 11), ``location_text`` (line 9 from ``Location:``),
        ``stage`` (``Int(1)``), ``data_type`` (line 1), ``comments``.
    """

    values: np.ndarray
    dt: float
    units: str
    lines: np.ndarray
    header: dict = field(default_factory=dict)


def looks_like_cosmos(first_line: bytes) -> bool:
    """Whether a file's first line is a COSMOS text header's (``(Format v01.20 with 13 text lines)``)."""
    return _FORMAT_LINE.search(first_line[:MAX_LINE].decode("latin-1")) is not None


def _fields(line: str, width: int, count: int) -> list[str]:
    return [line[i * width:(i + 1) * width] for i in range(count)]


def _fortran(spec: str, fail, where: str) -> tuple[int, int]:
    """``(values per line, width)`` of a Fortran format such as ``10I8`` or ``8F10.5``."""
    match = _FORTRAN.match(spec)
    if match is None:
        raise fail(f"cannot read the Fortran format ({spec}); expected one such as 10I8 or 8F10.5", where)
    repeat, width = int(match.group("repeat")), int(match.group("width"))
    if not (repeat >= 1 and width >= 1 and repeat * width <= MAX_LINE_WIDTH):
        raise fail(f"the Fortran format ({spec}) gives lines of {repeat} values of {width} characters; expected "
                   f"at least one value of at least one character, at most {MAX_LINE_WIDTH} characters a line "
                   "(COSMOS lines have 80)", where)
    return repeat, width


def _block(lines: list[str], start: int, count: int, spec: str, fail, what: str, convert):
    """``count`` numbers in the fixed-width format ``spec`` from line ``start`` (0-based): the values,
    the 1-based line of each, and the index of the line after them."""
    per_line, width = _fortran(spec, fail, f"line {start}")
    n_lines = math.ceil(count / per_line) if count else 0
    if start + n_lines > len(lines):
        raise fail(f"the file ends inside the {what}: {count} values need {n_lines} lines from line {start + 1}",
                   f"line {len(lines)}")
    values, where = [], []
    for k in range(n_lines):
        interrupts.check()
        line = lines[start + k].rstrip("\r\n")
        take = min(per_line, count - k * per_line)
        for text in _fields(line.ljust(per_line * width), width, take):
            try:
                values.append(convert(text.strip().replace("D", "E").replace("d", "e")))
            except ValueError:
                raise fail(f"cannot read {text.strip()!r} as a number of the {what} (format {spec}, "
                           f"{width} characters each)", f"line {start + k + 1}") from None
            where.append(start + k + 1)
    return values, np.asarray(where), start + n_lines


def parse(text: str, fail) -> Series:
    """Read the first channel's acceleration (module notes).

    Parameters
    ----------
    text : str
        The file's text.
    fail : callable
        ``fail(message, where)`` -> the exception to raise (``where``: ``"line 14"``).

    Returns
    -------
    Series
    """
    lines = text.splitlines()
    match = _FORMAT_LINE.search(lines[0][:MAX_LINE]) if lines else None
    if match is None:
        raise fail("not a COSMOS file: line 1 does not say '(Format v01.20 with 13 text lines)'", "line 1")
    n_text = int(match.group("lines"))
    if len(lines) <= n_text:
        raise fail(f"the text header should have {n_text} lines (line 1 says so), the file has {len(lines)}",
                   f"line {len(lines)}")
    unknown = _unknown(lines[min(12, n_text - 1)])
    ints, at = _header(lines, n_text, "Integer", fail, int)
    reals, at = _header(lines, at, "Real", fail, float)
    comment = _COMMENT_LINE.match(lines[at][:MAX_LINE]) if at < len(lines) else None
    if comment is None:
        raise fail("expected the comment count ('   1 Comment line(s) follow, each starting with a \"|\":')",
                   f"line {at + 1}")
    comments = [line.lstrip("|").strip() for line in lines[at + 1:at + 1 + int(comment.group("count"))]]
    at += 1 + int(comment.group("count"))
    data = _DATA_LINE.match(lines[at][:MAX_LINE]) if at < len(lines) else None
    if data is None:
        raise fail("expected the data line ('   8000 acceleration pts, approx   40 secs, units=cm/sec2 (04), "
                   "Format=(8F10.5)')", f"line {at + 1}")
    if data.group("what").lower() != "acceleration":
        raise fail(f"the first series is {data.group('what')}; rockslide reads acceleration", f"line {at + 1}")
    code = int(data.group("code"))
    if code not in PHYSICAL_UNITS:
        raise fail(f"the acceleration's unit code is {code} ({data.group('unit').strip()}); expected one of "
                   + ", ".join(f"{k} ({v})" for k, v in PHYSICAL_UNITS.items()), f"line {at + 1}")
    dt_ms = _value(reals, _DT_MS, unknown)
    if dt_ms is None or not dt_ms > 0:
        given = reals[_DT_MS - 1] if len(reals) >= _DT_MS else "missing"
        raise fail(f"Real({_DT_MS}), the sampling interval in ms, is {given}; expected a positive number",
                   f"line {n_text + 2}")
    count = int(data.group("count"))
    values, where, end = _block(lines, at + 1, count, data.group("format"), fail, "acceleration", float)
    more = sum(1 for line in lines[end:] if _FORMAT_LINE.search(line[:MAX_LINE]) and "acceleration" in line.lower())
    if more:
        raise fail(f"the file holds {more + 1} channels; rockslide reads one channel per file (CESMD's .V2c "
                   "files): split it", f"line {end + 1}")
    return Series(values=np.asarray(values, dtype=np.float64), dt=dt_ms / 1000.0, units=PHYSICAL_UNITS[code],
                  lines=where, header=_metadata(lines, ints, unknown, comments))


def _unknown(line: str) -> int | None:
    """The integer that means 'unknown' (line 13, columns 65-71), if it says."""
    try:
        return int(line[64:71])
    except ValueError:
        return None


def _header(lines: list[str], at: int, what: str, fail, convert):
    match = _COUNT_LINE.match(lines[at][:MAX_LINE]) if at < len(lines) else None
    if match is None or match.group("what").lower() != what.lower():
        raise fail(f"expected the {what.lower()} header's count line ('  100 {what}-header values follow on "
                   f"  10 lines, Format= (...)')", f"line {at + 1}")
    values, _, end = _block(lines, at + 1, int(match.group("count")), match.group("format"), fail,
                            f"{what.lower()} header", convert)
    return values, end


def _value(values: list, k: int, unknown):
    """``Int(k)`` / ``Real(k)`` or None when absent or unknown."""
    if len(values) < k or (unknown is not None and values[k - 1] == unknown):
        return None
    return values[k - 1]


def _metadata(lines: list[str], ints: list[int], unknown, comments: list[str]) -> dict:
    lines = [printable(line) for line in lines[:13]]          # the text header, as it is printed
    comments = [printable(line) for line in comments]
    station_line = lines[4][:MAX_LINE] if len(lines) > 4 else ""
    channel_line = lines[8][:MAX_LINE] if len(lines) > 8 else ""
    structure = _value(ints, _STRUCTURE, unknown)
    orientation = _value(ints, _ORIENTATION, unknown)
    location = _value(ints, _LOCATION, unknown)
    channel = re.search(r"Chan\s+(\d+)", channel_line)
    place = channel_line.split("Location:", 1)[1].strip() if "Location:" in channel_line else ""
    code = _STATION.search(station_line)
    network, station, name = code.groups() if code else (station_line[25:27], station_line[28:34], station_line[40:])
    return {
        "network": network.strip(),
        "station": station.strip(),
        "channel": channel.group(1) if channel else "",
        "location": "" if location is None else str(location),
        "cosmos": {
            "data_type": lines[0][:25].strip(),
            "stage": _value(ints, _STAGE, unknown),
            "series": _value(ints, _SERIES, unknown),
            "station_name": name.strip(),
            "structure_type": None if structure is None else
            f"{structure} ({STRUCTURE_TYPES.get(structure, 'not in Table 6')})",
            "orientation": None if orientation is None else (
                f"{orientation} deg" if 0 <= orientation <= 360 else ORIENTATIONS.get(orientation, str(orientation))),
            "location_text": place,
            "comments": "\n".join(comments),
        },
    }
