"""Accelerograms: find them, read them into SI, scale and align the two components.

`load_record` reads a file into a `Record`: float64 acceleration in [m/s^2], the sampling step
``dt`` [s], and the provenance of the samples: ``format``, ``units`` (the unit of the file's
numbers), ``path``, ``sha256`` (of the file's bytes) and ``start`` [s] (time of the first sample: 0
unless a time column says otherwise). `read_record` gives the same as an :class:`obspy.Trace`
(``stats.delta``, and the provenance in ``stats.rockslide``, an :class:`obspy.core.AttribDict`).

Supported formats (``format=None`` sniffs them in this order):

``at2``
    PEER NGA ``.AT2``: 4 header lines (units on line 3, ``NPTS``/``DT`` on line 4), then values.
``knet``
    K-NET / KiK-net ASCII (NIED), read by obspy; counts times the scale factor, mean removed.
``cosmos``
    COSMOS v1.20 (CESMD's ``.V2``/``.V2c`` building and free-field records): the first channel's
    acceleration, its station, structure type, orientation and location in ``Record.header``
    (`rockslide.io.cosmos`).
``column``
    Numbers separated by tabs, commas, semicolons and/or spaces, ``#`` comments, header lines
    before the numbers (column names with spaces and units, ``Time (s)<TAB>Acceleration (g)``; a
    line of units): a time column and an acceleration column, chosen by number or name. The unit
    of the acceleration is the header's where it states one (``g``, ``g's``, ``[gal]``,
    ``cm/s/s``...); a time column is uniform to the digits it is printed with; with ``dt`` only
    the acceleration column is read. One column is ``values``.
``values``
    All numbers in reading order, several per line allowed, after ``skip_lines`` lines; needs ``dt``.
any obspy waveform format
    ``SAC``, ``MSEED``, ...: the first and only trace, in the ``units`` given.

This is the only module of rockslide that imports obspy, and only when it needs it (K-NET, obspy's
formats, a Trace): loading obspy takes a tenth of a second, more than reading an AT2 file.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import math
import os
import re
import warnings
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import interrupts
from ..errors import CaseError, RecordError
from ..inputs import open_regular
from ..units import STANDARD_GRAVITY, unit_factor
from .files import atomic_write, expand_user

if TYPE_CHECKING:
    import obspy

RECORDS_ENV = "ROCKSLIDE_RECORDS"

#: Formats rockslide reads itself (the obspy ones are added by name).
OWN_FORMATS = ("at2", "knet", "cosmos", "column", "values")
#: obspy formats never used: reading (or even detecting) a PICKLE file unpickles it, which runs any
#: code the file holds. A record file is data, like a case file.
UNSAFE_OBSPY_FORMATS = frozenset({"PICKLE"})


@cache
def obspy_formats() -> tuple[str, ...]:
    """The waveform formats obspy reads (upper case, sorted), less `UNSAFE_OBSPY_FORMATS`."""
    from obspy.core.util.base import ENTRY_POINTS

    return tuple(sorted(set(ENTRY_POINTS["waveform"]) - UNSAFE_OBSPY_FORMATS))

#: [s] Largest sampling step read: an earthquake's acceleration has its energy at 0.1 to 20 Hz, so a
#: record needs a step of at most 0.025 s; a step above 1 s is a mistake of unit (ms written as s).
MAX_SAMPLING_STEP = 1.0
#: Largest record file read [bytes]: its size is checked before a byte is read (a 20 GB file is
#: refused at once). 1 GiB of plain numbers is 5e7 to 5e8 samples, read in about 10 bytes of memory
#: per character of the file (`_plain_values`).
MAX_RECORD_BYTES = 2**30
#: Most numbers read from text that is not plain numbers (comments, commas, a header row, several
#: columns): that reader keeps each number as a Python string first, about 400 bytes each, so this
#: bound keeps it within about 4 GB. Checked by counting before parsing.
MAX_TEXT_NUMBERS = 10**7
#: A peak above this [m/s^2] is almost certainly a unit mistake: warn.
ABSURD_PEAK = 10.0 * STANDARD_GRAVITY

_SUPPORTED = ("PEER NGA .AT2, K-NET/KiK-net ASCII, COSMOS v1.20 (.V2c), column text (time and acceleration), "
              "values text (format: values, with dt), or a waveform format obspy reads "
              "(SAC, MSEED, ...)")
_UNITS_HINT = "g, gal, m/s^2"

# A number as written in accelerograms, Fortran's .1234E-02 and 1.0D-02 included; nan and inf are
# read too, so that they can be reported as such.
# Possessive quantifiers: a token is matched once, in linear time (a token of thousands of digits
# followed by something else was scanned again from each of its digits).
_NUMBER_TEXT = r"[-+]?+(?:\d++(?:\.\d*+)?+|\.\d++)(?:[eEdD][-+]?+\d++)?+"
_NUMBER = re.compile(rf"{_NUMBER_TEXT}|[-+]?(?:nan|inf|infinity)", re.IGNORECASE)
_FIELD_SEPARATOR = re.compile(r"\s*[,;]\s*|\s+")
_AT2_NPTS = re.compile(r"\bNPTS\s*=\s*(\d{1,12})\b", re.IGNORECASE)
_AT2_DT = re.compile(rf"\bDT\s*=\s*({_NUMBER_TEXT})", re.IGNORECASE)
_AT2_OLD_STYLE = re.compile(rf"^\s*(\d{{1,12}})\s+({_NUMBER_TEXT})\s+NPTS\s*,?\s*DT\b", re.IGNORECASE)
_AT2_UNITS = re.compile(r"\bUNITS\s+OF\s+([A-Za-z/^*0-9]+)", re.IGNORECASE)


class RecordWarning(UserWarning):
    """A record that can be read but looks wrong (a peak above 10 g, most likely a unit mistake)."""


# --------------------------------------------------------------------------------------------------
# Where records are
# --------------------------------------------------------------------------------------------------

def records_dir(option: str | os.PathLike | None = None) -> Path:
    """The records directory.

    Parameters
    ----------
    option : str or path-like, optional
        The ``--records-dir`` option; wins when given (and not empty).

    Returns
    -------
    Path
        ``option``, else ``$ROCKSLIDE_RECORDS`` when set and not empty, else ``Path("records")``.
    """
    if option is not None and str(option) != "":
        return expand_user(option, source="records_dir")
    env = os.environ.get(RECORDS_ENV)
    if env:
        return expand_user(env, source=RECORDS_ENV)
    return Path("records")


def resolve_record_path(name: str, *, case_dir: Path | None, records_dir: Path,
                        source: str | None = None, field: str | None = None) -> Path:
    """Find a record file named in a case or on the command line.

    Parameters
    ----------
    name : str
        An absolute path (used as is) or a path relative to the case folder or the records folder.
    case_dir : Path or None
        The folder of the case file; looked in first.
    records_dir : Path
        The records folder (see :func:`records_dir`); looked in second.
    source, field : str, optional
        Named by the error (the case file and its key).

    Returns
    -------
    Path
        The first existing file: ``name`` if absolute, else ``case_dir / name``, else
        ``records_dir / name``.

    Raises
    ------
    RecordError
        Naming every place tried, when none is a file.
    """
    if str(name).strip() == "":
        raise RecordError("empty record name: expected a file name or path", source=source, field=field)
    path = Path(name).expanduser()
    if path.is_absolute():
        tried = [path]
    else:
        tried = [folder / path for folder in (case_dir, records_dir) if folder is not None]
    for candidate in tried:
        try:
            if candidate.exists() and not candidate.is_dir():  # a FIFO too: its reader refuses it
                return candidate
        except OSError as exc:                                 # a name too long, a folder not searchable
            shown = str(name) if len(str(name)) <= 60 else f"{str(name)[:57]}..."
            raise RecordError(f"cannot look for the record file {shown!r} in {candidate.parent}: "
                              f"{exc.strerror or exc}", source=source, field=field) from None
    places = ", ".join(str(p) for p in tried)
    raise RecordError(f"record file {str(name)!r} not found; tried: {places} "
                      f"(set --records-dir or ${RECORDS_ENV}, or give a path)", source=source, field=field)


# --------------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Context:
    """The file being read and how its errors are reported."""

    path: Path
    source: str | None
    field: str | None

    def error(self, message: str, where: str | None = None, *, cls=RecordError) -> RecordError:
        """A one-line RecordError naming the file, the place in it (``line 4``) and ``message``.

        The error keeps ``reason`` (``message``) and ``where`` for messages that quote it.
        """
        message = " ".join(message.split())
        if self.source is None:
            field = ", ".join(p for p in (self.field, where) if p) or None
            error = cls(message, source=str(self.path), field=field)
        else:
            location = ", ".join(p for p in (str(self.path), where) if p)
            error = cls(f"{location}: {message}", source=self.source, field=self.field)
        error.reason, error.where = message, where
        return error


class _Unrecognised(RecordError):
    """obspy's format detection found nothing (raised only while sniffing)."""


