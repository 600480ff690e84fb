"""COSMOS v1.20 records (`rockslide.io.cosmos` through `records.load_record`), on files written here in
the published layout (COSMOS Strong Motion Data Format, ver. 1.20, 2001: 13 text lines, the integer
and real headers with their count lines and Fortran formats, comments, the data line and the data,
then the channel's velocity and displacement as a V2 file has them)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import invoke, one_line_error

from rockslide.errors import RecordError
from rockslide.io import records as rec

UNKNOWN = -999


def cosmos_text(values, *, dt_ms=10.0, unit_code=4, unit_text="cm/sec2", orientation=90, structure=10,
                location=7, int_format=(10, 8), real_format=(6, 13, 6), data_format=(8, 10, 5), channels=1):
    """A V2 file of ``values`` in the layout of the format's version 1.20 (text widths as CESMD writes)."""
    n = len(values)
    ints = [UNKNOWN] * 100
    ints[0], ints[1], ints[2] = 2, 1, unit_code                 # Int(1) stage V2, Int(2) acceleration, Int(3) unit
    ints[10], ints[18] = 5, structure                             # Int(11) network (CGS), Int(19) structure type
    ints[53], ints[55] = orientation, location                    # Int(54) orientation, Int(56) location
    reals = [float(UNKNOWN)] * 100
    reals[61], reals[62] = dt_ms, n * dt_ms / 1000.0              # Real(62) interval [ms], Real(63) length [s]

    def fixed(numbers, per_line, width, decimals=None):
        cells = [(f"{x:{width}d}" if decimals is None else f"{x:{width}.{decimals}f}") for x in numbers]
        return ["".join(cells[i:i + per_line]) for i in range(0, len(cells), per_line)]

    text = [
        "Corrected acceleration    (Format v01.20 with 13 text lines) Src: 24601V2.CSMIP",
        "Record of                 Earthquake of Sun Jan 17, 1994 04:31 PST",
        "Hypocenter: 34.213  -118.537  H= 18km (SCSN)  ML=6.4 Mw=6.7",
        "Origin: 01/17/1994, 12:30:55.0 UTC (SCSN)",
        "Statn No: 05- 24601  Code:CE-24601  Los Angeles - 17-story Residential Bldg",
        "Coords: 34.0490  -118.2590  Site geology: Alluvium",
        "Recorder: SMA-1 s/n 5541 (13 Chns:  3 at Sta, 10 Remote)  Sensor: FBA-11",
        "Rcrd start time: 01/17/1994, 12:31:04.000 UTC (Q=5)  RcrdId: 24601-S1234-94017.01",
        "Sta Chan  5:  90 deg (Rcrdr Chan  5) Location: 6th floor:  West wall",
        f"Raw record length = {n * dt_ms / 1000:.3f} sec, Uncor max = 300.000 cm/s/s at 5.000 sec",
        "Processed: 02/01/94  Max = 300.000 cm/s/s at   5.000 sec",
        "Record filtered below 0.10 Hz (periods over 10.0 secs), and above 25.0 Hz",
        f"Values used when parameter or data value is unknown/unspecified:{UNKNOWN:7d},{UNKNOWN:7.1f}",
    ]
    per, width = int_format
    ints_block = fixed(ints, per, width)
    text.append(f"  100 Integer-header values follow on {len(ints_block):3d} lines, Format= ({per}I{width})")
    text += ints_block
    per, width, decimals = real_format
    reals_block = fixed(reals, per, width, decimals)
    text.append(f"  100 Real-header values follow on {len(reals_block):3d} lines, Format= ({per}F{width}.{decimals})")
    text += reals_block
    text.append('    1 Comment line(s) follow, each starting with a "|":')
    text.append("| Sensor location: 6th floor, west wall")
    per, width, decimals = data_format
    for series in ("acceleration", "velocity", "displacement"):
        block = fixed(values, per, width, decimals)
        text.append(f"{n:8d} {series} pts, approx {round(n * dt_ms / 1000):4d} secs, units={unit_text} "
                    f"({unit_code:02d}), Format=({per}F{width}.{decimals})")
        text += block
        text.append(f"End-of-data for Chan  5 {series}")
    one = "\n".join(text) + "\n"
    return one * channels


