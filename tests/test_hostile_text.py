"""Text that made a parser crawl or escape (issue 43, items 4, 10 and 14): every parser of text a
user gives (quantities, axes, intensity measures, hazard curves, column headers of records, COSMOS
headers) refuses or reads hostile text in time linear in its length, with one line naming it.

The crawls were regular expressions that backtracked (quadratic or cubic in the text: 60 s to
minutes for the sizes below, without ever returning to Python, so that Ctrl-C did nothing). Each
attack runs in a subprocess with a limit of 60 s, a hundred times what the linear parsers take
(under 0.5 s here), so that a crawl fails the test instead of hanging it; the property tests give
hypothesis a deadline of 5 s for inputs of up to 50 000 characters.
"""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from datetime import timedelta

import numpy as np
import pytest
from conftest import REPO, invoke, one_line_error
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockslide import interrupts
from rockslide.errors import CaseError, RecordError, RockslideError
from rockslide.io import cosmos, hazard
from rockslide.io import records as rec
from rockslide.units import parse_quantity

LIMIT_S = 60
PROPERTY = settings(deadline=timedelta(seconds=5), max_examples=40,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _bounded(code: str) -> str:
    """Run ``code`` in a fresh interpreter of this checkout; its stdout. Fails past `LIMIT_S`."""
    try:
        done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                              timeout=LIMIT_S, cwd=REPO)
    except subprocess.TimeoutExpired:
        pytest.fail(f"still parsing after {LIMIT_S} s (a parse that is not linear in its text)")
    assert done.returncode == 0, done.stderr
    return done.stdout


# --------------------------------------------------------------------------------------------------
# Quantities (item 10): 2000 digits and a "!" took 61-96 s to be refused
# --------------------------------------------------------------------------------------------------


def test_a_quantity_of_thousands_of_digits_is_refused_at_once():
    out = _bounded("""
        from rockslide.errors import CaseError
        from rockslide.units import parse_quantity
        from rockslide.analyses.sweep import parse_axis
        from rockslide.analyses.fragility import parse_im
        for call in (lambda: parse_quantity("1" * 2000 + "!", "length"),
                     lambda: parse_quantity("9" * 20000 + "." + "9" * 20000 + "e" + "1" * 5000 + "m!", "length"),
                     lambda: parse_axis("mu", "1" * 20000 + "!"),
                     lambda: parse_im("sa(" + " " * 20000)):
            try:
                call()
            except CaseError as exc:
                print(type(exc).__name__)
        """)
    assert out.split() == ["CaseError"] * 4


def test_a_height_of_2000_digits_on_the_command_line_is_one_line(tmp_path):
    one_line_error(invoke("criteria", "--height", "1" * 2000 + "!", "-o", tmp_path / "c.png"), "--height",
                   "cannot read")
    assert not (tmp_path / "c.png").exists()


@pytest.mark.parametrize("text, si", [("200 mm", 0.2), ("0.1 ms", 1e-4), (" 5e-3 s ", 5e-3), ("1e5m", 1e5),
                                      (".5 m", 0.5), ("+2.m", 2.0), ("1E3 mm", 1.0), ("-0", 0.0)])
def test_quantities_read_as_before(text, si):
    kind = "time" if text.strip().endswith("s") else "length"
    assert parse_quantity(text, kind) == pytest.approx(si, rel=1e-15)


@PROPERTY
@given(head=st.text(alphabet="0123456789.eE+- ", max_size=20), body=st.sampled_from("19. e"),
       repeat=st.integers(0, 50_000), tail=st.text(max_size=5))
def test_any_quantity_text_is_a_number_or_one_case_error(head, body, repeat, tail):
    text = head + body * repeat + tail
    try:
        value = parse_quantity(text, "length")
    except CaseError as exc:
        assert "\n" not in str(exc).strip() or "\n" in text
    else:
        assert math.isfinite(value)


