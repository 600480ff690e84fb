"""Tests of rockslide.case: parsing, defaults, round trip, case_with, bad inputs, properties."""

from __future__ import annotations

import copy
import dataclasses
import math
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rockslide.case import (
    CASE_KEYS,
    Block,
    Case,
    Contact,
    Ground,
    Initial,
    Output,
    Pulse,
    RecordSpec,
    Scale,
    Solver,
    case_to_dict,
    case_with,
    iter_case_keys,
    load_case,
    parse_case,
)
from rockslide.errors import CaseError

EXAMPLE = """\
name: kobe-800-mu052
gravity: 9.80665 m/s^2                                 # optional, default 9.80665
block:   {height: 0.2, width: 0.1, mass: 10.0}          # m, m, kg (all required)
contact: {mu_static: 0.52, mu_kinetic: 0.494, restitution: 0.8}
ground:
  horizontal: {file: kobe_jma_1995_ns_peer_rsn1106_kjm000.at2}
  vertical:   {file: kobe_jma_1995_ud_peer_rsn1106_kjmup.at2}
  scale: {pga_horizontal: 800 gal, vertical_factor: 1.0}
  tail: 2 s
  time_shift: 0 s
initial: {rotation: 0.0, rotation_rate: 0.0, slip_rate: 0.0}
solver:  {dt: 0.1 ms, events: located, method: kernel}
output:  {dir: out, interval: 0.1 ms}
"""

MINIMAL = """\
name: minimal
block: {height: 0.2, width: 0.1, mass: 10}
contact: {mu_static: 0.5, restitution: 0.9}
ground: {horizontal: el_centro.at2}
"""

SOURCE = "case.yaml"


def example_data() -> dict:
    return yaml.safe_load(EXAMPLE)


def variant(set_: dict | None = None, drop: tuple[str, ...] = (), base: str = EXAMPLE) -> str:
    """The YAML text of ``base`` with dotted keys set (creating sections) or dropped."""
    data = yaml.safe_load(base)
    for key in drop:
        *parents, last = key.split(".")
        node = data
        for part in parents:
            node = node[part]
        del node[last]
    for key, value in (set_ or {}).items():
        *parents, last = key.split(".")
        node = data
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = value
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def error_of(text: str) -> str:
    with pytest.raises(CaseError) as info:
        parse_case(text, source=SOURCE)
    return str(info.value)


# ------------------------------------------------------------------------------------------------
# Valid cases
# ------------------------------------------------------------------------------------------------


