"""Result <-> HDF5: exact round trips, the documented layout, atomic writes, clear errors."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import signal
import subprocess
import sys
import textwrap
from datetime import datetime
from pathlib import Path

import h5py
import numpy as np
import pytest

from rockslide.core.kernel import CAUSE_NAMES, HISTORY_COLUMNS
from rockslide.core.simulate import EVENT_DTYPE, Model, Settings, Summary, simulate
from rockslide.errors import OutputError
from rockslide.io import files, results
from rockslide.io.results import ResultWriter, StoredResult, read_result, summary_to_json_dict, write_result

REPO = Path(__file__).resolve().parents[1]
TEMP_NAME = re.compile(r"^\..+\.\d+\.tmp$")


def pulse_result(amplitude=6.0, mu=0.52, vertical=0.3, frequency=1.5, on_chunk=None, **settings):
    t = np.arange(0, 10, 0.01)
    ah = amplitude * np.sin(2 * np.pi * frequency * t) * np.exp(-((t - 4) / 2) ** 2)
    model = Model.from_block(0.1, 0.2, mu, 0.95 * mu, 0.8)
    return simulate(model, 0.01, ah, vertical * ah, Settings(tail=2.0, **settings), on_chunk=on_chunk)


@pytest.fixture(scope="module")
def result():
    r = pulse_result()
    assert {"SLIP", "ROCK", "ROCKSLIP"} <= set(r.summary.states_seen) and len(r.events) > 10
    return r


@pytest.fixture(scope="module")
def overturned():
    r = pulse_result(amplitude=5.5, mu=0.8, vertical=0.0)
    assert r.summary.overturned
    return r


CASE = {"name": "demo", "gravity": 9.80665,
        "block": {"height": 0.2, "width": 0.1, "mass": 10.0},
        "contact": {"mu_static": 0.52, "mu_kinetic": 0.494, "restitution": 0.8},
        "ground": {"horizontal": {"file": "kobe_ns.at2", "skip_lines": 0},
                   "scale": {"pga_horizontal": 6.0, "vertical_factor": 1.0}, "tail": 2.0,
                   "time_shift": 0.0},
        "output": {"dir": "out", "interval": None}}
CASE_TEXT = "name: demo  # Kobe, µ = 0.52\nblock: {height: 0.2 m, width: 0.1 m, mass: 10 kg}\n"


def records_for(folder: Path) -> list[dict]:
    return [{"role": "horizontal", "path": str(folder / "records" / "kobe_ns.at2"), "sha256": "a" * 64,
             "format": "at2", "units": "g", "scale_factor": 0.73},
            {"role": "vertical", "path": str(folder / "records" / "kobe_ud.at2"), "sha256": "b" * 64,
             "format": "at2", "units": "g", "scale_factor": 0.73}]


def write_full(path, result, folder, **kwargs):
    return write_result(path, result, name="demo", case_text=CASE_TEXT, case=CASE,
                        records=records_for(folder), extra_attrs={"command": "rockslide run"}, **kwargs)


def file_contents(path) -> dict:
    """Every dataset and attribute of an HDF5 file, keyed by path (``created`` left out)."""
    out = {}

    def visit(name, obj):
        for key, value in obj.attrs.items():
            if key in ("DIMENSION_LIST", "REFERENCE_LIST"):     # HDF5's object references: compared by name
                value = np.array([h5py.h5r.get_name(ref, obj.file.id) if isinstance(ref, h5py.Reference)
                                  else str(ref) for ref in np.ravel(value).tolist()], dtype=object)
            out[f"{name}@{key}"] = value
        if isinstance(obj, h5py.Dataset):
            out[name] = obj[()]
            out[f"{name}#dtype"] = obj.dtype

    with h5py.File(path, "r") as f:
        visit("/", f)
        f.visititems(visit)
    out.pop("/@created")
    return out


def assert_same_contents(a: dict, b: dict):
    assert a.keys() == b.keys()
    for key in a:
        if isinstance(a[key], np.ndarray):
            assert a[key].dtype == b[key].dtype, key
            assert np.array_equal(a[key], b[key], equal_nan=a[key].dtype.kind == "f"), key
        elif isinstance(a[key], float) and math.isnan(a[key]):
            assert math.isnan(b[key]), key
        else:
            assert a[key] == b[key], key


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# --------------------------------------------------------------------------------------------------
# Round trip
# --------------------------------------------------------------------------------------------------


def test_round_trip_is_exact(tmp_path, result):
    path = write_full(tmp_path / "out" / "demo.h5", result, tmp_path)
    assert path == tmp_path / "out" / "demo.h5" and path.is_file()
    stored = read_result(path)
    assert isinstance(stored, StoredResult)
    back = stored.result
    assert back.history.keys() == result.history.keys()
    for key in HISTORY_COLUMNS:
        assert back.history[key].dtype == result.history[key].dtype, key
        assert np.array_equal(back.history[key], result.history[key]), key
    assert back.events.dtype == EVENT_DTYPE
    assert np.array_equal(back.events, result.events)
    assert back.summary == result.summary
    assert back.summary.verdict == result.summary.verdict
    assert back.step == result.step
    for key in ("ground_time", "ground_horizontal", "ground_vertical"):
        assert np.array_equal(getattr(back, key), getattr(result, key)), key
    assert back.events_as_dicts() == result.events_as_dicts()
    assert stored.name == "demo"
    assert stored.case_text == CASE_TEXT
    assert stored.case == CASE
    assert [r["path"] for r in stored.records] == ["kobe_ns.at2", "kobe_ud.at2"]
    assert stored.records[0] == {**records_for(tmp_path)[0], "path": "kobe_ns.at2"}
    assert stored.attrs["command"] == "rockslide run"
    assert stored.attrs["verdict"] == "standing" and stored.attrs["status"] == "ok"


def test_none_fields_are_restored(tmp_path, result, overturned):
    standing = read_result(write_result(tmp_path / "a.h5", result, name="a")).result.summary
    assert standing.overturn_time is None and standing.direction is None
    assert standing.fall_start_time is None and standing.overturned is False
    fallen = read_result(write_result(tmp_path / "b.h5", overturned, name="b")).result.summary
    assert fallen == overturned.summary
    assert fallen.overturned is True and fallen.direction in (-1, 1)
    assert fallen.overturn_time == overturned.summary.overturn_time
    assert fallen.fall_start_time == overturned.summary.fall_start_time
    with h5py.File(tmp_path / "a.h5") as f:
        assert math.isnan(f.attrs["overturn_time"]) and math.isnan(f.attrs["fall_start_time"])
        assert f.attrs["direction"] == 0


def test_outcomes_outside_the_model_round_trip(tmp_path):
    r = pulse_result(amplitude=3.0, mu=2.0, vertical=0.0, slip_rate=0.5)    # nu = 1.9 > 4/3: Painleve at once
    assert r.summary.status == "painleve"
    back = read_result(write_result(tmp_path / "p.h5", r, name="p")).result
    assert back.summary == r.summary
    assert back.summary.verdict.startswith("outside the model (painleve")


def test_result_without_history(tmp_path):
    r = pulse_result(history_every=0)
    assert r.history["time"].size == 0
    back = read_result(write_result(tmp_path / "n.h5", r, name="n")).result
    assert all(back.history[k].size == 0 for k in HISTORY_COLUMNS)
    assert back.history["state"].dtype == np.int8
    assert back.summary == r.summary and np.array_equal(back.events, r.events)


def test_minimal_result_has_no_case_or_records(tmp_path, result):
    path = write_result(tmp_path / "m.h5", result, name="m")
    with h5py.File(path) as f:
        assert "case" not in f and "records" not in f
    stored = read_result(path)
    assert stored.case == {} and stored.case_text == "" and stored.records == []


# --------------------------------------------------------------------------------------------------
# Layout
# --------------------------------------------------------------------------------------------------


def documented_paths() -> set[str]:
    """The paths listed in the module docstring's layout table."""
    paths = re.findall(r"^\| `(/[^`]*)` \|", results.__doc__, flags=re.MULTILINE)
    assert paths, "no layout table in rockslide/results.py's docstring"
    return set(paths)