# --------------------------------------------------------------------------------------------------
# Hazard curves (item 4)
# --------------------------------------------------------------------------------------------------

OPENQUAKE_BODY = "lon,lat,depth,poe-0.1,poe-0.2\n0,0,0,0.1,0.01\n"


def test_hazard_files_that_crawled_are_read_or_refused_at_once(tmp_path):
    (tmp_path / "word.csv").write_text("# investigation_time=1 imt='PGA' " + "a" * 80_000 + "\n" + OPENQUAKE_BODY)
    (tmp_path / "quoted.csv").write_text("#,,\"investigation_time=1, imt='PGA', x='" + "a=' " * 20_000 + "\"\n"
                                         + OPENQUAKE_BODY)
    (tmp_path / "imt.csv").write_text("#,,\"investigation_time=1, imt=SA(" + " " * 20_000 + "\"\n" + OPENQUAKE_BODY)
    (tmp_path / "header.csv").write_text("PGA" + " " * 80_000 + "[g] rate\n0.1 0.01\n0.2 0.001\n")
    (tmp_path / "paren.csv").write_text("PGA (" + " " * 80_000 + "g rate\n0.1 0.01\n0.2 0.001\n")
    out = _bounded(f"""
        from rockslide.errors import CaseError
        from rockslide.io.hazard import read_hazard
        for name in ("word", "quoted", "imt", "header", "paren"):
            try:
                tables = read_hazard({str(tmp_path)!r} + "/" + name + ".csv")
                print(name, "read", len(tables))
            except CaseError as exc:
                print(name, "refused", str(exc).splitlines()[0][-200:].replace(" ", "_"))
        """)
    got = dict((line.split()[0], line.split()[1:]) for line in out.splitlines())
    assert got["word"] == ["read", "1"] and got["quoted"] == ["read", "1"]
    assert got["imt"][0] == "refused" and "unknown_intensity_measure" in got["imt"][1]
    assert got["header"] == ["read", "1"]
    assert got["paren"][0] in ("read", "refused")


def test_a_header_unit_and_a_measure_read_as_before(tmp_path):
    assert hazard._header_cell("PGA [g]") == ("PGA", "g")
    assert hazard._header_cell("level ( cm/s )") == ("level", "cm/s")
    assert hazard._header_cell("sa(0.3s)") == ("sa(0.3s)", None)
    assert hazard._header_cell("sa(0.3s) (g)") == ("sa(0.3s)", "g")
    assert hazard._header_cell("a [b] c") == ("a [b] c", None)
    assert hazard.parse_measure(" SA( 0.3 ) ", source="x") == hazard.Measure("sa", 0.3)
    assert hazard._cells("sa (0.3 s) [g]   rate") == ["sa (0.3 s) [g]", "rate"]
    fields = dict(hazard._FIELD.findall("generated_by='OQ 3', kind=mean, investigation_time=1.0, imt=\"SA(0.1)\""))
    assert fields == {"generated_by": "'OQ 3'", "kind": "mean", "investigation_time": "1.0", "imt": '"SA(0.1)"'}


@PROPERTY
@given(comment=st.text(max_size=200), pad=st.sampled_from(" a'\"=(,[#"), repeat=st.integers(0, 50_000),
       header=st.text(max_size=40))
def test_any_hazard_text_is_read_or_one_case_error(tmp_path, comment, pad, repeat, header):
    for text in (f"#{comment}{pad * repeat} investigation_time=1 imt=PGA\n{header}\n0,0,0,0.1\n",
                 f"{header}{pad * repeat}\n0.1 0.01\n0.2 0.001\n"):
        path = tmp_path / "h.csv"
        path.write_bytes(text.encode("utf-8", "replace"))
        try:
            hazard.read_hazard(path)
        except CaseError as exc:
            assert str(path) in str(exc)