class TestValid:
    def test_example_values_in_si(self):
        case = parse_case(EXAMPLE, source=SOURCE)
        assert case.name == "kobe-800-mu052"
        assert case.gravity == pytest.approx(9.80665)
        assert case.block == Block(height=0.2, width=0.1, mass=10.0)
        assert case.block.half_width == pytest.approx(0.05) == case.block.b
        assert case.block.half_height == pytest.approx(0.1) == case.block.h
        assert case.contact == Contact(mu_static=0.52, mu_kinetic=0.494, restitution=0.8)
        assert case.ground.horizontal == RecordSpec(file="kobe_jma_1995_ns_peer_rsn1106_kjm000.at2")
        assert case.ground.vertical == RecordSpec(file="kobe_jma_1995_ud_peer_rsn1106_kjmup.at2")
        assert case.ground.scale == Scale(pga_horizontal=pytest.approx(8.0), vertical_factor=1.0)
        assert case.ground.tail == 2.0
        assert case.ground.time_shift == 0.0
        assert case.initial == Initial()
        assert case.solver.dt == pytest.approx(1e-4)
        assert (case.solver.events, case.solver.method) == ("located", "kernel")
        assert case.output.dir == "out"
        assert case.output.interval == pytest.approx(1e-4)
        assert case.source == SOURCE
        assert case.text == EXAMPLE
        assert case.base_dir is None

    def test_defaults(self):
        case = parse_case(MINIMAL)
        assert case.source == "<case>"
        assert case.gravity == 9.80665
        assert case.contact.mu_kinetic == case.contact.mu_static == 0.5
        assert case.ground.vertical is None
        assert case.ground.scale == Scale()
        assert case.ground.scale.vertical_factor == 1.0
        assert (case.ground.tail, case.ground.time_shift) == (0.0, 0.0)
        assert case.initial == Initial(0.0, 0.0, 0.0)
        assert case.solver == Solver(dt=1e-4, events="located", method="kernel")
        assert case.output == Output(dir="out", interval=None)

    def test_bare_string_record(self):
        case = parse_case(MINIMAL)
        assert case.ground.horizontal == RecordSpec(file="el_centro.at2")
        assert case.ground.horizontal.skip_lines == 0

    def test_full_record_spec(self):
        text = variant({"ground.vertical": {
            "file": "ud.csv", "format": "csv", "units": "gal", "time_column": "t", "column": 2,
            "dt": "10 ms", "skip_lines": 3}})
        spec = parse_case(text).ground.vertical
        assert spec == RecordSpec(file="ud.csv", format="csv", units="gal", time_column="t", column=2,
                                  dt=pytest.approx(0.01), skip_lines=3)

    def test_unit_strings(self):
        text = variant({"block.height": "200 mm", "block.width": "10 cm", "gravity": "1 g",
                        "initial.rotation": "2 deg", "initial.rotation_rate": "-0.5 rad/s",
                        "initial.slip_rate": "-3 cm/s", "ground.scale.pga_vertical": "0.5 g",
                        "ground.scale.vertical_factor": None, "ground.tail": "500 ms"})
        case = parse_case(text)
        assert case.block.height == pytest.approx(0.2)
        assert case.block.width == pytest.approx(0.1)
        assert case.gravity == pytest.approx(9.80665)
        assert case.initial.rotation == pytest.approx(math.radians(2))
        assert case.initial.rotation_rate == pytest.approx(-0.5)
        assert case.initial.slip_rate == pytest.approx(-0.03)
        assert case.ground.scale.pga_vertical == pytest.approx(0.5 * 9.80665)
        assert case.ground.tail == pytest.approx(0.5)

    def test_a_bare_zero_acceleration_needs_no_unit(self):
        """0 means the same in every unit; any other bare acceleration is refused (TestBad)."""
        case = parse_case(variant({"ground.scale.pga_vertical": 0, "ground.scale.vertical_factor": None}))
        assert case.ground.scale.pga_vertical == 0.0

    def test_units_as_written_are_kept(self):
        case = parse_case(EXAMPLE)
        assert case.units["ground.scale.pga_horizontal"] == "gal"
        assert case.units["gravity"] == "m/s^2"
        assert "block.height" not in case.units                     # a bare number (SI)
        assert case_with(case, {"ground.scale.pga_horizontal": "0.5 g"}).units[
            "ground.scale.pga_horizontal"] == "g"

    def test_null_means_default(self):
        case = parse_case(variant({"initial": None, "output.interval": None, "gravity": None}))
        assert case.initial == Initial()
        assert case.output.interval is None
        assert case.gravity == 9.80665

    def test_factor_and_vertical_only(self):
        text = variant({"ground.scale": {"factor": 2.0, "vertical_factor": 0.0}},
                       drop=("ground.horizontal",))
        case = parse_case(text)
        assert case.ground.horizontal is None
        assert case.ground.scale == Scale(factor=2.0, vertical_factor=0.0)

    def test_interval_multiple_of_dt(self):
        case = parse_case(variant({"solver.dt": "0.1 ms", "output.interval": "1 ms"}))
        assert case.output.interval == pytest.approx(1e-3)
        assert parse_case(variant({"solver.dt": 0.01, "output.interval": 0.03})).output.interval == 0.03

    def test_limits_inclusive(self):
        case = parse_case(variant({"contact.restitution": 1, "contact.mu_static": 0,
                                   "contact.mu_kinetic": 0, "solver.dt": "10 ms",
                                   "output.interval": None, "initial.rotation": "89.9 deg"}))
        assert case.contact == Contact(0.0, 0.0, 1.0)
        assert case.solver.dt == pytest.approx(0.01)

    @pytest.mark.parametrize("text", [EXAMPLE, MINIMAL, variant({"ground.scale": {"factor": 0.5}})])
    def test_round_trip(self, text):
        case = parse_case(text, source=SOURCE, base_dir=Path("cases"))
        plain = case_to_dict(case)
        again = parse_case(yaml.safe_dump(case_to_dict(case, case_file=True)))
        assert dataclasses.replace(again, text=case.text, source=case.source,
                                   base_dir=case.base_dir) == case
        assert case_to_dict(again) == plain

    def test_case_to_dict_is_plain(self):
        plain = case_to_dict(parse_case(EXAMPLE), case_file=False)
        assert plain["ground"]["scale"] == {"pga_horizontal": pytest.approx(8.0), "vertical_factor": 1.0}
        assert plain["solver"]["dt"] == pytest.approx(1e-4)
        assert "text" not in plain and "source" not in plain

        def walk(obj):
            if isinstance(obj, dict):
                assert all(isinstance(k, str) for k in obj)
                for value in obj.values():
                    walk(value)
            else:
                assert isinstance(obj, (str, int, float)) and obj is not None
        walk(plain)

    def test_load_case(self, tmp_path):
        path = tmp_path / "kobe.yaml"
        path.write_text(EXAMPLE, encoding="utf-8")
        case = load_case(path)
        assert case.source == str(path)
        assert case.base_dir == path.absolute().parent
        assert case.text == EXAMPLE

    def test_load_case_missing_file(self, tmp_path):
        with pytest.raises(CaseError, match=r"nothere\.yaml: case file not found"):
            load_case(tmp_path / "nothere.yaml")

    def test_load_case_folder_and_binary(self, tmp_path):
        with pytest.raises(CaseError, match="is a folder"):
            load_case(tmp_path)
        bad = tmp_path / "bad.yaml"
        bad.write_bytes(b"name: \xff\xfe\n")
        with pytest.raises(CaseError, match=r"bad\.yaml: not UTF-8"):
            load_case(bad)