def test_layout_is_exactly_as_documented(tmp_path, result):
    path = write_full(tmp_path / "demo.h5", result, tmp_path)
    names = {"/"}
    with h5py.File(path) as f:
        f.visit(lambda name: names.add("/" + name))
    assert names == documented_paths()


def test_units_compression_and_codes(tmp_path, result):
    path = write_full(tmp_path / "demo.h5", result, tmp_path)
    expected_units = {"time": "s", "rotation": "rad", "rotation_rate": "rad/s", "slip": "m",
                      "slip_rate": "m/s"}
    with h5py.File(path) as f:
        for name, units in expected_units.items():
            ds = f["time_history"][name]
            assert ds.attrs["units"] == units and ds.dtype == np.float64
        for name in HISTORY_COLUMNS:
            ds = f["time_history"][name]
            assert ds.chunks and ds.compression == "gzip" and ds.compression_opts == 1 and ds.shuffle
        state = f["time_history/state"]
        assert state.dtype == np.int8
        assert state.attrs["codes"] == "0 REST, 1 SLIP, 2 ROCK, 3 ROCKSLIP, 4 OVERTURNED"
        assert [f["ground"][k].attrs["units"] for k in ("time", "horizontal", "vertical")] == \
            ["s", "m/s^2", "m/s^2"]

        def has_units(name, obj):
            if isinstance(obj, h5py.Dataset):
                assert "units" in obj.attrs, name
        f.visititems(has_units)
        assert f["events"].dtype.names == ("time", "from", "to", "cause", "edge", "slip_direction", "impact",
                                           "energy_loss")
        assert f["events"].dtype["edge"] == np.int8
        for name in ("from", "to", "cause", "impact"):          # text, not bytes
            assert h5py.check_string_dtype(f["events"].dtype[name]).encoding == "utf-8"
        assert {c.decode() for c in f["events"]["cause"]} <= set(CAUSE_NAMES)


