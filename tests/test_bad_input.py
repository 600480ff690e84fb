"""Bad input and faults through the command line, end to end.

What these tests protect, as a user meets it:

- every mistake in a case file, a record, an option or an output location ends with one line on
  stderr, ``rockslide: error: <file>: <field or line>: <what is wrong, what is expected>``, exit
  code 2, no traceback, and nothing new in the output folder (no result, figure or temporary file);
- whatever the text of a case file or a record, the command line gives a result or such a clean
  error (exit 0 or 2), never a traceback (exit 1);
- a run killed outright (SIGKILL) leaves the previous complete result or none, never a corrupt one;
  Ctrl-C (and SIGTERM) end a run with 130 (143) and no result, no temporary file;
- ``--debug`` shows the traceback; a bug shows one ``internal error`` line and exit code 1.

Everything runs offline: records are the shipped synthetic ones, copied into ``tmp_path``, or
written by the tests.
"""

from __future__ import annotations

import os
import pickle
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from conftest import (
    DROP,
    EXAMPLE,
    EXAMPLE_TEXT,
    QUICK,
    REPO,
    SHIPPED,
    _default_sigint,
    case_text,
    cli_subprocess,
    horizontal_only,
    listing,
    sha256,
)
from conftest import invoke as shared_invoke
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockslide.api import runs as api_runs
from rockslide.engine import prepare as runner
from rockslide.io import results
from rockslide.io.records import read_record, write_at2

SOLVER_LINE = 1 + next(i for i, line in enumerate(EXAMPLE_TEXT.splitlines()) if line.startswith("solver:"))
# ------------------------------------------------------------------------------------------------
# Helpers: cases, records, the command line
# ------------------------------------------------------------------------------------------------



PULSE = {"pulse": "rectangular", "amplitude": "0.5 g", "duration": "0.2 s"}


def pulse_only(pulse_changes, **changes) -> str:
    """A case whose only ground motion is a horizontal pulse (`PULSE` with keys changed, DROP removes
    one) and no scaling."""
    spec = {**PULSE, **pulse_changes}
    spec = {k: v for k, v in spec.items() if v is not DROP}
    return horizontal_only(spec, **{"ground.scale": DROP, **QUICK, **changes})


def at2_text(values_g, *, dt="0.0100", npts=None, units_line="ACCELERATION TIME SERIES IN UNITS OF G",
             line4=None) -> str:
    """A PEER AT2 file: 4 header lines, then 5 values per line."""
    values = [f"{v:15.7E}" if isinstance(v, float) else f"{v:>15}" for v in values_g]
    npts = len(values) if npts is None else npts
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", "test record", units_line,
             line4 or f"NPTS= {npts:7d}, DT= {dt} SEC,"]
    lines += ["".join(values[i:i + 5]) for i in range(0, len(values), 5)]
    return "\n".join(lines) + "\n"


def column_text(time_s, accel, *, header="time,acc") -> str:
    rows = [f"{t:.6f},{a:.6e}" for t, a in zip(time_s, accel, strict=True)]
    return "\n".join(([header] if header else []) + rows) + "\n"


def sine(n=1001, dt=0.01, amplitude_g=0.1):
    t = np.arange(n) * dt
    return t, amplitude_g * np.sin(2 * np.pi * t)


def shipped_with_line(name: str, line: int, text: str):
    """A shipped record with one line replaced (1-based line number)."""
    def make(ws: Path) -> str:
        lines = (ws / name).read_text().splitlines()
        lines[line - 1] = text
        return "\n".join(lines) + "\n"
    return make


def truncated_shipped(name: str, keep_lines: int):
    def make(ws: Path) -> str:
        return "\n".join((ws / name).read_text().splitlines()[:keep_lines]) + "\n"
    return make


class _Evil:
    """Unpickling this runs a command that creates the file ``pwned`` (it must never happen)."""

    def __reduce__(self):
        return (os.system, ("touch pwned",))


def invoke(args, **kwargs):
    """``rockslide ARGS`` (a list) in this process: `conftest.invoke`."""
    return shared_invoke(*args, **kwargs)


def assert_clean_error(result, expected=()):
    """Exit code 2, one line on stderr naming the problem, nothing on stdout, no traceback."""
    lines = result.stderr.splitlines()
    assert result.exit_code == 2, (result.exit_code, result.stderr, result.exception)
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rockslide: error: "), lines[0]
    assert "Traceback" not in result.stderr and result.stdout == ""
    for part in expected:
        assert part in lines[0], f"{part!r} not in {lines[0]!r}"
    return lines[0]


def write_files(folder: Path, files: dict) -> None:
    for name, content in files.items():
        if callable(content):
            content = content(folder)
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        elif content is None:
            path.mkdir()
        else:
            path.write_text(content, encoding="utf-8")


# ------------------------------------------------------------------------------------------------
# The table of bad inputs: (id, files to write, command line, parts of the message)
# ------------------------------------------------------------------------------------------------

RUN = ("run", "case.yaml")


def bad_case(id_, text, expected, args=RUN, files=None):
    return pytest.param({"case.yaml": text, **(files or {})}, args, expected, id=id_)


def bad_record(id_, record_name, content, expected, spec=None, args=RUN, **changes):
    spec = spec if spec is not None else record_name
    return pytest.param({record_name: content, "case.yaml": horizontal_only(spec, **changes)}, args,
                        expected, id=id_)


def _merge_key_bomb(levels: int = 9, width: int = 10) -> str:
    """664 bytes whose YAML merge keys expand to 10^9 entries (minutes and gigabytes to build)."""
    lines = ["name: x", "a0: &a0 {k0: 0}"]
    for i in range(1, levels + 1):
        lines.append(f"a{i}: &a{i} {{<<: [{', '.join([f'*a{i - 1}'] * width)}], k{i}: {i}}}")
    return "\n".join(lines) + "\n"


def _alias_bomb(levels: int = 9, width: int = 10) -> str:
    """The 'billion laughs': nested aliases that expand to 10^9 strings."""
    lines = ["name: x", "a0: &a0 [" + ", ".join(["lol"] * width) + "]"]
    for i in range(1, levels + 1):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * width) + "]")
    return "\n".join(lines) + "\n"


T, A = sine()
T_FINE, A_FINE = sine(n=1001, dt=0.002)
T_JUMP = T.copy()
T_JUMP[100] += 0.005          # one late sample: line 102 (after the header)

