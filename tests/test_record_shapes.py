"""Record files in the shapes laboratories write them (issue 27): named header lines, several
separators, units in the header, time columns printed to a few decimals, many columns.

Every file is written here from known numbers; the expected step, unit factor and values are those
numbers, never a run of the reader. Refusals go through the command line: one line, exit 2, the file,
the line and the option that would work.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from conftest import REPO

from rockslide.case import load_case
from rockslide.cli import main
from rockslide.engine.prepare import read_records
from rockslide.errors import RecordError
from rockslide.io.records import RecordWarning, load_record

G = 9.80665   # [m/s^2] standard gravity
GAL = 0.01    # [m/s^2]
RATE = 800    # [Hz] the shake table's sampling rate in the issue
N = 801       # samples: 0 to 1 s, so that the printed span is exact and span / count is 1/800


def _signal():
    """Times [s] and an acceleration [in the file's unit] printed to 6 decimals (read back exactly
    as the decimal numbers written)."""
    time = np.arange(N) / RATE
    accel = np.round(0.3 * np.sin(2 * np.pi * 7 * time), 6)
    return time, accel


def _table(header_lines, separator, columns, *, time_decimals=4) -> str:
    """``columns``: extra columns after (time, acceleration), each ``k * accel``."""
    time, accel = _signal()
    rows = []
    for t, a in zip(time, accel, strict=True):
        fields = [f"{t:.{time_decimals}f}", f"{a:.6f}"] + [f"{k * a:.6f}" for k in range(2, columns)]
        rows.append(separator.join(fields))
    return "\n".join([*header_lines, *rows]) + "\n"


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def _check(record, factor, *, column=1):
    """The record holds ``column * accel * factor`` [m/s^2] at the step 1/800 s."""
    _, accel = _signal()
    # span / count from the printed first and last times (0.0000 and 1.0000: exact), divided in float
    assert record.dt == pytest.approx(1 / RATE, rel=1e-12)
    # the numbers written (column * accel, printed to 6 decimals) times the unit factor, to float64
    np.testing.assert_allclose(record.data, np.round(column * accel, 6) * factor, rtol=1e-12, atol=0)


# --------------------------------------------------------------------------------------------------
# Shapes that read
# --------------------------------------------------------------------------------------------------

SEPARATED = {
    "tab": ("\t", "Time (s)\tAcceleration (g)"),
    "comma": (",", "Time (s),Acceleration (g)"),
    "semicolon": (";", "Time [s];Acceleration [g]"),
    "spaces": ("   ", "Time (s)   Acceleration (g)"),
    "single-space": (" ", "Time (s) Acceleration (g)"),
}


@pytest.mark.parametrize("shape", SEPARATED)
def test_named_header_with_units_any_separator(tmp_path, shape):
    """The names hold spaces and a unit in brackets; no option is needed: the header says g."""
    separator, header = SEPARATED[shape]
    record = load_record(_write(tmp_path, "r.txt", _table([header], separator, 2)))
    assert record.units == "g" and record.format == "column"
    _check(record, G)


def test_the_issue_file_eight_columns_time_to_four_decimals(tmp_path):
    """The user's Test100.txt: tab separated, 8 named columns, 800 Hz printed to 4 decimals (steps of
    0.0012 and 0.0013 s): read by name and by number, with and without skipping the header."""
    names = ["Time (s)", "Acceleration (g)"] + [f"Channel {k} (g)" for k in range(2, 8)]   # holding k * accel
    path = _write(tmp_path, "Test100.txt", _table(["\t".join(names)], "\t", 8))
    steps = np.diff([float(line.split("\t")[0]) for line in path.read_text().splitlines()[1:]])
    assert {round(s, 4) for s in steps} == {0.0012, 0.0013}   # the printed time is not uniform
    _check(load_record(path, time_column=1, column=2), G)
    _check(load_record(path, column="Acceleration"), G)       # the column stating seconds is the time
    _check(load_record(path, column="Channel 5 (g)"), G, column=5)
    _check(load_record(path, format="column", time_column=1, column=2, units="g", skip_lines=1), G)


def test_one_column_of_many_with_dt(tmp_path):
    """--column 2 --dt 0.00125: the other columns, time included, are not read."""
    path = _write(tmp_path, "many.txt", _table(["t a b c d e f g"], " ", 8, time_decimals=2))
    record = load_record(path, column=3, dt=1 / RATE, units="gal")
    _check(record, GAL, column=2)
    assert record.start == 0.0


def test_one_column_with_dt_in_a_case_file(tmp_path):
    _write(tmp_path, "many.txt", _table(["t a b c d e f g"], " ", 8, time_decimals=2))
    data = yaml.safe_load((REPO / "configs" / "example.yaml").read_text(encoding="utf-8"))
    data["ground"]["horizontal"] = {"file": "many.txt", "column": 2, "dt": 1 / RATE, "units": "g"}
    data["ground"].pop("vertical", None)
    case = load_case(data, base_dir=tmp_path)
    _check(read_records(case, tmp_path)["horizontal"], G)


def test_two_header_lines_names_then_units(tmp_path):
    path = _write(tmp_path, "two.csv", _table(["Time,Acceleration", "s,cm/s/s"], ",", 2))
    record = load_record(path)
    assert record.units == "cm/s^2"
    _check(record, GAL)


def test_title_line_above_the_names(tmp_path):
    path = _write(tmp_path, "title.txt", _table(["Test 100: granite block, table run 3",
                                                 "Time (s)\tAcc (m/s2)"], "\t", 2))
    _check(load_record(path), 1.0)


@pytest.mark.parametrize("word, factor", [
    ("g", G), ("g's", G), ("(g)", G), ("[g]", G), ("gal", GAL), ("(gal)", GAL), ("cm/s/s", GAL),
    ("cm/s^2", GAL), ("cm/s2", GAL), ("[cm/sec^2]", GAL), ("m/s/s", 1.0), ("m/s^2", 1.0),
    ("(m/s2)", 1.0), ("m/s²", 1.0), ("mm/s2", 1e-3),
])
def test_units_in_the_header(tmp_path, word, factor):
    path = _write(tmp_path, "u.csv", _table([f"time,accel {word}"], ",", 2))
    _check(load_record(path), factor)


def test_explicit_units_win_with_a_warning(tmp_path):
    """A header is free text; the person who gives units has looked: their unit is used, and the
    disagreement is said (a warning, not an error: a mislabelled header must stay readable)."""
    path = _write(tmp_path, "u.csv", _table(["time,accel g's"], ",", 2))
    with pytest.warns(RecordWarning, match=r"u\.csv.*states 'g' but units 'gal' were given"):
        record = load_record(path, units="gal")
    _check(record, GAL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _check(load_record(path, units="g"), G)   # agreeing: no warning


def test_time_in_milliseconds_by_its_header(tmp_path):
    time, accel = _signal()
    text = "Time (ms),Acc (g)\n" + "".join(f"{1000 * t:.3f},{a:.6f}\n" for t, a in zip(time, accel, strict=True))
    _check(load_record(_write(tmp_path, "ms.csv", text)), G)


def test_time_printed_with_significant_digits(tmp_path):
    """repr-style times drop trailing zeros (``1``, ``0.5``): they still read as exact."""
    time, accel = _signal()
    text = "".join(f"{float(t)!r} {float(a)!r}\n" for t, a in zip(time, accel, strict=True))
    record = load_record(_write(tmp_path, "g.txt", text), units="g")
    _check(record, G)


# --------------------------------------------------------------------------------------------------
# Refusals: one line, exit 2, the file, the line and the fix
# --------------------------------------------------------------------------------------------------

def _refusal(folder: Path, name: str, text: str, *args) -> str:
    _write(folder, name, text)
    result = CliRunner().invoke(main, ["info", str(folder / name), *args])
    lines = result.stderr.splitlines()
    assert result.exit_code == 2, (result.exit_code, result.stderr, result.exception)
    assert len(lines) == 1 and lines[0].startswith("rockslide: error: "), result.stderr
    assert "Traceback" not in result.stderr
    assert name in lines[0]
    return lines[0]


def _jumped() -> str:
    """800 Hz to 4 decimals with one sample missing after 0.5 s."""
    text = _table(["Time (s)\tAcc (g)"], "\t", 2).splitlines()
    return "\n".join(text[:402] + text[403:]) + "\n"


REFUSALS = {
    # a missing sample is one step off, far beyond the printed digits; giving dt reads it anyway
    "missing-sample": (_jumped(), (), ["line 403", "the time column must be uniform", "0.0025",
                                       "`dt:` (--dt)"]),
    "many-columns-no-choice": (_table(["a b c d"], " ", 4), ("--units", "g"),
                               ["column", "4 columns (a, b, c, d)", "--time-column", "--column",
                                "--dt"]),
    "time-named-no-column": (_table(["Time (s),A (g),B (g)"], ",", 3), (),
                             ["3 columns", "`column:` (--column)"]),
    "no-units-anywhere": (_table(["time,acc"], ",", 2), (), ["units", "--units"]),
    "unknown-column-name": (_table(["Time (s),Acc (g)"], ",", 2), ("--column", "Vel"),
                            ["'Vel' is not a column name", "Time (s), Acc (g)", "--column"]),
    "title-not-names": (_table(["granite block test 100"], " ", 2), ("--units", "g"),
                        ["line 1", "4 names", "2 values", "`skip_lines: 1` (--skip-lines 1)"]),
    "text-in-first-data-line": ("0.0 1.0\n0.1 x\n0.2 3\n", ("--units", "g"),
                                ["line 2", "'x'", "fix or remove the line"]),
    "number-led-header": ("800 Hz sampling\n0.0 1.0\n0.1 2\n", ("--units", "g"),
                          ["line 1", "'Hz'", "`skip_lines: 1` (--skip-lines 1)"]),
    "time-too-coarse": (_table(["t,a"], ",", 2, time_decimals=2), ("--units", "g"),
                        ["time_column", "printed to 0.01 s", "`dt: 0.00125` (--dt 0.00125)"]),
    "dt-and-time-column": (_table(["t,a"], ",", 2), ("--units", "g", "--dt", "0.00125", "--time-column", "1"),
                           ["dt", "remove one of them"]),
}


@pytest.mark.parametrize("case", REFUSALS)
def test_refusal_names_file_line_and_fix(tmp_path, case):
    text, args, words = REFUSALS[case]
    line = _refusal(tmp_path, "rec.txt", text, *args)
    for word in words:
        assert word in line, f"{word!r} not in {line!r}"


def test_a_missing_sample_reads_with_dt(tmp_path):
    """The refusal's fix works: with dt the time column is not read (the samples are taken as evenly
    spaced, the user's statement)."""
    path = _write(tmp_path, "j.txt", _jumped())
    with pytest.raises(RecordError):
        load_record(path)
    record = load_record(path, dt=1 / RATE)
    assert record.dt == 1 / RATE and record.data.size == N - 1
