"""The command line as a new user meets it (issue 12): what a run says about the ground motion it
applied and how near the block came to overturning, units that are never guessed, a free vibration
without a record, the shipped example and the examples of every ``--help`` working anywhere,
``python -m rockslide``, ``--debug`` wherever it is typed, no progress frames in log files, where
files go, and ``make`` honouring ``ROCKSLIDE_RECORDS``.

Mistakes and faults (one-line errors, exit codes, interrupted runs) are in test_bad_input.py.
"""

from __future__ import annotations

import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import yaml
from conftest import invoke, one_line_error
from rocking_reference import free_rocking_impacts

from rockslide.case import case_to_dict, load_case
from rockslide.cli import main
from rockslide.core.simulate import Model
from rockslide.io import example, results
from rockslide.io.records import read_record
from rockslide.units import STANDARD_GRAVITY, percent_text

REPO = Path(__file__).resolve().parents[1]
RECORDS = REPO / "records"
EXAMPLE = REPO / "configs" / "example.yaml"




@pytest.fixture(scope="module")
def example_run(tmp_path_factory):
    """The shipped example, run once: its --json, its printout and its result file."""
    out = tmp_path_factory.mktemp("example")
    as_json = invoke("run", EXAMPLE, "--out-dir", out / "json", "--json", "--no-plot")
    assert as_json.exit_code == 0, as_json.output
    printed = invoke("run", EXAMPLE, "--out-dir", out / "text", "--no-plot")
    assert printed.exit_code == 0, printed.output
    return json.loads(as_json.stdout), printed.stdout, results.read_result(out / "json" / "example.h5")


# --------------------------------------------------------------------------------------------------
# What was applied, and how near overturning (points 1 and 2)
# --------------------------------------------------------------------------------------------------


def test_the_ground_as_applied_is_in_json_hdf5_and_the_printout(example_run):
    """The example scales the horizontal record to 700 gal and the vertical by the same factor.
    Independently of the run: the factor is 7 m/s^2 over the horizontal record's peak as read, the
    vertical peak that factor times the vertical record's peak (one division and one product:
    equal to 2 ulp)."""
    payload, printed, stored = example_run
    peak_h = float(np.max(np.abs(read_record(RECORDS / "synthetic_kt_h.at2").data)))
    peak_v = float(np.max(np.abs(read_record(RECORDS / "synthetic_kt_v.at2").data)))
    factor = 7.0 / peak_h
    expected = {"pga_horizontal": 7.0, "pga_vertical": factor * peak_v,
                "scale_horizontal": factor, "scale_vertical": factor}
    assert set(payload["ground"]) == set(expected)
    for key, value in expected.items():
        assert payload["ground"][key] == pytest.approx(value, rel=5e-16), key
        assert stored.attrs[f"ground_{key}"] == payload["ground"][key], key
        assert stored.ground[key] == payload["ground"][key], key
    vertical_gal = factor * peak_v / 0.01
    assert (f"peaks 700 gal (0.714 g) H, {vertical_gal:.4g} gal ({factor * peak_v / STANDARD_GRAVITY:.3g} g) V "
            f"(records x{factor:.4g})") in printed


def test_alpha_and_the_distance_to_overturning(example_run):
    """alpha = atan(b/h) = atan(0.05 / 0.1) to 1 ulp; the ratio is max |phi| / alpha, the same in
    --json, HDF5 and the printout ('standing, 0.53 % of alpha')."""
    payload, printed, stored = example_run
    assert payload["alpha"] == pytest.approx(math.atan(0.5), rel=2.3e-16)
    assert payload["max_rotation_ratio"] == payload["max_rotation"] / payload["alpha"]
    assert 0.0 < payload["max_rotation_ratio"] < 1.0
    assert stored.attrs["alpha"] == payload["alpha"]
    assert stored.attrs["max_rotation_ratio"] == payload["max_rotation_ratio"]
    assert stored.result.summary.max_rotation_ratio == payload["max_rotation_ratio"]
    assert printed.splitlines()[0] == f"example: standing, {percent_text(payload['max_rotation_ratio'])} of alpha"
    assert f"(alpha {math.atan(0.5):.4f} rad, 26.57 deg)" in printed


