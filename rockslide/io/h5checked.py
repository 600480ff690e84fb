"""Checked reading of HDF5 files rockslide is given: every value's kind, shape and size is checked
before it is read (h5py lives in io only).

A file handed over by someone else can declare anything: an attribute of hundreds of MB, an array
of 10^8 elements where a scalar belongs, a dataset of 10^12 elements that gzip stores in a few KB,
text where a number belongs, NaN where a scale belongs. Every reader of rockslide's files (run,
sweep, fragility and risk files: `rockslide.io.results`) reads through this module:

- `attribute_values` reads a group's or dataset's attributes: each one's stored size is bounded
  (`MAX_ATTRIBUTE_BYTES`) and its shape checked (a scalar, or a short 1-D array of numbers) before
  it is read; the attributes rockslide itself reads have a kind (`ATTRIBUTE_KINDS`: text, a finite
  number, a positive one, a count...) that is checked on the value; text is made safe to print
  (`printable`).
- `read_dataset` reads a dataset of a given dimensionality and kind whose declared size in bytes,
  added to what the file has already had read (`Budget`), stays within `MAX_READ_BYTES`: bytes,
  not elements, and declared, not stored, so that a gzip bomb is refused before a byte is
  inflated.
- What they give back is an `Entries` dict: a key a file lacks is an `OutputError` naming the file
  and the key (`MissingEntry`), never a ``KeyError`` deep in a figure.

Every failure is an `OutputError` with one line naming the file and the attribute or dataset.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np

from ..errors import OutputError
from ..inputs import printable

__all__ = ["MAX_ATTRIBUTE_BYTES", "MAX_READ_BYTES", "MAX_TEXT_ELEMENTS", "ATTRIBUTE_KINDS", "Budget", "Entries",
           "MissingEntry", "attribute_values", "read_dataset", "printable", "plain"]

#: Largest attribute read [bytes], checked before it is read (the case text, at most 64 KiB, is the
#: largest rockslide writes).
MAX_ATTRIBUTE_BYTES = 1 << 20
#: Most elements of an attribute that is an array (flag values, a dimension list).
MAX_ATTRIBUTE_ELEMENTS = 4096
#: Most bytes of values read from one file, as declared by its datasets (type size times elements):
#: 512 MiB, a run's history of 13 million rows or a sweep of 5 million points.
MAX_READ_BYTES = 1 << 29
#: Most elements of a dataset of text (names of records, damage states, curves).
MAX_TEXT_ELEMENTS = 100_000

class MissingEntry(OutputError, KeyError):
    """An attribute or dataset a file lacks (an `OutputError`, and a ``KeyError`` for code that
    looks a key up and catches that)."""

    def __str__(self) -> str:
        return OutputError.__str__(self)


class Entries(dict):
    """The attributes or datasets of a file: a key it lacks is a `MissingEntry` naming the file."""

    def __init__(self, values=(), *, source: str = "", what: str = "attribute"):
        super().__init__(values)
        self.source = source
        self.what = what

    def __missing__(self, key):
        raise MissingEntry(f"damaged rockslide file (no {self.what} {key!r})", source=self.source or None)


def _finite(v):
    return isinstance(v, float) and math.isfinite(v)


def _json(v):
    if not isinstance(v, str):
        return False
    try:
        json.loads(v)
    except ValueError:
        return False
    return True


#: Kinds of value: a test and the words of what is expected.
KINDS = {
    "text": (lambda v: isinstance(v, str), "text"),
    "number": (_finite, "a finite number"),
    "number_or_nan": (lambda v: isinstance(v, float) and not math.isinf(v), "a finite number or NaN"),
    "positive": (lambda v: _finite(v) and v > 0, "a positive finite number"),
    "step": (lambda v: _finite(v) and v > 0, "a positive step [s]"),
    "fraction": (lambda v: _finite(v) and 0 < v < 1, "a number between 0 and 1"),
    "count": (lambda v: isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 10**12,
              "a count (an integer >= 0)"),
    "integer": (lambda v: isinstance(v, int) and not isinstance(v, bool) and abs(v) <= 2**63, "an integer"),
    "direction": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v in (-1, 0, 1), "-1, 0 or 1"),
    "bool": (lambda v: isinstance(v, (bool, int)) and v in (0, 1), "true or false"),
    "json": (_json, "JSON text"),
    "numbers": (lambda v: isinstance(v, list) and all(isinstance(x, (int, float)) for x in v), "a list of numbers"),
}

_TIMES = ("overturn_time", "fall_start_time")
#: The kind of each attribute rockslide reads from its files (any file, any group); an attribute
#: named here is checked wherever it is found. Others are read as they are (bounded in size).
ATTRIBUTE_KINDS = {
    # every file
    "format": "text", "format_version": "integer", "created": "text", "name": "text", "title": "text",
    "command_line": "text", "notes": "text", "units": "text", "long_name": "text", "_Netcdf4Dimid": "count",
    "flag_values": "numbers", "flag_masks": "numbers", "flag_meanings": "text", "given_as": "text", "option": "text",
    "codes": "text", "description": "text",
    **{f"{p}_version": "text" for p in ("rockslide", "python", "numpy", "numba", "h5py", "obspy", "scipy",
                                        "matplotlib")},
    # a run's summary and provenance
    "overturned": "bool", "undecided": "bool", **{t: "number_or_nan" for t in _TIMES}, "direction": "direction",
    "max_rotation": "number", "max_rotation_time": "number", "max_slip": "number", "residual_slip": "number",
    "impacts": "count", "status": "text", "end_time": "number", "alpha": "number_or_nan", "alpha_2": "number_or_nan",
    "max_rotation_ratio": "number_or_nan", "states_seen": "text", "verdict": "text",
    "integration_step": "step", "ensemble": "json", "yaml": "text",
    "role": "text", "path": "text", "sha256": "text",
    # studies
    "case_text": "text", "case_file": "text", "suite": "text", "suite_text": "text", "axes": "text",
    "sweep_key": "text", "events": "text", "mu_kinetic_ratio": "number_or_nan", "chunk_size": "count",
    "height": "positive",
    "intensity_measure": "text", "intensity_measure_units": "text", "intensity_measure_long_name": "text",
    "intensity_measure_label": "text", "intensity_measure_display_unit": "text",
    "intensity_measure_display_scale": "positive", "confidence_level": "fraction", "bootstrap_resamples": "count",
    "bootstrap_seed": "integer", "orientations_per_record": "count", "fit_method": "text",
    "damage_state": "text", "fragility_source": "text", "fragility_form": "text", "fragility_median": "positive",
    "fragility_beta": "positive", "fragility_uncertainty": "text", "service_life": "positive",
    "integration": "text", "age": "positive",
}
_PREFIXED_KINDS = (("time_in_state_", "number"), ("energy_", "number"), ("ground_", "number_or_nan"),
                   ("record_", "text"))


def kind_of(name: str) -> str | None:
    """The kind (a key of `KINDS`) of an attribute called ``name``, or None."""
    if name in ATTRIBUTE_KINDS:
        return ATTRIBUTE_KINDS[name]
    for prefix, kind in _PREFIXED_KINDS:
        if name.startswith(prefix):
            return kind
    return None


def plain(value):
    """An attribute value as a plain Python value (numpy scalars -> Python, bytes -> str, text made
    `printable`)."""
    if isinstance(value, bytes):
        return printable(value.decode("utf-8", "replace"))
    if isinstance(value, str):
        return printable(value)
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()] if value.dtype.kind in "SUO" else value.tolist()
    if isinstance(value, np.generic):
        return plain(value.item())
    return value


def _where(obj, name: str) -> str:
    path = getattr(obj, "name", None) or "/"
    return f"attribute {name!r} of {path}"


def storage_size(attr):
    """The bytes an attribute holds: HDF5 reports an empty one's zero bytes as an error."""
    try:
        return attr.get_storage_size()
    except RuntimeError:
        return 0