@dataclass(frozen=True)
class _Options:
    """The user's reading options (``None``: not given)."""

    units: str | None
    time_column: int | str | None
    column: int | str | None
    dt: float | None
    skip_lines: int


@dataclass
class _Parsed:
    """What a format reader found, before the checks common to all formats."""

    values: np.ndarray            # [m/s^2]
    dt: float                     # [s]
    units: str                    # unit of the file's numbers
    start: float = 0.0            # [s]
    lines: np.ndarray | None = None   # line number of each sample (text formats)
    stats: obspy.core.Stats | None = None   # obspy's header, kept for obspy formats


@dataclass(frozen=True)
class Record:
    """One component of an accelerogram in SI units, with its provenance (`load_record`).

    Attributes
    ----------
    data : numpy.ndarray
        float64 acceleration [m/s^2].
    dt : float
        [s] sampling step.
    start : float
        [s] time of the first sample.
    format : str
        ``at2``, ``knet``, ``column``, ``values`` or the obspy format, lower case.
    units : str
        The unit of the file's numbers.
    path : str or None
        The record file (None for a Trace made in memory, `from_trace`).
    sha256 : str or None
        Of the file's bytes.
    header : obspy.core.Stats or None
        obspy's header, for the formats obspy reads.
    """

    data: np.ndarray
    dt: float
    start: float
    format: str | None
    units: str | None
    path: str | None
    sha256: str | None
    header: obspy.core.Stats | None = None

    def trace(self) -> obspy.Trace:
        """The record as an :class:`obspy.Trace` (see `read_record`); the data are not copied."""
        import obspy
        from obspy.core import AttribDict

        trace = obspy.Trace(data=self.data, header=self.header)
        trace.stats.delta = self.dt
        trace.stats.calib = 1.0
        trace.stats.rockslide = AttribDict({"format": self.format, "units": self.units, "path": self.path,
                                            "sha256": self.sha256, "start": self.start})
        return trace

    @classmethod
    def from_trace(cls, trace: obspy.Trace) -> Record:
        """A Trace of `read_record`, or any Trace (provenance from ``stats.rockslide`` if it has
        one, else no file and a start of 0 s)."""
        meta = dict(trace.stats.get("rockslide", {}))
        return cls(data=trace.data, dt=float(trace.stats.delta), start=float(meta.get("start", 0.0)),
                   format=meta.get("format"), units=meta.get("units"), path=meta.get("path"),
                   sha256=meta.get("sha256"), header=trace.stats)

    @property
    def name(self) -> str:
        """What messages call the record: its file, else its obspy id (``NET.STA.LOC.CHA``)."""
        if self.path:
            return str(self.path)
        header = self.header or {}
        return ".".join(str(header.get(key, "")) for key in ("network", "station", "location", "channel"))


def load_record(path, *, format: str | None = None, units: str | None = None,
                time_column: int | str | None = None, column: int | str | None = None,
                dt: float | None = None, skip_lines: int = 0,
                source: str | None = None, field: str | None = None) -> Record:
    """Read an accelerogram into SI units.

    Parameters
    ----------
    path : str or path-like
        The record file.
    format : str, optional
        ``"at2"``, ``"knet"``, ``"column"``, ``"values"`` or an obspy format name (any case);
        ``None`` sniffs: AT2, K-NET, text, then obspy's own detection.
    units : str, optional
        Unit of the file's numbers (``"g"``, ``"gal"``, ``"m/s^2"``...). Required for column text,
        values and obspy formats; for AT2 and K-NET, which state their unit, it must agree.
    time_column, column : int or str, optional
        Column text: 1-based numbers, or names from the header row, of the time [s] and the
        acceleration columns. Required when the file has more than two columns; two columns are
        (time, acceleration).
    dt : float, optional
        Sampling step [s]. Required for values; for other formats it must agree with the file.
    skip_lines : int, optional
        Lines skipped at the top of a text file (column or values) before reading.
    source, field : str, optional
        What errors name (a case file and its key); by default the record file.

    Returns
    -------
    Record
        For obspy formats the samples are taken as they are in the file, times the unit factor
        (obspy's ``calib`` is not applied). obspy is imported only for K-NET and obspy's formats.

    Raises
    ------
    RecordError
        One line naming the file (and line or sample), what is wrong and what was expected.

    Warns
    -----
    RecordWarning
        When the peak is above 10 g.
    """
    path = Path(path)
    ctx = _Context(path, source, field)
    raw = _read_bytes(ctx)
    options = _Options(units, time_column, column, _check_dt_option(ctx, dt),
                       _check_skip_lines(ctx, skip_lines))
    kind = _choose_format(ctx, raw, format, options)
    with np.errstate(over="ignore", invalid="ignore"):    # a non-finite sample is reported in _finish
        parsed, kind = _parse(ctx, raw, kind, options)
    return _finish(ctx, parsed, kind, options, hashlib.sha256(raw).hexdigest())


def read_record(path, **options) -> obspy.Trace:
    """`load_record` as an :class:`obspy.Trace`: float64 data in [m/s^2], ``stats.delta`` [s],
    ``stats.calib`` 1, and ``stats.rockslide`` (``format``, ``units``, ``path``, ``sha256``,
    ``start`` [s]). The keyword ``options`` are those of `load_record`."""
    return load_record(path, **options).trace()


def _parse(ctx: _Context, raw: bytes, kind: str, options: _Options) -> tuple[_Parsed, str]:
    if kind == "at2":
        parsed = _read_at2(ctx, _decode(raw), options)
    elif kind == "knet":
        parsed = _read_knet(ctx, raw)
    elif kind == "cosmos":
        from . import cosmos

        series = cosmos.parse(_decode(raw), ctx.error)
        parsed = _Parsed(series.values * _unit_to_si(ctx, series.units, "COSMOS"), series.dt, series.units,
                         lines=series.lines, stats=series.header)
    elif kind in ("column", "values"):
        parsed, kind = _read_text(ctx, _decode(raw), options, values_only=(kind == "values"))
    elif kind == "obspy":
        parsed, kind = _read_unrecognised(ctx, raw, options)
    else:
        parsed, kind = _read_obspy(ctx, raw, options, kind)
    return parsed, kind


def record_info(path, **options) -> dict:
    """Summary of a record, for ``rockslide info RECORD``.

    Parameters
    ----------
    path : str or path-like
        The record file.
    **options
        The keyword options of :func:`read_record`.

    Returns
    -------
    dict
        ``format``, ``path``, ``npts``, ``dt`` [s], ``duration`` [s] (``npts * dt``, as PEER
        counts it), ``units`` (of the file), ``start`` [s], ``peak`` [m/s^2] (max ``|a|``),
        ``peak_gal``, ``peak_g``, ``peak_signed`` [m/s^2] (the sample at the peak, with its sign),
        ``peak_time`` [s] (its time, first one if tied), ``mean`` [m/s^2], ``sha256``; ``cosmos``:
        a COSMOS file's station, structure type, orientation and location (`io.cosmos`), else None;
        ``azimuth`` [rad]: a PEER AT2 component's azimuth from its title line (`at2_azimuth`), else
        None.
    """
    record = load_record(path, **options)
    data = record.data
    index = int(np.argmax(np.abs(data)))
    peak = float(abs(data[index]))
    dt = record.dt
    return {
        "format": record.format,
        "path": record.path,
        "npts": int(data.size),
        "dt": dt,
        "duration": (data.size - 1) * dt,      # the time the samples span, as a run applies them
        "units": record.units,
        "start": record.start,
        "peak": peak,
        "peak_gal": peak / unit_factor("gal", "acceleration"),
        "peak_g": peak / STANDARD_GRAVITY,
        "peak_signed": float(data[index]),
        "peak_time": record.start + index * dt,
        "mean": float(np.mean(data)),
        "sha256": record.sha256,
        "cosmos": dict(record.header["cosmos"]) if record.format == "cosmos" else None,
        "azimuth": at2_azimuth(record.path) if record.format == "at2" else None,
    }