@pytest.mark.parametrize("ratio, text", [(0.94, "94 %"), (0.9996, "100 %"), (0.0053, "0.53 %"),
                                         (0.1, "10 %"), (0.0, "0 %"), (1.37, "137 %")])
def test_percent_text(ratio, text):
    assert percent_text(ratio) == text


def test_a_bare_acceleration_is_refused_naming_the_key_and_what_it_would_mean(tmp_path):
    """The issue's example: 'pga_horizontal: 0.8' (meant: 0.8 g) ran at 0.8 m/s^2 and said
    'standing'. Now nothing runs, and the message says what 0.8 is in each unit."""
    case = tmp_path / "cabinet.yaml"
    text = EXAMPLE.read_text().replace("pga_horizontal: 700 gal", "pga_horizontal: 0.8")
    case.write_text(text.replace("../records/", str(RECORDS) + "/"))
    line = one_line_error(invoke("run", case, "--out-dir", tmp_path / "out"),
                          f"{case}: ground.scale.pga_horizontal: 0.8 has no unit",
                          "'0.8 g' is 7.845 m/s^2", "'0.8 gal' or '0.8 cm/s^2' is 0.0008158 g",
                          "'0.8 m/s^2' is 0.08158 g")
    assert "rockslide: error:" in line
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------------------------------
# A free vibration needs no record (point 7)
# --------------------------------------------------------------------------------------------------

FREE = """\
name: free
block:   {height: 0.2 m, width: 0.1 m, mass: 10 kg}
contact: {mu_static: 10, restitution: 0.8}
ground:  {tail: 1.5 s}
initial: {rotation: 0.2 rad}
solver:  {dt: 0.1 ms}
"""


def test_a_free_vibration_runs_without_a_record(tmp_path):
    """Released from 0.2 rad on still ground (no record, a tail), the block rocks freely: its
    impacts are those of the quadrature of free rocking (tests/rocking_reference.py) within 1e-8 s
    (test_exact.py: the kernel's located events agree to ~1e-12 s). The still ground is sampled at
    solver.dt, so the integration step is exactly 0.1 ms."""
    (tmp_path / "free.yaml").write_text(FREE)
    result = invoke("run", tmp_path / "free.yaml", "--out-dir", tmp_path, "--json", "--no-plot")
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    impacts = [e["time"] for e in payload["events"] if e["cause"] == "impact"]
    _, alpha, p2 = Model.from_block(0.1, 0.2, 10.0, 10.0, 0.8).constants
    expected = free_rocking_impacts(0.2, alpha, p2, 0.8, len(impacts))
    assert len(impacts) >= 5
    np.testing.assert_allclose(impacts, expected, rtol=0, atol=1e-8)
    assert payload["ground"] == {"pga_horizontal": 0.0, "pga_vertical": 0.0, "scale_horizontal": None,
                                 "scale_vertical": None}
    stored = results.read_result(tmp_path / "free.h5")
    assert stored.result.step == 1e-4 and stored.records == []
    assert stored.result.ground_time[-1] == pytest.approx(1.5, abs=1e-12)
    assert not stored.result.ground_horizontal.any() and not stored.result.ground_vertical.any()
    printed = invoke("run", tmp_path / "free.yaml", "--out-dir", tmp_path / "again", "--no-plot").stdout
    assert "ground as applied: still (no record: a free vibration)" in printed


# --------------------------------------------------------------------------------------------------
# The example, anywhere (point 5)
# --------------------------------------------------------------------------------------------------