def test_a_signal_ends_the_reading_of_a_hazard_file(tmp_path):
    """The line loops look at the flag `interrupts` sets (a signal handler of the command line
    only records the signal)."""
    path = tmp_path / "h.csv"
    path.write_text("level rate\n" + "".join(f"{0.01 * k} {1.0 / k}\n" for k in range(1, 2000)))
    interrupts._pending.append(2)
    try:
        with pytest.raises(interrupts.Interrupted):
            hazard.read_hazard(path)
    finally:
        interrupts._pending.clear()


# --------------------------------------------------------------------------------------------------
# Column text records: header sniffing (item 4)
# --------------------------------------------------------------------------------------------------

DATA = "".join(f"{i * 0.01:.2f} {0.1 * (-1) ** i:.3f}\n" for i in range(200))


def test_record_headers_that_crawled_are_read_at_once(tmp_path):
    heads = {"tab": "Time (s)\tAcc (" + " " * 80_000 + "g\n", "spaced": "Time (s)  Acc (" + " " * 80_000 + "x\n",
             "padded": "Time (s) Acc" + " " * 80_000 + "(g)\n", "nested": "(" + " (" * 40_000 + "\n",
             "digits": "Time (s) Acc (g)\n" + DATA + "1" * 80_000 + "x 0.1\n"}
    for name, head in heads.items():
        (tmp_path / f"{name}.txt").write_text(head + DATA)
    out = _bounded(f"""
        from rockslide.errors import RockslideError
        from rockslide.io.records import load_record
        for name in {list(heads)!r}:
            try:
                load_record({str(tmp_path)!r} + "/" + name + ".txt", units="g")
                print(name, "read")
            except RockslideError as exc:
                print(name, "refused")
        """)
    assert dict(line.split() for line in out.splitlines()) == {
        "tab": "read", "spaced": "read", "padded": "read", "nested": "read", "digits": "refused"}


def test_record_header_units_read_as_before():
    assert rec._stated_unit("Acceleration (g)") == ("acceleration", "g")
    assert rec._stated_unit("acc [ cm/s/s ]") == ("acceleration", "cm/s^2")
    assert rec._stated_unit("Acceleration g's") == ("acceleration", "g")
    assert rec._stated_unit("Acc (g) x") is None
    assert rec._unbracketed("(g)") == "g" and rec._without_unit(" Acc (g) ") == "Acc"
    assert rec._header_fields("Time (s) Acc (g)", 2) == ["Time (s)", "Acc (g)"]
    assert rec._header_fields("Time (a (b) c) x", 2) == ["Time (a (b) c)", "x"]


@PROPERTY
@given(name=st.text(max_size=30), pad=st.sampled_from(" ([{)]}g1"), repeat=st.integers(0, 50_000),
       separator=st.sampled_from([" ", "  ", "\t", ",", ";"]))
def test_any_record_header_is_read_or_one_record_error(tmp_path, name, pad, repeat, separator):
    path = tmp_path / "r.txt"
    path.write_bytes(f"Time (s){separator}{name}{pad * repeat}\n{DATA}".encode("utf-8", "replace"))
    try:
        rec.load_record(path, units="g")
    except RockslideError as exc:
        assert str(path) in str(exc)


# --------------------------------------------------------------------------------------------------
# COSMOS Fortran formats (item 14)
# --------------------------------------------------------------------------------------------------


def _cosmos(tmp_path, change):
    from test_cosmos import SAMPLES, cosmos_text

    path = tmp_path / "bad.V2c"
    path.write_text(change(cosmos_text(SAMPLES)))
    return path