def _read_bytes(ctx: _Context) -> bytes:
    if not ctx.path.exists():
        raise ctx.error("record file not found")
    if ctx.path.is_dir():
        raise ctx.error("is not a file (expected an accelerogram file)")

    def error(message, source):
        return ctx.error(message)

    try:
        with open_regular(ctx.path, what="record file", error=error, limit=MAX_RECORD_BYTES) as handle:
            raw = handle.read(MAX_RECORD_BYTES + 1)
    except OSError as exc:
        raise ctx.error(f"cannot read the file: {exc.strerror or exc}") from exc
    if len(raw) > MAX_RECORD_BYTES:
        raise ctx.error(f"the record file has more than {MAX_RECORD_BYTES} bytes; rockslide reads at most "
                        f"{MAX_RECORD_BYTES} (1 GiB)")
    if not raw.strip():
        raise ctx.error("the file is empty (no samples)")
    return raw


def _decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _check_dt_option(ctx: _Context, dt) -> float | None:
    if dt is None:
        return None
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.number)) \
            or not math.isfinite(dt) or dt <= 0:
        raise ctx.error(f"dt = {dt!r}; expected a positive sampling step in seconds")
    return float(dt)


def _check_skip_lines(ctx: _Context, skip_lines) -> int:
    if isinstance(skip_lines, bool) or not isinstance(skip_lines, (int, np.integer)) or skip_lines < 0:
        raise ctx.error(f"skip_lines = {skip_lines!r}; expected a whole number >= 0")
    return int(skip_lines)


def _choose_format(ctx: _Context, raw: bytes, format: str | None, options: _Options) -> str:
    """``"at2"``, ``"knet"``, ``"column"``, ``"values"``, an obspy name, or ``"obspy"`` (detect)."""
    if format is not None:
        name = str(format).strip()
        if name.lower() in OWN_FORMATS:
            return name.lower()
        if name.upper() in obspy_formats():
            return name.upper()
        raise ctx.error(f"unknown format {format!r}; expected one of {', '.join(OWN_FORMATS)} "
                        f"or an obspy format ({', '.join(obspy_formats())})", "format")
    first_line = raw.split(b"\n", 1)[0]
    if b"PEER NGA" in first_line.upper() or ctx.path.suffix.lower() == ".at2":
        return "at2"
    if raw.startswith(b"Origin Time"):
        return "knet"
    from . import cosmos  # here: most records are not COSMOS files

    if cosmos.looks_like_cosmos(first_line):
        return "cosmos"
    if b"\0" not in raw[:4096] and _looks_like_text_table(_decode(raw), options.skip_lines):
        return "column"
    return "obspy"


def _looks_like_text_table(text: str, skip_lines: int) -> bool:
    """Whether the first lines are numbers, after header lines (`_read_text`) whose last one has
    a field per column when there are header lines (column names)."""
    rows = list(itertools.islice(_content_lines(text, skip_lines), MAX_HEADER_LINES + 6))
    if not rows:
        return True  # only comments: the text reader says there are no samples
    header = list(itertools.takewhile(lambda row: _number(row[1][0]) is None, rows))
    data = rows[len(header):len(header) + 6]
    if not data or not all(_number(t) is not None for _, tokens in data for t in tokens):
        return False
    if not header:
        return True
    columns = len(data[0][1])
    lines = text.splitlines()
    return all(len(tokens) == columns for _, tokens in data) and any(
        len(_header_fields(lines[number - 1].split("#", 1)[0], columns)) == columns for number, _ in header)


def _reject_unused_options(ctx: _Context, kind: str, options: _Options) -> None:
    """time_column, column and skip_lines mean something for text records only."""
    if kind in ("column", "values"):
        return  # a values record refuses the column options itself
    given = (("time_column", options.time_column), ("column", options.column),
             ("skip_lines", options.skip_lines or None))
    unused = [name for name, value in given if value is not None]
    if unused:
        raise ctx.error(f"{' and '.join(unused)} only apply to text records (column or values), "
                        f"not to this {kind.upper()} record; remove them", unused[0])


def _finish(ctx: _Context, parsed: _Parsed, kind: str, options: _Options, sha256: str) -> Record:
    """Checks common to all formats, then the Record with its provenance."""
    _reject_unused_options(ctx, kind, options)
    values = np.asarray(parsed.values, dtype=np.float64)
    _require_samples(ctx, values.size)
    if not (math.isfinite(parsed.dt) and parsed.dt > 0):
        raise ctx.error(f"dt = {parsed.dt} s; expected a positive sampling step")
    if parsed.dt > MAX_SAMPLING_STEP:
        raise ctx.error(f"dt = {parsed.dt:g} s; expected a sampling step of at most {MAX_SAMPLING_STEP:g} s "
                        "(accelerograms are sampled at 50 to 1000 Hz: is the step in ms?)")
    if options.dt is not None and abs(options.dt - parsed.dt) > 1e-9 * parsed.dt:
        raise ctx.error(f"dt = {options.dt} s was given but the file's step is {parsed.dt} s; "
                        "remove dt or fix it", "dt")
    if options.units is not None and parsed.units != options.units and \
            _unit_to_si(ctx, options.units) != _unit_to_si(ctx, parsed.units):
        raise ctx.error(f"units {options.units!r} were given but the file is in {parsed.units!r}; "
                        "remove units or fix them", "units")
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        i = int(bad[0])
        where = f"line {int(parsed.lines[i])}" if parsed.lines is not None else None
        raise ctx.error(f"sample {i + 1} of {values.size} is {values[i]} (after conversion to m/s^2); "
                        "expected finite numbers", where)
    peak = float(np.max(np.abs(values)))
    if peak > ABSURD_PEAK:
        warnings.warn(f"{ctx.path}: peak acceleration {peak / STANDARD_GRAVITY:.4g} g is above 10 g "
                      f"(units {parsed.units!r}); check the units", RecordWarning, stacklevel=3)
    # the step as an obspy Trace holds it (the inverse of its sampling rate, which may differ from the
    # file's step in the last bit), as results have always been computed with it
    dt = 1.0 / (1.0 / parsed.dt)
    return Record(data=values, dt=dt, start=float(parsed.start), format=kind, units=parsed.units,
                  path=str(ctx.path), sha256=sha256, header=parsed.stats)


def _require_samples(ctx: _Context, count: int) -> None:
    if count == 0:
        raise ctx.error("the record is empty (no samples)")
    if count < 2:
        raise ctx.error(f"the record has {count} sample; expected at least 2")


def _unit_to_si(ctx: _Context, units: str | None, kind: str = "record") -> float:
    """Factor [m/s^2 per file unit]; RecordError when missing or unknown."""
    if units is None:
        stated = " (or name it in the column's header: 'Acceleration (g)')" if kind in ("column text", "values") \
            else ""
        raise ctx.error(f"give `units:` ({_UNITS_HINT}) for a {kind} record; the file does not "
                        f"say in which unit its numbers are (rockslide info: --units){stated}", "units")
    try:
        return unit_factor(str(units), "acceleration")
    except CaseError as exc:
        raise ctx.error(exc.message, "units") from None


# --------------------------------------------------------------------------------------------------
# Text: shared line handling
# --------------------------------------------------------------------------------------------------

def _number(token: str) -> float | None:
    """The float written in ``token`` (Fortran D exponent included), or None if it is not one."""
    if _NUMBER.fullmatch(token) is None:
        return None
    return float(token.replace("d", "e").replace("D", "E"))


def _content_lines(text: str, skip_lines: int = 0, first: int = 0):
    """Yield ``(line_number, tokens)`` of the lines holding data.

    Lines before ``max(skip_lines, first)`` are skipped; so are blank lines and comment lines
    (starting with ``#`` or ``;``). A ``#`` ends a line; fields are separated by commas,
    semicolons and/or whitespace (a trailing comma is ignored).
    """
    start = max(skip_lines, first)
    for number, line in enumerate(text.splitlines()[start:], start=start + 1):
        interrupts.check()                 # Ctrl-C ends the reading of a long file at once
        content = line.split("#", 1)[0].strip()
        if content.startswith(";"):
            continue
        content = content.rstrip(",").strip()
        if content:
            yield number, _FIELD_SEPARATOR.split(content) if "," in content or ";" in content \
                else content.split()


def _numbers(ctx: _Context, number: int, tokens: list[str], *, first_data: int | None = None) -> list[float]:
    """The numbers of one line; RecordError naming the line and the offending field (and, on the
    first line of numbers ``first_data``, how to skip it)."""
    values = []
    for position, token in enumerate(tokens, start=1):
        value = _number(token)
        if value is None:
            shown = repr(token) if token else "an empty field"
            hint = (f"; if the lines up to it are a header, skip them ({_fix('skip_lines', str(number))})"
                    if number == first_data else "; fix or remove the line")
            raise ctx.error(f"cannot read {shown} (field {position}) as a number{hint}", f"line {number}")
        values.append(value)
    return values