class TestSchema:
    def test_dataclass_defaults_match_schema(self):
        classes = {"initial": Initial, "solver": Solver, "output": Output, "ground.scale": Scale}
        for section, cls in classes.items():
            keys = CASE_KEYS
            for part in section.split("."):
                keys = keys[part]["keys"]
            defaults = {f.name: f.default for f in dataclasses.fields(cls)}
            if cls is Solver:       # dt: auto is the field auto; tolerance: {time, rotation} two fields
                assert defaults.pop("auto") is False
                keys = {**{k: v for k, v in keys.items() if k != "tolerance"},
                        **{f"tolerance_{k}": v for k, v in keys["tolerance"]["keys"].items()}}
            assert set(defaults) == set(keys)
            for name, spec in keys.items():
                assert spec["default"] == defaults[name], f"{section}.{name}"
        record_keys = list(CASE_KEYS["ground"]["keys"]["horizontal"]["keys"])    # a file's, then a pulse's
        file_keys = [f.name for f in dataclasses.fields(RecordSpec) if f.name != "azimuth"]
        pulse_keys = [f.name for f in dataclasses.fields(Pulse)]
        assert file_keys + pulse_keys == record_keys
        # one of two components: a file's keys and its azimuth
        assert list(CASE_KEYS["ground"]["keys"]["horizontal_1"]["keys"]) == [*file_keys, "azimuth"]
        assert {f.name for f in dataclasses.fields(Block)} == set(CASE_KEYS["block"]["keys"])
        assert {f.name for f in dataclasses.fields(Contact)} == set(CASE_KEYS["contact"]["keys"])
        # the case file's horizontal_1 is Ground.horizontal (the first of two components)
        assert {f.name for f in dataclasses.fields(Ground)} | {"horizontal_1"} == set(CASE_KEYS["ground"]["keys"])
        case_fields = {f.name for f in dataclasses.fields(Case)} - {"source", "base_dir", "text", "units"}
        assert case_fields == set(CASE_KEYS)

    def test_every_key_documented(self):
        for path, spec in iter_case_keys():
            assert spec["doc"], path
            assert isinstance(spec["required"], bool)


# ------------------------------------------------------------------------------------------------
# case_with
# ------------------------------------------------------------------------------------------------