def attribute_values(obj, source: str, *, skip=()) -> Entries:
    """The attributes of a group or dataset ``obj``, each bounded and checked before it is read.

    Parameters
    ----------
    obj : h5py.Group or h5py.Dataset
    source : str
        The file (for messages).
    skip : collection of str
        Attributes not read (HDF5's dimension-scale bookkeeping, which h5py reads itself): only
        their size is checked.

    Raises
    ------
    OutputError
        An attribute larger than `MAX_ATTRIBUTE_BYTES`, of more than one dimension, an array of more
        than `MAX_ATTRIBUTE_ELEMENTS` elements or of a kind rockslide does not write (references,
        compound types), or one of `ATTRIBUTE_KINDS` that is not of its kind.
    """
    out = Entries(source=source)
    for name in obj.attrs:
        try:
            attr = obj.attrs.get_id(name)
            size = storage_size(attr)
            shape = attr.shape
            dtype = attr.dtype
        except (OSError, KeyError, TypeError, ValueError) as exc:
            raise OutputError(f"damaged rockslide file ({_where(obj, name)}: {exc})", source=source) from None
        if size > MAX_ATTRIBUTE_BYTES:
            raise OutputError(f"not read: {_where(obj, name)} holds {size} bytes; rockslide reads attributes of "
                              f"at most {MAX_ATTRIBUTE_BYTES} bytes", source=source)
        count = int(np.prod(shape, dtype=object)) if shape else 1
        if name in skip:              # HDF5's own bookkeeping (read by h5py itself): bounded all the same
            if count > MAX_ATTRIBUTE_ELEMENTS:
                raise OutputError(f"not read: {_where(obj, name)} has {count} elements", source=source)
            continue
        text = h5py.check_string_dtype(dtype) is not None
        kind = kind_of(name)
        scalar = shape in ((), None)
        must_be_scalar = text or (kind is not None and kind != "numbers")
        if len(shape or ()) > 1 or count > MAX_ATTRIBUTE_ELEMENTS or (dtype.kind not in "biufS" and not text) \
                or (must_be_scalar and not scalar):
            expected = "a scalar" if must_be_scalar else "a scalar or a short list of numbers"
            raise OutputError(f"damaged rockslide file ({_where(obj, name)} is {dtype} of shape {shape}; "
                              f"expected {expected})", source=source)
        try:
            value = plain(obj.attrs[name])
        except (OSError, TypeError, ValueError, UnicodeDecodeError) as exc:
            raise OutputError(f"damaged rockslide file ({_where(obj, name)}: {exc})", source=source) from None
        if kind is not None:
            test, words = KINDS[kind]
            if not test(value):
                shown = repr(value) if len(repr(value)) <= 60 else repr(value)[:57] + "..."
                raise OutputError(f"damaged rockslide file ({name} = {shown}; expected {words}, "
                                  f"{_where(obj, name)})", source=source)
        out[name] = value
    return out