def _quick_values(rows) -> np.ndarray | None:
    """All numbers of ``rows`` in reading order, read with Python's ``float``, or None where that
    cannot be trusted. Tokens of ASCII without ``_`` or white space that ``float`` reads are
    exactly the numbers `_number` accepts, less the Fortran ``D`` exponent; such a record is read
    five times faster (the same values). Others go token by token through `_number` (the caller),
    which names the offending field."""
    tokens = [token for _, row in rows for token in row]
    text = "".join(tokens)
    if not (text.isascii() and "_" not in text and len(text.split()) <= 1):
        return None
    try:
        return np.array([float(token) for token in tokens], dtype=np.float64)
    except ValueError:
        return None


_PLAIN_CHARACTERS = b"0123456789+-.eE \t\r\n"
_WHITE_SPACE = np.array([ord(c) for c in " \t\r\n"], dtype=np.uint8)


def _token_starts(data: np.ndarray) -> np.ndarray:
    """The offsets where a white-space separated token starts in the bytes ``data``."""
    space = np.isin(data, _WHITE_SPACE)
    start = ~space
    start[1:] &= space[:-1]
    return np.flatnonzero(start)


def _plain_values(text: str, skip_lines: int, *,
                  per_line: bool = False) -> tuple[np.ndarray, np.ndarray] | None:
    """The numbers of a text of one plain number per line (several with ``per_line``; digits,
    signs, points, exponents and white space only, after ``skip_lines``), with the line number of
    each; None for any other text (the general reader then reads it and names what it cannot
    read). Linear in memory (about ten bytes per character of the file), where the general reader
    keeps each number as a Python string (about 400 bytes): a values record of 5e7 samples is read
    within about 5 GB."""
    start = 0
    for _ in range(skip_lines):
        start = text.find("\n", start) + 1
        if start == 0:
            return None
    try:
        body = text[start:].encode("ascii")
    except UnicodeEncodeError:
        return None
    if body.translate(None, _PLAIN_CHARACTERS):
        return None
    data = np.frombuffer(body, dtype=np.uint8)
    starts = _token_starts(data)
    newlines = np.flatnonzero(data == ord("\n"))
    line_of = np.searchsorted(newlines, starts)          # 0-based line of each number, after the skip
    if not per_line and np.any(np.diff(line_of) == 0):   # two numbers on a line: not this reader's
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")              # older numpy: a warning, and fewer values
            values = np.fromstring(body, dtype=np.float64, sep=" ") if starts.size else np.empty(0)
    except ValueError:                                   # "could not be read to its end"
        return None
    if values.size != starts.size:                       # a token that is not one number ("1-2", "e")
        return None
    return values, line_of + 1 + skip_lines


def _bound_text_numbers(ctx: _Context, text: str) -> None:
    """Refuse text with more than `MAX_TEXT_NUMBERS` fields before the general reader builds
    its strings (counted on the bytes, without building them)."""
    if len(text) <= MAX_TEXT_NUMBERS:                     # a field takes at least one character
        return
    count = _token_starts(np.frombuffer(text.encode("utf-8", "replace").replace(b",", b" "),
                                        dtype=np.uint8)).size
    if count > MAX_TEXT_NUMBERS:
        raise ctx.error(f"about {count:.3g} numbers in text with comments, commas, a header or several "
                        f"columns; rockslide reads at most {MAX_TEXT_NUMBERS:.0e} such numbers (write one "
                        "plain number per line, format: values with dt, to read up to "
                        f"{MAX_RECORD_BYTES} bytes)")


def _values_in_order(ctx: _Context, rows) -> tuple[np.ndarray, np.ndarray]:
    """All numbers of ``rows`` in reading order, with the line number of each (`_quick_values`
    where it can)."""
    rows = list(rows)
    quick = _quick_values(rows)
    if quick is not None:
        numbers = np.array([number for number, _ in rows], dtype=np.int64)
        return quick, np.repeat(numbers, [len(row) for _, row in rows])
    values: list[float] = []
    lines: list[int] = []
    for number, tokens in rows:
        row = _numbers(ctx, number, tokens)
        values.extend(row)
        lines.extend([number] * len(row))
    return np.array(values, dtype=np.float64), np.array(lines, dtype=np.int64)


# --------------------------------------------------------------------------------------------------
# PEER NGA AT2
# --------------------------------------------------------------------------------------------------

def _read_at2(ctx: _Context, text: str, options: _Options) -> _Parsed:
    """PEER AT2: 4 header lines (units on line 3, NPTS and DT on line 4), then values."""
    header = text.splitlines()[:4]
    if len(header) < 4:
        raise ctx.error(f"only {len(header)} line(s); a PEER AT2 file has 4 header lines, then values")
    units = _at2_units(ctx, header[2]) or options.units
    factor = _unit_to_si(ctx, units, "PEER AT2")
    npts, dt = _at2_npts_dt(ctx, header[3])
    plain = _plain_values(text, 4, per_line=True)
    values, lines = (plain[0], None) if plain is not None else (None, None)
    if values is None or not np.isfinite(values * factor).all():     # a line to be named
        _bound_text_numbers(ctx, text)
        values, lines = _values_in_order(ctx, _content_lines(text, first=4))
    if values.size != npts:
        raise ctx.error(f"header says NPTS = {npts} but the file has {values.size} values; "
                        "the record is truncated or the header is wrong", "line 4")
    return _Parsed(values * factor, dt, units, lines=lines)


def _at2_units(ctx: _Context, line: str) -> str | None:
    """The unit named on AT2 line 3 (``UNITS OF G``, ``CM/S/S``, ``CM/SEC^2``...), normalised."""
    match = _AT2_UNITS.search(line)
    if match is None:
        return None
    unit = _unit_word(match.group(1))
    if unit is None or unit[0] != "acceleration":
        raise ctx.error(f"units {match.group(1)!r} are not an acceleration unit "
                        f"({_UNITS_HINT}, cm/s/s); is this an acceleration (.AT2) record?",
                        "line 3")
    return unit[1]


_AT2_COMPONENT = re.compile(r"^[A-Za-z_-]*(\d{1,3}(?:\.\d*)?)$")


