"""A scanned body as planar bodies (rockslide/mesh.py; model-asymmetric.md section 9).

What these tests protect: a box mesh in each format gives the box's planar bodies (closed forms,
1e-10 where the file keeps the coordinates exactly); an off-centre body gives the b1, b2, h and k2
computed by hand, and its mirror image swaps b1 and b2 (pivot 1 on the -u side: model.md eq. 7);
turning a mesh about the vertical turns the azimuth; a mesh placed tilted rests on the hull facet
under its centre of mass; units; the rock of model-asymmetric.md section 1 from a mesh made to have
it; and every bad mesh is one line naming its file.

Tolerances: 1e-10 [m, m^2] on bodies of 0.1-1 m, where the divergence-theorem sums and the rotation
to rest round at 1e-16 relative; coordinates written to files are binary fractions (exact in float32
STL/PLY) or OBJ's decimals of the model-asymmetric numbers (exact to the digits written).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from rockslide import mesh as meshio
from rockslide.errors import CaseError, OutputError
from rockslide.mesh import SCREENING_NOTE, box_bodies, describe, planar_bodies, planar_body, read_mesh

TOL = 1e-10
EAST, NORTH, SOUTH, WEST = math.pi / 2, 0.0, math.pi, 1.5 * math.pi


def prism(profile, depth):
    """A closed prism: ``profile`` (x, z), star-shaped from its first vertex, extruded along y over
    ``[-depth/2, depth/2]``; faces outward."""
    p = np.asarray(profile, dtype=float)
    n = len(p)
    front = np.column_stack([p[:, 0], np.full(n, -depth / 2), p[:, 1]])
    back = front * [1.0, -1.0, 1.0]
    faces = []
    for i in range(1, n - 1):
        faces += [[0, i + 1, i], [n, n + i, n + i + 1]]
    for i in range(n):
        j = (i + 1) % n
        faces += [[i, j, n + j], [i, n + j, n + i]]
    mesh = trimesh.Trimesh(np.vstack([front, back]), faces, process=True)
    if mesh.volume < 0:
        mesh.invert()
    assert mesh.is_watertight and mesh.volume > 0
    return mesh


def box(width, depth, height):
    """A box of ``width`` along x (east), ``depth`` along y, standing on z = 0."""
    mesh = trimesh.creation.box(extents=(width, depth, height))
    mesh.apply_translation((0.0, 0.0, height / 2))
    return mesh


def written(mesh, path, **kwargs):
    mesh.export(path, **kwargs)
    return path


def _same(a, b, tol=TOL):
    for name in ("b1", "b2", "h", "k2", "volume"):
        assert getattr(a, name) == pytest.approx(getattr(b, name), abs=tol), name
    pa, pb = np.array(a.support), np.array(b.support)
    assert pa.shape == pb.shape
    assert np.max(np.min(np.linalg.norm(pa[:, None] - pb[None], axis=-1), axis=1)) < tol


# L-shaped profile: [0, 0.2] x [0, 0.1] (the foot) and [0, 0.1] x [0.1, 0.3] (the stem), areas 0.02 each.
# Centroid x = (0.1 + 0.05)/2 = 0.075, z = (0.05 + 0.2)/2 = 0.125. About the y axis through it, per unit
# mass: each rectangle's (a^2 + c^2)/12 = 0.05/12 plus its offset^2 = 0.025^2 + 0.075^2 = 0.00625.
L_PROFILE = [(0.1, 0.1), (0.1, 0.3), (0.0, 0.3), (0.0, 0.0), (0.2, 0.0), (0.2, 0.1)]
L_DEPTH = 0.25
L_B1, L_B2, L_H = 0.075, 0.125, 0.125
L_K2 = 0.05 / 12 + 0.00625
# about the x axis (u along y): depth^2/12 plus the z variance: mean of 0.1^2/12 + 0.075^2 and 0.2^2/12 + 0.075^2
L_K2_ACROSS = L_DEPTH**2 / 12 + 0.5 * (0.01 / 12 + 0.04 / 12) + 0.075**2


# --------------------------------------------------------------------------------------------------
# A box: mesh and sides agree
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name,kwargs", [("box.obj", {}), ("box.stl", {}), ("ascii.stl", {"file_type": "stl_ascii"}),
                                         ("box.ply", {}), ("ascii.ply", {"encoding": "ascii"})])
def test_box_mesh_is_the_box(tmp_path, name, kwargs):
    width, depth, height = 0.5, 0.25, 0.75        # binary fractions: exact in every format
    path = written(box(width, depth, height), tmp_path / name, **kwargs)
    bodies = planar_bodies(read_mesh(path, units="m"), azimuth=EAST, mass=120.0)
    along, across = bodies
    b, h = width / 2, height / 2
    assert (along.b1, along.b2, along.h) == pytest.approx((b, b, h), abs=TOL)
    assert along.k2 == pytest.approx((b * b + h * h) / 3, abs=TOL)
    assert (across.b1, across.b2) == pytest.approx((depth / 2, depth / 2), abs=TOL)
    assert across.k2 == pytest.approx(((depth / 2) ** 2 + h * h) / 3, abs=TOL)
    assert across.azimuth == pytest.approx(SOUTH)
    assert along.tilt == 0.0 and along.mass == 120.0 and along.faces == 12
    assert along.centre_of_mass == pytest.approx((0.0, 0.0, h), abs=TOL)
    for mesh_body, box_body in zip(bodies, box_bodies(width, depth, height, 120.0, EAST), strict=True):
        _same(mesh_body, box_body)
        assert mesh_body.azimuth == box_body.azimuth


def test_box_bodies_closed_forms():
    along, across = box_bodies(0.3, 0.2, 1.2, 80.0, math.radians(30))
    assert (along.b1, along.b2, along.h, along.azimuth) == (0.15, 0.15, 0.6, math.radians(30))
    assert along.k2 == pytest.approx((0.15**2 + 0.6**2) / 3, rel=1e-15)
    assert across.b1 == 0.1 and across.azimuth == pytest.approx(math.radians(120))
    assert along.inertia == pytest.approx(80.0 * (0.3**2 + 1.2**2) / 12, rel=1e-14)
    assert along.tan_alpha1 == pytest.approx(0.25, rel=1e-15)
    with pytest.raises(CaseError, match="depth"):
        box_bodies(0.3, -0.2, 1.2, 80.0, 0.0)


# --------------------------------------------------------------------------------------------------
# Off-centre bodies: hand numbers, the mirror, turning about the vertical
# --------------------------------------------------------------------------------------------------


def test_l_shape_by_hand():
    along, across = planar_bodies(prism(L_PROFILE, L_DEPTH), azimuth=EAST, density=2000.0)
    # u = +x: the foot reaches 0.125 m toward +x (pivot 2), the back 0.075 m toward -x (pivot 1)
    assert (along.b1, along.b2, along.h, along.k2) == pytest.approx((L_B1, L_B2, L_H, L_K2), abs=TOL)
    assert along.volume == pytest.approx(0.04 * L_DEPTH, abs=TOL)
    assert along.mass == pytest.approx(2000.0 * 0.04 * L_DEPTH, rel=1e-12)
    assert (across.b1, across.b2, across.k2) == pytest.approx((L_DEPTH / 2, L_DEPTH / 2, L_K2_ACROSS), abs=TOL)
    # seen from the other side (u = -x) the pivots change places
    west = planar_body(prism(L_PROFILE, L_DEPTH), azimuth=WEST)
    assert (west.b1, west.b2) == pytest.approx((L_B2, L_B1), abs=TOL)
    assert west.mass is None


def test_mirror_swaps_the_pivots():
    mesh = prism(L_PROFILE, L_DEPTH)
    mirror = mesh.copy()
    mirror.apply_transform(np.diag([-1.0, 1.0, 1.0, 1.0]))     # x -> -x (trimesh keeps the faces outward)
    original = planar_body(mesh, azimuth=EAST)
    mirrored = planar_body(mirror, azimuth=EAST)
    assert (mirrored.b1, mirrored.b2) == pytest.approx((original.b2, original.b1), abs=TOL)
    assert (mirrored.h, mirrored.k2) == pytest.approx((original.h, original.k2), abs=TOL)


@pytest.mark.parametrize("angle", [0.37, 2.0, -1.1])
def test_turning_about_the_vertical_turns_the_azimuth(angle):
    mesh = prism(L_PROFILE, L_DEPTH)
    turned = mesh.copy()
    turned.apply_transform(trimesh.transformations.rotation_matrix(angle, (0, 0, 1)))
    # turning by +angle (counter-clockwise seen from above) takes azimuth a (clockwise) to a - angle
    for azimuth in (EAST, 0.3):
        for a, b in zip(planar_bodies(mesh, azimuth=azimuth), planar_bodies(turned, azimuth=azimuth - angle),
                        strict=True):
            _same(a, b)


def test_tilted_box_rests_on_the_face_under_its_centre_of_mass():
    mesh = box(0.4, 0.3, 0.5)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.radians(30), (1, 0, 0)))
    # the vertical from the centre leaves the base 0.25/cos 30 = 0.289 m down, the side 0.15/cos 60 = 0.3 m
    along_x, along_y = planar_bodies(mesh, azimuth=EAST)
    assert along_x.tilt == pytest.approx(math.radians(30), abs=1e-12)
    assert (along_x.b1, along_x.b2, along_x.h) == pytest.approx((0.2, 0.2, 0.25), abs=TOL)
    assert (along_y.b1, along_y.b2) == pytest.approx((0.15, 0.15), abs=TOL)
    assert along_x.k2 == pytest.approx((0.2**2 + 0.25**2) / 3, abs=TOL)
    # a slender box tilted 30 deg: the vertical leaves through the side (0.05/cos 60 < 0.5/cos 30): it lies down
    slender = box(0.2, 0.1, 1.0)
    slender.apply_transform(trimesh.transformations.rotation_matrix(math.radians(30), (1, 0, 0)))
    lying = planar_body(slender, azimuth=NORTH)
    assert lying.tilt == pytest.approx(math.radians(60), abs=1e-12)
    assert (lying.h, lying.b1, lying.b2) == pytest.approx((0.05, 0.5, 0.5), abs=TOL)


def test_units(tmp_path):
    metres = prism(L_PROFILE, L_DEPTH)
    millimetres = metres.copy()
    millimetres.apply_scale(1000.0)
    a = planar_body(read_mesh(written(metres, tmp_path / "m.obj"), units="m"), azimuth=EAST)
    b = planar_body(read_mesh(written(millimetres, tmp_path / "mm.obj"), units="mm"), azimuth=EAST)
    _same(a, b, tol=1e-12)
    assert (b.b1, b.b2, b.h) == pytest.approx((L_B1, L_B2, L_H), abs=TOL)
    inches = planar_body(read_mesh(tmp_path / "m.obj", units="in"), azimuth=EAST)
    assert inches.h == pytest.approx(L_H * 0.0254, abs=TOL)


def test_rock_of_the_contract(tmp_path):
    """model-asymmetric.md section 1: b1 = 0.044, b2 = 0.129, h = 0.294 m, from a leaning parallelogram
    prism (base [0, 0.173] at z = 0, top shifted by s = 2 b1 - (b1 + b2) at z = 2h: centroid over x = b1)."""
    b1, b2, h = 0.044, 0.129, 0.294
    base, shift = b1 + b2, 2 * b1 - (b1 + b2)
    mesh = prism([(0.0, 0.0), (base, 0.0), (base + shift, 2 * h), (shift, 2 * h)], 0.12)
    body = planar_body(read_mesh(written(mesh, tmp_path / "rock.obj"), units="m"), azimuth=EAST, density=2650.0)
    assert (body.b1, body.b2, body.h) == pytest.approx((b1, b2, h), abs=1e-9)
    assert (body.tan_alpha1, body.tan_alpha2) == pytest.approx((0.1496598639, 0.4387755102), abs=1e-9)
    # a parallelogram's k2 = (base^2 + shift^2 + (2h)^2)/12, not the rectangle's default
    assert body.k2 == pytest.approx((base**2 + shift**2 + (2 * h) ** 2) / 12, abs=1e-9)
    assert body.half_widths == (body.b1, body.b2)


def test_describe_and_figure(tmp_path):
    from rockslide.plots import body_figure, save_figure

    mesh = read_mesh(written(prism(L_PROFILE, L_DEPTH), tmp_path / "statue.stl"), units="m")
    bodies = planar_bodies(mesh, azimuth=EAST, mass=50.0)
    lines = describe(bodies)
    text = "\n".join(lines)
    assert lines[0].startswith(str(tmp_path / "statue.stl"))
    assert "b1 = 0.075 m (pivot 1, the 270 deg side), b2 = 0.125 m" in text
    assert "from 0.6 g" in text and "from 1 g" in text        # b1/h = 0.6, b2/h = 1
    assert lines[-1] == SCREENING_NOTE
    assert describe(box_bodies(0.5, 0.25, 0.75, None, 0.0))[-1] == SCREENING_NOTE
    fig = body_figure(bodies)
    assert len(fig.axes) == 2 and "statue.stl" in fig._suptitle.get_text()
    assert save_figure(fig, tmp_path / "statue.png").stat().st_size > 10_000


def test_inside_out_mesh_is_turned(tmp_path):
    mesh = box(0.5, 0.25, 0.75)
    mesh.invert()
    read = read_mesh(written(mesh, tmp_path / "inside-out.ply"), units="m")
    body = planar_body(read, azimuth=EAST)
    assert body.volume == pytest.approx(0.5 * 0.25 * 0.75, abs=TOL) and body.b1 == pytest.approx(0.25, abs=TOL)
    assert any("turned outward" in note for note in body.notes)


# --------------------------------------------------------------------------------------------------
# Bad meshes: one line naming the file
# --------------------------------------------------------------------------------------------------


def _one_line(excinfo, path, *words):
    text = str(excinfo.value)
    assert "\n" not in text and str(path) in text, text
    for word in words:
        assert word in text, text


def test_not_closed(tmp_path):
    mesh = box(0.5, 0.25, 0.75)
    mesh.update_faces(np.arange(len(mesh.faces)) != 3)
    path = written(mesh, tmp_path / "open.obj")
    with pytest.raises(CaseError) as excinfo:
        read_mesh(path, units="m")
    _one_line(excinfo, path, "not closed", "3 edges")   # the hole of one triangle


def test_no_volume(tmp_path):
    flat = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0]],
                           [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]], process=False)
    path = written(flat, tmp_path / "flat.ply", encoding="ascii")
    with pytest.raises(CaseError) as excinfo:
        read_mesh(path, units="m")
    _one_line(excinfo, path, "no volume")


def test_centre_of_mass_outside_its_support(tmp_path):
    # a convex body whose vertical through the centre of mass crosses a steep hull facet (73 deg) far
    # below the centre of mass: turned onto that facet, the centre of mass is beyond it
    leaning = prism([(0, 0), (0.02, 0), (0.1, 1), (0.1, 2), (-0.3, 2), (-0.3, 1)], 0.2)
    path = written(leaning, tmp_path / "leaning.obj")
    with pytest.raises(CaseError) as excinfo:
        planar_body(read_mesh(path, units="m"), azimuth=EAST)
    _one_line(excinfo, path, "would not stand")


def test_degenerate_support(tmp_path):
    # a tetrahedron on a sliver: its base is 0.1 mm wide, under the 0.5 mm contact tolerance
    sliver = trimesh.Trimesh([[-0.2, 0, 0], [0.2, 0, 0], [0, 1e-4, 0], [0, 0, 0.3]],
                             [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]], process=False)
    sliver.fix_normals()
    path = written(sliver, tmp_path / "sliver.stl")
    mesh = read_mesh(path, units="m")
    with pytest.raises(CaseError) as excinfo:
        planar_body(mesh, azimuth=EAST)
    _one_line(excinfo, path, "a line", "contact tolerance")
    assert planar_body(mesh, azimuth=EAST, contact_tolerance=5e-5).b1 > 0   # a finer tolerance: it stands


@pytest.mark.parametrize("units,words", [(None, "needs its length unit"), ("", "needs its length unit"),
                                         ("furlong", "unknown length unit 'furlong'")])
def test_units_missing_or_unknown(tmp_path, units, words):
    path = written(box(0.5, 0.25, 0.75), tmp_path / "box.obj")
    with pytest.raises(CaseError) as excinfo:
        read_mesh(path, units=units)
    _one_line(excinfo, path, words)


@pytest.mark.parametrize("name", ["box.obj", "box.stl", "box.ply"])
def test_too_many_faces_before_parsing(tmp_path, monkeypatch, name):
    path = written(box(0.5, 0.25, 0.75), tmp_path / name)
    monkeypatch.setattr(meshio, "MAX_MESH_FACES", 11)
    with pytest.raises(CaseError) as excinfo:
        read_mesh(path, units="m")
    _one_line(excinfo, path, "12 faces", "at most 11")


def test_too_large(tmp_path, monkeypatch):
    path = written(box(0.5, 0.25, 0.75), tmp_path / "box.stl")
    monkeypatch.setattr(meshio, "MAX_MESH_BYTES", 500)
    with pytest.raises(CaseError) as excinfo:
        read_mesh(path, units="m")
    _one_line(excinfo, path, "684 bytes", "at most 500")
    # a PLY header that declares a billion faces is refused before a byte of them is parsed
    huge = tmp_path / "huge.ply"
    huge.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     b"property float z\nelement face 1000000000\nproperty list uchar int vertex_indices\n"
                     b"end_header\n" + bytes(36))
    with pytest.raises(CaseError) as excinfo:
        read_mesh(huge, units="m")
    _one_line(excinfo, huge, "1000000000 faces")


@pytest.mark.parametrize("name,content,words", [
    ("noise.stl", bytes(range(256)) * 3, "not an STL file"),
    ("noise.ply", b"\x00\x01garbage" * 40, "not a PLY file"),
    ("words.obj", b"hello world\nthis is not a mesh\n", "holds no triangles"),
    ("cut.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                b"property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n" + bytes(20),
     "cannot read the mesh file as PLY"),
])
def test_garbage(tmp_path, name, content, words):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(OutputError) as excinfo:
        read_mesh(path, units="m")
    _one_line(excinfo, path, words)


def test_missing_file_folder_and_format(tmp_path):
    (tmp_path / "folder.obj").mkdir()
    (tmp_path / "scan.3ds").write_bytes(b"x")
    for path, words in ((tmp_path / "none.obj", "not found"), (tmp_path / "folder.obj", "is a folder"),
                        (tmp_path / "scan.3ds", "unknown mesh format '.3ds'")):
        with pytest.raises(CaseError) as excinfo:
            read_mesh(path, units="m")
        _one_line(excinfo, path, words)


def test_density_and_mass_are_checked():
    mesh = prism(L_PROFILE, L_DEPTH)
    with pytest.raises(CaseError, match="not both"):
        planar_body(mesh, azimuth=EAST, density=2000.0, mass=10.0)
    with pytest.raises(CaseError, match="density must be positive"):
        planar_body(mesh, azimuth=EAST, density=-1.0)
    with pytest.raises(CaseError, match="contact_tolerance"):
        planar_body(mesh, azimuth=EAST, contact_tolerance=0.0)


def test_the_meshes_page_runs(tmp_path, monkeypatch, capsys):
    """docs/meshes.md's example runs as written and prints the text the page shows after it."""
    import re

    from conftest import REPO

    page = (REPO / "docs" / "meshes.md").read_text()
    code = re.findall(r"```python\n(.*?)```", page, flags=re.S)
    shown = re.findall(r"```text\n(.*?)```", page, flags=re.S)
    assert len(code) == 1 and len(shown) == 1
    monkeypatch.chdir(tmp_path)
    exec(compile(code[0], "docs/meshes.md", "exec"), {})          # noqa: S102 - the page's own example
    assert capsys.readouterr().out == shown[0]
    assert (tmp_path / "rock.png").stat().st_size > 10_000