def test_root_attributes(tmp_path, result):
    path = write_full(tmp_path / "demo.h5", result, tmp_path)
    with h5py.File(path) as f:
        attrs = dict(f.attrs)
    s = result.summary
    for field in dataclasses.fields(Summary):
        if field.name in ("time_in_state", "energy"):
            continue
        assert field.name in attrs, field.name
    assert attrs["states_seen"] == ",".join(s.states_seen)
    for state, seconds in s.time_in_state.items():
        assert attrs[f"time_in_state_{state}"] == seconds
    for term, joules in s.energy.items():
        assert attrs[f"energy_{term}"] == joules
    assert attrs["format"] == "rockslide-result" and attrs["format_version"] == 1
    assert attrs["name"] == "demo" and attrs["verdict"] == s.verdict
    assert attrs["integration_step"] == result.step
    assert isinstance(attrs["overturned"], (bool, np.bool_))
    created = datetime.fromisoformat(attrs["created"])
    assert created.utcoffset().total_seconds() == 0
    for package in ("rockslide", "python", "numpy", "numba", "h5py", "obspy", "scipy", "matplotlib"):
        assert isinstance(attrs[f"{package}_version"], str) and attrs[f"{package}_version"]
    assert attrs["h5py_version"] == h5py.__version__



@pytest.mark.parametrize("value", [
    "", "text", "Δt = 0.1 ms, µ", "a\nb", 0.0, -0.0, 1.5, math.nan, math.inf, -math.inf, 5e-324, 0, -1, 2**63 - 1,
    -2**63, 2**63, -2**63 - 1, True, False, np.float64(2.5), np.int32(3), np.bool_(True), np.arange(3),
    np.array([0.5, 1.5]), b"bytes"], ids=repr)