def at2_azimuth(path) -> float | None:
    """The azimuth [rad] of a PEER AT2 record's component, from the end of its title line (line 2:
    ``Kobe Japan, 1/16/1995, KJMA, 90`` or ``..., KJM090``: degrees clockwise from north); None
    when the line ends otherwise (``UP``, a vertical) or the file is not there."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(4096)
    except OSError:
        return None
    lines = _decode(head).splitlines()
    if len(lines) < 2:
        return None
    match = _AT2_COMPONENT.match(lines[1].rsplit(",", 1)[-1].strip())
    if match is None or not float(match.group(1)) <= 360.0:
        return None
    return math.radians(float(match.group(1)) % 360.0)         # 360: north, as 0 (PEER writes both)


def _at2_npts_dt(ctx: _Context, line: str) -> tuple[int, float]:
    """NPTS and DT [s] from AT2 line 4, in the PEER NGA (``NPTS=``, ``NPTS =``) or old style."""
    npts, dt = _AT2_NPTS.search(line), _AT2_DT.search(line)
    if npts and dt:
        count, step = int(npts.group(1)), _number(dt.group(1))
    elif old := _AT2_OLD_STYLE.match(line):
        count, step = int(old.group(1)), _number(old.group(2))
    else:
        raise ctx.error(f"cannot find NPTS and DT in {line.strip()[:60]!r}; expected "
                        "'NPTS=   7500, DT=   .0200 SEC' or '  4000    0.0100    NPTS, DT'", "line 4")
    if not (math.isfinite(step) and step > 0):
        raise ctx.error(f"DT = {step}; expected a positive sampling step in seconds", "line 4")
    return count, step


# --------------------------------------------------------------------------------------------------
# Column and values text
# --------------------------------------------------------------------------------------------------

def _read_text(ctx: _Context, text: str, options: _Options, *, values_only: bool) -> tuple[_Parsed, str]:
    """Column text (time and acceleration columns) or values text; returns the format found.

    Leading lines whose first field is not a number are header lines (`_header`): the last one
    with a name per column names the columns, a line of units alone (``s g g``, ``[s] [g]``) gives
    their units. With ``dt`` the time column is not read: one column, evenly spaced.
    """
    plain = _plain_values(text, options.skip_lines)
    if plain is not None:
        values, lines = plain
        if values.size:
            return _values_record(ctx, None, options, None, values=values, lines=lines), "values"
    _bound_text_numbers(ctx, text)
    rows = list(_content_lines(text, options.skip_lines))
    if not rows:
        raise ctx.error("the record is empty: no data lines (only blank or comment lines"
                        + (f" after skipping {options.skip_lines}" if options.skip_lines else "") + ")")
    if values_only:
        return _values_record(ctx, rows, options, None), "values"
    header_rows = list(itertools.takewhile(lambda row: _number(row[1][0]) is None,
                                           rows[:MAX_HEADER_LINES]))
    rows = rows[len(header_rows):]
    if not rows:
        raise ctx.error("the record is empty: a header row and no data lines" if header_rows else
                        "the record is empty: no data lines")
    if len(header_rows) == MAX_HEADER_LINES:
        raise ctx.error(f"no number in the first field of the first {MAX_HEADER_LINES} lines; expected "
                        f"a few header lines, then numbers (skip the header with {_fix('skip_lines', 'N')})",
                        f"line {header_rows[0][0]}")
    columns = len(rows[0][1])
    names, units = _header(ctx, text, header_rows, columns, rows[0][0])
    ambiguous = None
    if all(unit is None for unit in units):
        names, units, ambiguous = _comment_header(text, options.skip_lines, rows[0][0], columns, names, units)
    if ambiguous is not None and options.units is None:
        raise ctx.error(f"give `units:` ({_UNITS_HINT}) for this record (rockslide info: --units); its comment "
                        f"header is ambiguous: {ambiguous}", "units")
    if columns == 1:
        return _values_record(ctx, rows, options, units[0]), "values"
    quick = _quick_values(rows) if all(len(tokens) == columns for _, tokens in rows) else None
    if quick is not None:
        table = quick.reshape(len(rows), columns)
    else:                                 # line by line: the first fault met is the one reported
        table = []
        for number, tokens in rows:
            if len(tokens) != columns:
                raise ctx.error(f"{len(tokens)} values where line {rows[0][0]} has {columns}; column text "
                                "needs the same number of columns on every line (for several values per "
                                f"line in reading order use format: values, with dt and skip_lines)",
                                f"line {number}")
            table.append(_numbers(ctx, number, tokens, first_data=rows[0][0]))
        table = np.array(table, dtype=np.float64)
    lines = np.array([number for number, _ in rows], dtype=np.int64)
    time_index, value_index = _time_and_value_columns(ctx, options, names, units, columns)
    _require_samples(ctx, len(table))
    unit = _column_unit(ctx, options.units, units[value_index], names, value_index)
    values = table[:, value_index] * _unit_to_si(ctx, unit, "column text")
    if time_index is None:
        return _Parsed(values, options.dt, unit, lines=lines), "column"
    time_factor = 1.0
    if units[time_index] is not None and units[time_index][0] == "time":
        time_factor = unit_factor(units[time_index][1], "time")
    start, dt = _uniform_time(ctx, table[:, time_index] * time_factor,
                              [tokens[time_index] for _, tokens in rows], time_factor, lines)
    return _Parsed(values, dt, unit, start=start, lines=lines), "column"


#: Header lines read before the first line of numbers (more is not a column text file).
MAX_HEADER_LINES = 100


def _fix(key: str, value: str = "") -> str:
    """How to give a reading option, in a case file and on the command line: ``skip_lines: 3
    (--skip-lines 3)``."""
    option = "--" + key.replace("_", "-")
    return f"`{key}: {value}` ({option} {value})" if value else f"`{key}:` ({option})"


def _values_record(ctx: _Context, rows, options: _Options, stated, *, values=None, lines=None) -> _Parsed:
    """One value per sample in reading order, at the step ``dt`` given, from its ``rows`` or from
    ``values`` and ``lines`` already read; ``stated`` is the unit a header states (`_stated_unit`),
    or None."""
    if options.time_column is not None or options.column not in (None, 1, "1"):
        raise ctx.error("time_column or column was given but the file has one value per line "
                        f"(values text: give only {_fix('dt')} and units)", "column")
    if options.dt is None:
        raise ctx.error("give `dt:` (the sampling step in s) for a values record: the file has no "
                        "time column (rockslide info: --dt)", "dt")
    if values is None:
        values, lines = _values_in_order(ctx, rows)
    unit = _column_unit(ctx, options.units, stated, None, 0)
    return _Parsed(values * _unit_to_si(ctx, unit, "values"), options.dt, unit, lines=lines)


# --------------------------------------------------------------------------------------------------
# Column text: header lines, names and units
# --------------------------------------------------------------------------------------------------

_UNIT_TOKEN = re.compile(r"^[(\[{]?+[^()\[\]{}\s]++[)\]}]?+$")
_BRACKETS = "()[]{}"


def _bracketed_unit(text: str) -> tuple[int, str] | None:
    """A unit written last in a column name, in brackets (``Acceleration (g)``, ``acc [cm/s/s]``):
    ``(where its opening bracket is, the unit stripped)``, or None. String searches from the end,
    linear in the name (a regular expression took minutes on a name padded with 80 000 spaces)."""
    text = text.rstrip()
    if not text or text[-1] not in ")]}":
        return None
    opening = max(text.rfind(c) for c in "([{")
    inside = text[opening + 1:-1]
    if opening < 0 or not inside or any(c in inside for c in _BRACKETS):
        return None
    return opening, inside.strip() or inside


def _without_unit(field: str) -> str:
    """``field`` without its trailing unit in brackets, stripped (``Acc (g)`` -> ``Acc``)."""
    found = _bracketed_unit(field)
    return (field if found is None else field[:found[0]]).strip()


def _unbracketed(field: str) -> str:
    """``field`` with its trailing unit's brackets removed (``(g)`` -> ``g``)."""
    found = _bracketed_unit(field)
    return field if found is None else field[:found[0]] + found[1]


def _header(ctx: _Context, text: str, header_rows, columns: int,
            first_data: int) -> tuple[list[str] | None, list]:
    """Column names and stated units from the header lines.

    Returns
    -------
    names : list of str or None
        From the last header line with one field per column that is not a line of units.
    units : list
        Per column, ``(kind, unit)`` (`_unit_word`) from a line of units or the column's name;
        None where none is stated.
    """
    if not header_rows:
        return None, [None] * columns
    lines = text.splitlines()
    names, unit_row = None, None
    for number, _ in reversed(header_rows):
        fields = _header_fields(lines[number - 1].split("#", 1)[0], columns)
        if len(fields) != columns:
            continue
        words = [_unit_word(_unbracketed(field)) for field in fields]
        if unit_row is None and all(words) and all(_UNIT_TOKEN.match(f) for f in fields):
            unit_row = words
        elif names is None:
            names = fields
    if names is None and unit_row is None and len(header_rows) == 1:
        number, _ = header_rows[0]
        count = len(_header_fields(lines[number - 1].split("#", 1)[0], columns))
        if count > 1:
            raise ctx.error(f"the header row has {count} names but the first data line has {columns} "
                            f"values; fix the names or skip the row ({_fix('skip_lines', str(number))})",
                            f"line {number}")
    if unit_row is not None:
        return names, unit_row
    return names, [_stated_unit(name) for name in names] if names else [None] * columns


def _comment_header(text: str, skip_lines: int, first_data: int, columns: int,
                    names, units) -> tuple[list[str] | None, list, str | None]:
    """Names and units from the comment lines before the first line of numbers, for a file whose
    header lines state no unit (``# Time (s),Acceleration (g's)``, as PEER's and SLAMMER's CSV
    exports write it).

    A comment line counts when it splits into one field per column (`_header_fields`) and a field
    ends in a bracketed unit (`_bracketed_unit`): prose in a comment ("peak 0.5 g") states none.
    Comment lines that state different units make the header ambiguous: no unit is taken, and the
    third value says which lines disagree (the caller asks for ``units``).

    Returns
    -------
    names, units
        As `_header`: ``names`` kept when the header lines gave them.
    ambiguous : str or None
        The disagreement, in words, or None.
    """
    stated_lines = []
    for number, line in enumerate(text.splitlines()[skip_lines:first_data - 1], start=skip_lines + 1):
        content = line.strip().lstrip("\ufeff").strip()
        if not content.startswith("#"):
            continue
        fields = _header_fields(content.lstrip("#").split("#", 1)[0], columns)
        if len(fields) != columns:
            continue
        brackets = [_bracketed_unit(field) for field in fields]
        stated = [_unit_word(found[1]) if found else None for found in brackets]
        if any(stated):
            stated_lines.append((number, fields, stated))
    if not stated_lines:
        return names, units, None
    first, *others = stated_lines
    for other in others:
        if other[2] != first[2]:
            def said(entry):
                return " ".join(unit[1] if unit else "-" for unit in entry[2]) + f" (line {entry[0]})"
            return names, units, f"{said(first)} and {said(other)}"
    return names if names is not None else first[1], first[2], None