class TestCaseWith:
    def test_changes_applied(self):
        case = parse_case(EXAMPLE, source=SOURCE, base_dir=Path("cases"))
        new = case_with(case, {"contact.mu_static": 0.6, "ground.scale.pga_horizontal": "400 gal",
                               "block.width": "50 mm"})
        assert new.contact == Contact(0.6, 0.494, 0.8)
        assert new.ground.scale.pga_horizontal == pytest.approx(4.0)
        assert new.block.width == pytest.approx(0.05)
        assert new.block.height == case.block.height
        assert (new.source, new.base_dir) == (case.source, case.base_dir)
        assert case.contact.mu_static == 0.52  # the original is untouched

    def test_text_records_changes(self):
        case = parse_case(EXAMPLE)
        new = case_with(case, {"contact.mu_static": 0.6, "name": "sweep-1"})
        assert new.text.startswith(EXAMPLE)
        tail = new.text[len(EXAMPLE):]
        assert "contact.mu_static: 0.6" in tail and "name: 'sweep-1'" in tail
        assert all(line.startswith("#") for line in tail.splitlines())
        assert yaml.safe_load(new.text) == yaml.safe_load(EXAMPLE)

    def test_chained(self):
        case = case_with(case_with(parse_case(EXAMPLE), {"block.mass": 2}), {"block.height": 0.4})
        assert case.block == Block(height=0.4, width=0.1, mass=2.0)

    def test_unknown_key(self):
        with pytest.raises(CaseError, match=r"case.yaml: contact.mu_statc: unknown key \(did you mean "
                                            r"'mu_static'\?\)"):
            case_with(parse_case(EXAMPLE, source=SOURCE), {"contact.mu_statc": 0.5})

    @pytest.mark.parametrize("key, field", [("block.height.x", "block.height.x"),
                                            ("solvr.dt", "solvr"), ("", None), ("a\nb", None)])
    def test_bad_key_paths(self, key, field):
        with pytest.raises(CaseError) as info:
            case_with(parse_case(EXAMPLE), {key: 1})
        assert info.value.field == field

    def test_violating_mu_kinetic_rejected(self):
        with pytest.raises(CaseError) as info:
            case_with(parse_case(EXAMPLE, source=SOURCE), {"contact.mu_static": 0.4})
        message = str(info.value)
        assert message.startswith("case.yaml: contact.mu_kinetic: ")
        assert "mu_kinetic (0.494) must not exceed mu_static (0.4)" in message
        assert "contact.mu_static=0.4" in message

    def test_mu_kinetic_follows_default(self):
        case = parse_case(MINIMAL)
        assert case_with(case, {"contact.mu_static": 0.3}).contact.mu_kinetic == 0.3
        assert case_with(case, {"contact.mu_static": 0.3, "contact.mu_kinetic": 0.2}).contact == \
            Contact(0.3, 0.2, 0.9)

    def test_validation_applies(self):
        case = parse_case(EXAMPLE)
        with pytest.raises(CaseError, match=r"block\.width: must be greater than 0 m"):
            case_with(case, {"block.width": -1})
        with pytest.raises(CaseError, match=r"ground\.scale: pga_horizontal .* and factor .* exclusive"):
            case_with(case, {"ground.scale.factor": 2})
        with pytest.raises(CaseError, match="unknown length unit 'kg'"):
            case_with(case, {"block.width": "1 kg"})

    def test_none_removes_key(self):
        case = parse_case(EXAMPLE)
        new = case_with(case, {"ground.scale.pga_horizontal": None, "ground.scale.factor": 2})
        assert new.ground.scale == Scale(factor=2.0)
        assert case_with(case, {"ground.vertical": None}).ground.vertical is None

    def test_records(self):
        case = parse_case(MINIMAL)
        new = case_with(case, {"ground.horizontal.dt": "5 ms", "ground.vertical": Path("ud.at2")})
        assert new.ground.horizontal == RecordSpec(file="el_centro.at2", dt=pytest.approx(0.005))
        assert new.ground.vertical == RecordSpec(file="ud.at2")
        with pytest.raises(CaseError, match=r"ground\.vertical\.file: missing required key"):
            case_with(case, {"ground.vertical.dt": 0.01})


# ------------------------------------------------------------------------------------------------
# Bad inputs: (id, text, substrings the message must contain)
# ------------------------------------------------------------------------------------------------