def test_attributes_are_stored_as_h5pys_attrs_stores_them(tmp_path, value):
    """`results._Attributes` takes plain scalars through h5py's low-level API (its docstring): the
    HDF5 type (H5Tequal), shape and value of each attribute are those of ``attrs[name] = value``,
    h5py's own path, for new names, a name already there (replaced) and a name that is not ASCII;
    values h5py refuses are refused alike."""
    with h5py.File(tmp_path / "a.h5", "w") as f:
        fast, plain = f.create_group("fast"), f.create_group("plain")
        for name in ("new", "was_there", "Δ"):
            refused = []
            for group, write in ((fast, lambda g, n, v: results._Attributes(g).__setitem__(n, v)),
                                 (plain, lambda g, n, v: g.attrs.__setitem__(n, v))):
                group.attrs["was_there"] = "an older value, of another type"
                try:
                    write(group, name, value)
                except Exception as exc:  # noqa: BLE001 - what h5py refuses, both must refuse
                    refused.append(type(exc))
            assert refused in ([], [OverflowError, OverflowError], [TypeError, TypeError]), refused
            if refused:
                continue
            a, b = fast.attrs.get_id(name), plain.attrs.get_id(name)
            assert a.get_type() == b.get_type() and a.shape == b.shape and a.dtype == b.dtype, name
            if a.get_type().get_class() == h5py.h5t.STRING:        # H5Tequal leaves the character set out
                assert (a.get_type().get_cset(), a.get_type().is_variable_str()) == \
                    (b.get_type().get_cset(), b.get_type().is_variable_str()), name
            x, y = fast.attrs[name], plain.attrs[name]
            assert type(x) is type(y) and np.array_equal(x, y, equal_nan=np.asarray(x).dtype.kind == "f"), (x, y)
            assert name in results._Attributes(fast)


def test_case_is_flattened_with_dotted_keys(tmp_path, result):
    path = write_full(tmp_path / "demo.h5", result, tmp_path)
    with h5py.File(path) as f:
        case = f["case"].attrs
        assert case["yaml"] == CASE_TEXT
        assert case["contact.mu_static"] == 0.52
        assert case["ground.horizontal.file"] == "kobe_ns.at2"
        assert case["output.interval"] == ""            # None
        assert f["records/vertical"].attrs["scale_factor"] == 0.73


def test_no_absolute_path_is_stored(tmp_path, result):
    path = write_full(tmp_path / "demo.h5", result, tmp_path)
    strings = []

    def collect(name, obj):
        strings.extend(v for v in obj.attrs.values() if isinstance(v, str))

    with h5py.File(path) as f:
        collect("/", f)
        f.visititems(collect)
    assert strings
    for text in strings:
        assert str(tmp_path) not in text and not text.startswith("/"), text
        assert str(REPO) not in text, text


def test_extra_attributes_cannot_replace_standard_ones(tmp_path, result):
    with pytest.raises(ValueError, match="verdict"):
        write_result(tmp_path / "x.h5", result, name="x", extra_attrs={"verdict": "fine"})
    assert leftovers(tmp_path) == []


# --------------------------------------------------------------------------------------------------
# Streaming
# --------------------------------------------------------------------------------------------------


def test_streaming_gives_the_same_file(tmp_path, result):
    whole = write_full(tmp_path / "whole.h5", result, tmp_path)
    with ResultWriter(tmp_path / "streamed.h5") as writer:
        t = np.arange(0, 10, 0.01)
        ah = 6.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-((t - 4) / 2) ** 2)
        streamed_result = simulate(Model.from_block(0.1, 0.2, 0.52, 0.494, 0.8), 0.01, ah, 0.3 * ah,
                                   Settings(tail=2.0, chunk_steps=97 * 100),
                                   on_chunk=writer.append_history)
        assert streamed_result.history["time"].size == 0          # streamed, not kept
        assert writer.rows_written == result.history["time"].size
        assert not (tmp_path / "streamed.h5").exists()             # nothing before finish()
        writer.finish(streamed_result, name="demo", case_text=CASE_TEXT, case=CASE,
                      records=records_for(tmp_path), extra_attrs={"command": "rockslide run"})
    assert_same_contents(file_contents(whole), file_contents(tmp_path / "streamed.h5"))
    assert leftovers(tmp_path) == ["streamed.h5", "whole.h5"]


def assert_same_result(a, b):
    """Two results hold the same values to the bit, with the same types."""
    assert a.history.keys() == b.history.keys() == set(HISTORY_COLUMNS)
    for key in HISTORY_COLUMNS:
        assert a.history[key].dtype == b.history[key].dtype, key
        assert np.array_equal(a.history[key], b.history[key]), key
    assert a.events.dtype == b.events.dtype and np.array_equal(a.events, b.events)
    assert a.summary == b.summary and a.step == b.step
    for key in ("ground_time", "ground_horizontal", "ground_vertical"):
        assert getattr(a, key).dtype == getattr(b, key).dtype, key
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