def test_rockslide_example_writes_the_shipped_example(tmp_path):
    """The same records byte for byte as records/, and the same case as configs/example.yaml
    (apart from where its records are); an existing example is kept without --overwrite."""
    result = invoke("example", tmp_path / "ex")
    assert result.exit_code == 0, result.output
    written = sorted(p.relative_to(tmp_path / "ex").as_posix() for p in (tmp_path / "ex").rglob("*.at2"))
    assert len(written) == 14
    for name in written:            # the example's two records and the synthetic suite's twelve
        assert (tmp_path / "ex" / name).read_bytes() == (RECORDS / name).read_bytes(), name
    for name, repository in (("suite-synthetic.yaml", RECORDS / "suite-synthetic.yaml"),
                             ("spectrum-one-sine.yaml", REPO / "configs" / "spectrum-one-sine.yaml")):
        assert (tmp_path / "ex" / name).read_bytes() == repository.read_bytes(), name
    packaged, shipped = case_to_dict(load_case(tmp_path / "ex" / "example.yaml")), case_to_dict(load_case(EXAMPLE))
    for role in ("horizontal", "vertical"):
        assert Path(shipped["ground"][role].pop("file")).name == packaged["ground"][role].pop("file")
    assert packaged == shipped
    before = (tmp_path / "ex" / "example.yaml").read_bytes()
    one_line_error(invoke("example", tmp_path / "ex"), "example.yaml exists (use --overwrite")
    assert (tmp_path / "ex" / "example.yaml").read_bytes() == before
    assert invoke("example", tmp_path / "ex", "--overwrite").exit_code == 0


def help_examples() -> list[tuple[str, list[str]]]:
    """Every command line in the 'Example:' block of every --help (the group's first)."""
    out = []
    for name in [None, *sorted(main.commands)]:
        text = invoke(*([name] if name else []), "--help").stdout
        block = text.split("Example:", 1)[1].split("\n\n", 1)[0].replace("\\\n", " ")   # continued lines
        out += [(name or "rockslide", shlex.split(line)) for line in block.strip().splitlines()]
    return out


