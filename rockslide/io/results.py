"""Result <-> HDF5, with units and provenance (h5py lives here only).

A result file holds one simulation: the time histories, the ground motion as applied, the event
log, the summary, the case and the records it came from. Every file is written atomically: into a
temporary file in the destination folder (``.NAME.<pid>.tmp``, e.g. ``.kobe.h5.4711.tmp``), flushed,
synced and closed, then renamed onto ``NAME`` with `os.replace`. An exception (Ctrl-C included)
deletes the temporary file; a process killed outright (SIGKILL, power loss) may leave one behind,
but never a half-written ``NAME``: the previous file, if any, stays intact until the rename. Leftover
temporary files always start with ``.`` and end in ``.tmp``; they can be deleted at any time when no
run is writing.

Layout (format ``rockslide-result``, version 1):

| path | type | units | content |
|---|---|---|---|
| `/` | group (attrs) | | summary, status, verdict, provenance (below) |
| `/time_history` | group | | the response on the output grid |
| `/time_history/time` | float64[n] | s | time |
| `/time_history/rotation` | float64[n] | rad | signed rotation `phi = lam * theta` |
| `/time_history/rotation_rate` | float64[n] | rad/s | `d phi / dt` |
| `/time_history/slip` | float64[n] | m | slip displacement `x` relative to the ground |
| `/time_history/slip_rate` | float64[n] | m/s | slip velocity `d x / dt` |
| `/time_history/state` | int8[n] | - | state code; attribute `codes` (below) |
| `/ground` | group | | the ground motion as applied (scaled, tail included) |
| `/ground/time` | float64[m] | s | sample times |
| `/ground/horizontal` | float64[m] | m/s^2 | horizontal ground acceleration |
| `/ground/vertical` | float64[m] | m/s^2 | vertical ground acceleration (up positive) |
| `/events` | compound[k] | | the event log (fields below) |
| `/event` | int64[k] | 1 | the event log's index: its netCDF-4 dimension `event` |
| `/case` | group (attrs) | | if a case is given: `yaml` (the case file's text) and the case's keys |
| `/records` | group | | if records are given |
| `/records/horizontal` | group (attrs) | | the horizontal record file (attributes below) |
| `/records/vertical` | group (attrs) | | the same for the vertical record |

- A block on a floor (``ground.floor``): ``/ground`` is the floor's motion, the block's support, and
  a group ``/base`` holds the ground under the building (``time`` [s], ``horizontal`` and
  ``vertical`` [m/s^2], scaled, without the tail), labelled as ``/ground`` is.
- ``/time_history/state`` attribute ``codes`` = "0 REST, 1 SLIP, 2 ROCK, 3 ROCKSLIP, 4 OVERTURNED".
- ``/events`` fields: ``time`` (f8) [s]; ``from``, ``to`` (UTF-8 text, state names); ``cause``
  (UTF-8 text: slip-start, liftoff, slip-stop, slip-reversal, impact, liftoff-end, overturn, flight,
  painleve); ``edge`` (i1, the pivot ``lam``: +1 left, -1 right); ``slip_direction`` (i1,
  ``sigma``); ``impact`` (UTF-8 text: the branch of the impact law, stick, slip or flat; empty for
  other events); ``energy_loss`` (f8) [J]: the kinetic energy an impact took (>= 0; 0 for other
  events). h5py hands text in compound datasets over as ``bytes`` (``.decode()`` them);
  `read_result` gives the log back as the core holds it (`EVENT_DTYPE`).
- ``/records/<role>`` attributes: ``role``, ``path`` (the file name only, never a folder),
  ``sha256`` (of the file's bytes), ``format``, ``units`` (of the file), ``scale_factor``.
- ``/case`` holds the case (``case.case_to_dict``) as attributes with dotted keys such as
  ``contact.mu_static`` (SI values; None stored as "").

Every dataset carries a ``units`` attribute; the time histories are chunked and compressed (gzip
level 1 with shuffle). The file is a netCDF-4 one: ``time`` of ``/time_history`` and of ``/ground``
is the dimension scale of its group's columns and ``/event`` that of ``/events``, so that
``xarray.open_dataset(path, engine="h5netcdf")`` opens the event log (and ``group="time_history"``,
``group="ground"`` the histories). Root attributes:

- the summary: ``overturned`` (bool), ``overturn_time`` [s], ``direction``, ``fall_start_time`` [s],
  ``max_rotation`` [rad], ``max_rotation_time`` [s], ``max_slip`` [m], ``residual_slip`` [m],
  ``impacts``, ``states_seen`` (comma-joined names), ``status`` (ok | flight | painleve),
  ``end_time`` [s], ``alpha`` [rad] (``atan(b/h)``), ``max_rotation_ratio`` (``max_rotation /
  alpha``: 0.94 is 94 % of the way to the angle past which gravity tips the block over),
  ``time_in_state_REST`` ... [s] (one per state), ``energy_kinetic`` ... [J] (one per energy term).
  A time that is None is stored as NaN, a direction that is None as 0; `read_result` gives back
  None.
- the ground motion as applied, if given: ``ground_pga_horizontal``, ``ground_pga_vertical``
  [m/s^2] (peaks of the scaled records) and ``ground_scale_horizontal``, ``ground_scale_vertical``
  (the factors applied to the records; NaN for an absent record); with two horizontal components
  also ``ground_azimuth_1``, ``ground_azimuth_2``, ``ground_orientation`` [rad], ``ground_pga_1``,
  ``ground_pga_2``, ``ground_pga_along``, ``ground_pga_across`` [m/s^2] and ``ground_ignored_share``
  (`COMPONENT_KEYS`).
- ``verdict``, ``name``, ``integration_step`` [s], ``format`` = "rockslide-result",
  ``format_version`` = 1, ``created`` (ISO 8601, UTC);
- versions: ``rockslide_version``, ``python_version``, ``numpy_version``, ``numba_version``,
  ``h5py_version``, ``obspy_version``, ``scipy_version``, ``matplotlib_version`` ("not installed"
  when missing);
- any ``extra_attrs`` given to the writer.

Records keep their file name only, never a folder; the case is stored as written.

Sweep files (`write_sweep`, `read_sweep`; format ``rockslide-sweep``, version 1) hold a grid of
summaries instead, in the netCDF-4 data model so that ``xarray.open_dataset(path,
engine="h5netcdf")`` gives a labelled dataset: one 1-D dataset per axis made an HDF5 dimension scale
(``units``, ``long_name``, ``_Netcdf4Dimid``), one dataset per variable attached to the axes in
order, and the provenance as root attributes. They are written atomically in the same way.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import functools
import itertools
import math
import os
import platform
import re
import signal
import sys
import threading
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

import h5py
import numpy as np

from .. import interrupts
from .._version import __version__
from ..core import local_threads
from ..core.layout import HISTORY_COLUMNS, STATE_NAMES
from ..errors import OutputError
from ..inputs import regular_size
from . import h5checked
from .files import (
    Staging,
    cannot_write_in_folder,
    check_destination,
    error_reason,
    open_new,
    publish,
    remove_quietly,
    temporary_path,
)

if TYPE_CHECKING:
    from ..core.simulate import Result, Summary

FORMAT = "rockslide-result"
FORMAT_VERSION = 1

#: Units of the time-history columns (``kernel.HISTORY_COLUMNS``).
HISTORY_UNITS = {"time": "s", "rotation": "rad", "rotation_rate": "rad/s", "slip": "m",
                 "slip_rate": "m/s", "state": "-"}
#: The ``codes`` attribute of ``/time_history/state``.
STATE_CODES = ", ".join(f"{code} {name}" for code, name in enumerate(STATE_NAMES))
GROUND_UNITS = {"time": "s", "horizontal": "m/s^2", "vertical": "m/s^2"}
RECORD_KEYS = ("role", "path", "sha256", "format", "units", "scale_factor")
#: The roles of ``/records`` groups: ``horizontal`` (with two components, the first), ``vertical``,
#: ``horizontal_2`` (the second horizontal component).
RECORD_ROLES = ("horizontal", "vertical", "horizontal_2")
#: With two horizontal components (`prepare.Components`), root attributes ``ground_<key>``: the
#: azimuths and orientation [rad], the scaled peaks [m/s^2] and the share the planar model ignores.
COMPONENT_KEYS = ("azimuth_1", "azimuth_2", "orientation", "pga_1", "pga_2", "pga_along", "pga_across",
                  "ignored_share")
#: Packages whose versions are stored as ``<name>_version`` root attributes.
VERSIONED_PACKAGES = ("rockslide", "python", "numpy", "numba", "h5py", "obspy", "scipy", "matplotlib")

_CHUNK_ROWS = 16384
#: gzip level 1 with shuffle: 1.7 times as fast as level 4 both ways, for a file 10 % larger (the
#: shipped example's result: 382 KB against 345 KB, written in 44 ms against 74 ms, read in 24 ms
#: against 40 ms; results/bench_startup.md). Every gzip reader reads either level.
_COMPRESSION = {"compression": "gzip", "compression_opts": 1, "shuffle": True}
_SUMMARY_SCALARS = ("overturned", "overturn_time", "direction", "fall_start_time", "max_rotation",
                    "max_rotation_time", "max_slip", "residual_slip", "impacts", "status", "end_time",
                    "alpha", "max_rotation_ratio", "undecided", "alpha_2")
#: The ground motion as applied (`records.GroundMotion.as_applied`), root attributes ``ground_<key>``.
GROUND_KEYS = ("pga_horizontal", "pga_vertical", "scale_horizontal", "scale_vertical")
_PROVENANCE = ("verdict", "name", "integration_step", "format", "format_version", "created",
               *(f"{p}_version" for p in VERSIONED_PACKAGES))


@dataclass
class StoredResult:
    """A result file read back.

    Attributes
    ----------
    name : str
        The case name stored with the result.
    result : Result
        Histories, events, summary, step and ground motion, as `simulate` returned them.
    case_text : str
        The case file's text ("" if none was stored).
    case : dict
        The case as a nested dict (``{}`` if none was stored); values "" are given back as None.
    records : list of dict
        One dict per record (keys ``RECORD_KEYS``), horizontal first.
    attrs : dict
        All root attributes as plain Python values (summary, provenance, extra attributes).
    ground : dict
        The ground motion as applied (keys ``GROUND_KEYS``, SI; None where not stored), ``{}`` if
        the file has none.
    base : dict
        For a block on a floor, the ground motion under the building (``/base``): ``time`` [s],
        ``horizontal`` and ``vertical`` [m/s^2]; ``{}`` otherwise.
    """

    name: str
    result: Result
    case_text: str
    case: dict
    records: list[dict]
    attrs: dict
    ground: dict = dataclasses.field(default_factory=dict)
    base: dict = dataclasses.field(default_factory=dict)


# --------------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------------


class ResultWriter:
    """Write one result file, streaming the time history (bounded memory).

    Parameters
    ----------
    path : str or Path
        The result file (``.h5``). Its folder is created if missing.
    overwrite : bool
        Replace an existing file. Without it an existing file is an `OutputError`, raised here,
        before any computation.
    staging : files.Staging, optional
        Publish the file with the other files of ``staging`` (`files.Staging.publish`) instead of
        on its own in `finish`.
    keep_rows : int
        Also keep the streamed history in memory while it has at most this many rows, so that
        `written_result` gives the result as stored without reading the file back (0: keep none).

    Notes
    -----
    Use it as a context manager::

        with ResultWriter("out/kobe.h5") as writer:
            result = simulate(model, dt, ah, av, settings, on_chunk=writer.append_history)
            writer.finish(result, name="kobe", case_text=text)

    Nothing appears at ``path`` until `finish` returns (or ``staging`` publishes). An exception in
    the ``with`` block (KeyboardInterrupt included) closes and deletes the temporary file and
    propagates; leaving the block without calling `finish` discards the temporary file as well. A
    write that fails (a full disk) is an `OutputError` naming the file, and nothing is left behind.
    """

    def __init__(self, path, *, overwrite: bool = False, staging: Staging | None = None, keep_rows: int = 0):
        self.path = check_destination(path, overwrite=overwrite)
        self.overwrite = overwrite
        self.staging = staging
        self.tmp = staging.stage(self.path) if staging is not None else temporary_path(self.path)
        self._rows = 0
        self._whole_history = False         # written at once by write_history, not streamed
        self._done = False
        self._keep_rows = keep_rows
        self._kept: list[np.ndarray] | None = [] if keep_rows > 0 else None
        self._written: Result | None = None
        self._file, self._raw = _create_hdf5(self.tmp, self.path)
        try:
            history = self._file.create_group("time_history", track_order=True)
            self._datasets = {}
            for name in HISTORY_COLUMNS:
                dtype = np.int8 if name == "state" else np.float64
                ds = history.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype,
                                            chunks=(_CHUNK_ROWS,), **_COMPRESSION)
                attrs = _Attributes(ds)
                attrs["units"] = HISTORY_UNITS[name]
                if name == "state":
                    attrs["codes"] = STATE_CODES
                self._datasets[name] = ds
            self._raw.check()
        except BaseException as exc:
            self.discard()
            _raise_write_error(exc, self._raw, self.path)

    # -- context manager ---------------------------------------------------------------------------
    def __enter__(self) -> ResultWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if not self._done:
            self.discard()
        return False

    # -- streaming ---------------------------------------------------------------------------------
    @property
    def rows_written(self) -> int:
        """Number of history rows appended so far."""
        return self._rows

    def append_history(self, rows: np.ndarray) -> None:
        """Append history rows (``float64[n, 6]``, columns ``kernel.HISTORY_COLUMNS``)."""
        self._check_open()
        if self._whole_history:
            raise ValueError("the whole time history was already written (write_history)")
        rows = np.asarray(rows, dtype=np.float64)
        if rows.ndim != 2 or rows.shape[1] != len(HISTORY_COLUMNS):
            raise ValueError(f"history rows must be float64[n, {len(HISTORY_COLUMNS)}], got {rows.shape}")
        n = rows.shape[0]
        if n == 0:
            return
        try:
            interrupts.check()
            start, end = self._rows, self._rows + n
            for i, name in enumerate(HISTORY_COLUMNS):
                ds = self._datasets[name]
                ds.resize((end,))
                ds[start:end] = rows[:, i].astype(ds.dtype) if name == "state" else rows[:, i]
            self._raw.check()
            self._rows = end
        except BaseException as exc:
            self.discard()
            _raise_write_error(exc, self._raw, self.path)
        if self._kept is not None:
            if end <= self._keep_rows:
                self._kept.append(rows.T.copy())     # columns, as the core holds a history
            else:
                self._kept = None                    # too long to keep: the caller reads the file

    def write_history(self, history: dict) -> None:
        """Write a whole time history held in memory (a `Result`'s ``history``) and compress it
        now: what `finish` does with ``result.history``, done before it (a run's history, on a
        thread of its own while its ensemble computes). `finish` is then given that result."""
        self._check_open()
        if self._rows or self._whole_history:
            raise ValueError("the time history was already written")
        try:
            interrupts.check()
            if history and len(history.get("time", ())):
                self._write_history_dict(history)
                self._file.flush()              # its chunks are compressed now, not at finish
            self._raw.check()
        except BaseException as exc:
            self.discard()
            _raise_write_error(exc, self._raw, self.path)
        self._whole_history = True

    def finish(self, result: Result, *, name: str, case_text: str = "", case: dict | None = None,
               records=(), extra_attrs: dict | None = None, ground: dict | None = None,
               extra_groups: dict | None = None) -> Path:
        """Write the ground motion, events, summary and metadata, then publish the file (or leave it
        to the writer's ``staging``).

        The streamed history is used if rows were appended, the one `write_history` wrote if it was
        called; otherwise ``result.history`` is written. The arguments are those of `write_result`.

        Returns
        -------
        Path
            The result file.
        """
        self._check_open()
        try:
            interrupts.check()
            streamed = self._rows > 0 and not self._whole_history
            if self._rows == 0 and not self._whole_history and result.history and len(result.history.get("time", ())):
                self._write_history_dict(result.history)
            _write_body(self._file, result, name=name, case_text=case_text, case=case,
                        records=records, extra_attrs=extra_attrs, ground=ground, extra_groups=extra_groups)
            self._file.flush()
            self._file.close()
            self._raw.close()
            self._raw.check()
        except BaseException as exc:
            self.discard()
            _raise_write_error(exc, self._raw, self.path)
        self._done = True
        if self._keep_rows > 0 and (not streamed or self._kept is not None):
            history = _history_columns(self._kept) if streamed else result.history
            self._written = dataclasses.replace(result, history=_as_stored(history))
        self._kept = None
        if self.staging is None:
            publish(self.tmp, self.path, overwrite=self.overwrite)
        return self.path

    def written_result(self) -> Result | None:
        """After `finish`: the result as the file holds it (equal to the ``result`` of
        `read_result`), from memory; None without ``keep_rows`` or when the streamed history had
        more rows than that (then read the file)."""
        return self._written

    def discard(self) -> None:
        """Close and delete the temporary file (nothing is published). Safe to call twice.

        A second Ctrl-C cannot interrupt it: SIGINT is held back until the file is gone.
        """
        with _sigint_held():
            self._done = True
            self._datasets = {}
            remove_quietly(self.tmp)          # POSIX: unlink first, so that nothing is left even if closing fails
            try:
                if self._file.id.valid:
                    self._file.close()
            except Exception:  # noqa: BLE001 - closing a broken file must not hide the first error
                pass
            self._raw.close()
            remove_quietly(self.tmp)          # Windows cannot unlink an open file

    # -- internals ---------------------------------------------------------------------------------
    def _check_open(self) -> None:
        if self._done:
            raise OutputError("the result writer is closed (finish() was called or it failed)",
                              source=str(self.path))

    def _write_history_dict(self, history: dict) -> None:
        n = len(history["time"])
        for name in HISTORY_COLUMNS:
            ds = self._datasets[name]
            ds.resize((n,))
            ds[...] = np.asarray(history[name], dtype=ds.dtype)
        self._rows = n


def _history_columns(chunks: list[np.ndarray]) -> dict[str, np.ndarray]:
    """History arrays by name from the columns of streamed chunks (``float64[6, n]`` each)."""
    columns = chunks[0] if len(chunks) == 1 else np.concatenate(chunks, axis=1)
    return {name: columns[i] for i, name in enumerate(HISTORY_COLUMNS)}


def _as_stored(history: dict) -> dict[str, np.ndarray]:
    """A history as `read_result` gives it back: contiguous columns, state as int8, float64 else."""
    if not history:
        return {name: np.empty(0, np.int8 if name == "state" else np.float64) for name in HISTORY_COLUMNS}
    return {name: np.ascontiguousarray(history[name], dtype=np.int8 if name == "state" else np.float64)
            for name in HISTORY_COLUMNS}


def write_result(path, result: Result, *, name: str, case_text: str = "", case: dict | None = None,
                 records=(), extra_attrs: dict | None = None, ground: dict | None = None,
                 overwrite: bool = False) -> Path:
    """Write ``result`` to the HDF5 file ``path`` (layout in the module docstring), atomically.

    Parameters
    ----------
    path : str or Path
        The result file; its folder is created if missing.
    result : Result
    name : str
        The case name.
    case_text : str
        The case file's text (stored as ``/case`` attribute ``yaml``).
    case : dict, optional
        The case as a nested dict (``case.case_to_dict``), stored as flattened ``/case`` attributes.
    records : list of dict
        The record files (``role``, ``path``, ``sha256``, ``format``, ``units``, ``scale_factor``);
        only the file name of ``path`` is stored.
    extra_attrs : dict, optional
        More root attributes (scalars or strings); they may not replace the standard ones.
    ground : dict, optional
        The ground motion as applied (`records.GroundMotion.as_applied`: keys ``GROUND_KEYS``, SI),
        stored as root attributes ``ground_<key>``.
    overwrite : bool
        Replace an existing file.

    Returns
    -------
    Path

    Raises
    ------
    OutputError
        The file exists (without ``overwrite``) or cannot be written.
    """
    with ResultWriter(path, overwrite=overwrite) as writer:
        return writer.finish(result, name=name, case_text=case_text, case=case, records=records,
                             extra_attrs=extra_attrs, ground=ground)


def _write_body(f: h5py.File, result: Result, *, name, case_text, case, records, extra_attrs,
                ground=None, extra_groups=None) -> None:
    group = f.create_group("ground", track_order=True)
    for key, values in (("time", result.ground_time), ("horizontal", result.ground_horizontal),
                        ("vertical", result.ground_vertical)):
        values = np.asarray(values, dtype=np.float64)
        options = {"chunks": (min(values.size, _CHUNK_ROWS),), **_COMPRESSION} if values.size else {}
        ds = group.create_dataset(key, data=values, **options)
        _Attributes(ds)["units"] = GROUND_UNITS[key]

    events = _events_for_file(result.events)
    ds = f.create_dataset("events", data=events, dtype=events.dtype)
    _label_dimensions(f, ds)
    attrs = _Attributes(ds)
    attrs["units"] = "time: s, energy_loss: J"
    attrs["description"] = ("time [s], from/to: state names, cause, edge: pivot lam (+1 left, -1 right, 0 "
                            "none), slip_direction: sigma, impact: branch of the impact law (stick, slip, "
                            "flat), energy_loss: kinetic energy the impact took [J]")

    if case_text or case:
        group = f.create_group("case", track_order=True)
        attrs = _Attributes(group)
        attrs["yaml"] = case_text or ""
        for key, value in _flatten(case or {}).items():
            if key == "yaml":
                raise ValueError("a case key may not be called 'yaml'")
            attrs[key] = value

    records = list(records or ())
    if records:
        top = f.create_group("records", track_order=True)
        for record in records:
            role = str(record.get("role") or "")
            if role not in RECORD_ROLES:
                raise ValueError(f"record role must be one of {', '.join(RECORD_ROLES)}, got {role!r}")
            attrs = _Attributes(top.create_group(role, track_order=True))
            for key in RECORD_KEYS:
                value = record.get(key)
                if key == "path" and value not in (None, ""):
                    value = _file_name(value)
                attrs[key] = _attr_value(value)

    for group_name, (dimension, variables) in (extra_groups or {}).items():
        _write_labelled(f.create_group(group_name, track_order=True), [dimension], variables)

    attrs = _Attributes(f)
    for key, value in summary_attributes(result.summary).items():
        attrs[key] = value
    for key in GROUND_KEYS if ground else ():
        value = ground.get(key)
        attrs[f"ground_{key}"] = math.nan if value is None else float(value)
    components = (ground or {}).get("components") or {}
    for key in COMPONENT_KEYS if components else ():
        attrs[f"ground_{key}"] = float(components[key])
    attrs["verdict"] = result.summary.verdict
    attrs["name"] = name
    attrs["integration_step"] = float(result.step)
    attrs["format"] = FORMAT
    attrs["format_version"] = FORMAT_VERSION
    attrs["created"] = datetime.now(UTC).isoformat(timespec="seconds")
    for key, value in versions().items():
        attrs[key] = value
    for key, value in (extra_attrs or {}).items():
        if key in attrs:
            raise ValueError(f"extra attribute {key!r} would replace a standard attribute")
        attrs[key] = _attr_value(value)


def _write_labelled(group, coords, variables) -> None:
    """Labelled arrays into ``group`` in the netCDF-4 data model (`write_dataset`'s body; a run
    file's ``/ensemble``): each coordinate a dimension scale (with ``_Netcdf4Dimid``), each variable
    attached to its dimensions' scales in order."""
    scales = {}
    for i, (name, values, a) in enumerate(coords):
        ds = group.create_dataset(name, data=_column(values))
        attrs = _Attributes(ds)
        for key, value in a.items():
            attrs[key] = _attr_value(value)
        ds.make_scale(name)
        attrs["_Netcdf4Dimid"] = np.int32(i)
        scales[name] = ds
    for name, (dims, values, a) in variables.items():
        values = _array(values)          # a variable keeps its type (flags and counts: integers)
        if values.size > 65536 and values.dtype.kind in "biuf":
            ds = _compressed_dataset(group, name, values)
        else:
            ds = group.create_dataset(name, data=values)
        attrs = _Attributes(ds)
        for key, value in a.items():
            attrs[key] = value if isinstance(value, np.ndarray) else _attr_value(value)
        for i, dim in enumerate(dims):
            ds.dims[i].attach_scale(scales[dim])


def _compressed_dataset(group, name: str, values: np.ndarray):
    """``values`` (numbers) as the dataset ``name`` of ``group``, chunked as h5py chooses and
    compressed (`_COMPRESSION`), its chunks compressed on every core: HDF5 runs its filters on the
    one thread that writes (a 10^6-case sweep's file holds 18 such arrays; one of 1000 x 1001
    doubles took 139 ms that way and 81 ms so, on 2 cores). Each chunk goes through the dataset's
    own filters in their order, done here (shuffle: the bytes regrouped by their place in an
    element; deflate: zlib at level 1), and is written as it is stored (``write_direct_chunk``); a
    chunk past the array's edge is filled with zeros, as HDF5 fills it. A reader finds the file
    h5py itself would have written."""
    import zlib
    from concurrent.futures import ThreadPoolExecutor

    ds = group.create_dataset(name, shape=values.shape, dtype=values.dtype, chunks=True, **_COMPRESSION)
    chunk = ds.chunks
    starts = list(itertools.product(*(range(0, n, c) for n, c in zip(values.shape, chunk, strict=True))))

    def compressed(start):
        block = values[tuple(slice(a, a + c) for a, c in zip(start, chunk, strict=True))]
        if block.shape != chunk:
            full = np.zeros(chunk, dtype=values.dtype)
            full[tuple(slice(0, n) for n in block.shape)] = block
            block = full
        shuffled = np.ascontiguousarray(block).view(np.uint8).reshape(-1, values.dtype.itemsize).T
        return zlib.compress(shuffled.tobytes(), _COMPRESSION["compression_opts"])

    with ThreadPoolExecutor(max_workers=max(1, min(len(starts), local_threads()))) as pool:
        for start, data in zip(starts, pool.map(compressed, starts), strict=True):
            ds.id.write_direct_chunk(start, data)
    return ds


def _label_dimensions(f: h5py.File, events) -> None:
    """Make the file a netCDF-4 one that ``xarray.open_dataset(path, engine="h5netcdf")`` opens (the
    root: the event log; ``group="time_history"`` or ``group="ground"``: the histories): ``time`` of
    each group is made the dimension scale of its columns, and the event log gets an ``event``
    dimension (its index)."""
    for group in ("time_history", "ground"):
        if group not in f or "time" not in f[group]:
            continue
        time = f[group]["time"]
        time.make_scale("time")
        for name, ds in f[group].items():
            if name != "time":
                ds.dims[0].attach_scale(time)
    index = f.create_dataset("event", data=np.arange(events.shape[0], dtype=np.int64))
    attrs = _Attributes(index)
    attrs["units"] = "1"
    attrs["long_name"] = "index of the event in the log"
    index.make_scale("event")
    events.dims[0].attach_scale(index)


def _events_for_file(events) -> np.ndarray:
    """The event log as ``/events`` holds it: `core.simulate.EVENT_DTYPE` with its names as UTF-8
    text (variable length) instead of the core's fixed-length bytes."""
    from ..core.simulate import EVENT_DTYPE  # here: a file of a risk or a sweep has no events

    events = np.asarray(events).astype(EVENT_DTYPE)
    out = np.empty(events.shape, dtype=[(name, h5py.string_dtype("utf-8") if EVENT_DTYPE[name].kind == "S"
                                        else EVENT_DTYPE[name]) for name in EVENT_DTYPE.names])
    for name in EVENT_DTYPE.names:
        out[name] = ([v.decode() for v in events[name]] if EVENT_DTYPE[name].kind == "S"
                     else events[name])
    return out


def _events_from_file(stored: np.ndarray) -> np.ndarray:
    """The event log as the core holds it (`EVENT_DTYPE`), from text names or, in files written
    before they were text, fixed-length bytes (fields a file lacks stay empty)."""
    from ..core.simulate import EVENT_DTYPE

    out = np.zeros(stored.shape, dtype=EVENT_DTYPE)
    for name in EVENT_DTYPE.names:
        if name not in stored.dtype.names:        # written before impacts were described
            continue
        values = stored[name]
        if EVENT_DTYPE[name].kind == "S":
            values = [v.encode() if isinstance(v, str) else bytes(v) for v in values]
        out[name] = values
    return out


def summary_attributes(summary: Summary) -> dict:
    """The summary as the result file's root attributes (None as NaN or 0, lists joined)."""
    out = {}
    for key in _SUMMARY_SCALARS:
        value = getattr(summary, key)
        if key in ("overturn_time", "fall_start_time"):
            value = math.nan if value is None else float(value)
        elif key == "direction":
            value = 0 if value is None else int(value)
        elif key in ("overturned", "undecided"):
            value = bool(value)
        elif key == "impacts":
            value = int(value)
        elif key == "status":
            value = str(value)
        else:
            value = float(value)
        out[key] = value
    out["states_seen"] = ",".join(summary.states_seen)
    for state, seconds in summary.time_in_state.items():
        out[f"time_in_state_{state}"] = float(seconds)
    for term, joules in summary.energy.items():
        out[f"energy_{term}"] = float(joules)
    return out


def versions() -> dict[str, str]:
    """Versions of Python and of the packages a result depends on (``<name>_version`` keys)."""
    installed = installed_versions()
    out = {}
    for package in VERSIONED_PACKAGES:
        if package == "python":
            version = platform.python_version()
        elif package in installed:
            version = installed[package]
        else:
            import importlib.metadata

            try:
                version = importlib.metadata.version(package)
            except importlib.metadata.PackageNotFoundError:
                version = __version__ if package == "rockslide" else "not installed"
        out[f"{package}_version"] = version
    return out


@functools.lru_cache(maxsize=1)
def installed_versions() -> dict[str, str]:
    """The versions of the installed distributions, by normalised name, read from the names of
    their ``NAME-VERSION.dist-info`` folders on ``sys.path`` (the layout installers write; the first
    on the path wins, as for imports). What importlib.metadata gives, without its import and the
    parsing of whole metadata files: 30 ms of a run. A distribution installed otherwise (an
    ``.egg-info``) is missing here, and `versions` asks importlib.metadata for it."""
    found: dict[str, str] = {}
    for entry in sys.path:
        try:
            names = os.listdir(entry or ".")
        except OSError:
            continue
        for name in names:
            stem = name[:-len(".dist-info")]
            if name.endswith(".dist-info") and stem.count("-") == 1:
                project, version = stem.split("-")
                found.setdefault(re.sub(r"[-_.]+", "_", project).lower(), version)
    return found


def _flatten(tree: dict, prefix: str = "") -> dict:
    out = {}
    for key, value in tree.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(_flatten(value, dotted + "."))
        else:
            out[dotted] = _attr_value(value)
    return out


#: The plain Python scalars an attribute most often holds, with the numpy type and HDF5 type that
#: h5py's ``attrs[name] = value`` gives them: variable-length UTF-8 text, IEEE float64, int64 and
#: h5py's boolean enum (`_Attributes`).
_SCALAR_TYPES = {kind: (dtype, h5py.h5t.py_create(dtype, logical=True)) for kind, dtype in (
    (str, h5py.string_dtype("utf-8")), (float, np.dtype("<f8")), (int, np.dtype("<i8")), (bool, np.dtype(bool)))}
_SCALAR_SPACE = h5py.h5s.create(h5py.h5s.SCALAR)


class _Attributes:
    """An HDF5 object's attributes for writing: ``_Attributes(obj)[name] = value`` stores what
    ``obj.attrs[name] = value`` stores, the same HDF5 type and value, and ``name in`` asks the file.

    A plain Python ``str``, ``float``, ``int`` (within int64) or ``bool`` under a new ASCII name goes
    through h5py's low-level `h5py.h5a`, with the types of `_SCALAR_TYPES`, skipping what the
    generality of ``attrs`` costs (any data, shape or type; replacing an attribute): the example's
    fragility file (195 attributes) is written in 69 ms instead of 79-85 ms, a run file (173) in
    86-88 ms instead of 92-93 ms (medians of 15 in one process, alternating with ``attrs``, on the
    2-core development machine, 2026-11-29). Anything else goes through ``obj.attrs``.
    """

    __slots__ = ("_obj",)

    def __init__(self, obj):
        self._obj = obj

    def __contains__(self, name) -> bool:
        return name in self._obj.attrs

    def __setitem__(self, name: str, value) -> None:
        kind = type(value)
        if kind in _SCALAR_TYPES and type(name) is str and name.isascii() and \
                (kind is not int or -2**63 <= value < 2**63):
            key = name.encode()
            if not h5py.h5a.exists(self._obj.id, key):
                dtype, htype = _SCALAR_TYPES[kind]
                attr = h5py.h5a.create(self._obj.id, key, htype, _SCALAR_SPACE)
                try:
                    attr.write(np.array(value, dtype=dtype))
                except BaseException:
                    attr.close()
                    h5py.h5a.delete(self._obj.id, key)
                    raise
                attr.close()
                return
        self._obj.attrs[name] = value


def _attr_value(value):
    """A value HDF5 can hold as an attribute: None -> "", paths and other objects -> str."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple, np.ndarray)) and all(
            isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in value):
        return np.asarray(value)
    return str(value)


class _RawFile:
    """The file HDF5 writes through (h5py's file-object driver), never failing under it.

    libhdf5 cannot close a file it failed to write (a full disk): every later flush fails again and
    the process crashes at exit; and an exception raised inside h5py's driver callbacks corrupts
    the calls that follow. So a write that fails is recorded (`error`, the first one) and reported
    as done: HDF5 goes on, unaware, and closes the file normally. The writer checks `error` after
    each of its steps (`check`) and discards the file.

    What HDF5 writes after the failure is kept in memory (`_patches`, the bytes of each write at its
    offset) and laid over what it reads back, and a read past the end of what the disk holds gives
    zeros: HDF5 then always reads what it wrote, never stale or missing bytes, which it could
    misread into a crash (seen once as a segfault while creating a dataset after the disk filled).
    Only what is written after the failure is held, until the writer discards the file.
    """

    def __init__(self, path: Path):
        self._file = open_new(path, "w+b", buffering=0)  # closed by close()
        self.error: OSError | None = None
        self._pos = 0
        self._patches: list[tuple[int, bytes]] = []

    def check(self) -> None:
        """Raise the first write error, if any."""
        if self.error is not None:
            raise self.error

    def write(self, data) -> int:
        view = memoryview(data).cast("B")
        if self.error is None:
            done = 0
            try:
                self._file.seek(self._pos)
                while done < view.nbytes:
                    done += self._file.write(view[done:])
            except OSError as exc:
                self.error = exc
        if self.error is not None:
            self._patches.append((self._pos, bytes(view)))
        self._pos += view.nbytes
        return view.nbytes

    def truncate(self, size=None):
        size = self._pos if size is None else size
        if self.error is None:
            try:
                self._file.truncate(size)
            except OSError as exc:
                self.error = exc
        self._patches = [(offset, data[:max(0, size - offset)]) for offset, data in self._patches if offset < size]
        return size

    def readinto(self, buffer) -> int:
        view = memoryview(buffer).cast("B")
        self._file.seek(self._pos)
        got = 0
        while got < view.nbytes:
            n = self._file.readinto(view[got:])
            if not n:
                break
            got += n
        view[got:] = bytes(view.nbytes - got)          # past the end of the disk's file: zeros
        start, end = self._pos, self._pos + view.nbytes
        for offset, data in self._patches:               # in order: a later write wins
            low, high = max(start, offset), min(end, offset + len(data))
            if low < high:
                view[low - start:high - start] = data[low - offset:high - offset]
        self._pos = end
        return view.nbytes

    def read(self, size=-1):
        if size is None or size < 0:
            size = max(0, self._size() - self._pos)
        buffer = bytearray(size)
        self.readinto(buffer)
        return bytes(buffer)

    def _size(self) -> int:
        on_disk = os.fstat(self._file.fileno()).st_size
        return max([on_disk] + [offset + len(data) for offset, data in self._patches])

    def seek(self, offset, whence=0):
        if whence not in (0, 1, 2):
            raise ValueError(f"invalid whence ({whence!r})")
        base = 0 if whence == 0 else self._pos if whence == 1 else self._size()   # only the end asks the disk
        self._pos = base + offset
        return self._pos

    def tell(self):
        return self._pos

    def flush(self):
        pass

    def close(self):
        self._file.close()


def _create_hdf5(tmp: Path, path: Path):
    """A new HDF5 file written through a `_RawFile` at ``tmp``: ``(h5py.File, _RawFile)``."""
    try:
        raw = _RawFile(tmp)
    except OSError as exc:
        raise cannot_write_in_folder(path, exc) from None
    try:
        return h5py.File(raw, "w", track_order=True), raw
    except BaseException as exc:
        raw.close()
        remove_quietly(tmp)
        _raise_write_error(exc, raw, path)


def _raise_write_error(exc: BaseException, raw: _RawFile, path: Path):
    """Re-raise a failure while writing ``path``: an OSError (what the disk said, when it said
    something) becomes one `OutputError` line; anything else (Ctrl-C, a bug) propagates as is."""
    if isinstance(exc, OSError) or raw.error is not None:
        cause = raw.error if raw.error is not None else exc
        hint = "; free some space or choose another output folder" if getattr(cause, "errno", None) in (
            errno.ENOSPC, errno.EDQUOT, errno.EFBIG) else ""
        raise OutputError(f"cannot write the file ({error_reason(cause)}); nothing was written{hint}",
                          source=str(path)) from None
    raise exc


def _file_name(path) -> str:
    """The last component of a path, POSIX or Windows style."""
    return str(path).replace("\\", "/").rstrip("/").rsplit("/", 1)[-1]


# --------------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------------


def read_result(path) -> StoredResult:
    """Read a result file written by `write_result` or `ResultWriter`.

    Returns
    -------
    StoredResult
        Its ``result`` plots and summarises like a fresh `Result`.

    Raises
    ------
    OutputError
        The file is missing, not HDF5, or not a rockslide result (of a known version).
    """
    source = str(path)
    path = Path(path)
    if not path.exists():
        raise OutputError("result file not found", source=source)
    if path.is_dir():
        raise OutputError("is a folder, expected a result file (.h5)", source=source)
    regular_size(path, what="result file (.h5)", error=OutputError)      # a FIFO would block
    try:
        f = h5py.File(path, "r", locking=False)    # our own lock guards the files (io.files)
    except OSError as exc:
        reason = "not an HDF5 file" if "signature" in str(exc) or "file format" in str(exc) else error_reason(exc)
        raise OutputError(f"cannot read as a rockslide result ({reason})", source=source) from None
    with f:
        attrs = h5checked.attribute_values(f, source)
        if attrs.get("format") != FORMAT:
            raise OutputError(f"not a rockslide result (an HDF5 file without format = {FORMAT!r})",
                              source=source)
        _data_only(f, source)
        version = attrs.get("format_version")
        if version != FORMAT_VERSION:
            raise OutputError(f"result format version {version!r} is not supported "
                              f"(this rockslide reads version {FORMAT_VERSION})", source=source)
        try:
            budget = h5checked.Budget(source)
            _check_result_layout(f)
            budget.check_total(_result_datasets(f))
            stored = _read_body(f, attrs, budget)
            _check_result_values(stored)
            return stored
        except OutputError:
            raise
        except (KeyError, ValueError, TypeError, OverflowError, IndexError, OSError) as exc:
            raise OutputError(f"damaged rockslide result ({error_reason(exc)})", source=source) from None


#: Largest attribute read from a file rockslide is given [bytes] (`h5checked.MAX_ATTRIBUTE_BYTES`).
MAX_ATTRIBUTE_BYTES = h5checked.MAX_ATTRIBUTE_BYTES
#: Most rows of a result's time history or ground motion read back (the bound of a run's history).
MAX_RESULT_ROWS = 10**8


def _result_datasets(f: h5py.File) -> list:
    """The datasets `read_result` reads (after `_check_result_layout`)."""
    groups = [("time_history", HISTORY_COLUMNS), ("ground", tuple(GROUND_UNITS))]
    groups += [("base", tuple(GROUND_UNITS))] if "base" in f else []
    return [f["events"]] + [f[group][name] for group, names in groups for name in names]


def _check_result_layout(f: h5py.File) -> None:
    """Every column a result needs, one-dimensional, numeric, of one length per group and at most
    `MAX_RESULT_ROWS` rows, with stored data: checked on the shapes, before anything is read
    (a small file declaring 1e12 rows is refused at once). ValueError says what is wrong."""
    groups = [("time_history", HISTORY_COLUMNS), ("ground", tuple(GROUND_UNITS))]
    events = f["events"]
    if not isinstance(events, h5py.Dataset) or events.ndim != 1 or events.dtype.names is None:
        raise ValueError("/events is not a table of events")
    if "base" in f:                            # a block on a floor: the ground under the building
        groups.append(("base", tuple(GROUND_UNITS)))
    for group, names in groups:
        lengths = set()
        for name in names:
            ds = f[group][name]
            if not isinstance(ds, h5py.Dataset) or ds.ndim != 1 or ds.dtype.kind not in "iuf":
                raise ValueError(f"/{group}/{name} is not a column of numbers")
            if ds.shape[0] > MAX_RESULT_ROWS:
                raise ValueError(f"/{group}/{name} declares {ds.shape[0]} rows; rockslide reads at most "
                                 f"{MAX_RESULT_ROWS:.0e}")
            if ds.shape[0] and ds.id.get_storage_size() == 0:
                raise ValueError(f"/{group}/{name} declares {ds.shape[0]} rows but stores none")
            lengths.add(ds.shape[0])
        if len(lengths) > 1:
            raise ValueError(f"the columns of /{group} have different lengths ({', '.join(map(str, sorted(lengths)))})")


def _check_result_values(stored: StoredResult) -> None:
    """The values a figure and a summary are made of: finite times and samples, a positive step, a
    direction of -1, 0 or 1, a name that fits a case's. ValueError says what is wrong."""
    from ..case import MAX_NAME_LENGTH  # the case files' (and yaml's) module: loaded where a file is read

    result = stored.result
    for label, values in (("/time_history", list(result.history.values())),
                          ("/ground", [result.ground_time, result.ground_horizontal, result.ground_vertical])):
        if not all(np.isfinite(column).all() for column in values):
            raise ValueError(f"{label} holds values that are not finite numbers")
    if not (math.isfinite(result.step) and result.step > 0):
        raise ValueError(f"integration_step = {result.step!r}; expected a positive step [s]")
    if len(stored.name) > MAX_NAME_LENGTH:
        raise ValueError(f"a name of {len(stored.name)} characters; a case's name has at most {MAX_NAME_LENGTH}")


def _data_only(f: h5py.File, source: str) -> None:
    """Refuse a file that would make rockslide read anything but itself: a link to another place
    (soft or external link) or a dataset whose values live elsewhere (external storage, a virtual
    dataset). A result handed over by someone else is read as data only, never as a way to read
    (or block on) another file of the reader's machine."""
    problems = []

    def visit(name, link):
        if not isinstance(link, h5py.HardLink):
            problems.append(f"{name} is a {type(link).__name__} (a link to elsewhere)")
            return None
        obj = f.get(name)
        if isinstance(obj, h5py.Dataset) and (obj.external or obj.is_virtual):
            problems.append(f"{name}'s values live in another file")
        return None

    f.visititems_links(visit)
    if problems:
        raise OutputError(f"not read: {problems[0]}; a rockslide file holds all its data itself", source=source)


def _read_body(f: h5py.File, attrs: dict, budget: h5checked.Budget) -> StoredResult:
    from ..core.simulate import Result

    def column(group, name, dtype):
        return h5checked.read_dataset(f[group][name], budget).astype(dtype, copy=False)

    history = {name: column("time_history", name, np.int8 if name == "state" else np.float64)
               for name in HISTORY_COLUMNS}
    events = _events_from_file(h5checked.read_dataset(f["events"], budget, kinds="V"))
    result = Result(
        history=history,
        events=events,
        summary=_summary_from_attrs(attrs),
        step=float(attrs["integration_step"]),
        ground_time=column("ground", "time", np.float64),
        ground_horizontal=column("ground", "horizontal", np.float64),
        ground_vertical=column("ground", "vertical", np.float64),
    )
    case_text, case = "", {}
    if "case" in f:
        case_attrs = dict(h5checked.attribute_values(_group(f, "case"), budget.source))
        case_text = case_attrs.pop("yaml", "")
        case = _unflatten(case_attrs)
    records = []
    if "records" in f:
        for role in RECORD_ROLES:
            if role in _group(f, "records"):
                group = h5checked.attribute_values(_group(f, f"records/{role}"), budget.source)
                records.append({key: _none_if_empty(group.get(key, "")) for key in RECORD_KEYS})
    ground = {key: None if math.isnan(attrs[f"ground_{key}"]) else float(attrs[f"ground_{key}"])
              for key in GROUND_KEYS if f"ground_{key}" in attrs}
    if "ground_orientation" in attrs:
        ground["components"] = {key: float(attrs[f"ground_{key}"]) for key in COMPONENT_KEYS}
    base = {key: column("base", key, np.float64) for key in ("time", "horizontal", "vertical")} \
        if "base" in f else {}
    return StoredResult(name=str(attrs.get("name", "")), result=result, case_text=case_text,
                        case=case, records=records, attrs=attrs, ground=ground, base=base)


def _group(f: h5py.File, name: str) -> h5py.Group:
    group = f[name]
    if not isinstance(group, h5py.Group):
        raise ValueError(f"/{name} is not a group")
    return group


def _summary_from_attrs(attrs: dict) -> Summary:
    from ..core.simulate import Summary

    def time_or_none(key):
        value = attrs[key]
        return None if math.isnan(value) else float(value)

    overturned = bool(attrs["overturned"])
    if attrs["direction"] not in (-1, 0, 1):
        raise ValueError(f"direction = {attrs['direction']!r}; expected -1, 0 or 1")
    direction = int(attrs["direction"])
    seen = attrs["states_seen"]
    return Summary(
        overturned=overturned,
        overturn_time=time_or_none("overturn_time"),
        direction=None if direction == 0 else direction,
        fall_start_time=time_or_none("fall_start_time"),
        max_rotation=float(attrs["max_rotation"]),
        max_rotation_time=float(attrs["max_rotation_time"]),
        max_slip=float(attrs["max_slip"]),
        residual_slip=float(attrs["residual_slip"]),
        impacts=int(attrs["impacts"]),
        states_seen=seen.split(",") if seen else [],
        time_in_state={key[len("time_in_state_"):]: float(value) for key, value in attrs.items()
                       if key.startswith("time_in_state_")},
        status=str(attrs["status"]),
        end_time=float(attrs["end_time"]),
        energy={key[len("energy_"):]: float(value) for key, value in attrs.items()
                if key.startswith("energy_")},
        alpha=float(attrs.get("alpha", math.nan)),
        max_rotation_ratio=float(attrs.get("max_rotation_ratio", math.nan)),
        undecided=bool(attrs.get("undecided", False)),
        alpha_2=float(attrs.get("alpha_2", attrs.get("alpha", math.nan))),     # files before: a rectangle
    )


_plain = h5checked.plain


def _none_if_empty(value):
    return None if isinstance(value, str) and value == "" else value


def _unflatten(flat: dict) -> dict:
    tree: dict = {}
    for dotted, value in flat.items():
        node = tree
        *parents, leaf = dotted.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = _none_if_empty(value)
    return tree


# --------------------------------------------------------------------------------------------------
# Sweeps: one file per grid, netCDF-4 style
# --------------------------------------------------------------------------------------------------

SWEEP_FORMAT = "rockslide-sweep"
SWEEP_FORMAT_VERSION = 1
FRAGILITY_FORMAT = "rockslide-fragility"
FRAGILITY_FORMAT_VERSION = 1
RISK_FORMAT = "rockslide-risk"
RISK_FORMAT_VERSION = 1
#: The ``format`` of each kind of rockslide file and its version (`file_format`).
FORMATS = {FORMAT: FORMAT_VERSION, SWEEP_FORMAT: SWEEP_FORMAT_VERSION,
           FRAGILITY_FORMAT: FRAGILITY_FORMAT_VERSION, RISK_FORMAT: RISK_FORMAT_VERSION}
#: What messages call each kind of file, and what it is a "rockslide ..." of; its name's ending.
_FORMAT_WHAT = {SWEEP_FORMAT: ("sweep file", "sweep", ".sweep.h5"),
                FRAGILITY_FORMAT: ("fragility file", "fragility analysis", ".fragility.h5"),
                RISK_FORMAT: ("risk file", "risk analysis", ".risk.h5")}


@dataclass
class StoredSweep:
    """A sweep file read back (`read_sweep`).

    Attributes
    ----------
    coords : list of (str, numpy.ndarray, dict)
        The axes in dimension order: name, values, attributes.
    variables : dict
        ``name -> (array shaped like the grid, attributes)``.
    attrs : dict
        Root attributes as plain Python values.
    """

    coords: list
    variables: dict
    attrs: dict


@dataclass
class StoredDataset:
    """A netCDF-4 style file read back (`read_dataset`).

    Attributes
    ----------
    coords : list of (str, numpy.ndarray, dict)
        The dimensions in order: name, coordinate values (strings as ``str``), attributes.
    variables : dict
        ``name -> (dimension names, array, attributes)``.
    attrs : dict
        Root attributes as plain Python values.
    """

    coords: list
    variables: dict
    attrs: dict


def write_sweep(path, coords, variables, *, attrs: dict | None = None, overwrite: bool = False,
                staging: Staging | None = None) -> Path:
    """Write a sweep's results on its grid to the HDF5 file ``path``, atomically.

    `write_dataset` with every variable on every axis, in order, and ``format`` =
    "rockslide-sweep".

    Parameters
    ----------
    path : str or Path
        The file (``OUT/NAME.sweep.h5``); its folder is created if missing.
    coords : sequence of (str, array_like, dict)
        The axes in dimension order: name, values (1-D), attributes.
    variables : mapping of str to (array_like, dict)
        Arrays shaped like the grid, and their attributes (``units``, ``long_name``...).
    attrs : dict, optional
        More root attributes (scalars, strings or 1-D numeric arrays).
    overwrite : bool
        Replace an existing file.
    staging : files.Staging, optional
        Publish the file with the other files of ``staging`` instead of at once.

    Returns
    -------
    Path

    Raises
    ------
    OutputError
        The file exists (without ``overwrite``) or cannot be written.
    ValueError
        A variable's shape is not the grid's, or a name is used twice.
    """
    dims = tuple(str(name) for name, _, _ in coords)
    return write_dataset(path, coords, {name: (dims, values, a) for name, (values, a) in variables.items()},
                         format=SWEEP_FORMAT, attrs=attrs, overwrite=overwrite, staging=staging)


def write_dataset(path, coords, variables, *, format: str, attrs: dict | None = None,
                  overwrite: bool = False, staging: Staging | None = None) -> Path:
    """Write labelled arrays to the HDF5 file ``path`` in the netCDF-4 data model, atomically.

    ``xarray.open_dataset(path, engine="h5netcdf")`` (or netCDF tools) read a labelled dataset:
    each dimension is a 1-D dataset at the root (float64, or variable-length UTF-8 strings: netCDF's
    ``string``) made an HDF5 dimension scale (with its attributes and ``_Netcdf4Dimid``), and each
    variable is a root dataset whose dimensions are attached to those scales in order. Root
    attributes: ``format``, ``format_version`` (from :data:`FORMATS`), ``created``, the
    `versions`, then ``attrs``. Written to a temporary file in the folder, then renamed.

    Parameters
    ----------
    path : str or Path
        The file; its folder is created if missing.
    coords : sequence of (str, array_like, dict)
        The dimensions in order: name, coordinate values (1-D numbers or strings), attributes.
    variables : mapping of str to (tuple of str, array_like, dict)
        Each variable's dimension names (a subset of ``coords``, in any order; ``()`` for a
        scalar), values shaped accordingly (numbers or strings) and attributes.
    format : str
        A key of :data:`FORMATS`.
    attrs : dict, optional
        More root attributes (scalars, strings or 1-D numeric arrays).
    overwrite : bool
        Replace an existing file.
    staging : files.Staging, optional
        Publish the file with the other files of ``staging`` instead of at once.

    Raises
    ------
    OutputError
        The file exists (without ``overwrite``) or cannot be written.
    ValueError
        A variable's shape does not match its dimensions, a dimension is unknown, or a name is
        used twice.
    """
    path = check_destination(path, overwrite=overwrite)
    coords = [(str(name), _column(values), dict(a)) for name, values, a in coords]
    sizes = {name: values.size for name, values, _ in coords}
    names = [name for name, _, _ in coords] + list(variables)
    if len(set(names)) != len(names):
        raise ValueError(f"names must be unique, got {names}")
    for name, (dims, values, _) in variables.items():
        unknown = [d for d in dims if d not in sizes]
        if unknown:
            raise ValueError(f"variable {name!r} has unknown dimensions {unknown}")
        if np.shape(values) != tuple(sizes[d] for d in dims):
            raise ValueError(f"variable {name!r} has shape {np.shape(values)}, its dimensions {dims} "
                             f"{tuple(sizes[d] for d in dims)}")
    tmp = staging.stage(path) if staging is not None else temporary_path(path)
    f, raw = _create_hdf5(tmp, path)
    try:
        with f:
            root = _Attributes(f)
            root["format"] = format
            root["format_version"] = FORMATS[format]
            root["created"] = datetime.now(UTC).isoformat(timespec="seconds")
            for key, value in {**versions(), **(attrs or {})}.items():
                root[key] = _attr_value(value)
            _write_labelled(f, coords, variables)
            f.flush()
        raw.close()
        raw.check()
    except BaseException as exc:
        remove_quietly(tmp)
        with contextlib.suppress(Exception):
            if f.id.valid:
                f.close()
        raw.close()
        remove_quietly(tmp)
        _raise_write_error(exc, raw, path)
    if staging is None:
        publish(tmp, path, overwrite=overwrite)
    return path


def _array(values) -> np.ndarray:
    """Numbers as they are; strings as HDF5 variable-length UTF-8 (netCDF-4 ``string``)."""
    values = np.asarray(values)
    if values.dtype.kind in "USO":
        return np.asarray(values, dtype=object).astype(h5py.string_dtype("utf-8"))
    return values


def _column(values) -> np.ndarray:
    """A coordinate: float64 numbers, or strings."""
    values = np.asarray(values)
    return _array(values) if values.dtype.kind in "USO" else np.asarray(values, dtype=np.float64)


def _what(format: str) -> str:
    return _FORMAT_WHAT.get(format, ("file", "file", ""))[0]


def file_format(path) -> str | None:
    """The ``format`` attribute of a rockslide HDF5 file (a key of :data:`FORMATS`: result, sweep or
    fragility file), or None if the file cannot be read as one."""
    try:
        regular_size(path, what="file", error=OutputError)
    except OutputError:
        return None                             # the reader of the kind asked says why
    try:
        with h5py.File(path, "r", locking=False) as f:
            size = h5checked.storage_size(f.attrs.get_id("format")) if "format" in f.attrs else 0
            value = _plain(f.attrs.get("format")) if size <= MAX_ATTRIBUTE_BYTES else None
    except OSError:
        return None
    return value if isinstance(value, str) and value in FORMATS else None


def read_sweep(path) -> StoredSweep:
    """Read a sweep file written by `write_sweep`.

    Raises
    ------
    OutputError
        The file is missing, not HDF5, or not a rockslide sweep (of a known version).
    """
    stored = read_dataset(path, format=SWEEP_FORMAT)
    return StoredSweep(coords=stored.coords,
                       variables={name: (values, a) for name, (_, values, a) in stored.variables.items()},
                       attrs=stored.attrs)


def read_dataset(path, *, format: str) -> StoredDataset:
    """Read a file written by `write_dataset` with ``format`` (a key of :data:`FORMATS`).

    Raises
    ------
    OutputError
        The file is missing, not HDF5, or not of that format (and a known version).
    """
    what, short, suffix = _FORMAT_WHAT.get(format, ("file", "file", ""))
    source = str(path)
    path = Path(path)
    if not path.exists():
        raise OutputError(f"{what} not found", source=source)
    if path.is_dir():
        raise OutputError(f"is a folder, expected a {what} ({suffix})", source=source)
    regular_size(path, what=f"{what} ({suffix})", error=OutputError)
    try:
        f = h5py.File(path, "r", locking=False)    # our own lock guards the files (io.files)
    except OSError as exc:
        raise OutputError(f"cannot read as a rockslide {short} ({error_reason(exc)})", source=source) from None
    with f:
        attrs = h5checked.attribute_values(f, source)
        if attrs.get("format") != format:
            raise OutputError(f"not a rockslide {short} (format is not {format!r})", source=source)
        if attrs.get("format_version") != FORMATS[format]:
            raise OutputError(f"{short} format version {attrs.get('format_version')!r} is "
                              f"not supported (this rockslide reads {FORMATS[format]})",
                              source=source)
        _data_only(f, source)
        budget = h5checked.Budget(source)
        try:
            attributes = {name: _dataset_attrs(ds, source) for name, ds in f.items() if isinstance(ds, h5py.Dataset)}
            scales = {name: ds for name, ds in f.items()        # is_scale reads CLASS, bounded above
                      if isinstance(ds, h5py.Dataset) and ds.is_scale}
            order = sorted(scales, key=lambda n: attributes[n].get("_Netcdf4Dimid", 0))
            budget.check_total(ds for ds in f.values() if isinstance(ds, h5py.Dataset))
            _check_dataset_layout(f, scales, format)
            coords = [(name, _coordinate(scales[name], budget), attributes[name]) for name in order]
            variables = h5checked.Entries(
                {name: (tuple(_dim_name(dim) for dim in ds.dims),
                        h5checked.read_dataset(ds, budget, ndim=None, text=True), attributes[name])
                 for name, ds in f.items() if isinstance(ds, h5py.Dataset) and name not in scales},
                source=source, what="variable")
        except OutputError:
            raise
        except (KeyError, ValueError, TypeError, IndexError, OSError, RuntimeError) as exc:
            raise OutputError(f"damaged rockslide {short} ({error_reason(exc)})", source=source) from None
    for _, _, a in coords:
        a.pop("_Netcdf4Dimid", None)
    return StoredDataset(coords=coords, variables=variables, attrs=attrs)


def _coordinate(ds, budget: h5checked.Budget) -> np.ndarray:
    """A dimension's values: 1-D text, or finite numbers (a figure's axis)."""
    values = h5checked.read_dataset(ds, budget, text=True)
    if values.dtype.kind in "iuf" and not np.isfinite(values).all():
        raise ValueError(f"the dimension {ds.name.lstrip('/')!r} holds values that are not finite numbers")
    return values


#: Root attributes that say when and how a file was written, not what it holds (`same_results`).
_PROVENANCE_ATTRS = frozenset({"created", "command_line"})


def same_results(a: StoredDataset, b: StoredDataset) -> bool:
    """Whether two files of `read_dataset` hold the same results: the same dimensions, variables
    (values, NaN where NaN, and attributes) and root attributes, less those of their writing (the
    time, the command line, the versions of the packages). A figure drawn from one shows the other.
    """
    def content(attrs):
        return {k: v for k, v in attrs.items() if k not in _PROVENANCE_ATTRS and not k.endswith("_version")}

    def equal(x, y) -> bool:
        x, y = np.asarray(x), np.asarray(y)
        if x.shape != y.shape or x.dtype.kind != y.dtype.kind:
            return False
        return bool(np.array_equal(x, y, equal_nan=x.dtype.kind in "fc"))

    if [name for name, _, _ in a.coords] != [name for name, _, _ in b.coords] \
            or a.variables.keys() != b.variables.keys():
        return False
    if not all(equal(x, y) and ax == ay for (_, x, ax), (_, y, ay) in zip(a.coords, b.coords, strict=True)):
        return False
    if not all(a.variables[n][0] == b.variables[n][0] and equal(a.variables[n][1], b.variables[n][1])
               and a.variables[n][2] == b.variables[n][2] for n in a.variables):
        return False
    return _attrs_equal(content(a.attrs), content(b.attrs))


def _attrs_equal(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a)


#: What each kind of file must hold to be drawn, printed and read: (dimensions, variables, root
#: attributes); a variable's last dimensions, where given (None: any), and its values, numbers
#: (``"number"``) or text (``"text"``). The attributes' kinds are `h5checked.ATTRIBUTE_KINDS`.
REQUIRED = {
    SWEEP_FORMAT: ((), {name: (None, "number") for name in ("overturned", "status", "modes", "max_rotation",
                                                            "residual_slip", "overturn_time", "max_rotation_ratio")},
                   ()),
    FRAGILITY_FORMAT: (("level", "damage_state"), {"exceeded": (("damage_state",), "number"),
                                                   "definition": (("damage_state",), "text")},
                       ("intensity_measure",)),
    RISK_FORMAT: (("curve", "point", "im"), {"rate": (("curve",), "number"), "density": (("curve", "im"), "number"),
                                            "hazard_level": (("curve", "point"), "number"),
                                            "hazard_rate": (("curve", "point"), "number"),
                                            "fragility": (("im",), "number")},
                  ("intensity_measure", "intensity_measure_display_scale", "intensity_measure_display_unit",
                   "intensity_measure_label", "damage_state", "fragility_form", "fragility_source")),
}


def _check_dataset_layout(f: h5py.File, scales: dict, format: str) -> None:
    """The dimensions and variables a file of ``format`` needs (`REQUIRED`), every coordinate
    one-dimensional and every variable shaped by its dimensions, at most `MAX_RESULT_ROWS` values
    each: checked on the shapes before anything is read. ValueError says what is wrong."""
    dims, names, attributes = REQUIRED.get(format, ((), {}, ()))
    if not scales:
        raise ValueError("no dimensions")
    for name in dims:
        if name not in scales:
            raise ValueError(f"no dimension {name!r}")
    for name in attributes:
        if name not in f.attrs:
            raise ValueError(f"no attribute {name!r}")
    for name, (last, kind) in names.items():
        if not isinstance(f.get(name, getlink=True), h5py.HardLink) or not isinstance(f[name], h5py.Dataset):
            raise ValueError(f"no variable {name!r}")
        ds = f[name]
        text = h5py.check_string_dtype(ds.dtype) is not None
        if (kind == "text") != text or (kind == "number" and ds.dtype.kind not in "biuf"):
            raise ValueError(f"the variable {name!r} is {ds.dtype}; expected {kind}")
        dims_of = tuple(_dim_name(dim) for dim in ds.dims)
        if last is not None and dims_of[len(dims_of) - len(last):] != last:
            raise ValueError(f"the variable {name!r} has dimensions ({', '.join(dims_of)}); expected them to end "
                             f"with ({', '.join(last)})")
        if format == SWEEP_FORMAT and set(dims_of) != set(scales):
            raise ValueError(f"the variable {name!r} has dimensions ({', '.join(dims_of)}); expected every axis "
                             f"({', '.join(scales)})")
    lengths = {}
    for name, ds in scales.items():
        if ds.ndim != 1:
            raise ValueError(f"the dimension {name!r} is not one-dimensional")
        lengths[name] = ds.shape[0]
    for name, ds in f.items():
        if not isinstance(ds, h5py.Dataset) or name in scales:
            continue
        if ds.size > MAX_RESULT_ROWS:
            raise ValueError(f"{name} declares {ds.size} values; rockslide reads at most {MAX_RESULT_ROWS:.0e}")
        dims_of = [_dim_name(dim) for dim in ds.dims]
        expected = tuple(lengths.get(dim, -1) for dim in dims_of)
        if ds.shape != expected:
            raise ValueError(f"{name} has shape {ds.shape} where its dimensions "
                             f"({', '.join(dims_of) or 'none'}) give {expected}")


def _dim_name(dim) -> str:
    return dim[0].name.rsplit("/", 1)[-1] if len(dim) else ""


def _dataset_attrs(ds, source: str) -> dict:
    """A dataset's attributes (bounded and checked, `h5checked.attribute_values`), less HDF5's
    dimension-scale bookkeeping; ``_Netcdf4Dimid`` kept as a count for the order of dimensions."""
    skip = {"CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST"}
    return dict(h5checked.attribute_values(ds, source, skip=skip))


# --------------------------------------------------------------------------------------------------
# JSON
# --------------------------------------------------------------------------------------------------


def summary_to_json_dict(summary: Summary, events=()) -> dict:
    """The summary (and event log) as a JSON-ready dict (``rockslide run --json``).

    None stays None (``null``); a non-finite float becomes None too, so the output is strict JSON.
    ``events`` (EVENT_DTYPE array or list of dicts) becomes a list of
    ``{"time", "from", "to", "cause"}``, with ``"impact"`` (the branch) and ``"energy_loss"`` [J] for
    impacts.
    """
    out = {}
    for f in dataclasses.fields(summary):
        out[f.name] = _json_value(getattr(summary, f.name))
        if f.name == "status":
            out["verdict"] = summary.verdict
    out["events"] = [_event_dict(e) for e in events]
    return out


def json_ready(value):
    """``value`` (nested dicts, lists, numpy scalars) as strict JSON values: a non-finite float
    becomes None."""
    return _json_value(value)


def _json_value(value):
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _json_value(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_json_value(v) for v in value]
    return str(value)


def _event_dict(event) -> dict:
    def text(v):
        return v.decode() if isinstance(v, bytes) else str(v)

    out = {"time": _json_value(float(event["time"])), "from": text(event["from"]),
           "to": text(event["to"]), "cause": text(event["cause"])}
    if "impact" in _fields(event) and text(event["impact"]):
        out["impact"] = text(event["impact"])
        out["energy_loss"] = _json_value(float(event["energy_loss"]))
    return out


def _fields(event):
    return event.keys() if isinstance(event, dict) else event.dtype.names


# --------------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------------


@contextlib.contextmanager
def _sigint_held():
    """Hold SIGINT back (POSIX, main thread) for a short cleanup; it is delivered afterwards."""
    held = (hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread())
    if held:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        if held:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


__all__ = ["write_result", "read_result", "ResultWriter", "StoredResult", "summary_to_json_dict", "json_ready",
           "write_sweep", "read_sweep", "StoredSweep", "SWEEP_FORMAT", "SWEEP_FORMAT_VERSION",
           "check_destination", "temporary_path", "versions", "FORMAT", "FORMAT_VERSION",
           "HISTORY_UNITS", "GROUND_UNITS", "STATE_CODES"]