@pytest.mark.parametrize("chunk_steps", [97 * 100, None, "early"])
def test_the_result_kept_in_memory_is_the_file_read_back(tmp_path, chunk_steps):
    """What the writer keeps for the run's figure (`ResultWriter.written_result`) equals what
    `read_result` gives back from the file: a history streamed in 13 chunks, given whole to
    `finish`, or written whole before it (`ResultWriter.write_history`)."""
    with ResultWriter(tmp_path / "r.h5", keep_rows=10**6) as writer:
        if chunk_steps is None:
            kept = pulse_result()
        elif chunk_steps == "early":
            kept = pulse_result()
            writer.write_history(kept.history)
            assert writer.rows_written == kept.history["time"].size
        else:
            kept = pulse_result(chunk_steps=chunk_steps, on_chunk=writer.append_history)
            assert kept.history["time"].size == 0 and writer.rows_written == 119_901
        writer.finish(kept, name="demo", case_text=CASE_TEXT, case=CASE, records=records_for(tmp_path))
    assert_same_result(writer.written_result(), read_result(tmp_path / "r.h5").result)


def test_a_history_longer_than_keep_rows_is_read_from_the_file(tmp_path, result):
    """Up to ``keep_rows`` streamed rows are kept; beyond, or without ``keep_rows``, none."""
    rows = np.column_stack([result.history[k] for k in HISTORY_COLUMNS])
    for keep, parts, expected in ((25, (10, 15), 25), (24, (10, 15), None), (0, (25,), None)):
        with ResultWriter(tmp_path / f"s{keep}.h5", keep_rows=keep) as writer:
            start = 0
            for n in parts:
                writer.append_history(rows[start:start + n])
                start += n
            writer.finish(result, name="s")
        written = writer.written_result()
        if expected is None:
            assert written is None, keep
        else:
            assert written.history["time"].size == expected
            assert_same_result(written, read_result(tmp_path / f"s{keep}.h5").result)


def test_streamed_rows_win_over_result_history(tmp_path, result):
    rows = np.column_stack([result.history[k] for k in HISTORY_COLUMNS])
    with ResultWriter(tmp_path / "s.h5") as writer:
        writer.append_history(rows[:10])
        writer.append_history(rows[10:25])
        writer.append_history(np.zeros((0, 6)))
        writer.finish(result, name="s")
    back = read_result(tmp_path / "s.h5").result
    assert np.array_equal(back.history["rotation"], result.history["rotation"][:25])
    assert np.array_equal(back.history["state"], result.history["state"][:25])


def test_a_history_written_before_finish_gives_the_file_finish_writes(tmp_path, result):
    """`ResultWriter.write_history` (a run's history written while its ensemble computes) then
    `finish` with that result: the same datasets, attributes and values as `finish` alone; the
    history is not written twice, and no rows may be appended or the history written again."""
    with ResultWriter(tmp_path / "alone.h5") as writer:
        writer.finish(result, name="r", case_text=CASE_TEXT, case=CASE)
    with ResultWriter(tmp_path / "early.h5") as writer:
        writer.write_history(result.history)
        with pytest.raises(ValueError, match="already written"):
            writer.write_history(result.history)
        with pytest.raises(ValueError, match="already written"):
            writer.append_history(np.zeros((1, 6)))
        writer.finish(result, name="r", case_text=CASE_TEXT, case=CASE)
    alone, early = read_result(tmp_path / "alone.h5"), read_result(tmp_path / "early.h5")
    assert_same_result(alone.result, early.result)
    assert early.result.history["time"].size == result.history["time"].size
    assert {k: str(v) for k, v in alone.attrs.items() if k != "created"} == \
        {k: str(v) for k, v in early.attrs.items() if k != "created"}
    with ResultWriter(tmp_path / "none.h5") as writer:
        writer.write_history({})                          # no history: nothing written, once
        with pytest.raises(ValueError, match="already written"):
            writer.write_history(result.history)
    with h5py.File(tmp_path / "alone.h5") as a, h5py.File(tmp_path / "early.h5") as b:
        names_a, names_b = [], []
        a.visit(names_a.append)
        b.visit(names_b.append)
        assert names_a == names_b
        for name in names_a:
            if isinstance(a[name], h5py.Dataset):
                assert (a[name].shape, a[name].dtype, a[name].compression, a[name].shuffle, a[name].chunks) == \
                    (b[name].shape, b[name].dtype, b[name].compression, b[name].shuffle, b[name].chunks), name