SAMPLES = np.round(300.0 * np.sin(np.linspace(0, 6 * math.pi, 203)), 5)


def test_values_dt_units_and_header_read_back(tmp_path):
    """203 samples at 8 per line (the last line short); cm/s/s to m/s^2 exactly 1e-2; dt from the
    real header's milliseconds."""
    path = tmp_path / "24601_5.V2c"
    path.write_text(cosmos_text(SAMPLES, dt_ms=5.0))
    record = rec.load_record(path)
    assert record.format == "cosmos" and record.units == "cm/s^2"
    assert record.dt == 0.005 and record.data.size == 203
    np.testing.assert_array_equal(record.data, SAMPLES * 0.01)
    header = record.header
    assert (header["network"], header["station"], header["channel"], header["location"]) == ("CE", "24601", "5", "7")
    cosmos = header["cosmos"]
    assert cosmos["orientation"] == "90 deg" and cosmos["structure_type"] == "10 (building)"
    assert cosmos["location_text"] == "6th floor:  West wall"
    assert cosmos["station_name"] == "Los Angeles - 17-story Residential Bldg"
    assert cosmos["stage"] == 2 and cosmos["comments"] == "Sensor location: 6th floor, west wall"
    assert rec.read_record(path).stats.cosmos.orientation == "90 deg"


@pytest.mark.parametrize("code, text, factor", [(2, "g", 9.80665), (10, "gal", 0.01)])
def test_other_units_and_formats(tmp_path, code, text, factor):
    """The widths come from each header's Fortran format (5I10, 5F15.6, 5F16.7 here)."""
    path = tmp_path / "rec.v2"
    path.write_text(cosmos_text(SAMPLES / 1000, unit_code=code, unit_text=text, int_format=(5, 10),
                                real_format=(5, 15, 6), data_format=(5, 16, 7), orientation=600))
    record = rec.load_record(path)
    written = np.array([float(f"{x:16.7f}") for x in SAMPLES / 1000])      # the file's numbers
    np.testing.assert_allclose(record.data, written * factor, rtol=1e-15)
    assert record.header["cosmos"]["orientation"] == "longitudinal (relative to structure)"


def test_explicit_format_and_units_that_agree(tmp_path):
    path = tmp_path / "rec.txt"
    path.write_text(cosmos_text(SAMPLES))
    assert rec.load_record(path, format="cosmos", units="gal").dt == 0.01


@pytest.mark.parametrize("damage, part", [
    (lambda t: t.replace("Integer-header values follow", "Integer header values follow"), "line 14"),
    (lambda t: t.replace("Format= (10I8)", "Format= (10X8)"), "Fortran format"),
    (lambda t: t.replace("units=cm/sec2 (04)", "units=counts (50)"), "unit code is 50"),
    (lambda t: t.replace("  10.000000", "       oops", 1), "cannot read 'oops'"),
    (lambda t: t.split("End-of-data")[0][:-400], "ends inside the acceleration"),
    (lambda t: t + t, "holds 2 channels"),
])
def test_a_damaged_file_is_one_line_and_exit_2(tmp_path, damage, part):
    path = tmp_path / "bad.V2c"
    path.write_text(damage(cosmos_text(SAMPLES)))
    with pytest.raises(RecordError, match=part.replace("(", r"\(")):
        rec.load_record(path)
    one_line_error(invoke("info", path), str(path), part)


def test_a_negative_interval_is_refused(tmp_path):
    path = tmp_path / "bad.V2c"
    path.write_text(cosmos_text(SAMPLES, dt_ms=-5.0))
    one_line_error(invoke("info", path), "Real(62)")