BAD = [
    # YAML itself
    ("syntax-flow", "name: x\nblock: {height: 0.2\n",
     ["line 3, column 1", "invalid YAML", "expected ',' or '}'", "from line 2, column 8"]),
    ("syntax-indent", "name: a\n  b: c\n", ["line 2, column 4", "mapping values are not allowed here"]),
    ("syntax-tab", "name: x\nblock:\n\theight: 1\n", ["line 3, column 1", "'\\t'"]),
    ("syntax-quote", "name: 'abc\n", ["line 2, column 1", "unexpected end of stream"]),
    ("syntax-two-documents", "name: a\n---\nname: b\n", ["line 2, column 1", "single document"]),
    ("control-character", "name: a\x01b\n", ["line 1, column 8", "#x0001", "not allowed"]),
    ("python-tag", "name: !!python/object/apply:os.system ['echo hi']\n",
     ["line 1, column 7", "unsupported YAML tag", "python/object/apply:os.system"]),
    ("python-name-tag",
     variant({"gravity": "X"}).replace("gravity: X", "gravity: !!python/name:os.getcwd ''"),
     ["unsupported YAML tag", "python/name:os.getcwd"]),
    ("tag-bad-int", variant({"block.mass": "X"}).replace("mass: X", "mass: !!int ten"),
     ["line 6, column 9", "'ten' is not a valid !!int value"]),
    ("tag-bad-timestamp", "name: !!timestamp yesterday\n", ["line 1, column 7", "!!timestamp"]),
    ("unhashable-key", "? [1]\n: 2\n", ["line 1", "unhashable key"]),
    ("empty", "", ["empty", "name, gravity, block"]),
    ("comment-only", "# nothing\n", ["empty"]),
    ("top-level-list", "- name: a\n", ["top level must be a mapping", "got a list"]),
    ("top-level-string", "hello\n", ["top level must be a mapping", "got a string 'hello'"]),
    # unknown keys, at every level
    ("unknown-top", variant({"nmae": "x"}), ["nmae: unknown key (did you mean 'name'?)"]),
    ("unknown-top-misplaced", variant({"mu_static": 0.5}),
     ["mu_static: unknown key (did you mean 'contact.mu_static'? it belongs under 'contact')"]),
    ("unknown-top-nonstring", EXAMPLE + "1: 2\n", [": 1: unknown key (expected one of: name, gravity"]),
    ("unknown-key-newline", EXAMPLE + '"a\\nb": 1\n', ["'a\\nb': unknown key"]),
    ("unknown-block", variant({"block.hieght": 0.2}),
     ["block.hieght: unknown key (did you mean 'height'?)"]),
    ("unknown-contact", variant({"contact.mu_statc": 0.5}),
     ["case.yaml: contact.mu_statc: unknown key (did you mean 'mu_static'?)"]),
    ("unknown-ground", variant({"ground.horizontl": "a.at2"}),
     ["ground.horizontl: unknown key (did you mean 'horizontal'?)"]),
    ("unknown-record-h", variant({"ground.horizontal.fiel": "a.at2"}),
     ["ground.horizontal.fiel: unknown key (did you mean 'file'?)"]),
    ("unknown-record-v", variant({"ground.vertical.colum": 2}),
     ["ground.vertical.colum: unknown key (did you mean 'column'?)"]),
    ("unknown-scale", variant({"ground.scale.pga_horizonal": 8}),
     ["ground.scale.pga_horizonal: unknown key (did you mean 'pga_horizontal'?)"]),
    ("unknown-initial", variant({"initial.rotaton": 0.1}),
     ["initial.rotaton: unknown key (did you mean 'rotation'?)"]),
    ("unknown-solver", variant({"solver.step": 0.1}),
     ["solver.step: unknown key (expected one of: dt, events, method, tolerance)"]),
    ("unknown-output", variant({"output.folder": "x"}), ["output.folder: unknown key"]),
    # required keys
    ("missing-name", variant(drop=("name",)), ["case.yaml: name: missing required key"]),
    ("missing-block", variant(drop=("block",)), ["block: missing required key"]),
    ("missing-height", variant(drop=("block.height",)), ["block.height: missing required key", "[m]"]),
    ("missing-width", variant(drop=("block.width",)), ["block.width: missing required key"]),
    ("missing-mass", variant(drop=("block.mass",)), ["block.mass: missing required key", "[kg]"]),
    ("missing-contact", variant(drop=("contact",)), ["contact: missing required key"]),
    ("missing-mu-static", variant(drop=("contact.mu_static",)),
     ["contact.mu_static: missing required key"]),
    ("missing-restitution", variant(drop=("contact.restitution",)),
     ["contact.restitution: missing required key"]),
    ("missing-ground", variant(drop=("ground",)), ["ground: missing required key"]),
    ("null-block", variant({"block": None}), ["block: is null, a value is required"]),
    ("null-file", variant({"ground.vertical.file": None}),
     ["ground.vertical.file: is null, a value is required"]),
    ("no-records", variant({"ground.tail": "0 s"}, drop=("ground.horizontal", "ground.vertical", "ground.scale")),
     ["ground: needs a record", "ground.horizontal or ground.vertical", "or, for a free vibration"]),
    ("missing-file", variant({"ground.horizontal": {"dt": 0.01}}),
     ["ground.horizontal.file: missing required key"]),
    # types
    ("type-block-list", variant({"block": [0.2, 0.1, 10]}),
     ["block: expected a mapping (keys: height, width, mass, orientation, centre_of_mass_height, half_widths, depth, "
      "radius_of_gyration, mesh, mesh_units, density), got a list [0.2, 0.1, 10]"]),
    ("type-contact-string", variant({"contact": "rough"}), ["contact: expected a mapping", "'rough'"]),
    ("type-scale-number", variant({"ground.scale": 2}),
     ["ground.scale: expected a mapping", "got an integer 2"]),
    ("type-height-list", variant({"block.height": [1, 2]}),
     ["block.height: expected a length", "got list"]),
    ("type-mass-bool", variant({"block.mass": True}), ["block.mass: expected a mass", "got True"]),
    ("type-gravity-date", variant({"gravity": "X"}).replace("gravity: X", "gravity: 2001-12-14"),
     ["gravity: expected a", "got date"]),
    ("type-name-int", variant({"name": 12.5}), ["name: expected a name", "got a number 12.5"]),
    ("type-name-slash", variant({"name": "../etc"}), ["name: expected a name", "'../etc'"]),
    ("type-name-dash", variant({"name": "-x"}), ["name: expected a name", "'-x'"]),
    ("type-record-list", variant({"ground.horizontal": ["a.at2"]}),
     ["ground.horizontal: expected a file name or a mapping", "got a list ['a.at2']"]),
    ("type-file-empty", variant({"ground.horizontal": {"file": ""}}),
     ["ground.horizontal.file: expected a non-empty string", "got a string ''"]),
    ("type-file-number", variant({"ground.horizontal": 12}),
     ["ground.horizontal: expected a file name or a mapping", "got an integer 12"]),
    ("type-skip-negative", variant({"ground.horizontal.skip_lines": -1}),
     ["ground.horizontal.skip_lines: expected a whole number >= 0", "got an integer -1"]),
    ("type-skip-float", variant({"ground.horizontal.skip_lines": 1.5}),
     ["ground.horizontal.skip_lines: expected a whole number >= 0", "got a number 1.5"]),
    ("type-column-zero", variant({"ground.vertical.column": 0}),
     ["ground.vertical.column: expected a column number >= 1"]),
    ("type-time-column-empty", variant({"ground.vertical.time_column": " "}),
     ["ground.vertical.time_column: expected a column number >= 1", "non-empty header name"]),
    ("type-format-list", variant({"ground.vertical.format": ["at2"]}),
     ["ground.vertical.format: expected a non-empty string", "got a list"]),
    ("choice-events", variant({"solver.events": "locatd"}),
     [("solver.events: expected one of 'located', 'step-end', got a string 'locatd' "
       "(did you mean 'located'?)")]),
    ("choice-method", variant({"solver.method": "fast"}),
     ["solver.method: expected one of 'kernel', 'reference', got a string 'fast'"]),
    ("type-output-dir", variant({"output.dir": ""}), ["output.dir: expected a non-empty string"]),
    ("type-initial-list", variant({"initial": [0]}), ["initial: expected a mapping"]),
    # units
    ("unit-height-kg", variant({"block.height": "20 kg"}),
     ["block.height: unknown length unit 'kg'", "m, cm, mm"]),
    ("unit-dt-unknown", variant({"solver.dt": "1 fortnight"}), ["solver.dt: unknown time unit 'fortnight'"]),
    ("unit-mu-with-unit", variant({"contact.mu_static": "0.5 m"}),
     ["contact.mu_static: unknown dimensionless unit 'm'"]),
    ("unit-garbage", variant({"block.width": "wide"}), ["block.width: cannot read 'wide' as a length"]),
    ("unit-rotation-rate", variant({"initial.rotation_rate": "1 m/s"}),
     ["initial.rotation_rate: unknown angular_rate unit 'm/s'"]),
    ("unit-record-units", variant({"ground.vertical.units": "furlongs"}),
     ["ground.vertical.units: unknown acceleration unit 'furlongs'"]),
    ("unit-record-units-type", variant({"ground.vertical.units": 9.81}),
     ["ground.vertical.units: expected an acceleration unit", "got a number 9.81"]),
    ("unit-nan", variant({"ground.tail": float("nan")}), ["ground.tail:", "not a finite number"]),
    ("unit-inf", variant({"block.mass": "1e400 kg"}), ["block.mass:", "not a finite number"]),
    ("unit-huge-int", variant({"block.mass": 10**400}), ["block.mass:", "too large"]),
    # physical bounds
    ("height-zero", variant({"block.height": 0}), ["block.height: must be greater than 0 m, got 0 m"]),
    ("width-negative", variant({"block.width": "-10 cm"}),
     ["block.width: must be greater than 0 m, got -0.1 m (from '-10 cm')"]),
    ("mass-zero", variant({"block.mass": 0.0}), ["block.mass: must be greater than 0 kg, got 0 kg"]),
    ("gravity-negative", variant({"gravity": "-1 g"}),
     ["gravity: must be greater than 0 m/s^2", "(from '-1 g')"]),
    ("mu-static-negative", variant({"contact.mu_static": -0.1}),
     ["contact.mu_static: must be at least 0, got -0.1"]),
    ("mu-kinetic-negative", variant({"contact.mu_kinetic": -0.1}),
     ["contact.mu_kinetic: must be at least 0, got -0.1"]),
    ("mu-kinetic-above-static", variant({"contact.mu_static": 0.5, "contact.mu_kinetic": 0.6}),
     ["contact.mu_kinetic: mu_kinetic (0.6) must not exceed mu_static (0.5)"]),
    ("restitution-high", variant({"contact.restitution": 1.2}),
     ["contact.restitution: must be at least 0 and at most 1, got 1.2"]),
    ("restitution-negative", variant({"contact.restitution": -0.1}),
     ["contact.restitution: must be at least 0 and at most 1, got -0.1"]),
    ("dt-zero", variant({"solver.dt": 0, "output.interval": None}),
     ["solver.dt: must be greater than 0 s and at most 0.01 s, got 0 s"]),
    ("dt-large", variant({"solver.dt": "20 ms", "output.interval": None}),
     ["solver.dt: must be greater than 0 s and at most 0.01 s, got 0.02 s (from '20 ms')"]),
    ("interval-below-dt", variant({"output.interval": "0.05 ms"}),
     ["output.interval: must be at least solver.dt (0.0001 s), got 5e-05 s"]),
    ("interval-not-multiple", variant({"output.interval": "0.15 ms"}),
     ["output.interval: must be a whole multiple of solver.dt (0.0001 s), got 0.00015 s", "1.5 steps"]),
    ("tail-negative", variant({"ground.tail": "-1 s"}), ["ground.tail: must be at least 0 s, got -1 s"]),
    ("pga-horizontal-zero", variant({"ground.scale.pga_horizontal": 0}),
     ["ground.scale.pga_horizontal: must be greater than 0 m/s^2, got 0 m/s^2"]),
    ("pga-vertical-negative",
     variant({"ground.scale.pga_vertical": "-1 m/s^2", "ground.scale.vertical_factor": None}),
     ["ground.scale.pga_vertical: must be at least 0 m/s^2, got -1 m/s^2"]),
    ("pga-horizontal-bare", variant({"ground.scale.pga_horizontal": 0.8}),
     ["ground.scale.pga_horizontal: 0.8 has no unit", "'0.8 g' is 7.845 m/s^2", "'0.8 m/s^2' is 0.08158 g"]),
    ("pga-horizontal-bare-string", variant({"ground.scale.pga_horizontal": "800"}),
     ["ground.scale.pga_horizontal: 800 has no unit", "'800 gal' or '800 cm/s^2' is 0.8158 g"]),
    ("pga-vertical-bare", variant({"ground.scale.pga_vertical": 3, "ground.scale.vertical_factor": None}),
     ["ground.scale.pga_vertical: 3 has no unit", "'3 g' is 29.42 m/s^2"]),
    ("gravity-bare", variant({"gravity": 9.81}), ["gravity: 9.81 has no unit", "'9.81 m/s^2' is 1 g"]),
    ("factor-zero", variant({"ground.scale": {"factor": 0}}),
     ["ground.scale.factor: must be greater than 0, got 0"]),
    ("vertical-factor-negative", variant({"ground.scale.vertical_factor": -0.5}),
     ["ground.scale.vertical_factor: must be at least 0, got -0.5"]),
    ("pga-and-factor", variant({"ground.scale.factor": 2}),
     ["ground.scale: pga_horizontal (8 m/s^2) and factor (2) are exclusive"]),
    ("pga-vertical-and-factor",
     variant({"ground.scale.pga_vertical": "3 m/s^2", "ground.scale.vertical_factor": 0.5}),
     ["ground.scale: pga_vertical (3 m/s^2) and vertical_factor (0.5) are exclusive"]),
    ("pga-without-record", variant(drop=("ground.horizontal",)),
     ["ground.scale.pga_horizontal: given, but there is no ground.horizontal record"]),
    ("vertical-factor-without-record", variant({"ground.scale.vertical_factor": 0.5},
                                               drop=("ground.vertical",)),
     ["ground.scale.vertical_factor: given (0.5), but there is no ground.vertical record"]),
    ("rotation-too-large", variant({"initial.rotation": 2}),
     ["initial.rotation: must be in absolute value less than pi/2 rad (90 deg), got 2 rad"]),
    ("rotation-minus-90deg", variant({"initial.rotation": "-90 deg"}),
     ["initial.rotation: must be in absolute value less than pi/2", "(from '-90 deg')"]),
    ("record-dt-zero", variant({"ground.vertical.dt": 0}),
     ["ground.vertical.dt: must be greater than 0 s, got 0 s"]),
]