class Budget:
    """The bytes of values a reader may still read from one file (`MAX_READ_BYTES` at first)."""

    def __init__(self, source: str, limit: int = MAX_READ_BYTES):
        self.source = source
        self.left = limit
        self.limit = limit

    def check_total(self, datasets) -> None:
        """Refuse at once a file whose ``datasets`` declare more bytes in all than are left."""
        total = sum(declared_bytes(ds) for ds in datasets)
        if total > self.left:
            raise OutputError(f"not read: its datasets declare {total} bytes of values; rockslide reads at most "
                              f"{self.limit} bytes ({self.limit / 2**20:.0f} MiB) of one file", source=self.source)

    def take(self, nbytes: int, what: str) -> None:
        if nbytes > self.left:
            raise OutputError(f"not read: {what} declares {nbytes} bytes of values and the file "
                              f"{self.limit - self.left} before it; rockslide reads at most {self.limit} bytes "
                              f"({self.limit / 2**20:.0f} MiB) of one file", source=self.source)
        self.left -= nbytes


def declared_bytes(ds) -> int:
    """The bytes the values of dataset ``ds`` take once read, from its declared shape and type
    (not from what it stores: a compressed dataset of zeros declares gigabytes in a few KB)."""
    count = int(np.prod(ds.shape, dtype=object)) if ds.shape else 1
    return count * max(int(ds.dtype.itemsize), 1)


def read_dataset(ds, budget: Budget, *, ndim: int | None = 1, kinds: str = "biuf", text: bool = False,
                 what: str | None = None) -> np.ndarray:
    """The values of dataset ``ds``: ``ndim`` dimensions (None: any), numbers of ``kinds`` (numpy
    kind letters) or, with ``text``, strings too; their declared size charged to ``budget`` before a
    byte is read. Strings come back as ``str`` made `printable`.

    Raises
    ------
    OutputError
        Not a dataset of that shape or kind, more than `MAX_TEXT_ELEMENTS` strings, or beyond the
        budget; or HDF5 cannot read it (a damaged chunk).
    """
    what = what or ds.name
    source = budget.source
    if not isinstance(ds, h5py.Dataset):
        raise OutputError(f"damaged rockslide file ({what} is not a dataset)", source=source)
    is_text = h5py.check_string_dtype(ds.dtype) is not None
    if (ndim is not None and ds.ndim != ndim) or not (ds.dtype.kind in kinds or (text and is_text)):
        expected = f"{ndim}-D " if ndim is not None else ""
        expected += "numbers or text" if text else "numbers"
        raise OutputError(f"damaged rockslide file ({what} is {ds.dtype} of shape {ds.shape}; expected "
                          f"{expected})", source=source)
    count = int(np.prod(ds.shape, dtype=object)) if ds.shape else 1
    if is_text and count > MAX_TEXT_ELEMENTS:
        raise OutputError(f"not read: {what} declares {count} strings; rockslide reads at most "
                          f"{MAX_TEXT_ELEMENTS}", source=source)
    budget.take(declared_bytes(ds), what)
    try:
        if is_text:
            values = ds.asstr("utf-8", "replace")[()]
            if isinstance(values, np.ndarray):
                return np.array([printable(v) for v in values.ravel()], dtype=object).reshape(values.shape)
            return np.array(printable(values), dtype=object)
        return ds[()]
    except (OSError, ValueError, TypeError) as exc:
        raise OutputError(f"damaged rockslide file (cannot read {what}: {' '.join(str(exc).split())})",
                          source=source) from None