@pytest.mark.slow
def test_every_help_example_works_outside_the_checkout(tmp_path, monkeypatch):
    """In an empty folder, after `rockslide example` (itself an example), every example of every
    --help runs (run and sweep first, so that `plot` finds what they wrote; figures at 40 dpi to
    save time), except `table1`, which needs the paper's third-party records and the repository's
    case files."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ROCKSLIDE_RECORDS", raising=False)
    examples = help_examples()
    order = {"rockslide": 0, "example": 0, "run": 1, "sweep": 2, "fragility": 2}
    done = set()
    for _, words in sorted(examples, key=lambda e: order.get(e[1][1], 3)):
        assert words[0] == "rockslide", words
        if words[1] == "table1" or tuple(words) in done:
            continue
        done.add(tuple(words))
        again = ["--overwrite"] if words[1] in {"example", "run", "sweep", "fragility", "criteria"} else []
        coarse = ["--dpi", "40"] if words[1] in {"run", "sweep", "fragility", "criteria", "plot"} else []
        result = invoke(*words[1:], *again, *coarse)
        assert result.exit_code == 0, (words, result.output)
    assert {w[1] for _, w in examples} >= {"example", "run", "plot", "info", "sweep", "fragility", "criteria",
                                          "table1"}
    assert (tmp_path / "out" / "example-impact.pdf").read_bytes()[:5] == b"%PDF-"
    assert (tmp_path / "out" / "example.sweep.png").is_file() and (tmp_path / "criteria.png").is_file()


# --------------------------------------------------------------------------------------------------
# Consistency (point 7)
# --------------------------------------------------------------------------------------------------


def test_python_dash_m_rockslide_is_the_command():
    done = subprocess.run([sys.executable, "-m", "rockslide", "--version"], capture_output=True, text=True,
                          cwd=REPO, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"rockslide, version {__import__('rockslide').__version__}"


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_is_taken_before_or_after_the_command(tmp_path, where):
    args = ["info", tmp_path / "nosuch.at2"]
    args = ["--debug", *args] if where == "before" else [*args, "--debug"]
    result = invoke(*args)
    assert result.exit_code != 0 and type(result.exception).__name__ == "RecordError"
    one_line_error(invoke("info", tmp_path / "nosuch.at2"), "nosuch.at2: record file not found")


def test_debug_after_a_double_dash_is_an_argument(tmp_path):
    """After '--' everything is an argument: a file called --debug, not the option."""
    one_line_error(invoke("info", "--", "--debug"), "--debug: record file not found")


def test_table1_takes_out_dir_and_its_former_name_out():
    help_text = invoke("table1", "--help").stdout
    assert "--out-dir" in help_text and not re.search(r"--out\b(?!-)", help_text)
    for option in ("--out-dir", "--out"):
        one_line_error(invoke("table1", "--configs", "nosuch", option, "x"), "--configs: nosuch: folder not found")
    one_line_error(invoke("table1", "--out", "x", "--out-dir", "y"), "--out: --out is the former name of --out-dir")


def test_criteria_options_take_units(tmp_path):
    """--ah-max and --av take accelerations with units, like case files (bare numbers: see
    test_bad_input.py)."""
    result = invoke("criteria", "--ah-max", "500gal", "--av=-0.2g,0g", "-o", tmp_path / "c.png", "--dpi", "60")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "c.png").read_bytes()[:4] == b"\x89PNG"


def test_no_progress_frames_when_stderr_is_not_a_terminal(tmp_path):
    """A sweep logs plain lines: tqdm draws only on a terminal (here stderr is a pipe)."""
    result = invoke("sweep", EXAMPLE, "--mu", "0.5,0.6", "--pga", "700gal", "--records-dir", RECORDS,
                    "--out-dir", tmp_path, "--no-plot")
    assert result.exit_code == 0, result.output
    assert "\r" not in result.stderr and "case/s" not in result.stderr and "%|" not in result.stderr
    assert "2 cases" in result.stdout


# --------------------------------------------------------------------------------------------------
# Where files go (point 6)
# --------------------------------------------------------------------------------------------------


def test_inputs_resolve_against_the_case_file_outputs_against_the_current_folder(tmp_path, monkeypatch):
    cases, work = tmp_path / "cases", tmp_path / "work"
    cases.mkdir()
    work.mkdir()
    for name in ("synthetic_kt_h.at2", "synthetic_kt_v.at2"):
        shutil.copy(RECORDS / name, cases / name)
    text = EXAMPLE.read_text().replace("../records/", "").replace("tail: 2 s", "tail: 0 s")
    (cases / "example.yaml").write_text(text.replace("dt: 0.1 ms", "dt: 1 ms"))
    monkeypatch.chdir(work)
    monkeypatch.setenv("ROCKSLIDE_RECORDS", str(tmp_path / "elsewhere"))
    result = invoke("run", "../cases/example.yaml", "--no-plot")
    assert result.exit_code == 0, result.output
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.h5")) == ["work/out/example.h5"]


def test_shipped_case_files_write_into_the_ignored_out_folder():
    """Running a shipped case from the repository's root writes under out/, which git ignores, never
    into the tracked tree (results/ holds only what `make table1` and `make bench` commit)."""
    ignored = (REPO / ".gitignore").read_text().splitlines()
    assert "out/" in ignored
    for path in [EXAMPLE, *sorted((REPO / "configs" / "table1").glob("*.yaml"))]:
        assert Path(load_case(path).output.dir).parts[0] == "out", path


# --------------------------------------------------------------------------------------------------
# make honours ROCKSLIDE_RECORDS (point 4)
# --------------------------------------------------------------------------------------------------


@pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")
@pytest.mark.parametrize("environment, arguments, expected", [
    ("/data/env-records", [], "/data/env-records"),                    # an exported ROCKSLIDE_RECORDS
    (None, ["RECORDS=/data/make-records"], "/data/make-records"),      # RECORDS=
    ("/data/env-records", ["RECORDS=/data/make-records"], "/data/env-records"),   # the variable first
    ("", [], None),                                                    # set but empty: the defaults
    (None, [], None),
])
def test_make_honours_rockslide_records(environment, arguments, expected):
    """What every recipe sees (make test, make table1...) as ROCKSLIDE_RECORDS; the defaults are
    ../shared/records when it exists, else ./records."""
    env = {k: v for k, v in os.environ.items() if k not in ("ROCKSLIDE_RECORDS", "RECORDS", "MAKEFLAGS")}
    if environment is not None:
        env["ROCKSLIDE_RECORDS"] = environment
    probe = 'probe: ; @echo "$$ROCKSLIDE_RECORDS"'
    done = subprocess.run(["make", "--no-print-directory", "-s", f"--eval={probe}", "probe", *arguments],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    if expected is None:
        shared = REPO.parent / "shared" / "records"
        expected = str(shared if shared.is_dir() and any(shared.iterdir()) else REPO / "records")
        # make's abspath keeps symbolic links, resolve() follows them: compare the places
        assert Path(done.stdout.strip()).resolve() == Path(expected).resolve()
    else:
        assert done.stdout.strip() == expected
    dry = subprocess.run(["make", "-n", "table1", *arguments], cwd=REPO, env=env, capture_output=True,
                         text=True, timeout=60)
    assert f'--records-dir "{expected}"' in dry.stdout


def test_xarray_and_h5netcdf_are_dependencies():
    """The Python API returns xarray datasets and every file opens with xarray's h5netcdf engine:
    both are dependencies (an old install line's ``rockslide[xarray]`` still installs)."""
    import tomllib

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    names = {re.split(r"[<>=\[ ]", d, maxsplit=1)[0] for d in project["dependencies"]}
    assert {"xarray", "h5netcdf"} <= names
    assert "xarray" in project["optional-dependencies"]


def test_events_are_read_back_from_files_written_before_they_were_text(tmp_path, example_run):
    """Result files of the first layout held the event names as fixed-length bytes: they read the same."""
    _, _, stored = example_run
    path = tmp_path / "old.h5"
    results.write_result(path, stored.result, name="old")
    with h5py.File(path, "r+") as f:
        del f["events"]
        f.create_dataset("events", data=stored.result.events)           # EVENT_DTYPE: S10/S14
    assert np.array_equal(results.read_result(path).result.events, stored.result.events)
    with h5py.File(path, "r") as f:
        assert f["events"].dtype["cause"].kind == "S"


def test_case_to_dict_for_a_case_file_round_trips_through_yaml(tmp_path):
    """case_to_dict(case_file=True) writes accelerations with their unit (a case file needs them)."""
    case = load_case(EXAMPLE)
    data = case_to_dict(case, case_file=True)
    assert data["gravity"] == "9.80665 m/s^2"
    assert data["ground"]["scale"]["pga_horizontal"].endswith(" m/s^2")
    (tmp_path / "again.yaml").write_text(yaml.safe_dump(data))
    assert case_to_dict(load_case(tmp_path / "again.yaml")) == case_to_dict(case)


def test_example_module_names_its_records():
    assert [name for name, _, _ in example.RECORDS] == ["synthetic_kt_h.at2", "synthetic_kt_v.at2"]


def test_criteria_takes_the_block_of_a_case_file(tmp_path):
    """``rockslide criteria CASE.yaml`` maps the case's block (its title names its size); an option
    given beside it wins; a bad case file is the usual one-line error."""
    from conftest import invoke

    done = invoke("criteria", REPO / "configs" / "example.yaml", "-o", tmp_path / "c.png")
    assert done.exit_code == 0, done.output
    wider = invoke("criteria", REPO / "configs" / "example.yaml", "--width", "0.2 m", "-o", tmp_path / "w.png")
    assert wider.exit_code == 0 and (tmp_path / "w.png").read_bytes() != (tmp_path / "c.png").read_bytes()
    plain = invoke("criteria", "-o", tmp_path / "p.png")       # the defaults are the example's block
    assert plain.exit_code == 0 and (tmp_path / "p.png").read_bytes() == (tmp_path / "c.png").read_bytes()
    missing = invoke("criteria", tmp_path / "nope.yaml", "-o", tmp_path / "n.png")
    assert missing.exit_code == 2 and "case file not found" in missing.stderr