BAD_INPUTS = [
    # -- the case file: YAML itself ----------------------------------------------------------------------
    bad_case("yaml-unclosed-brace", "name: x\nblock: {height: 0.2\n",
             ["case.yaml: line 3, column 1", "invalid YAML", "expected ',' or '}'"]),
    bad_case("yaml-tab-indent", "name: x\nblock:\n\theight: 1\n",
             ["case.yaml: line 3, column 1", "'\\t'", "indent with spaces"]),
    bad_case("yaml-duplicate-key", EXAMPLE_TEXT + "solver: {dt: 1 ms}\n",
             [f"case.yaml: line {len(EXAMPLE_TEXT.splitlines()) + 1}, column 1", "duplicate key 'solver'",
              f"first given on line {SOLVER_LINE}", "give each key once"]),
    bad_case("yaml-duplicate-nested-key",
             EXAMPLE_TEXT.replace("mu_static: 0.52,", "mu_static: 0.52, mu_static: 0.6,"),
             ["case.yaml: line", "duplicate key 'mu_static'"]),
    bad_case("yaml-python-object-tag", "name: !!python/object/apply:os.system ['touch pwned']\n",
             ["case.yaml: line 1, column 7", "unsupported YAML tag", "plain data"]),
    bad_case("yaml-not-utf8", b"name: caf\xe9\n", ["case.yaml", "not UTF-8", "YAML case file"]),
    bad_case("case-empty", "", ["case.yaml", "the case file is empty", "expected a mapping"]),
    bad_case("case-top-level-list", "- name: x\n", ["case.yaml", "top level must be a mapping",
                                                    "got a list"]),
    pytest.param({}, ("run", "nosuch.yaml"), ["nosuch.yaml", "case file not found"],
                 id="case-file-missing"),
    pytest.param({"folder.yaml": None}, ("run", "folder.yaml"),
                 ["folder.yaml", "is a folder, expected a case file"], id="case-file-is-a-folder"),
    # -- keys --------------------------------------------------------------------------------------------
    bad_case("unknown-key-typo", case_text({"contact.mu_statik": 0.5}),
             ["case.yaml: contact.mu_statik: unknown key", "did you mean 'mu_static'?"]),
    bad_case("unknown-key-misplaced", case_text({"dt": "1 ms"}),
             ["case.yaml: dt: unknown key",
              "did you mean 'ground.horizontal.dt', 'ground.vertical.dt' or 'solver.dt'?"]),
    bad_case("unknown-key-record", case_text({"ground.horizontal.fiel": "x.at2"}),
             ["ground.horizontal.fiel: unknown key", "did you mean 'file'?"]),
    bad_case("missing-name", case_text({"name": DROP}), ["case.yaml: name: missing required key"]),
    bad_case("missing-height", case_text({"block.height": DROP}),
             ["case.yaml: block.height: missing required key", "full height", "[m]"]),
    bad_case("missing-restitution", case_text({"contact.restitution": DROP}),
             ["contact.restitution: missing required key", "coefficient of restitution"]),
    bad_case("missing-records", case_text({"ground.horizontal": DROP, "ground.vertical": DROP, "ground.tail": DROP}),
             ["case.yaml: ground: needs a record", "ground.horizontal or ground.vertical", "ground.tail"]),
    # -- types -------------------------------------------------------------------------------------------
    bad_case("type-block-list", case_text({"block": [0.2, 0.1, 10]}),
             ["case.yaml: block: expected a mapping (keys: height, width, mass, orientation, "
              "centre_of_mass_height, half_widths, depth, radius_of_gyration, mesh, mesh_units, density)",
              "got a list"]),
    bad_case("type-mass-bool", case_text({"block.mass": True}),
             ["block.mass: expected a mass", "'10 kg'", "got True"]),
    bad_case("type-mu-word", case_text({"contact.mu_static": "high"}),
             ["contact.mu_static: cannot read 'high' as a number", "expected a plain number"]),
    bad_case("type-name-path", case_text({"name": "../escape"}),
             ["case.yaml: name: expected a name made of letters, digits", "'../escape'"]),
    bad_case("type-method-typo", case_text({"solver.method": "kernal"}),
             ["solver.method: expected one of 'kernel', 'reference'", "did you mean 'kernel'?"]),
    # -- units -------------------------------------------------------------------------------------------
    bad_case("unit-unknown", case_text({"block.height": "0.2 meters"}),
             ["block.height: unknown length unit 'meters'", "expected one of: m, cm, mm"]),
    bad_case("unit-wrong-kind", case_text({"ground.tail": "2 m"}),
             ["ground.tail: unknown time unit 'm'", "expected one of: s, ms"]),
    bad_case("unit-on-friction", case_text({"contact.mu_static": "0.5 m"}),
             ["contact.mu_static: unknown dimensionless unit 'm'", "without unit"]),
    bad_case("unit-number-missing", case_text({"block.width": "mm"}),
             ["block.width: cannot read 'mm' as a length", "a number and a unit"]),
    bad_case("unit-record-unknown", horizontal_only({"file": "synthetic_kt_h.at2", "units": "furlong"}),
             ["ground.horizontal.units: unknown acceleration unit 'furlong'", "gal"]),
    bad_case("value-nan", case_text({"gravity": float("nan")}),
             ["case.yaml: gravity:", "not a finite number"]),
    # -- physical bounds ---------------------------------------------------------------------------------
    bad_case("height-zero", case_text({"block.height": 0}),
             ["block.height: must be greater than 0 m, got 0 m"]),
    bad_case("width-negative", case_text({"block.width": "-10 cm"}),
             ["block.width: must be greater than 0 m, got -0.1 m (from '-10 cm')"]),
    bad_case("mass-zero", case_text({"block.mass": "0 kg"}), ["block.mass: must be greater than 0 kg"]),
    bad_case("mu-negative", case_text({"contact.mu_static": -0.1, "contact.mu_kinetic": DROP}),
             ["contact.mu_static: must be at least 0, got -0.1"]),
    bad_case("mu-kinetic-above-static", case_text({"contact.mu_kinetic": 0.6}),
             ["contact.mu_kinetic: mu_kinetic (0.6) must not exceed mu_static (0.52)"]),
    bad_case("restitution-above-one", case_text({"contact.restitution": 1.2}),
             ["contact.restitution: must be at least 0 and at most 1, got 1.2"]),
    bad_case("restitution-negative", case_text({"contact.restitution": -0.2}),
             ["contact.restitution: must be at least 0 and at most 1, got -0.2"]),
    bad_case("dt-zero", case_text({"solver.dt": 0}), ["solver.dt: must be greater than 0 s", "got 0 s"]),
    bad_case("dt-plain-number-meant-ms", case_text({"solver.dt": 0.1}),
             ["solver.dt: must be greater than 0 s and at most 0.01 s, got 0.1 s",
              "a number without unit is in s", "'0.1 ms'"]),
    bad_case("rotation-90-deg", case_text({"initial.rotation": "90 deg"}),
             ["initial.rotation: must be in absolute value less than pi/2 rad (90 deg)"]),
    bad_case("interval-not-multiple", case_text({"output.interval": "0.15 ms"}),
             ["output.interval: must be a whole multiple of solver.dt", "1.5 steps"]),
    bad_case("scale-pga-and-factor", case_text({"ground.scale.factor": 2}),
             ["case.yaml: ground.scale: pga_horizontal", "and factor (2) are exclusive"]),
    # -- checks that need the records --------------------------------------------------------------------
    bad_record("dt-above-record-step", "fine.csv", column_text(T_FINE, A_FINE),
               ["case.yaml: solver.dt: dt = 0.005 s is larger than the record's sampling step 0.002 s",
                "expected dt <= 0.002 s"], spec={"file": "fine.csv", "units": "g"},
               **{"solver.dt": "5 ms"}),
    # a vertical motion that lifts the block is an outcome (status 'flight'): tests/test_engine.py
    bad_case("tail-absurd", case_text({"ground.tail": "1e12 s"}),
             ["case.yaml: ground.tail: a tail of 1e+12 s adds", "expected at most 1e+08 samples"]),
    bad_case("dt-absurdly-small", case_text({"solver.dt": 1e-300}),
             ["case.yaml: solver.dt: dt = 1e-300 s gives", "use a larger dt"]),
    bad_case("output-every-nanosecond", case_text({"solver.dt": 1e-9}),
             ["case.yaml: output.interval: output every 1e-09 s", "set a larger output.interval"]),
    # -- records -----------------------------------------------------------------------------------------
    bad_case("record-missing", horizontal_only("kt_h.at2"),
             ["case.yaml: ground.horizontal.file: record file 'kt_h.at2' not found", "tried:",
              "--records-dir"]),
    bad_record("record-empty", "empty.csv", "", ["empty.csv", "the file is empty (no samples)"],
               spec={"file": "empty.csv", "units": "g"}),
    bad_record("record-comments-only", "notes.csv", "# nothing here\n\n",
               ["notes.csv", "no data lines"], spec={"file": "notes.csv", "units": "g"}),
    bad_record("record-time-beyond-decimal", "far.csv", "time,acc\n0,0.1\n0.01,0.2\n0D1000000000000000000,0.3\n",
               ["far.csv", "time_column: the time column does not increase"],
               spec={"file": "far.csv", "units": "g"}),
    bad_record("record-binary-garbage", "noise.bin", np.random.default_rng(1).bytes(3000),
               ["noise.bin", "unknown format", "supported: PEER NGA .AT2"],
               spec={"file": "noise.bin", "units": "g"}),
    bad_record("record-pickle-is-not-run", "evil.bin", pickle.dumps(_Evil()),
               ["evil.bin", "unknown format"], spec={"file": "evil.bin", "units": "g"}),
    bad_record("record-format-pickle-refused", "evil.bin", pickle.dumps(_Evil()),
               ["evil.bin", "format: unknown format 'PICKLE'", "expected one of at2"],
               spec={"file": "evil.bin", "units": "g", "format": "PICKLE"}),
    bad_record("record-format-unknown", "rec.csv", column_text(T, A),
               ["rec.csv", "format: unknown format 'excel'"],
               spec={"file": "rec.csv", "units": "g", "format": "excel"}),
    bad_record("record-at2-truncated", "short.at2", truncated_shipped("synthetic_kt_h.at2", 300),
               ["short.at2", "line 4", "NPTS = 2001", "truncated"]),
    bad_record("record-at2-no-npts", "nohead.at2", at2_text([0.1, 0.2], line4="2 values, 0.01 s"),
               ["nohead.at2", "line 4", "cannot find NPTS and DT", "expected 'NPTS="]),
    bad_record("record-at2-velocity", "vel.at2",
               at2_text([0.1, 0.2], units_line="VELOCITY TIME SERIES IN UNITS OF CM/S"),
               ["vel.at2", "line 3", "not an acceleration unit"]),
    bad_case("record-units-contradict-file",
             horizontal_only({"file": "synthetic_kt_h.at2", "units": "gal"}),
             ["synthetic_kt_h.at2: units: units 'gal' were given but the file is in 'g'",
              "remove units or fix them"]),
    bad_record("record-units-missing", "rec.csv", column_text(T, A),
               ["rec.csv", "units", "give `units:` (g, gal, m/s^2) for a column text record"]),
    bad_record("record-nan-sample", "nan.at2",
               shipped_with_line("synthetic_kt_h.at2", 10, "NaN 0.0 0.0 0.0 0.0"),
               ["nan.at2", "line 10", "sample 26 of 2001 is nan", "expected finite numbers"]),
    bad_record("record-infinite-sample", "inf.csv",
               column_text(T, A).replace(f"{T[50]:.6f},{A[50]:.6e}", f"{T[50]:.6f},inf"),
               ["inf.csv", "line 52", "is inf", "expected finite numbers"],
               spec={"file": "inf.csv", "units": "g"}),
    bad_record("record-not-a-number", "typo.csv",
               column_text(T, A).replace(f"{T[20]:.6f},{A[20]:.6e}", f"{T[20]:.6f},0.1.2"),
               ["typo.csv", "line 22", "cannot read '0.1.2' (field 2) as a number"],
               spec={"file": "typo.csv", "units": "g"}),
    bad_record("record-time-not-uniform", "jump.csv", column_text(T_JUMP, A),
               ["jump.csv", "line 102", "the time column must be uniform"],
               spec={"file": "jump.csv", "units": "g"}),
    bad_record("record-time-backwards", "back.csv", column_text(T[::-1], A),
               ["back.csv", "time_column", "does not increase"], spec={"file": "back.csv", "units": "g"}),
    bad_record("record-ragged-columns", "ragged.csv",
               column_text(T, A).replace("\n0.030000,", "\n0.030000,1,"),
               ["ragged.csv", "line 5", "3 values where line 2 has 2"],
               spec={"file": "ragged.csv", "units": "g"}),
    bad_record("record-header-only", "head.csv", "time,acc\n", ["head.csv", "a header row and no data lines"],
               spec={"file": "head.csv", "units": "g"}),
    bad_record("record-one-sample", "one.csv", "0.0,0.1\n", ["one.csv", "expected at least 2"],
               spec={"file": "one.csv", "units": "g"}),
    bad_record("record-three-columns", "three.csv", "t,ns,ew\n0,1,2\n0.01,1,2\n",
               ["three.csv", "column", "the file has 3 columns (t, ns, ew)",
                "give the acceleration column, `column:` (--column)"],
               spec={"file": "three.csv", "units": "g"}),
    bad_record("record-column-out-of-range", "rec.csv", column_text(T, A),
               ["rec.csv", "column = 5 is out of range: the file has 2 columns"],
               spec={"file": "rec.csv", "units": "g", "column": 5}),
    bad_record("record-values-without-dt", "vals.txt", "0.1 0.2 0.3\n0.4\n",
               ["vals.txt", "give `dt:`", "values record"],
               spec={"file": "vals.txt", "units": "g", "format": "values"}),
    bad_record("record-all-zeros-scaled-to-pga", "zeros.csv", column_text(T, 0 * A),
               ["case.yaml: ground.scale.pga_horizontal: the record", "zeros.csv is all zeros",
                "cannot be scaled"],
               spec={"file": "zeros.csv", "units": "g"}),
    # -- two records that do not share one time grid -----------------------------------------------------
    bad_case("records-different-step", case_text({"ground.vertical": {"file": "v.csv", "units": "g"}}),
             ["case.yaml: horizontal", "synthetic_kt_h.at2 and vertical", "v.csv have different dt "
              "(0.01 s and 0.02 s)", "rockslide does not resample"],
             files={"v.csv": column_text(*sine(n=2001, dt=0.02))}),
    bad_case("records-different-length", case_text({"ground.vertical": {"file": "v.csv", "units": "g"}}),
             ["case.yaml: horizontal", "have different lengths (2001 and 1500 samples)",
              "expected the same number of samples"],
             files={"v.csv": column_text(*sine(n=1500, dt=0.01))}),
    bad_case("records-different-start", case_text({"ground.vertical": {"file": "v.csv", "units": "g"}}),
             ["case.yaml: horizontal", "start at different times (0.0 s and 1.0 s)"],
             files={"v.csv": column_text(sine(n=2001)[0] + 1.0, sine(n=2001)[1])}),
    # -- analytic pulses ---------------------------------------------------------------------------------
    bad_case("pulse-missing-amplitude", pulse_only({"amplitude": DROP}),
             ["case.yaml: ground.horizontal.amplitude: missing required key", "peak acceleration"]),
    bad_case("pulse-unknown-shape", pulse_only({"pulse": "square"}),
             ["ground.horizontal.pulse: expected one of 'rectangular', 'half-sine'", "'ricker'"]),
    bad_case("pulse-period-for-duration", pulse_only({"period": "0.5 s"}),
             ["ground.horizontal.period: a rectangular pulse takes duration, not period"]),
    bad_case("pulse-missing-period", pulse_only({"pulse": "one-sine", "duration": DROP}),
             ["ground.horizontal.period: missing: a one-sine pulse needs its period [s]"]),
    bad_case("pulse-negative-duration", pulse_only({"duration": "-0.2 s"}),
             ["ground.horizontal.duration: must be greater than 0 s"]),
    bad_case("pulse-cycles-of-a-sine", pulse_only({"pulse": "half-sine", "cycles": 2}),
             ["ground.horizontal.cycles: only the cycloidal pulses", "a half-sine pulse has none"]),
    bad_case("pulse-no-cycles", pulse_only({"pulse": "cycloidal-a", "duration": DROP, "period": "0.4 s",
                                            "cycles": 0}),
             ["ground.horizontal.cycles: must be at least 1, got 0"]),
    bad_case("pulse-amplitude-length", pulse_only({"amplitude": "0.5 m"}),
             ["ground.horizontal.amplitude: unknown acceleration unit 'm'"]),
    bad_case("pulse-with-file-key", pulse_only({"units": "g"}),
             ["ground.horizontal.units: is a key of a record file, not of a pulse", "give either file or pulse"]),
    bad_case("pulse-key-on-a-file", horizontal_only({"file": "synthetic_kt_h.at2", "amplitude": "0.5 g"}),
             ["ground.horizontal.amplitude: is a key of a pulse; give 'pulse' too"]),
    bad_case("pulse-and-file", pulse_only({}, **{"ground.vertical": "synthetic_kt_v.at2"}),
             ["ground.vertical: is a record file while ground.horizontal is a pulse"]),
    bad_case("pulse-scaled", pulse_only({}, **{"ground.scale": {"factor": 2}}),
             ["ground.scale.factor: scales record files", "ground.horizontal.amplitude"]),
    bad_case("pulses-without-common-grid",
             pulse_only({}, **{"ground.vertical": {"pulse": "one-sine", "amplitude": "0.1 g",
                                                   "period": "0.1414213562 s"}}),
             ["ground.vertical: the horizontal and vertical pulses do not share a sampling grid",
              "no common sampling step"]),
    # a vertical pulse that lifts the block is an outcome (status 'flight'): tests/test_engine.py
    # -- options and outputs -----------------------------------------------------------------------------
    pytest.param({"case.yaml": case_text(), "out/example.h5": "previous result"}, RUN,
                 ["out/example.h5 exists (use --overwrite to replace it)"], id="output-exists"),
    pytest.param({"case.yaml": case_text({"output.dir": "blocked"}), "blocked": "a file, not a folder"},
                 RUN, ["blocked: cannot create the output folder"], id="output-folder-is-a-file"),
    # -- rockslide info ----------------------------------------------------------------------------------
    pytest.param({}, ("info", "nosuch.at2"), ["nosuch.at2: record file not found"], id="info-missing"),
    pytest.param({"folder.at2": None}, ("info", "folder.at2"),
                 ["folder.at2: is not a file (expected an accelerogram file)"], id="info-folder"),
    pytest.param({"rec.csv": column_text(T, A)}, ("info", "rec.csv"),
                 ["rec.csv: units: give `units:`", "rockslide info: --units"], id="info-no-units"),
    pytest.param({"rec.csv": column_text(T, A)}, ("info", "rec.csv", "--units", "g", "--dt", "-1"),
                 ["rec.csv: dt = -1.0; expected a positive sampling step"], id="info-negative-dt"),
    pytest.param({"rec.csv": column_text(T, A)}, ("info", "rec.csv", "--units", "g", "--column", "accel"),
                 ["rec.csv: column: column 'accel' is not a column name; the 2 columns are time, acc"],
                 id="info-column-name"),
    # -- rockslide plot ----------------------------------------------------------------------------------
    pytest.param({}, ("plot", "out/nosuch.h5"), ["out/nosuch.h5: result file not found"], id="plot-missing"),
    pytest.param({"case.yaml": case_text()}, ("plot", "case.yaml", "-o", "out/x.png"),
                 ["case.yaml: cannot read as a rockslide result (not an HDF5 file)"], id="plot-not-hdf5"),
    pytest.param({"other.h5": lambda ws: _plain_hdf5(ws / "other.h5")},
                 ("plot", "other.h5", "-o", "out/x.png"),
                 ["other.h5: not a rockslide result"], id="plot-foreign-hdf5"),
    pytest.param({"half.h5": lambda ws: _truncated_result(ws)}, ("plot", "half.h5", "-o", "out/x.png"),
                 ["half.h5: cannot read as a rockslide result"], id="plot-truncated-result"),
    pytest.param({}, ("plot", "out/nosuch.h5", "--time-shift", "nan"),
                 ["--time-shift: cannot read 'nan' as a time"], id="plot-time-shift-nan"),
    pytest.param({}, ("plot", "out/nosuch.h5", "--time-shift", "-25 kg"),
                 ["--time-shift: unknown time unit 'kg'"], id="plot-time-shift-unit"),
    pytest.param({}, ("plot", "out/nosuch.h5", "--window", "36:30"),
                 ["--window: the end must come after the start, got '36:30'"], id="plot-window-backwards"),
    pytest.param({}, ("plot", "out/nosuch.h5", "--crop", "everything"),
                 ["--crop: expected START:END", "auto, all"], id="plot-crop-word"),
    # -- rockslide criteria ------------------------------------------------------------------------------
    pytest.param({}, ("criteria", "--height", "tall", "-o", "out/c.png"),
                 ["--height: cannot read 'tall' as a length", "'200 mm'"], id="criteria-height-word"),
    pytest.param({}, ("criteria", "--width", "-5 cm", "-o", "out/c.png"),
                 ["--height/--width: height and width must be positive lengths"],
                 id="criteria-width-negative"),
    pytest.param({}, ("criteria", "--av=-1.5g", "-o", "out/c.png"),
                 ["--av: each vertical acceleration must be above -1 g"], id="criteria-av-flies"),
    pytest.param({}, ("criteria", "--av", "0g,half", "-o", "out/c.png"),
                 ["--av: cannot read 'half' as an acceleration"], id="criteria-av-word"),
    pytest.param({}, ("criteria", "--av=-0.5,0.5", "-o", "out/c.png"),
                 ["--av: -0.5 has no unit", "'-0.5 g' is -4.903 m/s^2"], id="criteria-av-bare"),
    pytest.param({}, ("criteria", "--ah-max", "1.5", "-o", "out/c.png"),
                 ["--ah-max: 1.5 has no unit", "'1.5 m/s^2' is 0.153 g"], id="criteria-ah-max-bare"),
    pytest.param({}, ("criteria", "--ah-max", "0g", "-o", "out/c.png"),
                 ["--ah-max: expected a positive finite value, got 0"], id="criteria-ah-max-zero"),
    pytest.param({}, ("criteria", "--mu-max", "0", "-o", "out/c.png"),
                 ["--mu-max: expected a positive finite value"], id="criteria-mu-max-zero"),
    pytest.param({}, ("criteria", "-o", "out/c.txt"),
                 ["out/c.txt: unknown figure format '.txt'", ".png"], id="criteria-output-format"),
    pytest.param({"out/c.png": b"previous figure"}, ("criteria", "-o", "out/c.png"),
                 ["out/c.png exists (use --overwrite to replace it)"], id="criteria-output-exists"),
    # -- hostile YAML (issue 16.4): bounded before it is built --------------------------------------------
    bad_case("yaml-merge-key-bomb", _merge_key_bomb(), ["case.yaml: line", "expands to more than 10000 values"]),
    bad_case("yaml-alias-bomb", _alias_bomb(), ["case.yaml: line", "expands to more than 10000 values"]),
    bad_case("yaml-nested-too-deep", "name: x\nblock: " + "[" * 30 + "]" * 30 + "\n",
             ["case.yaml: line", "nested more than 20 levels deep"]),
    bad_case("yaml-recursive-alias", "name: &a [x, *a]\n", ["alias refers to a node that contains it"]),
    bad_case("case-file-too-large", EXAMPLE_TEXT + ("# " + "x" * 98 + "\n") * 700,
             ["case.yaml: the case file has", "expected at most 65536"]),
    # -- values beyond what float64 and the model represent (issue 16.5, 16.9) -----------------------------
    bad_case("dt-denormal", case_text({"solver.dt": 5e-324}), ["solver.dt: dt = 4.94066e-324 s gives",
                                                                "use a larger dt"]),
    bad_case("interval-longer-than-run", case_text({"output.interval": "1e20 s"}),
             ["output.interval: 1e+20 s is longer than the run (22 s"]),
    bad_record("record-at2-dt-1e300", "slow.at2", shipped_with_line("synthetic_kt_h.at2", 4,
                                                                    "NPTS=    2001, DT=    1e300 SEC,"),
               ["slow.at2", "dt = 1e+300 s; expected a sampling step of at most 1 s"]),
    bad_record("record-1e307-g-sample", "spike.at2",
               shipped_with_line("synthetic_kt_h.at2", 10, "  1.0000000E+307 0.0 0.0 0.0 0.0"),
               ["case.yaml: ground.scale: the scaled ground motion reaches", "expected at most 1e+06 g"],
               **{"ground.scale": {"factor": 1}}),
    bad_record("record-overflow-in-g-one-line", "inf.at2",       # 1e308 g * 9.80665 overflows: no numpy warning
               shipped_with_line("synthetic_kt_h.at2", 10, "  1.0000000E+308 0.0 0.0 0.0 0.0"),
               ["inf.at2", "line 10", "is inf (after conversion to m/s^2)", "expected finite numbers"]),
    bad_case("mass-absurd", case_text({"block.mass": "1e30 kg"}),
             ["block.mass: 1e+30 kg is outside what rockslide computes reliably", "1e-20 to 1e+20 kg"]),
    bad_case("block-subatomic", case_text({"block.width": 1e-15}),
             ["block.width: 1e-15 m is outside what rockslide computes reliably"]),
    bad_case("gravity-tiny", case_text({"gravity": "1e-300 m/s^2"}), ["gravity: 1e-300 m/s^2 is outside"]),
    bad_case("slip-rate-absurd", case_text({"initial.slip_rate": 1e300}),
             ["initial.slip_rate: 1e+300 m/s is outside", "in absolute value 0 to 1e+06 m/s"]),
    bad_case("time-shift-absurd", case_text({"ground.time_shift": "1e12 s"}),
             ["ground.time_shift: the ground motion starts at t = 1e+12 s", "within +-1e+06 s"]),
    bad_case("output-dir-nul", case_text({"output.dir": "out\x00put"}),
             ["output.dir: expected text without control characters", "\\x00"]),
    bad_case("record-name-nul", horizontal_only("kt\x00h.at2"),
             ["ground.horizontal.file: expected text without control characters", "\\x00"]),
    bad_case("name-too-long", case_text({"name": "n" * 250}),
             ["name: expected at most 200 characters", "got 250"]),
    bad_case("name-of-a-megabyte", case_text({"name": "n" * 1_000_000}),
             ["case.yaml: the case file has 1000", "expected at most 65536"]),
    bad_case("name-ending-in-sweep", case_text({"name": "x.sweep"}),
             ["name: a name ending in '.sweep' would write the files of the sweep of case 'x'"]),
    bad_case("name-ending-in-fragility", case_text({"name": "x.fragility"}),
             ["name: a name ending in '.fragility' would write the files of the fragility of case 'x'"]),
    pytest.param({"case.yaml": case_text(QUICK)}, ("run", "case.yaml", "--out-dir", "o" * 300),
                 ["a folder name of 300 bytes"], id="out-dir-name-too-long"),
    # -- issue 28.8: paths the system cannot take ---------------------------------------------------------
    pytest.param({"case.yaml": case_text(QUICK)}, ("run", "case.yaml", "--out-dir", "/".join(["d" * 200] * 25)),
                 ["once absolute); expected at most 4051", "choose a shorter output folder"],
                 id="out-dir-longer-than-path-max"),
    bad_case("record-name-of-300-characters", horizontal_only("r" * 300 + ".at2", **QUICK),
             ["case.yaml: ground.horizontal.file: cannot look for the record file", "File name too long"]),
    pytest.param({}, ("info", "r" * 300 + ".at2"), ["File name too long", "give a shorter one"],
                 id="info-name-of-300-characters"),
    pytest.param({}, ("plot", "p" * 300 + ".h5"), ["File name too long", "give a shorter one"],
                 id="plot-name-of-300-characters"),
    # -- the dask scheduler (issue 16.5, 16.6) ------------------------------------------------------------
    pytest.param({"case.yaml": case_text()}, ("sweep", "case.yaml", "--mu", "0.5", "--scheduler", "tcp://[::1"),
                 ["--scheduler: expected an address like tcp://HOST:PORT, got 'tcp://[::1'"], id="scheduler-ipv6-open"),
    pytest.param({"case.yaml": case_text()}, ("sweep", "case.yaml", "--mu", "0.5", "--scheduler", "tls://[::1]:1"),
                 ["--scheduler: tls://[::1]:1 is a TLS scheduler: give", "--tls-ca-file"], id="scheduler-tls"),
    pytest.param({"case.yaml": case_text()}, ("sweep", "case.yaml", "--mu", "0.5", "--scheduler", "inproc://x"),
                 ["--scheduler: inproc:// addresses are not supported"], id="scheduler-inproc"),
    pytest.param({"case.yaml": case_text()}, ("sweep", "case.yaml", "--mu", "0.5", "--workers", "0"),
                 ["--workers: must be within 1 ..."], id="sweep-workers-zero"),
    pytest.param({"case.yaml": case_text()}, ("sweep", "case.yaml", "--mu", "0.5", "--mu", "0.6"),
                 ["Invalid value for '--mu': given 2 times; give it once (a comma list"], id="sweep-axis-twice"),
    # -- click's own errors, one line too (issue 16.12) ---------------------------------------------------
    pytest.param({}, ("run",), ["rockslide run: Missing argument 'CASE_FILE'", "see 'rockslide run --help'"],
                 id="usage-missing-argument"),
    pytest.param({}, ("runn", "case.yaml"), ["No such command 'runn'"], id="usage-unknown-command"),
    pytest.param({"case.yaml": case_text()}, ("run", "case.yaml", "--robust"),
                 ["rockslide run: No such option '--robust'", "--robustness"], id="usage-unknown-option"),
    pytest.param({}, ("info", "rec\x00.at2"), ["a file or folder name holds a NUL character"],
                 id="path-with-nul-through-the-api"),
    pytest.param({}, ("criteria", "--av", "nan", "-o", "out/c.png"),
                 ["--av: cannot read 'nan' as an acceleration"], id="criteria-av-nan"),
    pytest.param({}, ("criteria", "--av", "1e400 g", "-o", "out/c.png"),
                 ["--av: '1e400 g' is not a finite number"], id="criteria-av-overflow"),
    # -- rockslide table1 --------------------------------------------------------------------------------
    pytest.param({}, ("table1", "--configs", "nosuch", "--out", "out"),
                 ["--configs: nosuch: folder not found", "Table 1 case files"], id="table1-configs-missing"),
    pytest.param({"configs/fig06a-mu050.yaml": case_text({"contact.mu_static": "slippery"})},
                 ("table1", "--configs", "configs", "--out", "out", "--records-dir", "."),
                 ["fig06a-mu050.yaml: contact.mu_static: cannot read 'slippery'"], id="table1-bad-case"),
]