@pytest.mark.parametrize("change, part", [
    (lambda t: t.replace("Format= (10I8)", "Format= (0I8)"), "lines of 0 values"),
    (lambda t: t.replace("Format=(8F10.5)", "Format=(0F10.5)"), "lines of 0 values"),
    (lambda t: t.replace("Format= (10I8)", "Format= (999999999I8)"), "at most 1000 characters a line"),
    (lambda t: t.replace("Format=(8F10.5)", "Format=(8F999999999.5)"), "at most 1000 characters a line"),
    (lambda t: t.replace("Format= (10I8)", "Format= (10I0)"), "of 0 characters"),
    (lambda t: t.replace("Format= (10I8)", "Format= (" + "1" * 5000 + "I8)"), "line 14"),
    (lambda t: t.replace("  100 Integer-header", "1" * 5000 + " Integer-header", 1), "line 14"),
    (lambda t: t.replace("with 13 text lines", "with " + "9" * 5000 + " text lines"), "unknown format"),
])
def test_a_cosmos_format_out_of_bounds_is_one_line(tmp_path, change, part):
    """A repeat count of 0 divided by zero (internal error); a huge count or width made a line of
    gigabytes; thousands of digits made int() raise."""
    path = _cosmos(tmp_path, change)
    with pytest.raises(RecordError, match=part.replace("(", r"\(")):
        rec.load_record(path)
    one_line_error(invoke("info", path), str(path))


@PROPERTY
@given(spec=st.text(alphabet="0123456789IFEDGifedg.() x", max_size=30))
def test_any_fortran_format_is_read_or_refused(spec):
    def fail(message, where):
        return RecordError(message, field=where)

    try:
        per_line, width = cosmos._fortran(spec, fail, "line 1")
    except RecordError:
        return
    assert per_line >= 1 and width >= 1 and per_line * width <= cosmos.MAX_LINE_WIDTH


def test_values_of_a_cosmos_file_still_read(tmp_path):
    from test_cosmos import SAMPLES

    record = rec.load_record(_cosmos(tmp_path, lambda t: t))
    assert np.allclose(record.data, SAMPLES * 1e-2, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------------------------------
# Control characters from files (item 13): escaped where the text is read
# --------------------------------------------------------------------------------------------------

TITLE = "\x1b]0;owned\x07"


def test_a_cosmos_station_name_is_printed_with_its_escapes_escaped(tmp_path):
    path = _cosmos(tmp_path, lambda t: t.replace("Los Angeles - 17-story", "Los Angeles" + TITLE + " - 17-story"))
    assert rec.load_record(path).header["cosmos"]["station_name"].startswith("Los Angeles\\x1b]0;owned\\x07")
    done = invoke("info", path)
    assert done.exit_code == 0, done.output
    assert "\x1b" not in done.output and "\x07" not in done.output and "\\x1b]0;owned" in done.output


def test_an_openquake_kind_is_printed_with_its_escapes_escaped(tmp_path):
    from test_risk import openquake_csv

    levels = np.geomspace(0.1, 3.0, 20)
    path = openquake_csv(tmp_path / "h.csv", levels, [-np.expm1(-1e-4 * levels ** -2.0 * 50.0)])
    path.write_text(path.read_text().replace("kind='mean'", f"kind='mean{TITLE}'"))
    assert "\\x1b" in hazard.read_hazard(path)[0].kind
    done = invoke("risk", "--median", "0.5g", "--beta", "0.4", "--hazard", path, "--out-dir", tmp_path, "--no-plot")
    assert done.exit_code == 0, done.output
    assert "\x1b" not in done.output and "\x07" not in done.output and "\\x1b" in done.output


@pytest.mark.parametrize("kind", ["columns", "cosmos"])
def test_a_signal_ends_the_reading_of_a_record(tmp_path, kind):
    """As for hazard files: the loops over lines look at the flag a handled signal sets."""
    if kind == "cosmos":
        path = _cosmos(tmp_path, lambda t: t)
    else:
        path = tmp_path / "r.txt"
        path.write_text("Time (s) Acc (g)\n" + DATA)
    interrupts._pending.append(15)
    try:
        with pytest.raises(interrupts.Interrupted):
            rec.load_record(path, **({"units": "g"} if kind == "columns" else {}))
    finally:
        interrupts._pending.clear()