def test_writer_rejects_bad_rows_and_second_finish(tmp_path, result):
    with ResultWriter(tmp_path / "w.h5") as writer:
        with pytest.raises(ValueError, match=r"float64\[n, 6\]"):
            writer.append_history(np.zeros((3, 5)))
    assert leftovers(tmp_path) == []
    with ResultWriter(tmp_path / "w.h5") as writer:
        writer.finish(result, name="w")
        with pytest.raises(OutputError, match="closed"):
            writer.finish(result, name="w")
    assert leftovers(tmp_path) == ["w.h5"]


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_exception_in_the_block_leaves_nothing(tmp_path, result, error):
    with pytest.raises(type(error)):
        with ResultWriter(tmp_path / "out" / "x.h5") as writer:
            writer.append_history(np.zeros((1000, 6)))
            assert TEMP_NAME.match(writer.tmp.name) and writer.tmp.exists()
            raise error
    assert leftovers(tmp_path / "out") == []


def test_leaving_the_block_without_finish_publishes_nothing(tmp_path):
    with ResultWriter(tmp_path / "x.h5") as writer:
        writer.append_history(np.zeros((10, 6)))
    assert leftovers(tmp_path) == []


def test_failed_rewrite_keeps_the_previous_file(tmp_path, result, overturned):
    path = write_full(tmp_path / "x.h5", result, tmp_path)
    before = path.read_bytes()
    with pytest.raises(RuntimeError, match="midway"):
        with ResultWriter(path, overwrite=True) as writer:
            writer.append_history(np.ones((5000, 6)))
            assert read_result(path).result.summary == result.summary   # still the old file
            raise RuntimeError("midway")
    assert path.read_bytes() == before
    assert leftovers(tmp_path) == ["x.h5"]
    # and a successful rewrite replaces it
    write_result(path, overturned, name="again", overwrite=True)
    assert read_result(path).name == "again"
    assert leftovers(tmp_path) == ["x.h5"]


# --------------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------------