def _truncated_result(ws: Path) -> bytes:
    """The first half of a real result file (as a copy interrupted midway leaves it)."""
    (ws / "made.yaml").write_text(case_text(QUICK))
    assert invoke(["run", "made.yaml", "--no-plot", "--out-dir", "made"]).exit_code == 0
    data = (ws / "made" / "example.h5").read_bytes()
    shutil.rmtree(ws / "made")
    (ws / "made.yaml").unlink()
    return data[:len(data) // 2]


def _plain_hdf5(path: Path) -> bytes:
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    return path.read_bytes()


def test_bad_input_table_is_large_and_distinct():
    ids = [p.id for p in BAD_INPUTS]
    assert len(ids) >= 40 and len(set(ids)) == len(ids)


@pytest.mark.parametrize("files, args, expected", BAD_INPUTS)
def test_bad_input_gives_one_clean_line_and_no_output(ws, files, args, expected):
    write_files(ws, files)
    before = listing(ws)
    result = invoke(args)
    assert_clean_error(result, expected)
    assert listing(ws) == before          # no result, figure or temporary file appeared
    assert not (ws / "pwned").exists()     # no YAML tag or pickle ran code


# ------------------------------------------------------------------------------------------------
# Messages that are warnings, not errors
# ------------------------------------------------------------------------------------------------


def test_absurd_peak_is_a_warning_and_info_continues(ws):
    (ws / "huge.csv").write_text(column_text(T, 150 * A))   # 15 g: surely cm/s^2 written as g
    result = invoke(["info", "huge.csv", "--units", "g"])
    assert result.exit_code == 0, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rockslide: warning: ")
    assert "huge.csv" in lines[0] and "above 10 g" in lines[0] and "check the units" in lines[0]
    assert "samples   1001" in result.stdout


def test_absurd_peak_is_a_warning_and_the_run_continues(ws):
    (ws / "huge.csv").write_text(column_text(T, 150 * A))
    (ws / "case.yaml").write_text(horizontal_only({"file": "huge.csv", "units": "g"},
                                                  **{"solver.dt": "1 ms", "ground.tail": "0 s"}))
    result = invoke(["run", "case.yaml", "--no-plot"])
    assert result.exit_code == 0, result.stderr
    assert [line for line in result.stderr.splitlines() if "above 10 g" in line]
    assert "Traceback" not in result.stderr
    assert results.read_result(ws / "out" / "example.h5").name == "example"


# ------------------------------------------------------------------------------------------------
# Existing results: refused unless --overwrite, and input errors come first
# ------------------------------------------------------------------------------------------------



def test_existing_result_is_kept_without_overwrite_and_replaced_with_it(ws):
    (ws / "case.yaml").write_text(case_text(QUICK))
    assert invoke(["run", "case.yaml", "--no-plot"]).exit_code == 0
    h5 = ws / "out" / "example.h5"
    first = sha256(h5)
    assert_clean_error(invoke(["run", "case.yaml", "--no-plot"]), ["example.h5 exists", "--overwrite"])
    assert sha256(h5) == first
    inode = h5.stat().st_ino
    result = invoke(["run", "case.yaml", "--no-plot", "--overwrite"])
    assert result.exit_code == 0, result.stderr
    assert h5.stat().st_ino != inode                   # a new file renamed into place
    assert results.read_result(h5).name == "example"
    assert listing(ws / "out") == ["example.h5"]


@pytest.mark.slow      # a run and eight figures drawn, 14 s on 2 cores
def test_plot_redraws_its_own_figure_and_replaces_another_file_only_with_overwrite(ws):
    """`plot` always redraws the result's own figure; with -o it does not replace another file (the
    review's case: a run's figure drawn over its sweep's maps) unless --overwrite; a window or crop
    wholly outside the result (0 to 20 s here) is an error, not empty panels."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    assert invoke(["run", "case.yaml", "--dpi", "20"]).exit_code == 0
    other = ws / "out" / "example.sweep.png"
    other.write_bytes(b"the sweep's maps")
    assert_clean_error(invoke(["plot", "out/example.h5", "-o", other, "--dpi", "20"]),
                       ["example.sweep.png exists", "--overwrite"])
    assert other.read_bytes() == b"the sweep's maps"
    for args in (["plot", "out/example.h5", "--dpi", "20"], ["plot", "out/example.h5", "-o", "out/example.png"],
                 ["plot", "out/example.h5", "-o", other, "--overwrite", "--dpi", "20"]):
        result = invoke(args)
        assert result.exit_code == 0, result.stderr
    assert other.read_bytes()[:4] == b"\x89PNG"
    for option, value in (("--crop", "50:60"), ("--window", "-10:-1")):
        assert_clean_error(invoke(["plot", "out/example.h5", option, value, "-o", "out/x.png"]),
                           [f"{option}: {value.replace(':', ' to ')} s is outside the result"])
    assert not (ws / "out" / "x.png").exists()


def test_table1_publishes_its_figures_and_tables_together(ws, monkeypatch):
    """The review's case: Ctrl-C while `table1` writes left new figures beside the old table and
    said nothing was written. The figures are now staged with the tables: a failure while the
    second table is written leaves the folder as it was (the run itself is replaced by a stand-in;
    the paper's records are not needed)."""
    from rockslide.analyses import table1
    from rockslide.io import files

    class Row:
        runs = {None: {}}

    def figures(results_, out, overwrite=True, staging=None):
        with files.atomic_write(out / "fig06.png", overwrite=True, staging=staging) as handle:
            handle.write(b"new figure")
        return [out / "fig06.png"]

    def failing_markdown(*args):
        raise KeyboardInterrupt

    out = ws / "results"
    out.mkdir()
    (out / "table1.md").write_text("the previous table")
    monkeypatch.setattr(table1, "run_table", lambda configs, records_dir: ([Row()], {}))
    monkeypatch.setattr(table1, "write_figures", figures)
    monkeypatch.setattr(table1, "csv_text", lambda rows, gravities: "new,csv\n")
    monkeypatch.setattr(table1, "previous_figures", lambda configs: {})
    monkeypatch.setattr(table1, "markdown", failing_markdown)
    with pytest.raises(KeyboardInterrupt):
        table1.reproduce(ws, ws, out)
    assert listing(out) == ["table1.md"] and (out / "table1.md").read_text() == "the previous table"
    monkeypatch.setattr(table1, "markdown", lambda *args: "the new table")
    monkeypatch.setattr(table1, "row_checks", lambda rows, gravity: [])
    table1.reproduce(ws, ws, out)
    assert listing(out) == ["fig06.png", "table1.csv", "table1.md"]
    assert (out / "table1.md").read_text() == "the new table"


def test_an_interrupted_example_leaves_no_file_and_no_folder(ws, monkeypatch):
    """The review's case: Ctrl-C during `rockslide example` left empty folders (and could leave
    the case files without their records). The set is staged and published together; the folders
    it made are removed again."""
    from rockslide.io import example

    def interrupted(folder, staging=None):
        raise KeyboardInterrupt

    monkeypatch.setattr(example, "write_suite_records", interrupted)
    before = listing(ws)
    with pytest.raises(KeyboardInterrupt):
        example.write_example(ws / "deep" / "ex")
    assert listing(ws) == before and not (ws / "deep").exists()
    monkeypatch.undo()
    written = example.write_example(ws / "deep" / "ex")
    assert sorted(str(p.relative_to(ws / "deep" / "ex")) for p in written) == listing(ws / "deep" / "ex")


def test_input_errors_are_reported_before_an_existing_result(ws):
    write_files(ws, {"out/example.h5": "previous", "case.yaml": horizontal_only("kt_h.at2")})
    assert_clean_error(invoke(["run", "case.yaml"]), ["ground.horizontal.file", "not found"])


# ------------------------------------------------------------------------------------------------
# --debug and bugs
# ------------------------------------------------------------------------------------------------



def test_debug_shows_the_traceback_of_a_user_error(ws):
    (ws / "case.yaml").write_text(case_text({"contact.restitution": 1.5}))
    proc = cli_subprocess(["--debug", "run", "case.yaml"], ws)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 1
    assert "Traceback (most recent call last)" in stderr
    assert "CaseError: case.yaml: contact.restitution: must be at least 0 and at most 1" in stderr
    assert not (ws / "out").exists()


def test_internal_error_is_one_line_suggesting_debug(ws, monkeypatch):
    def broken(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(runner, "prepare", broken)
    (ws / "case.yaml").write_text(case_text())
    result = invoke(["run", "case.yaml"])
    assert result.exit_code == 1
    assert result.stderr.splitlines() == [
        "rockslide: internal error: ZeroDivisionError: float division by zero; this is a bug in "
        "rockslide, please report it (run again with --debug for the traceback)"]
    assert "Traceback" not in result.stderr
    assert not (ws / "out").exists()
    debug = invoke(["--debug", "run", "case.yaml"])
    assert debug.exit_code == 1 and isinstance(debug.exception, ZeroDivisionError)


def test_system_error_names_the_file_in_one_line(ws, monkeypatch):
    def disk_full(self, rows):
        raise OSError(28, "No space left on device", str(self.tmp))

    monkeypatch.setattr(api_runs, "HELD_HISTORY_ROWS", 0)       # the history streams into the file
    monkeypatch.setattr(results.ResultWriter, "append_history", disk_full)
    (ws / "case.yaml").write_text(case_text(QUICK))
    result = invoke(["run", "case.yaml"])
    assert result.exit_code == 1
    (line,) = result.stderr.splitlines()
    assert line.startswith("rockslide: error: ") and "No space left on device" in line and "--debug" in line
    assert listing(ws / "out") == []                   # the temporary file was removed


# ------------------------------------------------------------------------------------------------
# Killed, interrupted, terminated: the previous complete result or none
# ------------------------------------------------------------------------------------------------

LONG_CASE = {
    "name": "slow",
    "ground.horizontal": "fine_h.at2", "ground.vertical": "fine_v.at2",
    "ground.scale": {"pga_horizontal": "400 gal"},
    "ground.tail": "1800 s",            # half an hour of free vibration...
    "solver.dt": "0.001 ms",            # ...at one microsecond: a run of a minute or so
    "output.interval": "5 ms",          # 364 001 rows: they stream into a temporary file from the start
}


def write_long_case(ws: Path) -> None:
    """A case that runs long enough to be stopped midway: 1 kHz records (so that the kernel returns
    to Python, where signals are handled, every 50 s of simulated time), a long tail, a tiny step."""
    for component, name in (("h", SHIPPED[0]), ("v", SHIPPED[1])):
        record = read_record(ws / name)
        t = np.arange(record.stats.npts) * record.stats.delta
        fine = np.arange(0.0, t[-1] + 1e-9, 0.001)
        write_at2(ws / f"fine_{component}.at2", np.interp(fine, t, record.data) / 9.80665, 0.001,
                  title="synthetic, resampled at 1 kHz", component=component)
    (ws / "case.yaml").write_text(case_text(LONG_CASE))
    assert (20.0 + 1800.0) / 0.005 > api_runs.HELD_HISTORY_ROWS      # streamed, not held until the end


def wait_for_temporary_file(proc, folder: Path, name: str, timeout: float = 120.0) -> Path:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = sorted(folder.glob(f".{name}.*.tmp"))
        if found:
            return found[0]
        if proc.poll() is not None:
            pytest.fail(f"the run ended before writing (exit {proc.returncode}): {proc.stderr.read()}")
        time.sleep(0.05)
    proc.kill()
    pytest.fail(f"no temporary file .{name}.<pid>.tmp appeared within {timeout} s")


posix_signals = pytest.mark.skipif(os.name != "posix", reason="POSIX signals (SIGKILL, SIGTERM, SIGINT)")



@pytest.mark.slow      # a subprocess of `python -m rockslide`
@posix_signals
@pytest.mark.parametrize("previous", [False, True], ids=["no-previous-result", "previous-result"])
def test_sigkill_midway_leaves_the_previous_result_or_none(ws, previous):
    write_long_case(ws)
    out = ws / "out"
    before = None
    if previous:
        quick = case_text({**LONG_CASE, "ground.tail": "0 s", "solver.dt": "1 ms"})
        (ws / "quick.yaml").write_text(quick)
        assert invoke(["run", "quick.yaml", "--no-plot"]).exit_code == 0
        before = sha256(out / "slow.h5")
    proc = cli_subprocess(["run", "case.yaml", "--no-plot", "--overwrite"], ws)
    try:
        tmp = wait_for_temporary_file(proc, out, "slow.h5")
        time.sleep(1.0)                                  # well into the run
        assert proc.poll() is None, "the run ended before it could be killed"
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate()
    assert proc.returncode == -signal.SIGKILL
    left = set(listing(out))
    assert left <= {"slow.h5", tmp.name}                # at most the leftover temporary file
    if previous:
        assert sha256(out / "slow.h5") == before        # untouched, and complete:
        stored = results.read_result(out / "slow.h5")
        assert stored.name == "slow" and stored.result.summary.end_time == pytest.approx(20.0, abs=0.1)
    else:
        assert not (out / "slow.h5").exists()


@posix_signals
@pytest.mark.parametrize("signum, code, word", [(signal.SIGINT, 130, "interrupted"),
                                                (signal.SIGTERM, 143, "terminated")],
                         ids=["ctrl-c", "sigterm"])
@pytest.mark.slow      # a subprocess of `python -m rockslide`
def test_interrupted_run_exits_cleanly_without_any_file(ws, signum, code, word):
    """Deterministic: the signal goes as soon as the run's temporary file exists (the run is then
    computing, for a minute), and whenever it lands it is acted on at the next kernel chunk."""
    write_long_case(ws)
    out = ws / "out"
    proc = cli_subprocess(["run", "case.yaml", "--no-plot"], ws, preexec_fn=_default_sigint)
    try:
        wait_for_temporary_file(proc, out, "slow.h5")
        proc.send_signal(signum)
        _, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == code, stderr
    *notes, last = stderr.splitlines()
    assert last == f"rockslide: {word} (no partial result was written)", stderr
    assert all(line.startswith("rockslide: note: ") for line in notes), stderr   # the work estimate
    assert listing(out) == []                           # no result, no temporary file


# ------------------------------------------------------------------------------------------------
# Properties: whatever the input, a result or a clean error
# ------------------------------------------------------------------------------------------------


def assert_result_or_clean_error(result, folder: Path):
    """Exit 0 with a readable result, or exit 2 with one line; never a traceback (exit 1)."""
    assert "Traceback" not in result.stderr, result.stderr
    assert result.exit_code in (0, 2), (result.exit_code, result.stderr, result.exception)
    if result.exit_code == 2:
        assert len(result.stderr.splitlines()) == 1 and result.stderr.startswith("rockslide: error: ")
        assert [p for p in listing(folder) if p.endswith((".h5", ".png", ".tmp"))] == []
    else:
        assert not [p for p in listing(folder) if p.endswith(".tmp")]
        for line in result.stderr.splitlines():
            assert line.startswith("rockslide: warning: "), line


@pytest.fixture(scope="module")
def fuzz_root(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    for name in SHIPPED:
        shutil.copy(REPO / "records" / name, root / name)
    return root


def fresh_folder(root: Path) -> Path:
    folder = Path(tempfile.mkdtemp(dir=root))
    for name in SHIPPED:
        shutil.copy(root / name, folder / name)
    return folder


def _paths(data, prefix=()):
    for key, value in data.items():
        yield ".".join((*prefix, key))
        if isinstance(value, dict):
            yield from _paths(value, (*prefix, key))


# Values that stay cheap to run when valid (no long tails or tiny steps), and many that are not valid.
FUZZ_VALUES = st.one_of(
    st.sampled_from([None, True, False, 0, 1, -1, 2, 0.3, 0.5, 0.9, 1.5, 1e-3, 1e300, -1e300,
                     float("nan"), float("inf"), "", "abc", "800 gal", "-5 deg", "1 ms", "2 s", "0.1 m",
                     "1e400 kg", "10 g", "located", "step-end", "reference", "kernel", "g", "gal",
                     "synthetic_kt_v.at2", "nosuch.at2", ".", "out", "values", "column", "at2", [], {},
                     [1, 2], {"file": "synthetic_kt_v.at2"}, {"a": 1}]),
    st.floats(min_value=-2.0, max_value=2.0),
    st.text(alphabet="ab.:-_ 0123456789", max_size=8),
)
CASE_PATHS = [p for p in _paths(EXAMPLE) if p not in ("output.dir", "solver.dt", "ground.tail")] + [
    "contact.mu_statc", "ground.horizontal.units", "ground.vertical.format", "ground.scale.factor",
    "ground.scale.pga_vertical", "output.interval", "initial.rotation"]


@settings(deadline=None, max_examples=40, suppress_health_check=[HealthCheck.too_slow])
@given(changes=st.dictionaries(st.sampled_from(CASE_PATHS), FUZZ_VALUES | st.just(DROP), min_size=1,
                               max_size=3))
def test_random_case_files_give_a_result_or_a_clean_error(fuzz_root, changes):
    folder = fresh_folder(fuzz_root)
    text = case_text({**QUICK, **changes})
    (folder / "case.yaml").write_text(text, encoding="utf-8")
    result = invoke(["run", folder / "case.yaml", "--no-plot", "--out-dir", folder / "out",
                     "--records-dir", folder])
    assert_result_or_clean_error(result, folder)
    if result.exit_code == 0:
        assert results.read_result(folder / "out" / f"{yaml.safe_load(text)['name']}.h5")
    shutil.rmtree(folder)


LINE_PARTS = ["0", "0.01", "-1.5e-3", ".5", "1D-02", "nan", "inf", "-inf", "1e400", "1,2", "1 2 3",
              "time,acc", "t ns ew", "# comment", ";", "", "\t", ",", "PEER NGA STRONG MOTION",
              "ACCELERATION TIME SERIES IN UNITS OF G", "UNITS OF CM/S/S", "NPTS=    3, DT=   0.0100 SEC",
              "NPTS= 0, DT= 0", "Origin Time       1995/01/17 05:46:00", "\x00", "é", "0.02,0.1", "0.01,0.2"]
RECORD_TEXT = st.lists(st.lists(st.sampled_from(LINE_PARTS), max_size=4).map(" ".join), max_size=12) \
    .map("\n".join)


@settings(deadline=None, max_examples=150, suppress_health_check=[HealthCheck.too_slow])
@given(content=RECORD_TEXT.map(str.encode) | st.binary(max_size=300),
       suffix=st.sampled_from([".at2", ".csv", ".txt", ""]),
       options=st.lists(st.sampled_from([("--units", "g"), ("--units", "gal"), ("--dt", "0.01"),
                                         ("--format", "values"), ("--format", "column"),
                                         ("--column", "2"), ("--time-column", "time"),
                                         ("--skip-lines", "1")]), max_size=3, unique=True))
def test_random_record_bytes_through_info_give_a_summary_or_a_clean_error(fuzz_root, content, suffix,
                                                                          options):
    folder = Path(tempfile.mkdtemp(dir=fuzz_root))
    record = folder / f"rec{suffix}"
    record.write_bytes(content)
    result = invoke(["info", record, *[word for option in options for word in option]])
    assert_result_or_clean_error(result, folder)
    if result.exit_code == 0:
        assert "samples" in result.stdout
    shutil.rmtree(folder)


@settings(deadline=None, max_examples=25, suppress_health_check=[HealthCheck.too_slow])
@given(text=RECORD_TEXT, units=st.sampled_from(["g", "gal", "m/s^2"]))
def test_random_record_text_through_run_gives_a_result_or_a_clean_error(fuzz_root, text, units):
    folder = fresh_folder(fuzz_root)
    (folder / "rec.txt").write_text(text, encoding="utf-8")
    (folder / "case.yaml").write_text(horizontal_only({"file": "rec.txt", "units": units}, **QUICK,
                                                      **{"ground.scale": {"factor": 1}}))
    result = invoke(["run", folder / "case.yaml", "--no-plot", "--out-dir", folder / "out"])
    assert_result_or_clean_error(result, folder)
    shutil.rmtree(folder)


@pytest.mark.parametrize("args, env, expected", [
    (["run", "case.yaml", "--out-dir", "~nosuchuser-rockslide/out"], {},
     "rockslide: error: --out-dir: '~nosuchuser-rockslide' names no user's home folder here"),
    (["run", "case.yaml", "--records-dir", "~nosuchuser-rockslide"], {},
     "rockslide: error: --records-dir: '~nosuchuser-rockslide' names no user's home folder here"),
    (["run", "case.yaml"], {"ROCKSLIDE_RECORDS": "~nosuchuser-rockslide/records"},
     "rockslide: error: ROCKSLIDE_RECORDS: '~nosuchuser-rockslide' names no user's home folder here"),
    (["run", "--", "--debug"], {}, "rockslide: error: --debug: case file not found"),
], ids=["out-dir-no-such-user", "records-dir-no-such-user", "env-no-such-user", "debug-after-double-dash"])
def test_bad_environment_and_options_are_one_line(ws, args, env, expected):
    """Issue 28's exit-1 cases: a home folder of nobody, and '--debug' after '--' (an argument then,
    a case file that does not exist, not the debug switch): one line, exit 2, in a process of its own."""
    (ws / "case.yaml").write_text(case_text())
    done = subprocess.run([sys.executable, "-m", "rockslide", *args], cwd=ws, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(REPO), **env}, timeout=120)
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == [expected]


@pytest.mark.slow      # a subprocess of `python -m rockslide`
def test_a_matplotlib_backend_in_the_environment_does_not_stop_a_run(ws):
    """MPLBACKEND=nonsense made matplotlib's import fail (exit 1, internal error): rockslide draws on
    Agg whatever the environment names."""
    (ws / "case.yaml").write_text(case_text(QUICK))
    done = subprocess.run([sys.executable, "-m", "rockslide", "run", "case.yaml"], cwd=ws, capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": str(REPO), "MPLBACKEND": "nonsense"},
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert (ws / "out" / "example.png").stat().st_size > 0


def test_unbounded_work_is_refused_before_it_starts(ws, monkeypatch):
    """Issue 28's unbounded inputs: sa(T) at 1e-9 s (7 TiB of oscillator response), an oscillator
    response above the bound on a real record, and 300 criteria panels are refused in one line
    before any work; a 2-case sweep with a huge --chunk-size asks for the disk its 2 cases need."""
    from rockslide.analyses import fragility as fr

    (ws / "case.yaml").write_text(case_text(QUICK))
    shutil.copy(REPO / "records" / "suite-synthetic.yaml", ws / "suite.yaml")
    shutil.copytree(REPO / "records" / "suite-synthetic", ws / "suite-synthetic")
    fragility = ["fragility", "case.yaml", "--suite", "suite.yaml", "--levels", "0.1g,0.2g", "--no-plot"]
    assert_clean_error(invoke([*fragility, "--im", "sa(1e-9s)"]), ["--im", "within 0.001 s ... 100 s", "1e-09 s"])
    monkeypatch.setattr(fr, "MAX_OSCILLATOR_POINTS", 1000)
    assert_clean_error(invoke([*fragility, "--im", "sa(0.5s)"]), ["--im", "points of the oscillator's response"])
    panels = ",".join(f"{k / 1000:.3f}g" for k in range(300))
    assert_clean_error(invoke(["criteria", f"--av={panels}", "-o", "c.png"]), ["--av", "at most 12"])
    assert not (ws / "c.png").exists()
    done = invoke(["sweep", "case.yaml", "--mu", "0.3,0.5", "--chunk-size", "1000000000", "--no-plot"])
    assert done.exit_code == 0, done.stderr