def _header_fields(line: str, columns: int) -> list[str]:
    """The fields of a header line: split at tabs, else semicolons, else commas, else runs of two
    spaces or more, else single spaces with a bracketed unit kept with its name
    (``Time (s) Acc (g)``); quotes around a field removed."""
    line = line.strip().rstrip(",;").strip()
    for separator in ("\t", ";", ","):
        if separator in line:
            fields = line.split(separator)
            break
    else:
        fields = re.split(r"\s{2,}", line)
        if len(fields) != columns:
            fields, depth = [], 0        # depth: brackets the last field leaves open
            for word in line.split():
                if fields and (word[0] in "([{" or depth > 0):
                    fields[-1].append(word)
                else:
                    fields.append([word])
                    depth = 0
                depth += sum(word.count(c) for c in "([{") - sum(word.count(c) for c in ")]}")
            fields = [" ".join(words) for words in fields]
    return [field.strip().strip("\"'").strip() for field in fields]


def _unit_word(word: str) -> tuple[str, str] | None:
    """``(kind, unit)`` for a unit as headers write it (``g``, ``g's``, ``gal``, ``cm/s/s``,
    ``cm/sec^2``, ``m/s²``, ``mm/s2``, ``s``, ``sec``, ``ms``): ``kind`` ``"acceleration"`` or
    ``"time"``, ``unit`` a name `rockslide.units.unit_factor` knows. None for anything else."""
    unit = word.strip().strip("\"'").lower().replace("²", "^2").replace(" ", "").replace("’", "'")
    unit = re.sub(r"sec(?:s|onds?)?\b", "s", unit)
    unit = re.sub(r"/s/s$", "/s^2", unit)
    if unit in ("g's", "gs"):
        unit = "g"
    for kind in ("acceleration", "time"):
        try:
            unit_factor(unit, kind)
        except CaseError:
            continue
        return kind, unit
    return None


def _stated_unit(name: str) -> tuple[str, str] | None:
    """The unit a column name states: in brackets at its end, else its last word
    (``Acceleration g's``, ``acc_gal``); None when it states none."""
    bracketed = _bracketed_unit(name)
    if bracketed:
        return _unit_word(bracketed[1])
    words = re.split(r"[\s_]+", name.strip())
    return _unit_word(words[-1]) if len(words) > 1 else None


def _column_unit(ctx: _Context, given: str | None, stated, names, index: int) -> str | None:
    """The unit of the acceleration column: ``units`` when given (a RecordWarning when the header
    states another), else the one the header states; None when neither says."""
    if stated is not None and stated[0] != "acceleration":
        stated = None
    if given is None:
        return None if stated is None else stated[1]
    if stated is not None and _unit_to_si(ctx, given) != unit_factor(stated[1], "acceleration"):
        column = f"column {names[index]!r}" if names else "the header"
        warnings.warn(f"{ctx.path}: {column} states {stated[1]!r} but units {given!r} were given; "
                      f"reading the numbers in {given!r} as given (remove units to use the header's)",
                      RecordWarning, stacklevel=5)
    return given


def _time_and_value_columns(ctx: _Context, options: _Options, header, units,
                            columns: int) -> tuple[int | None, int]:
    """0-based indices of the time column (None with ``dt``: not read) and of the acceleration.

    Without ``time_column``, the one column whose header states a time unit or is named ``time``
    or ``t`` is the time column.
    """
    time_spec, value_spec = options.time_column, options.column
    timed = [i for i, unit in enumerate(units) if unit is not None and unit[0] == "time"] or \
        [i for i, name in enumerate(header or ()) if name.strip().casefold() in ("time", "t")]
    if time_spec is None and options.dt is None and len(timed) == 1:
        time_spec = timed[0] + 1
    listed = f" ({', '.join(header)})" if header else ""
    numbers = f"numbers 1 to {columns}" + (" or header names" if header else "")
    if options.dt is not None:
        if time_spec is not None:
            raise ctx.error("time_column and dt were both given; dt takes the samples as evenly spaced "
                            "and does not read the time column: remove one of them", "dt")
        if value_spec is None and columns > 2:
            raise ctx.error(f"the file has {columns} columns{listed}; give the acceleration column, "
                            f"{_fix('column')}: {numbers}", "column")
        return None, _column_index(ctx, 2 if value_spec is None else value_spec, "column", header, columns)
    if columns == 2:
        time_spec = 1 if time_spec is None else time_spec
        if value_spec is None:
            value_spec = 2 if _column_index(ctx, time_spec, "time_column", header, columns) == 0 else 1
    elif time_spec is not None and value_spec is None:
        raise ctx.error(f"the file has {columns} columns{listed}; give the acceleration column, "
                        f"{_fix('column')}: {numbers}", "column")
    elif time_spec is None or value_spec is None:
        raise ctx.error(f"the file has {columns} columns{listed}; give time_column and column "
                        f"(--time-column, --column: {numbers}), or column and dt (--column, --dt: "
                        "the time column is then not read)", "column")
    time_index = _column_index(ctx, time_spec, "time_column", header, columns)
    value_index = _column_index(ctx, value_spec, "column", header, columns)
    if time_index == value_index:
        raise ctx.error(f"time_column and column are both column {time_index + 1}; "
                        "expected two different columns (--time-column, --column)", "column")
    return time_index, value_index


def _column_index(ctx: _Context, spec, what: str, header, columns: int) -> int:
    """0-based index of a column given by 1-based number or header name (the name with or without
    its bracketed unit, any case)."""
    option = "--" + what.replace("_", "-")
    if isinstance(spec, str) and not spec.strip().isdigit():
        if header is None:
            raise ctx.error(f"{what} {spec!r} is a name but the file has no header row; give a "
                            f"column number from 1 to {columns} ({option})", what)
        wanted = spec.strip()
        bare = [_without_unit(name) for name in header]
        for candidates, fold in ((header, False), (bare, False), (header, True), (bare, True)):
            found = [i for i, name in enumerate(candidates)
                     if (name.casefold() == wanted.casefold() if fold else name == wanted)]
            if found:
                return found[0]
        raise ctx.error(f"{what} {spec!r} is not a column name; the {columns} columns are "
                        f"{', '.join(header)} ({option} takes a name or a number)", what)
    if isinstance(spec, bool) or not isinstance(spec, (int, np.integer, str)):
        raise ctx.error(f"{what} = {spec!r}; expected a column number (1 to {columns}) or name", what)
    number = int(spec)
    if not 1 <= number <= columns:
        raise ctx.error(f"{what} = {spec!r} is out of range: the file has {columns} columns "
                        f"(numbers 1 to {columns}, {option})", what)
    return number - 1


# --------------------------------------------------------------------------------------------------
# Column text: the time column
# --------------------------------------------------------------------------------------------------

def _printed_exponent(token: str) -> int | None:
    """The exponent of the last printed digit of a number `_number` reads (``Decimal(token)``'s:
    ``64.43999`` -> -5, ``1.5e-3`` -> -4, ``100`` -> 0), or None for nan and inf."""
    mantissa, _, power = token.lower().replace("d", "e").partition("e")
    if not mantissa or not (mantissa[-1].isdigit() or mantissa[-1] == "."):
        return None                                               # nan, inf, infinity
    return (int(power) if power else 0) - len(mantissa.partition(".")[2])


def _significant_digits(token: str) -> int:
    """Digits printed from the first non-zero one to the last (``0.00125`` -> 3, ``0.0`` -> 0)."""
    mantissa = token.lower().replace("d", "e").partition("e")[0]
    return len("".join(c for c in mantissa if c.isdigit()).lstrip("0"))


def _printed_units(tokens: list[str]) -> np.ndarray:
    """[file unit] How far each printed time may be from the time it stands for, times 2: one unit
    of its last printed digit, or less where the column shows that the writer printed more.

    A column printed with a fixed number of decimals (``%.4f``) has that unit everywhere. A
    column printed with a fixed number of significant digits (``%g``, ``repr``) drops trailing
    zeros: ``1`` stands for 1.00000 there. So the unit of a token is at most the unit of its
    leading digit at the most significant digits the column prints (``S``), but not below the
    finest printed digit of the column (``E``); a zero has the unit of ``E``.
    """
    exponents = np.array([_printed_exponent(t) for t in tokens], dtype=np.int64)
    finest = int(exponents.min())
    if finest == int(exponents.max()):       # fixed decimals (zeros included): that unit everywhere
        return np.full(exponents.size, 10.0 ** max(-300, min(300, finest)))
    significant = np.array([_significant_digits(t) for t in tokens], dtype=np.int64)
    most = int(significant.max())
    by_digits = np.maximum(finest, exponents + significant - most)
    unit = np.where(significant == 0, finest, np.minimum(exponents, by_digits))
    return 10.0 ** np.clip(unit, -300, 300)


