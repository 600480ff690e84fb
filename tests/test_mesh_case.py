"""A body from a mesh in a case file (issue 39.2-39.4, model-asymmetric.md section 9):
``block: {mesh: rock.obj, mesh_units: m, density: 2650 kg/m^3}`` gives the planar body along
``block.orientation`` (the mesh's x axis when not given) and its second plane across it.

What these tests protect: a box mesh written by the test runs as the equivalent block (the same
body to 1e-10 m; the same motion, since both run the same kernel path); turning the mesh about the
vertical turns the direction its body is taken along; a case changed key by key (a sweep over
orientations, the second plane) derives its body again from the mesh; a case written back
(`case_to_dict`) reads as the same case; every bad mesh key is one line naming it, exit 2.

Tolerances: 1e-10 m on bodies of 0.1-2 m (the mesh's mass properties round at 1e-16 relative,
tests/test_mesh.py); 1e-9 relative on rotations of runs whose bodies differ by that rounding only,
over a pulse of a second without chaotic growth (a rocking block's sensitivity over one pulse is
below 1e4, so 1e-15 in the body stays under 1e-11).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
import yaml
from conftest import invoke, one_line_error

import rockslide
from rockslide.case import case_to_dict, case_with, load_case, other_plane
from rockslide.errors import CaseError

TOL = 1e-10
WIDTH, DEPTH, HEIGHT = 0.5, 0.375, 1.75           # binary fractions: exact in an OBJ file


def box_obj(path, width=WIDTH, depth=DEPTH, height=HEIGHT, turn=0.0):
    """A box of ``width`` along x (east), ``depth`` along y, on z = 0, turned by ``turn`` [rad]
    counter-clockwise seen from above, written as OBJ."""
    mesh = trimesh.creation.box(extents=(width, depth, height))
    mesh.apply_translation((0.0, 0.0, height / 2))
    if turn:
        mesh.apply_transform(trimesh.transformations.rotation_matrix(turn, (0, 0, 1)))
    mesh.export(path)
    return path


def l_prism(path):
    """An L-shaped prism (tests/test_mesh.py's L_PROFILE, 0.25 m deep): its centre of mass is off the
    middle of its base along x."""
    profile = np.array([(0.1, 0.1), (0.1, 0.3), (0.0, 0.3), (0.0, 0.0), (0.2, 0.0), (0.2, 0.1)])
    n = len(profile)
    front = np.column_stack([profile[:, 0], np.full(n, -0.125), profile[:, 1]])
    back = front * [1.0, -1.0, 1.0]
    faces = [f for i in range(1, n - 1) for f in ([0, i + 1, i], [n, n + i, n + i + 1])]
    faces += [f for i in range(n) for f in ([i, (i + 1) % n, n + (i + 1) % n], [i, n + (i + 1) % n, n + i])]
    mesh = trimesh.Trimesh(np.vstack([front, back]), faces, process=True)
    if mesh.volume < 0:
        mesh.invert()
    mesh.export(path)
    return path


def two_components(folder, peak_g: float = 1.0) -> dict:
    """The ground of two horizontal components written into ``folder``: a 2 Hz sine of ``peak_g``
    for a second along east and 0.6 of it along south, then a second of rest."""
    t = np.arange(0, 2.0, 0.01)
    wave = peak_g * 9.80665 * np.sin(2 * np.pi * t / 0.5) * (t < 1.0)
    for name, scale in (("h1.txt", 1.0), ("h2.txt", 0.6)):
        np.savetxt(folder / name, np.column_stack([t, scale * wave]))
    return {"horizontal_1": {"file": "h1.txt", "azimuth": "90 deg", "units": "m/s^2"},
            "horizontal_2": {"file": "h2.txt", "azimuth": "180 deg", "units": "m/s^2"}, "tail": "1 s"}


def case(block: dict, **ground) -> dict:
    ground = ground or {"horizontal": {"pulse": "one-sine", "amplitude": "0.45 g", "period": "0.6 s"},
                        "tail": "1 s"}
    return {"name": "body", "block": block, "contact": {"mu_static": 0.8, "restitution": 0.8}, "ground": ground}


def mesh_block(path, **more) -> dict:
    return {"mesh": str(path), "mesh_units": "m", "density": "2000 kg/m^3", **more}


def test_a_box_mesh_is_the_box(tmp_path):
    """The body derived from a box mesh is the box: b1 = b2 = width/2, h = height/2, the box's radius
    of gyration, mass = density x volume; its run is the run of that body given by its sizes."""
    body = load_case(case(mesh_block(box_obj(tmp_path / "box.obj"))), base_dir=tmp_path).block
    b, h = WIDTH / 2, HEIGHT / 2
    assert body.half_widths == pytest.approx((b, b), abs=TOL)
    assert body.centre_of_mass_height == pytest.approx(h, abs=TOL)
    assert body.radius_of_gyration == pytest.approx(math.sqrt((b * b + h * h) / 3), abs=TOL)
    assert body.mass == pytest.approx(2000.0 * WIDTH * DEPTH * HEIGHT, rel=1e-12)
    assert (body.height, body.width) == pytest.approx((HEIGHT, WIDTH), abs=TOL)
    sizes = {"centre_of_mass_height": f"{h!r} m", "half_widths": [f"{b!r} m", f"{b!r} m"],
             "radius_of_gyration": f"{math.sqrt((b * b + h * h) / 3)!r} m", "mass": "1 kg"}
    from_mesh = rockslide.run(case(mesh_block(tmp_path / "box.obj")), history=False).summary
    by_sizes = rockslide.run(case(sizes), history=False).summary
    assert from_mesh.max_rotation > 0.05                 # it rocks: the comparison means something
    assert from_mesh.max_rotation == pytest.approx(by_sizes.max_rotation, rel=1e-9)
    assert (from_mesh.verdict, from_mesh.impacts) == (by_sizes.verdict, by_sizes.impacts)


def test_the_orientation_is_the_direction_in_the_mesh_frame(tmp_path):
    """A box turned by 30 deg about the vertical, taken along its own width's azimuth, is the box
    along its width; along its depth's azimuth, the box across (to 1e-8 m: trimesh writes an OBJ's
    coordinates to 8 decimals, and the turned box's are not binary fractions)."""
    turned = box_obj(tmp_path / "turned.obj", turn=math.radians(30))
    # x (azimuth 90 deg) turned counter-clockwise by 30 deg points to azimuth 60 deg
    along = load_case(case(mesh_block(turned, orientation="60 deg")), base_dir=tmp_path).block
    across = load_case(case(mesh_block(turned, orientation="150 deg")), base_dir=tmp_path).block
    assert along.half_widths == pytest.approx((WIDTH / 2, WIDTH / 2), abs=1e-8)
    assert across.half_widths == pytest.approx((DEPTH / 2, DEPTH / 2), abs=1e-8)
    assert along.orientation == pytest.approx(math.radians(60))


def test_an_off_centre_mesh_and_its_second_plane(tmp_path):
    """The L prism along east has b1 = 0.075 m, b2 = 0.125 m (tests/test_mesh.py by hand); turned
    by a change of orientation (a sweep's point, the second plane) its body is derived again."""
    path = l_prism(tmp_path / "l.obj")
    body = load_case(case(mesh_block(path)), base_dir=tmp_path)
    assert body.block.half_widths == pytest.approx((0.075, 0.125), abs=TOL)
    assert body.block.asymmetric and body.block.both_planes
    west = case_with(body, {"block.orientation": "270 deg"})
    assert west.block.half_widths == pytest.approx((0.125, 0.075), abs=TOL)
    across = other_plane(body, 0.0)
    assert across.block.half_widths == pytest.approx((0.125, 0.125), abs=TOL)
    again = load_case(case_to_dict(body), base_dir=tmp_path)
    assert again.block == body.block


def test_a_mesh_case_file_runs_and_names_both_planes(tmp_path):
    """From the command line: the case file beside its mesh, the printout says the body and both
    planes, the JSON holds them."""
    l_prism(tmp_path / "l.obj")
    (tmp_path / "l.yaml").write_text(yaml.safe_dump(case(mesh_block("l.obj"))))
    result = invoke("run", tmp_path / "l.yaml", "--no-plot", "--out-dir", tmp_path, "--json")
    assert result.exit_code == 0, result.output
    import json

    data = json.loads(result.stdout)
    assert data["planes"]["depth"]["note"].startswith("one horizontal component")
    text = invoke("run", tmp_path / "l.yaml", "--no-plot", "--out-dir", tmp_path, "--overwrite")
    assert "body of l.obj along azimuth 90 deg" in text.stdout and "uncoupled screening" in text.stdout


def test_a_sweep_over_orientations_takes_each_body_from_the_mesh(tmp_path):
    """Each point of an --azimuth sweep of a mesh with two components is the run of the case turned to
    it: the body along that azimuth, under the component along it."""
    path = l_prism(tmp_path / "l.obj")
    base = load_case(case(mesh_block(path, orientation="90 deg"), **two_components(tmp_path)), base_dir=tmp_path)
    angles = (90.0, 270.0, 200.0)
    with pytest.warns(UserWarning, match="a sweep screens the width plane only"):
        sweep = rockslide.sweep(base, azimuth=[f"{a} deg" for a in angles])
    assert (sweep["max_rotation"].values > 0.01).sum() >= 2          # it rocks: the bodies decide
    for i, angle in enumerate(angles):
        run = rockslide.run(case_with(base, {"block.orientation": f"{angle} deg"}), history=False).summary
        point = sweep.isel(azimuth=i)
        assert float(point["max_rotation"]) == pytest.approx(run.max_rotation, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("extra,key,words", [
    ({"width": "0.2 m"}, "block.width", "exclusive"),
    ({"mesh_units": None}, "block.mesh_units", "length unit"),
    ({"density": None}, "block.density", "or block.mass"),
    ({"mass": "10 kg"}, "block.density", "not both"),
    ({"mesh_units": "furlong"}, "block.mesh_units", "expected one of"),
])
def test_bad_mesh_keys_are_one_line(ws, extra, key, words):
    box_obj(ws / "box.obj")
    block = {k: v for k, v in {**mesh_block("box.obj"), **extra}.items() if v is not None}
    (ws / "case.yaml").write_text(yaml.safe_dump(case(block)))
    one_line_error(invoke("run", "case.yaml"), key, words)
    assert not (ws / "out").exists()


def test_a_bad_mesh_is_one_line_naming_the_key_and_the_file(ws):
    mesh = trimesh.creation.box(extents=(0.2, 0.2, 0.5))
    mesh.update_faces(np.arange(len(mesh.faces)) != 0)            # one face gone: not closed
    mesh.export(ws / "open.obj")
    (ws / "case.yaml").write_text(yaml.safe_dump(case(mesh_block("open.obj"))))
    one_line_error(invoke("run", "case.yaml"), "block.mesh", "open.obj")
    (ws / "case.yaml").write_text(yaml.safe_dump(case(mesh_block("missing.obj"))))
    one_line_error(invoke("run", "case.yaml"), "block.mesh", "missing.obj")


def test_a_mesh_under_two_components_needs_its_orientation(tmp_path):
    box_obj(tmp_path / "box.obj")
    two = {"horizontal_1": {"file": "a.txt", "azimuth": "0 deg"},
           "horizontal_2": {"file": "b.txt", "azimuth": "90 deg"}}
    with pytest.raises(CaseError, match="block.orientation.*is needed for a mesh"):
        load_case(case(mesh_block("box.obj"), **two), base_dir=tmp_path)


def test_mesh_keys_need_a_mesh(tmp_path):
    with pytest.raises(CaseError, match="block.density.*is a mesh's"):
        load_case(case({"height": "1 m", "width": "0.2 m", "mass": "1 kg", "density": "2000 kg/m^3"}))


# --------------------------------------------------------------------------------------------------
# Ensembles over the body (issue 39.4): uncertain corners and inertia, a mesh turned per member
# --------------------------------------------------------------------------------------------------

ROCK = {"centre_of_mass_height": "0.294 m", "half_widths": ["0.044 m", "0.129 m"], "mass": "330 kg"}


def test_uncertain_corners_and_inertia_are_each_members_body():
    """Each member of an ensemble over b1, b2 and the radius of gyration runs as the case with that
    member's body (its corners and inertia the nominal ones times the member's factors)."""
    nominal = {**ROCK, "radius_of_gyration": "0.177 m"}
    rock = {**case(nominal, horizontal={"pulse": "one-sine", "amplitude": "0.25 g", "period": "0.4 s"},
                   tail="1 s"),
            "uncertain": {"b1": {"uniform": [0.8, 1.2]}, "b2": {"normal": {"mean": 1.0, "std": 0.05}},
                          "radius_of_gyration": {"uniform": [0.95, 1.05]}}}
    members = rockslide.ensemble(rock, 6)
    assert len(set(np.round(members["max_rotation"].values, 12))) > 1           # the members differ
    for i in (0, 3, 5):
        f1, f2, fk = (float(members[f"sample_{q}"][i]) for q in ("b1", "b2", "radius_of_gyration"))
        body = {**ROCK, "half_widths": [f"{0.044 * f1!r} m", f"{0.129 * f2!r} m"],
                "radius_of_gyration": f"{0.177 * fk!r} m"}
        alone = rockslide.run({**rock, "block": body, "uncertain": None}, history=False).summary
        assert float(members["max_rotation"][i]) == pytest.approx(alone.max_rotation, rel=1e-12, abs=1e-15)


def test_an_ensemble_over_orientations_turns_the_mesh_per_member(tmp_path):
    """Members of an L prism's ensemble over its orientation each run the body the mesh has along
    the member's orientation (derived again, not the nominal body turned), in both planes."""
    path = l_prism(tmp_path / "l.obj")
    base = load_case({**case(mesh_block(path, orientation="90 deg"), **two_components(tmp_path)),
                      "uncertain": {"orientation": {"uniform": ["0 deg", "360 deg"]}}}, base_dir=tmp_path)
    members = rockslide.ensemble(base, 6)
    rocking = (members["max_rotation"].values > 0.01) & ~members["overturned"].values.astype(bool)
    assert rocking.sum() >= 2                            # members that rock: their bodies decide
    for i in range(6):
        angle = float(members["sample_orientation"][i])
        alone = rockslide.run(case_with(base, {"block.orientation": angle, "uncertain": None}), history=False).planes
        worse = alone[alone["worse"]]              # each member is screened in both planes, as a run is
        assert ("width", "depth")[int(members["plane"][i])] == alone["worse"]
        assert bool(members["overturned"][i]) == worse["overturned"]
        if not worse["overturned"]:
            assert float(members["max_rotation_ratio"][i]) == pytest.approx(worse["max_rotation_ratio"], rel=1e-12,
                                                                            abs=1e-15)


def test_members_whose_corners_leave_no_room_for_their_inertia_are_left_out():
    """A radius of gyration near the largest the body can have (sqrt(max(b1, b2)^2 + h^2)): members
    drawn with a smaller b2 can no longer have it, and are left out and said (issue 43.11), counted
    here from the drawn factors."""
    h, b1, b2 = 0.294, 0.044, 0.129
    k = 0.995 * math.hypot(b2, h)
    rock = {**case({**ROCK, "radius_of_gyration": f"{k!r} m"},
                   horizontal={"pulse": "one-sine", "amplitude": "0.25 g", "period": "0.4 s"}, tail="1 s"),
            "uncertain": {"b2": {"uniform": [0.9, 1.0]}}}
    members = rockslide.ensemble(rock, 40)
    f2 = members["sample_b2"].values
    expected = k > np.hypot(np.maximum(b1, b2 * f2), h)
    assert 0 < expected.sum() < 40
    summary = __import__("json").loads(members.attrs["ensemble"])
    assert summary["n_drawn_outside"] == expected.sum()
    assert any("uncertain.b2" in reason for reason in summary["drawn_outside"])


def test_the_examples_rock_case_runs(tmp_path):
    """``rockslide example`` writes rock.yaml beside rock.obj: the body is the rock of
    docs/asymmetric.md (its OBJ written to 6 digits: 1e-6 m), and it runs as written."""
    assert invoke("example", tmp_path / "ex").exit_code == 0
    block = load_case(tmp_path / "ex" / "rock.yaml").block
    assert block.half_widths == pytest.approx((0.044, 0.129), abs=1e-6)
    assert block.centre_of_mass_height == pytest.approx(0.294, abs=1e-6)
    result = invoke("run", tmp_path / "ex" / "rock.yaml", "--no-plot", "--out-dir", tmp_path)
    assert result.exit_code == 0, result.output
    assert "body of rock.obj along azimuth 90 deg" in result.stdout


def test_a_run_of_a_body_draws_its_planes(tmp_path):
    """``rockslide run`` of a mesh's case also writes NAME.body.png (its silhouette in both planes,
    with both tipping angles); a rectangle's run does not, and a run without figures removes one
    left from before."""
    l_prism(tmp_path / "l.obj")
    (tmp_path / "l.yaml").write_text(yaml.safe_dump(case(mesh_block("l.obj"))))
    result = invoke("run", tmp_path / "l.yaml", "--out-dir", tmp_path)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "body.body.png").stat().st_size > 10_000 and "body.body.png" in result.stdout
    again = invoke("run", tmp_path / "l.yaml", "--out-dir", tmp_path, "--overwrite", "--no-plot")
    assert again.exit_code == 0 and not (tmp_path / "body.body.png").exists()
    (tmp_path / "r.yaml").write_text(yaml.safe_dump({**case({"height": "1 m", "width": "0.3 m", "mass": "1 kg"}),
                                                     "name": "plain"}))
    assert invoke("run", tmp_path / "r.yaml", "--out-dir", tmp_path).exit_code == 0
    assert not (tmp_path / "plain.body.png").exists()