@pytest.mark.parametrize("text, expected", [pytest.param(t, e, id=i) for i, t, e in BAD])
def test_bad_input(text, expected):
    message = error_of(text)
    assert message.startswith(f"{SOURCE}: ")
    assert "\n" not in message
    for part in expected:
        assert part in message, f"{part!r} not in {message!r}"


def test_bad_table_is_large_and_distinct():
    assert len(BAD) >= 30
    assert len({i for i, _, _ in BAD}) == len(BAD)
    assert len({t for _, t, _ in BAD}) == len(BAD)


def test_error_fields():
    with pytest.raises(CaseError) as info:
        parse_case(variant({"contact.restitution": 2}), source=SOURCE)
    assert (info.value.source, info.value.field) == (SOURCE, "contact.restitution")


# ------------------------------------------------------------------------------------------------
# Properties: whatever the text, a Case or a CaseError
# ------------------------------------------------------------------------------------------------

TOKENS = ["name", "block", "contact", "ground", "height", "mu_static", "horizontal", "file", "scale",
          ":", ": ", " ", "  ", "\n", "\n  ", "{", "}", "[", "]", ",", "- ", "? ", "&a ", "*a", "'", '"',
          "#", "|", ">", "\t", "!!python/object:os.system", "!!binary", "!!set", "!!float", "!!str",
          "~", "null", "true", "0.2", "-1", "1e400", ".nan", ".inf", "800 gal", "0.1 ms", "5 deg",
          "2001-12-14", "---", "...", "%YAML 1.1", "\x00", "\ufeff", "é"]

SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(), st.integers(min_value=10**300, max_value=10**400),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=20),
    st.sampled_from(["800 gal", "0.1 ms", "5 deg", "1 g", "-3 m", "abc", "", "located", "kernel",
                     "x.at2", "1e400 kg", "0", "nan"]),
)
VALUES = st.one_of(SCALARS, st.lists(SCALARS, max_size=3),
                   st.dictionaries(st.text(max_size=8), SCALARS, max_size=3))


def _paths(data, prefix=()):
    for key, value in data.items():
        yield (*prefix, key)
        if isinstance(value, dict):
            yield from _paths(value, (*prefix, key))


EXAMPLE_PATHS = list(_paths(example_data()))


def _parse_or_case_error(text):
    try:
        case = parse_case(text, source=SOURCE)
    except CaseError as exc:
        message = str(exc)
        assert message.startswith(SOURCE) and "\n" not in message
        return None
    assert isinstance(case, Case)
    return case


@settings(deadline=None, max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(TOKENS), max_size=40).map("".join))
def test_random_yamlish_text(text):
    _parse_or_case_error(text)


@settings(deadline=None, max_examples=100)
@given(st.text(max_size=200))
def test_random_text(text):
    _parse_or_case_error(text)


@settings(deadline=None, max_examples=300)
@given(st.lists(st.tuples(st.sampled_from(EXAMPLE_PATHS), st.booleans(), VALUES), min_size=1, max_size=3))
@example(mutations=[(("solver", "dt"), False, 5e-324)])    # found by CI: output.interval / dt overflowed
def test_random_mutations(mutations):
    data = example_data()
    for path, drop, value in mutations:
        node = data
        for part in path[:-1]:
            node = node.get(part) if isinstance(node, dict) else None
        if not isinstance(node, dict):
            continue
        if drop:
            node.pop(path[-1], None)
        else:
            node[path[-1]] = copy.deepcopy(value)
    _parse_or_case_error(yaml.safe_dump(data, allow_unicode=True))