def _uniform_time(ctx: _Context, time: np.ndarray, tokens: list[str], factor: float,
                  lines: np.ndarray) -> tuple[float, float]:
    """Start [s] and step [s] of a time column; RecordError unless finite, increasing and uniform
    to the digits it is printed with.

    The step is ``(t[-1] - t[0]) / (n - 1)``, the span over the count. The times are uniform when
    each is within half a unit of its last printed digit (`_printed_units`), plus the uncertainty
    of the line through the first and the last time (half their units), plus ``1e-6 dt + 1e-9`` s
    of floating point, but less than ``0.45 dt`` (a missing or repeated sample moves a time by
    ``dt``); each step likewise within half the units of its two times of ``dt`` (a step off is
    named where it is, not where the drift it causes leaves the grid). A time column of a record
    sampled at 800 Hz printed to 4 decimals (0.0012, 0.0013 alternately) is uniform, the SCT 1985
    file's 64.43999 among its 0.02 s steps too.
    """
    bad = np.flatnonzero(~np.isfinite(time))
    if bad.size:
        raise ctx.error(f"time {time[bad[0]]} is not a finite number; fix or remove the line, or give "
                        f"{_fix('dt')} not to read the time column", f"line {int(lines[bad[0]])}")
    n = time.size
    with np.errstate(over="ignore", invalid="ignore"):
        steps = np.diff(time)
        dt = float((time[-1] - time[0]) / (n - 1))
        unit = _printed_units(tokens) * factor
        printed = float(np.median(unit))
        if math.isfinite(dt) and dt > 0 and printed > dt:
            raise ctx.error(f"the time column is printed to {printed:.3g} s, coarser than its step {dt:.6g} s: "
                            f"it cannot show the sampling; give {_fix('dt', f'{dt:.6g}')} not to read it",
                            "time_column")
        if not (math.isfinite(dt) and dt > 0 and np.median(steps) > 0):
            raise ctx.error("the time column does not increase; expected times in seconds, evenly spaced "
                            f"(if the samples are evenly spaced, give {_fix('dt')} not to read the time "
                            "column)", "time_column")
        # below half a step, so that a missing or repeated sample is never within the tolerance
        slack = 1e-6 * dt + 1e-9
        step_tolerance = np.minimum(0.5 * (unit[1:] + unit[:-1]) + 0.5 * (unit[0] + unit[-1]) / (n - 1),
                                    0.45 * dt) + slack
        grid = time[0] + np.arange(n) * dt
        tolerance = np.minimum(0.5 * unit + 0.5 * max(unit[0], unit[-1]), 0.45 * dt) + slack
        # a step off (a missing sample) is named where it is; a slow drift where it leaves the grid
        off_step = np.flatnonzero(~(np.abs(steps - dt) <= step_tolerance))
        off_grid = np.flatnonzero(~(np.abs(time - grid) <= tolerance))
    if off_step.size:
        i = int(off_step[0])
        problem = (f"the time step to {time[i + 1]:.9g} s is {steps[i]:.9g} s, {abs(steps[i] - dt):.3g} s off "
                   f"the uniform step {dt:.9g} s (span / intervals), beyond its printed digits "
                   f"(±{step_tolerance[i]:.2g} s)")
        line = int(lines[i + 1])
    elif off_grid.size:
        i = int(off_grid[0])
        problem = (f"time {time[i]:.9g} s is {abs(time[i] - grid[i]):.3g} s off the uniform grid (start "
                   f"{time[0]:.9g} s, step {dt:.9g} s), beyond its printed digits (±{tolerance[i]:.2g} s)")
        line = int(lines[i])
    else:
        return float(time[0]), dt
    raise ctx.error(f"{problem}: the time column must be uniform; if the samples are evenly spaced give "
                    f"{_fix('dt')} not to read it, else resample the record", f"line {line}")


# --------------------------------------------------------------------------------------------------
# obspy: K-NET and every waveform format it reads
# --------------------------------------------------------------------------------------------------

def _obspy_trace(ctx: _Context, raw: bytes, obspy_format: str | None) -> obspy.Trace:
    """The one trace of a file read by obspy (``obspy_format`` None: obspy detects it)."""
    import obspy

    detected = obspy_format is None
    if detected:
        obspy_format = _detect_obspy_format(raw)
        if obspy_format is None:
            raise ctx.error(f"unknown format; supported: {_SUPPORTED}", cls=_Unrecognised)
    try:
        stream = obspy.read(io.BytesIO(raw), format=obspy_format)
    except Exception as exc:  # obspy's readers raise anything on a file that is not theirs
        detail = f" ({type(exc).__name__}: {exc})"
        if detected:
            raise ctx.error(f"unknown format{detail}; supported: {_SUPPORTED}", cls=_Unrecognised) from exc
        raise ctx.error(f"cannot read as {obspy_format}{detail}") from exc
    if len(stream) != 1:
        raise ctx.error(f"the file has {len(stream)} traces; expected exactly one (one component per "
                        "file: split it, e.g. with obspy's Stream.select and write)")
    return stream[0]


def _detect_obspy_format(raw: bytes) -> str | None:
    """The first obspy waveform format whose detector accepts ``raw`` (obspy's own order), None if
    none does. Like ``obspy.read(format=None)``, but never tries the UNSAFE_OBSPY_FORMATS."""
    import tempfile

    from obspy.core.util.base import ENTRY_POINTS, buffered_load_entry_point

    with tempfile.TemporaryDirectory(prefix="rockslide-") as folder:
        path = os.path.join(folder, "record")
        with open(path, "wb") as file:
            file.write(raw)
        for name, entry in ENTRY_POINTS["waveform"].items():
            if name in UNSAFE_OBSPY_FORMATS:
                continue
            try:
                is_format = buffered_load_entry_point(entry.dist.name, f"obspy.plugin.waveform.{name}",
                                                      "isFormat")
                if is_format(path):
                    return name
            except Exception:  # noqa: BLE001 - a detector failing on a file that is not its format
                continue
    return None


def _read_knet(ctx: _Context, raw: bytes) -> _Parsed:
    """K-NET / KiK-net ASCII: counts times the header's scale factor, in gal, mean removed.

    obspy puts the ``Scale Factor  2000(gal)/8388608`` line into ``stats.calib`` as
    [m/s^2 per count] and leaves the counts in the data; NIED recommends removing the mean.
    """
    trace = _obspy_trace(ctx, raw, "KNET")
    if "knet" not in trace.stats:
        raise ctx.error("incomplete K-NET header (no 'Memo.' line, the last of the 17 header lines)")
    values = trace.data.astype(np.float64) * trace.stats.calib
    return _Parsed(values - values.mean(), trace.stats.delta, "gal", stats=trace.stats)


def _read_obspy(ctx: _Context, raw: bytes, options: _Options,
                obspy_format: str | None) -> tuple[_Parsed, str]:
    """Any obspy waveform format: the samples as they are, times the unit factor of ``units``."""
    trace = _obspy_trace(ctx, raw, obspy_format)
    kind = str(trace.stats.get("_format") or obspy_format).lower()
    factor = _unit_to_si(ctx, options.units, kind.upper())
    return _Parsed(trace.data.astype(np.float64) * factor, float(trace.stats.delta), options.units,
                   stats=trace.stats), kind


def _read_unrecognised(ctx: _Context, raw: bytes, options: _Options) -> tuple[_Parsed, str]:
    """Neither AT2, K-NET nor clean text: obspy's detection, then column text as a last resort.

    A text file that obspy does not know either is most likely column text with a flaw in its
    first lines: the text reader's complaint, with its line number, then goes into the message.
    """
    try:
        return _read_obspy(ctx, raw, options, None)
    except _Unrecognised:
        if b"\0" in raw[:4096]:
            raise
        try:
            return _read_text(ctx, _decode(raw), options, values_only=False)
        except RecordError as text_error:
            where = f"{text_error.where}: " if text_error.where else ""
            raise ctx.error(f"unknown format; read as column text, {where}{text_error.reason}; "
                            f"supported: {_SUPPORTED}") from None