def test_existing_file_is_refused_before_any_work(tmp_path, result, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write_result("out/x.h5", result, name="x")
    before = (tmp_path / "out" / "x.h5").read_bytes()
    for attempt in (lambda: ResultWriter("out/x.h5"), lambda: write_result("out/x.h5", result, name="y")):
        with pytest.raises(OutputError) as info:
            attempt()
        assert str(info.value) == "out/x.h5 exists (use --overwrite to replace it)"
    assert leftovers(tmp_path / "out") == ["x.h5"]
    assert (tmp_path / "out" / "x.h5").read_bytes() == before


def test_folder_is_created(tmp_path, result):
    path = write_result(tmp_path / "a" / "b" / "c.h5", result, name="c")
    assert path.is_file()


def test_unwritable_folder(tmp_path, result):
    blocker = tmp_path / "plainfile"
    blocker.write_text("not a folder")
    target = blocker / "sub" / "x.h5"
    with pytest.raises(OutputError) as info:
        write_result(target, result, name="x")
    message = str(info.value)
    assert str(blocker / "sub") in message and "folder" in message and "\n" not in message
    with pytest.raises(OutputError, match="plainfile"):
        ResultWriter(blocker / "x.h5")


def test_result_path_that_is_a_folder(tmp_path, result):
    (tmp_path / "x.h5").mkdir()
    with pytest.raises(OutputError, match="is a folder"):
        write_result(tmp_path / "x.h5", result, name="x", overwrite=True)


def test_read_missing_file(tmp_path):
    with pytest.raises(OutputError) as info:
        read_result(tmp_path / "nothing.h5")
    assert "nothing.h5" in str(info.value) and "not found" in str(info.value)


def test_read_a_file_that_is_not_hdf5(tmp_path):
    path = tmp_path / "notes.h5"
    path.write_text("time,rotation\n0,0\n")
    with pytest.raises(OutputError) as info:
        read_result(path)
    message = str(info.value)
    assert "notes.h5" in message and "not an HDF5 file" in message and "\n" not in message


def test_read_an_hdf5_file_that_is_not_a_result(tmp_path):
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    with pytest.raises(OutputError, match=r"other\.h5.*not a rockslide result"):
        read_result(path)


def test_read_a_damaged_result(tmp_path, result):
    path = write_result(tmp_path / "d.h5", result, name="d")
    with h5py.File(path, "a") as f:
        del f["events"]
    with pytest.raises(OutputError, match=r"d\.h5: damaged rockslide result"):
        read_result(path)


# --------------------------------------------------------------------------------------------------
# Kill and Ctrl-C in the middle of a write
# --------------------------------------------------------------------------------------------------

WRITER_SCRIPT = textwrap.dedent("""
    import signal, sys, time
    import numpy as np
    from rockslide.io.results import ResultWriter
    # Ctrl-C raises KeyboardInterrupt even if this process inherited an ignored SIGINT (background jobs)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    rows = np.random.default_rng(1).random((200_000, 6))
    with ResultWriter(sys.argv[1], overwrite=True) as writer:
        writer.append_history(rows)
        print("appending", flush=True)
        for _ in range(2_000):
            writer.append_history(rows[:20_000])
            time.sleep(0.005)
    print("not interrupted", flush=True)
""")


def start_writer(target: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))}
    proc = subprocess.Popen([sys.executable, "-c", WRITER_SCRIPT, str(target)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    if line.strip() != "appending":
        proc.kill()
        pytest.fail(f"writer did not start: {line!r} {proc.stderr.read()}")
    return proc


@pytest.mark.parametrize("previous", [False, True], ids=["new", "rewrite"])
def test_killed_writer_never_leaves_a_half_written_result(tmp_path, result, previous):
    target = tmp_path / "x.h5"
    before = write_result(target, result, name="old").read_bytes() if previous else None
    proc = start_writer(target)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    names = leftovers(tmp_path)
    if previous:
        assert target.read_bytes() == before
        assert read_result(target).name == "old"
        names.remove("x.h5")
    else:
        assert not target.exists()
    # a killed process may leave its temporary file: a dot file ending in .tmp, never the result name
    assert names in ([], [f".x.h5.{proc.pid}.{files.place_token()}.tmp"])
    assert all(TEMP_NAME.match(name) for name in names)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX-only")
def test_ctrl_c_during_a_write_leaves_nothing(tmp_path):
    target = tmp_path / "x.h5"
    proc = start_writer(target)
    # Python may swallow a KeyboardInterrupt raised inside a weakref callback ("Exception ignored
    # in ..."); like a user, press Ctrl-C again if the first one was lost.
    for _ in range(20):
        proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=3)
            break
        except subprocess.TimeoutExpired:
            continue
    else:
        proc.kill()
        proc.communicate()
        pytest.fail("the writer did not stop on SIGINT")
    assert proc.returncode != 0 and "KeyboardInterrupt" in err
    assert leftovers(tmp_path) == []


# --------------------------------------------------------------------------------------------------
# JSON
# --------------------------------------------------------------------------------------------------


def test_summary_to_json_dict(result, overturned):
    out = summary_to_json_dict(result.summary, result.events)
    text = json.dumps(out, allow_nan=False)
    back = json.loads(text)
    assert back["overturned"] is False and back["overturn_time"] is None
    assert back["direction"] is None and back["fall_start_time"] is None
    assert back["verdict"] == "standing" and back["status"] == "ok"
    assert back["states_seen"] == result.summary.states_seen
    assert back["time_in_state"] == result.summary.time_in_state
    assert back["max_rotation"] == result.summary.max_rotation
    assert back["events"] == result.events_as_dicts()
    assert set(back["events"][0]) == {"time", "from", "to", "cause"}
    fallen = json.loads(json.dumps(summary_to_json_dict(overturned.summary, overturned.events)))
    assert fallen["overturned"] is True and fallen["overturn_time"] == overturned.summary.overturn_time
    assert fallen["events"][-1]["to"] == "OVERTURNED"


def test_summary_to_json_dict_is_strict_json():
    s = Summary(overturned=False, overturn_time=None, direction=None, fall_start_time=None,
                max_rotation=0.0, max_rotation_time=0.0, max_slip=0.0, residual_slip=0.0, impacts=0,
                states_seen=["REST"], time_in_state={"REST": 1.0}, status="ok", end_time=1.0,
                energy={"balance_residual": float("nan")})
    out = summary_to_json_dict(s)
    assert out["energy"] == {"balance_residual": None} and out["events"] == []
    json.dumps(out, allow_nan=False)


def test_the_versions_stored_are_those_importlib_metadata_gives():
    """`results.versions` reads the installed distributions from their ``.dist-info`` folders'
    names instead of importlib.metadata (30 ms of a run): the same versions."""
    import importlib.metadata
    import platform

    from rockslide.io import results

    expected = {f"{package}_version": importlib.metadata.version(package)
                for package in results.VERSIONED_PACKAGES if package != "python"}
    assert results.versions() == {**expected, "python_version": platform.python_version()}
    assert set(results.VERSIONED_PACKAGES) - {"python"} <= set(results.installed_versions())


def test_after_the_disk_fills_hdf5_reads_back_what_it_wrote(tmp_path):
    """`_RawFile` once a write failed (the disk full): every later write is kept in memory and
    laid over what is read back, and reading past the end gives zeros, so libhdf5 never reads stale
    or missing bytes (it once crashed doing so); the first error is kept for `check`."""
    import errno

    from rockslide.io.results import _RawFile

    raw = _RawFile(tmp_path / "f.tmp")
    raw.write(b"A" * 10)

    class Full:
        def __init__(self, inner):
            self.inner = inner

        def write(self, data):
            raise OSError(errno.ENOSPC, "No space left on device")

        def __getattr__(self, name):
            return getattr(self.inner, name)

    raw._file = Full(raw._file)
    raw.seek(5)
    assert raw.write(b"BBBBBBBBBB") == 10            # reported as done
    raw.seek(30)
    raw.write(b"CC")
    raw.seek(0)
    assert raw.read(32) == b"AAAAA" + b"B" * 10 + b"\0" * 15 + b"CC"
    assert raw.seek(0, 2) == 32 and raw.tell() == 32
    with pytest.raises(OSError, match="No space left"):
        raw.check()
    raw.close()
    assert (tmp_path / "f.tmp").read_bytes() == b"A" * 10      # nothing after the failure reached the disk


@pytest.mark.parametrize(("shape", "dtype"), [((1000, 1001), np.float64), ((70001,), np.float64),
                                              ((333, 777), np.int8), ((301, 300), np.int32), ((65537,), np.int64)])
def test_a_large_variable_is_stored_as_hdf5_would_store_it(tmp_path, shape, dtype):
    """`results._compressed_dataset` compresses the chunks itself, on threads: the dataset has the
    chunks and filters of h5py's own compressed write of the same array, HDF5 reads the values back
    through its filters (edge chunks included), and each stored chunk, all filters applied (mask 0),
    holds the bytes of h5py's chunk at the same place once inflated (shuffled alike, an edge chunk's
    padding alike)."""
    import zlib

    rng = np.random.default_rng(7)
    values = (rng.random(shape) * 100).astype(dtype)
    if values.dtype.kind == "f":
        values[values < 30] = np.nan
    with h5py.File(tmp_path / "x.h5", "w") as f:
        results._compressed_dataset(f, "ours", values)
        f.create_dataset("theirs", data=values, chunks=True, **results._COMPRESSION)
    with h5py.File(tmp_path / "x.h5") as f:
        ours, theirs = f["ours"], f["theirs"]
        assert (ours.chunks, ours.compression, ours.compression_opts, ours.shuffle, ours.dtype) == \
               (theirs.chunks, theirs.compression, theirs.compression_opts, theirs.shuffle, theirs.dtype)
        assert np.array_equal(ours[...], values, equal_nan=True)
        assert ours.id.get_num_chunks() == theirs.id.get_num_chunks() > 1
        for i in range(ours.id.get_num_chunks()):
            start = ours.id.get_chunk_info(i).chunk_offset
            mask, stored = ours.id.read_direct_chunk(start)
            assert mask == 0
            assert zlib.decompress(stored) == zlib.decompress(theirs.id.read_direct_chunk(start)[1])