CHANGE_KEYS = [p for p, _ in iter_case_keys()] + ["contact.mu_statc", "block.height.x", "nope"]


@settings(deadline=None, max_examples=200)
@given(st.dictionaries(st.sampled_from(CHANGE_KEYS), VALUES, min_size=1, max_size=3))
def test_random_case_with(changes):
    case = parse_case(EXAMPLE, source=SOURCE)
    try:
        new = case_with(case, changes)
    except CaseError as exc:
        assert "\n" not in str(exc)
        return
    assert isinstance(new, Case)
    again = parse_case(yaml.safe_dump(case_to_dict(new, case_file=True)))
    assert dataclasses.replace(again, text=new.text, source=new.source, base_dir=new.base_dir) == new


def test_a_mapping_parses_as_the_same_yaml_and_round_trips():
    """`parse_case` and `load_case` take a mapping as the YAML it would be written as: the same
    case, the same errors (an acceleration without its unit), and `case_to_dict` reads back."""
    text = (Path(__file__).resolve().parents[1] / "configs" / "example.yaml").read_text()
    from_text = parse_case(text, base_dir=Path("configs"))
    data = yaml.safe_load(text)
    from_data = parse_case(data, base_dir=Path("configs"))
    assert case_to_dict(from_data) == case_to_dict(from_text)
    assert case_to_dict(load_case(case_to_dict(from_text), base_dir=Path("configs"))) == case_to_dict(from_text)
    data["ground"]["scale"]["pga_horizontal"] = 8.0
    with pytest.raises(CaseError, match="ground.scale.pga_horizontal"):
        parse_case(data)
    with pytest.raises(CaseError, match="expected the YAML text of a case"):
        parse_case(42)