# --------------------------------------------------------------------------------------------------
# Two components
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class GroundMotion:
    """The ground acceleration applied to the block, both components on one time grid.

    Attributes
    ----------
    dt : float
        [s] sampling step of both components.
    start : float
        [s] time of the first sample.
    horizontal, vertical : numpy.ndarray
        [m/s^2] accelerations as applied (scaled); zeros when the record is absent. Read-only.
        Samples ``(n,)``; for analytic pulses (`prepare.pulse_ground`) interval end values
        ``(2, n)`` that may jump at the samples (`rockslide.core.simulate.ground_array`).
    horizontal_factor, vertical_factor : float
        Scale factors applied to each record (1.0 when the record is absent).
    files : tuple of dict
        One dict per record given: ``role`` (``"horizontal"`` or ``"vertical"``), ``path``,
        ``sha256``, ``format``, ``units``.
    """

    dt: float
    start: float
    horizontal: np.ndarray
    vertical: np.ndarray
    horizontal_factor: float
    vertical_factor: float
    files: tuple

    def as_applied(self) -> dict:
        """The ground motion as applied, in SI: ``pga_horizontal`` and ``pga_vertical`` [m/s^2]
        (the peaks of the scaled components, 0 for an absent record), ``scale_horizontal`` and
        ``scale_vertical`` (the factors applied to each record; None for an absent record)."""
        given = {entry["role"] for entry in self.files}
        return {
            "pga_horizontal": float(np.max(np.abs(self.horizontal), initial=0.0)),
            "pga_vertical": float(np.max(np.abs(self.vertical), initial=0.0)),
            "scale_horizontal": float(self.horizontal_factor) if "horizontal" in given else None,
            "scale_vertical": float(self.vertical_factor) if "vertical" in given else None,
        }


def still_ground(dt: float) -> GroundMotion:
    """No record: one sample of still ground at t = 0, at the sampling step ``dt`` [s] (the
    solver's step, so that it integrates at exactly that step). A case's ``ground.tail`` then
    appends the free vibration."""
    return GroundMotion(dt=float(dt), start=0.0, horizontal=_frozen(np.zeros(1)),
                        vertical=_frozen(np.zeros(1)), horizontal_factor=1.0, vertical_factor=1.0,
                        files=())


def combine(horizontal: Record | obspy.Trace | None, vertical: Record | obspy.Trace | None, *,
            pga_horizontal: float | None = None, factor: float | None = None,
            pga_vertical: float | None = None, vertical_factor: float = 1.0,
            source: str | None = None, still_dt: float | None = None) -> GroundMotion:
    """Scale and align a horizontal and a vertical record (the paper's Table 1 convention).

    Parameters
    ----------
    horizontal, vertical : Record or obspy.Trace or None
        Records from `load_record` or `read_record` ([m/s^2]); at least one. Both: same ``delta``
        (relative 1e-9), number of samples and start.
    pga_horizontal : float, optional
        [m/s^2] peak to scale the horizontal to; sets the common factor ``k = pga / max|h|``.
    factor : float, optional
        The common factor ``k`` itself (exclusive with ``pga_horizontal``); default 1.
    pga_vertical : float, optional
        [m/s^2] peak to scale the vertical to, instead of ``k * vertical_factor``.
    vertical_factor : float, optional
        Extra factor of the vertical: it is multiplied by ``k * vertical_factor``, so scaling to a
        PGA keeps the record's V/H ratio (times this factor).
    source : str, optional
        What errors name (the case file).
    still_dt : float, optional
        [s] With no record at all, give the still ground sampled at this step (`still_ground`: a
        free vibration) instead of an error; the scale options must then keep their defaults.

    Returns
    -------
    GroundMotion

    Raises
    ------
    RecordError
        On conflicting options, a missing component to scale, a zero peak to scale to a PGA, or
        records that do not share one time grid (rockslide does not resample).
    """
    if horizontal is None and vertical is None:
        if still_dt is not None and pga_horizontal is None and pga_vertical is None and \
                factor is None and vertical_factor == 1.0:
            return still_ground(still_dt)
        raise RecordError("no record: give a horizontal and/or a vertical record", source=source)
    if pga_horizontal is not None and factor is not None:
        raise RecordError("give either pga_horizontal or factor, not both", source=source,
                          field="factor")
    if pga_vertical is not None and vertical_factor != 1.0:
        raise RecordError("give either pga_vertical or vertical_factor, not both", source=source,
                          field="vertical_factor")
    for name, value, positive in (("pga_horizontal", pga_horizontal, True), ("factor", factor, False),
                                  ("pga_vertical", pga_vertical, True),
                                  ("vertical_factor", vertical_factor, False)):
        _check_scale(name, value, positive, source)
    horizontal, vertical = (r if r is None or isinstance(r, Record) else Record.from_trace(r)
                            for r in (horizontal, vertical))
    if horizontal is not None and vertical is not None:
        check_same_grid(horizontal, vertical, source)
    h = None if horizontal is None else np.asarray(horizontal.data, dtype=np.float64)
    v = None if vertical is None else np.asarray(vertical.data, dtype=np.float64)

    if pga_horizontal is not None:
        if h is None:
            raise RecordError("pga_horizontal is given but there is no horizontal record to scale "
                              "(use pga_vertical for a vertical record alone)", source=source,
                              field="pga_horizontal")
        k = pga_horizontal / _peak_to_scale(horizontal, h, "pga_horizontal", source)
    else:
        k = 1.0 if factor is None else float(factor)
    if pga_vertical is not None:
        if v is None:
            raise RecordError("pga_vertical is given but there is no vertical record to scale",
                              source=source, field="pga_vertical")
        kv = pga_vertical / _peak_to_scale(vertical, v, "pga_vertical", source)
    else:
        kv = k * float(vertical_factor)

    reference = horizontal if horizontal is not None else vertical
    npts = len(reference.data)
    with np.errstate(over="ignore", invalid="ignore"):   # an overflow is refused by the run's checks
        h = None if h is None else k * h
        v = None if v is None else kv * v
    return GroundMotion(
        dt=float(reference.dt),
        start=reference.start,
        horizontal=_frozen(np.zeros(npts) if h is None else h),
        vertical=_frozen(np.zeros(npts) if v is None else v),
        horizontal_factor=1.0 if h is None else k,
        vertical_factor=1.0 if v is None else kv,
        files=tuple({"role": role, "path": record.path, "sha256": record.sha256, "format": record.format,
                     "units": record.units}
                    for role, record in (("horizontal", horizontal), ("vertical", vertical)) if record is not None),
    )


def _check_scale(name: str, value, positive: bool, source: str | None) -> None:
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
            or not math.isfinite(value) or (positive and value <= 0):
        expected = "a positive acceleration in m/s^2" if positive else "a finite number"
        raise RecordError(f"{name} = {value!r}; expected {expected}", source=source, field=name)


def check_same_grid(horizontal: Record, vertical: Record, source: str | None,
                    roles: tuple[str, str] = ("horizontal", "vertical")) -> None:
    """Refuse two records that do not share one time grid (step, length, start): rockslide does not
    resample. ``roles`` name them in the message."""
    dh, dv = float(horizontal.dt), float(vertical.dt)
    names = f"{roles[0]} {horizontal.name} and {roles[1]} {vertical.name}"
    if abs(dh - dv) > 1e-9 * max(dh, dv):
        raise RecordError(f"{names} have different dt ({dh} s and {dv} s); resample one of them "
                          "(rockslide does not resample)", source=source)
    nh, nv = len(horizontal.data), len(vertical.data)
    if nh != nv:
        raise RecordError(f"{names} have different lengths ({nh} and {nv} samples); expected the "
                          "same number of samples (cut or pad one of them)", source=source)
    sh, sv = horizontal.start, vertical.start
    if abs(sh - sv) > 1e-6 * dh:
        raise RecordError(f"{names} start at different times ({sh} s and {sv} s); expected the "
                          "same start", source=source)


def _peak_to_scale(record: Record, data: np.ndarray, option: str, source: str | None) -> float:
    peak = float(np.max(np.abs(data))) if data.size else 0.0
    if peak == 0.0:
        raise RecordError(f"the record {record.name} is all zeros: it cannot be scaled to "
                          f"{option}", source=source, field=option)
    return peak


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=np.float64)
    array.setflags(write=False)
    return array


# --------------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------------

def write_at2(path, values_g, dt: float, *, title: str, component: str, staging=None) -> Path:
    """Write accelerations [g] as a PEER NGA ``.AT2`` file (4-line header, 5 values per line).

    Used for the records the project makes itself (``records/``); ``read_record`` reads them back.
    With ``staging`` (`files.Staging`) the file is published with the rest of a set.
    """
    path = Path(path)
    values = np.asarray(values_g, dtype=np.float64)
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", f"{title}, {component}",
             "ACCELERATION TIME SERIES IN UNITS OF G", f"NPTS= {values.size:7d}, DT= {dt:9.4f} SEC,"]
    for i in range(0, values.size, 5):
        lines.append("".join(f"{v:15.7E}" for v in values[i:i + 5]))
    with atomic_write(path, overwrite=True, mode="w", what="record", staging=staging) as handle:
        handle.write("\n".join(lines) + "\n")
    return path
