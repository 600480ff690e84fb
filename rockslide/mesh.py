"""Scanned bodies: a closed triangle mesh (OBJ, STL, PLY) as planar bodies (model-asymmetric.md section 9).

A rock or a statue scanned as a closed mesh gives, for a horizontal shaking direction ``u``, the
planar body of the asymmetric model: the corner distances ``b1``, ``b2`` from the vertical through
the centre of mass (CM), the CM's height ``h`` above the resting plane and the radius of gyration
about the horizontal axis through the CM perpendicular to ``u`` (``k2 = I_cm / M``).

Conventions (docs/meshes.md):

- **Mesh frame.** ``+x`` is east, ``+y`` north, ``+z`` up, as a scan exported with ``z`` up. An
  azimuth is measured clockwise from north (``+y``), as ``block.orientation`` and the components'
  azimuths (docs/two-components.md): ``u = (sin az, cos az, 0)``; 90 deg is ``+x``.
- **Resting.** The body rests on the facet of its convex hull that the vertical through the CM
  crosses below the CM (section 9, rule 2), turned by the smallest rotation that makes that facet
  horizontal (about a horizontal axis; ``tilt`` is its angle). Azimuths are those of the mesh frame
  after that rotation; a mesh standing on its base is not turned.
- **Pivots.** A positive ground acceleration along ``u`` (``ah > 0``, the ground accelerating toward
  ``u``) pushes the body toward ``-u`` and tips it over the corner on the ``-u`` side: that is pivot 1
  (model.md eq. 7: ``ah > 0`` tips the block over its left corner, ``lam = +1``, with ``u`` pointing
  right). So ``b1`` is the distance from the CM's projection to the support polygon's boundary along
  ``-u``, ``b2`` along ``+u``; mirroring the mesh across the vertical plane through ``u``'s normal
  swaps them.
- **The other axis** is ``u`` turned 90 deg clockwise (azimuth + 90 deg), as a box's depth is to its
  width; `planar_bodies` gives both.

The planar body is an uncoupled screening: it ignores rocking about the other edges of the support
polygon and every 3-D coupling (`SCREENING_NOTE`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import CaseError, OutputError, exception_text
from .inputs import open_regular

__all__ = ["read_mesh", "PlanarBody", "planar_body", "planar_bodies", "box_bodies", "describe", "body_of_file",
           "rectangle_k2",
           "MESH_FORMATS", "MESH_LENGTH_UNITS", "MAX_MESH_BYTES", "MAX_MESH_FACES", "CONTACT_TOLERANCE",
           "SCREENING_NOTE"]

#: The formats read, by file suffix (lower case).
MESH_FORMATS = {".obj": "obj", ".stl": "stl", ".ply": "ply"}
#: Length units of a mesh's coordinates and their size [m].
MESH_LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254, "ft": 0.3048}
#: The largest mesh file read [bytes]: a binary STL of `MAX_MESH_FACES` faces is 100 MB.
MAX_MESH_BYTES = 256 * 2**20
#: The most triangles (and vertices) a mesh may have; counted from the file's header or lines before
#: it is parsed, so that a huge file is one line, not an out-of-memory.
MAX_MESH_FACES = 2_000_000
#: The default contact tolerance [m]: the vertices within it of the resting plane carry the body.
CONTACT_TOLERANCE = 5e-4
#: What every printout of a planar body says.
SCREENING_NOTE = ("The planar body is an uncoupled screening: it ignores rocking about the other edges "
                  "of the support polygon and any 3-D coupling.")


def read_mesh(path, *, units: str):
    """Read a closed triangle mesh from an OBJ, STL (ASCII or binary) or PLY file, in metres.

    Parameters
    ----------
    path : str or Path
        The file; its suffix names the format (`MESH_FORMATS`).
    units : str
        The length unit of the file's coordinates (`MESH_LENGTH_UNITS`: ``"m"``, ``"cm"``, ``"mm"``,
        ``"in"``, ``"ft"``). Required: mesh files do not say it, and scans come in m and mm alike.

    Returns
    -------
    trimesh.Trimesh
        Coordinates [m], duplicate vertices merged, faces turned outward when the file had them
        inward or mixed (a closed mesh's winding can be made consistent safely; what was done is in
        ``mesh.metadata["rockslide_notes"]``). ``mesh.metadata["rockslide_source"]`` is the file name.

    Raises
    ------
    CaseError
        Units missing or unknown, an unknown suffix, more than `MAX_MESH_BYTES` bytes or
        `MAX_MESH_FACES` faces or vertices, a mesh that is not closed or encloses no volume.
    OutputError
        The file is missing, not a regular file, unreadable, or not a mesh of its format.
    """
    source = str(path)
    factor = _length_factor(units, source)
    fmt = MESH_FORMATS.get(Path(source).suffix.lower())
    if fmt is None:
        raise CaseError(f"unknown mesh format {Path(source).suffix or '(no suffix)'!r}; expected one of "
                        f"{', '.join(MESH_FORMATS)}", source=source)
    with open_regular(path, what="mesh file", error=CaseError, limit=MAX_MESH_BYTES,
                      bound_text=" (a binary STL of 2 million faces is 100 MB: simplify the scan)") as handle:
        data = handle.read(MAX_MESH_BYTES + 1)
    _check_counts(data, fmt, source)
    trimesh = _trimesh()
    import io

    try:
        loaded = trimesh.load(io.BytesIO(data), file_type=fmt, force="mesh", process=False)
        faces = np.asarray(loaded.faces, dtype=np.int64)
        vertices = np.asarray(loaded.vertices, dtype=float)
    except Exception as exc:        # a parser's own error: garbage or a truncated file
        raise OutputError(f"cannot read the mesh file as {fmt.upper()}: {exception_text(exc)}",
                          source=source) from None
    if faces.ndim != 2 or faces.shape[0] == 0 or faces.shape[1] != 3:
        raise OutputError(f"cannot read the mesh file as {fmt.upper()}: it holds no triangles", source=source)
    if faces.shape[0] > MAX_MESH_FACES or vertices.shape[0] > MAX_MESH_FACES:
        raise CaseError(f"the mesh has {faces.shape[0]} triangles and {vertices.shape[0]} vertices; rockslide "
                        f"reads at most {MAX_MESH_FACES} of each (simplify the scan)", source=source)
    if not np.isfinite(vertices).all():
        raise OutputError("the mesh file has coordinates that are not finite numbers", source=source)
    mesh = trimesh.Trimesh(vertices=vertices * factor, faces=faces, process=True)
    mesh.metadata["rockslide_source"] = source
    mesh.metadata["rockslide_notes"] = []
    _solid(mesh)
    return mesh


@dataclass(frozen=True)
class PlanarBody:
    """A body's planar model for one horizontal direction (model-asymmetric.md sections 1 and 9).

    Attributes
    ----------
    azimuth : float
        The direction ``u`` of the ground acceleration [rad], clockwise from north (``+y``).
    b1, b2 : float
        Distances [m] from the vertical through the CM to pivot 1 (on the ``-u`` side: ``ah > 0``
        along ``u`` tips the body over it, ``lam = +1``) and to pivot 2 (the ``+u`` side).
    h : float
        Height of the CM above the resting plane [m].
    k2 : float
        ``I_cm / M`` [m^2], about the horizontal axis through the CM perpendicular to ``u``.
    mass : float or None
        [kg], given or density x volume; None when neither was given.
    volume : float
        [m^3].
    centre_of_mass : tuple of 3 floats
        [m], in the mesh frame (as read, before the body was turned to rest).
    support : tuple of (s, t) pairs
        The support polygon's vertices [m], counter-clockwise, from the CM's projection: ``s`` along
        ``u``, ``t`` along the other horizontal axis (azimuth + 90 deg).
    tilt : float
        The angle [rad] the mesh was turned to rest on its facet (0 for a mesh on its base).
    contact_tolerance : float
        [m] (`CONTACT_TOLERANCE`).
    plane : str
        Which plane this is, in words (``"azimuth 90 deg"``, ``"width"``, ``"depth"``, or ``"shaking"``:
        the one direction of a body under one horizontal component).
    source : str or None
        The mesh file, for messages and captions.
    notes : tuple of str
        What was done to the mesh on reading (faces turned outward).
    faces : int
        The mesh's triangle count (0 for a box given by its sides).
    outline : ndarray, shape (n, 3, 2)
        The mesh's triangles that face the viewer, projected on the vertical plane of ``u``:
        ``(s, z)`` [m] with ``z`` the height above the resting plane; their union is the silhouette
        (`plots.body_figure`). Not compared.
    """

    azimuth: float
    b1: float
    b2: float
    h: float
    k2: float
    mass: float | None
    volume: float
    centre_of_mass: tuple[float, float, float]
    support: tuple[tuple[float, float], ...]
    tilt: float = 0.0
    contact_tolerance: float = CONTACT_TOLERANCE
    plane: str = ""
    source: str | None = None
    notes: tuple[str, ...] = ()
    faces: int = 0
    outline: np.ndarray = field(default=None, repr=False, compare=False)

    @property
    def radius_of_gyration(self) -> float:
        """``sqrt(k2)`` [m]."""
        return math.sqrt(self.k2)

    @property
    def inertia(self) -> float | None:
        """``I_cm = M k2`` [kg m^2], None without a mass."""
        return None if self.mass is None else self.mass * self.k2

    @property
    def tan_alpha1(self) -> float:
        """``b1 / h``: the static tipping ratio ``ah/G`` over pivot 1 (``ah > 0``)."""
        return self.b1 / self.h

    @property
    def tan_alpha2(self) -> float:
        """``b2 / h``: the static tipping ratio ``-ah/G`` over pivot 2 (``ah < 0``)."""
        return self.b2 / self.h

    @property
    def half_widths(self) -> tuple[float, float]:
        """``(b1, b2)`` [m], as the case key ``block.half_widths``."""
        return (self.b1, self.b2)


def planar_body(mesh, *, azimuth: float, density: float | None = None, mass: float | None = None,
                contact_tolerance: float = CONTACT_TOLERANCE) -> PlanarBody:
    """The planar body of a closed mesh for ground motion along ``azimuth`` (model-asymmetric.md §9).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        A closed mesh [m] (`read_mesh`), in the mesh frame (x east, y north, z up). A mesh whose faces
        point inward is turned outward in place (as `read_mesh` does).
    azimuth : float
        The direction ``u`` [rad], clockwise from north (``+y``).
    density : float, optional
        [kg/m^3]; the mass is ``density * volume``.
    mass : float, optional
        [kg], instead of a density. Neither: ``mass`` is None (the planar body's motion does not depend
        on it).
    contact_tolerance : float
        [m]: the vertices within it of the resting plane make the support polygon (default 0.5 mm).

    Returns
    -------
    PlanarBody

    Raises
    ------
    CaseError
        Naming the mesh's file: a mesh not closed or without volume, a support polygon that is a
        point or a line, a centre of mass outside its support, a bad density, mass or tolerance.
    """
    return planar_bodies(mesh, azimuth=azimuth, density=density, mass=mass,
                         contact_tolerance=contact_tolerance)[0]


def planar_bodies(mesh, *, azimuth: float, density: float | None = None, mass: float | None = None,
                  contact_tolerance: float = CONTACT_TOLERANCE) -> tuple[PlanarBody, PlanarBody]:
    """The planar bodies of a closed mesh along ``azimuth`` and along ``azimuth + 90 deg``: the two
    planes of the screening in both planes (model-asymmetric.md section 9). Parameters and errors as
    `planar_body`."""
    source = _source(mesh)
    azimuth = _finite(azimuth, "azimuth", source)
    tolerance = _finite(contact_tolerance, "contact_tolerance", source)
    if tolerance <= 0.0:
        raise CaseError(f"contact_tolerance must be positive [m], got {tolerance!r}", source=source)
    rest = _resting(mesh, tolerance, source)
    body_mass = _mass(density, mass, rest["volume"], source)
    return tuple(_along(rest, az, body_mass, tolerance, source, mesh) for az in (azimuth, azimuth + 0.5 * math.pi))


#: Meshes read by `body_of_file`, by file (path, size, modification time) and unit: a sweep over
#: orientations or a case changed key by key reads and measures its mesh once.
_RESTING_CACHE: dict = {}
#: The most meshes `_RESTING_CACHE` keeps (the oldest is dropped).
_RESTING_CACHE_SIZE = 4


def body_of_file(path, *, units: str, azimuth: float, density: float | None = None,
                 mass: float | None = None) -> PlanarBody:
    """The planar body along ``azimuth`` of the mesh in file ``path``: `read_mesh` then `planar_body`,
    the mesh read and rested once per file and unit (a case's ``block.mesh``, `case.Block`).

    Parameters
    ----------
    path : str or Path
        The mesh file (OBJ, STL, PLY).
    units : str
        Its length unit (`MESH_LENGTH_UNITS`).
    azimuth : float
        The shaking direction [rad], clockwise from north, in the mesh frame.
    density, mass : float, optional
        [kg/m^3] or [kg], as `planar_body`.

    Raises
    ------
    CaseError, OutputError
        As `read_mesh` and `planar_body`, naming the file.
    """
    source = str(path)
    try:
        stat = Path(path).stat()
        key = (str(Path(path).resolve()), stat.st_size, stat.st_mtime_ns, str(units))
    except OSError:                     # missing or unreadable: `read_mesh` says which, naming the file
        key = None
    cached = _RESTING_CACHE.get(key) if key is not None else None
    if cached is None:
        mesh = read_mesh(path, units=units)
        cached = (mesh, _resting(mesh, CONTACT_TOLERANCE, source))
        if key is not None:
            while len(_RESTING_CACHE) >= _RESTING_CACHE_SIZE:
                _RESTING_CACHE.pop(next(iter(_RESTING_CACHE)))
            _RESTING_CACHE[key] = cached
    mesh, rest = cached
    azimuth = _finite(azimuth, "azimuth", source)
    return _along(rest, azimuth, _mass(density, mass, rest["volume"], source), CONTACT_TOLERANCE, source, mesh)


def rectangle_k2(b1, b2, h):
    """``I_cm / M`` [m^2] of the uniform rectangle with corners ``b1``, ``b2`` from the vertical
    through its centre of mass, ``h`` below it: ``(bm^2 + h^2) / 3``, ``bm = (b1 + b2) / 2``
    (model-asymmetric.md section 1: the default inertia). Floats or numpy arrays. The numerical core
    has its own (`core.simulate.Model.k2`), which it may not import from here."""
    bm = 0.5 * (b1 + b2)
    return (bm * bm + h * h) / 3.0


def box_bodies(width: float, depth: float, height: float, mass: float | None, orientation: float
               ) -> tuple[PlanarBody, PlanarBody]:
    """A box's two planar bodies: along its width (azimuth ``orientation``, ``b1 = b2 = width/2``) and
    along its depth (``orientation + 90 deg``, ``depth/2``), ``h = height/2``, ``k2`` the box's about
    each axis (``(b^2 + h^2)/3``). The same numbers as the box's mesh (tests/test_mesh.py).

    Parameters
    ----------
    width, depth, height : float
        [m]; ``block.width``, the depth along the rocking axis, ``block.height``.
    mass : float or None
        [kg].
    orientation : float
        The azimuth of the width [rad], clockwise from north (``block.orientation``).
    """
    orientation = _finite(orientation, "orientation", None)
    if mass is not None and not _finite(mass, "mass", None) > 0.0:
        raise CaseError(f"the box's mass must be positive [kg], got {mass!r}", field="mass")
    sides = {"width": width, "depth": depth, "height": height}
    for name, value in sides.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise CaseError(f"the box's {name} must be a positive length [m], got {value!r}", field=name)
    h = 0.5 * height
    bodies = []
    for plane, az, along, across in (("width", orientation, width, depth),
                                     ("depth", orientation + 0.5 * math.pi, depth, width)):
        b = 0.5 * along
        t = 0.5 * across
        support = ((b, -t), (b, t), (-b, t), (-b, -t))
        outline = np.array([[[-b, 0.0], [b, 0.0], [b, height]], [[-b, 0.0], [b, height], [-b, height]]])
        bodies.append(PlanarBody(azimuth=az, b1=b, b2=b, h=h, k2=rectangle_k2(b, b, h), mass=mass,
                                 volume=width * depth * height, centre_of_mass=(0.0, 0.0, h), support=support,
                                 plane=plane, outline=outline))
    return tuple(bodies)


def describe(bodies) -> list[str]:
    """Lines of text on one body or on the bodies of `planar_bodies` (``rockslide info rock.obj``):
    volume, mass, centre of mass, support polygon, and per plane ``b1``, ``b2``, ``h``, the inertia
    and the static tipping accelerations [g] in each direction, then `SCREENING_NOTE`."""
    if isinstance(bodies, PlanarBody):
        bodies = (bodies,)
    first = bodies[0]
    lines = []
    what = f"a closed mesh of {first.faces} triangles" if first.faces else "a box"
    lines.append(f"{first.source + ': ' if first.source else ''}{what}, volume {first.volume:.4g} m^3, "
                 + (f"mass {first.mass:.4g} kg" if first.mass is not None else "mass not given (a density or "
                    "a mass gives it; the planar body's motion does not depend on it)"))
    lines.extend(f"  note: {note}" for note in first.notes)
    cx, cy, cz = first.centre_of_mass
    lines.append(f"centre of mass: ({cx:.4g}, {cy:.4g}, {cz:.4g}) m in the mesh frame (x east, y north, z up)")
    if first.faces:
        lines.append(f"rests on the facet of the convex hull under the centre of mass, "
                     f"{'turned ' + _deg(first.tilt) + ' to lie flat' if first.tilt else 'as it lies (not turned)'}")
    s = np.array(first.support)
    lines.append(f"support polygon: {len(first.support)} vertices, {np.ptp(s[:, 0]):.4g} m along "
                 f"{_deg(first.azimuth)} x {np.ptp(s[:, 1]):.4g} m across"
                 + (f" (vertices within {first.contact_tolerance * 1e3:.3g} mm of the resting plane)"
                    if first.faces else ""))
    for body in bodies:
        side1, side2 = _deg(body.azimuth + math.pi), _deg(body.azimuth)
        label = f"{body.plane} ({_deg(body.azimuth)})" if body.plane in ("width", "depth") else body.plane
        inertia = f", I_cm {body.inertia:.4g} kg m^2" if body.inertia is not None else ""
        lines.append(f"along {label}: b1 = {body.b1:.4g} m (pivot 1, the {side1} side), b2 = {body.b2:.4g} m "
                     f"(the {side2} side), h = {body.h:.4g} m, radius of gyration {body.radius_of_gyration:.4g} m "
                     f"(k2 = {body.k2:.4g} m^2{inertia})")
        lines.append(f"  static tipping (b_i/h): the ground accelerating toward {side2} (ah > 0) tips it over pivot 1 "
                     f"from {body.tan_alpha1:.4g} g (alpha_1 = {math.degrees(math.atan(body.tan_alpha1)):.3g} deg), "
                     f"toward {side1} (ah < 0) over pivot 2 from {body.tan_alpha2:.4g} g "
                     f"(alpha_2 = {math.degrees(math.atan(body.tan_alpha2)):.3g} deg)")
    lines.append(SCREENING_NOTE)
    return lines


# --------------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------------


def _trimesh():
    import trimesh  # loaded only where a mesh is read or measured (about a second)

    return trimesh


def _length_factor(units, source: str) -> float:
    known = ", ".join(MESH_LENGTH_UNITS)
    if units is None or (isinstance(units, str) and not units.strip()):
        raise CaseError(f"a mesh needs its length unit (units=, one of {known}): mesh files do not say it",
                        source=source, field="units")
    key = units.strip().lower() if isinstance(units, str) else None
    if key not in MESH_LENGTH_UNITS:
        raise CaseError(f"unknown length unit {units!r} for a mesh; expected one of {known}", source=source,
                        field="units")
    return MESH_LENGTH_UNITS[key]


def _check_counts(data: bytes, fmt: str, source: str) -> None:
    """Refuse a file whose header or lines declare more than `MAX_MESH_FACES` faces or vertices,
    before a parser allocates for them; refuse what is not the format at all."""
    if fmt == "stl":
        binary = len(data) >= 84 and 84 + 50 * int.from_bytes(data[80:84], "little") == len(data)
        if binary:
            faces = int.from_bytes(data[80:84], "little")
        elif data.lstrip()[:5].lower() == b"solid":
            faces = data.count(b"endfacet")
        else:
            count = int.from_bytes(data[80:84], "little") if len(data) >= 84 else 0
            raise OutputError(f"not an STL file: neither ASCII ('solid ...') nor binary (84 + 50 x {count} "
                              f"declared faces = {84 + 50 * count} bytes, the file has {len(data)})", source=source)
        counts = {"faces": faces}
    elif fmt == "ply":
        end = data.find(b"end_header", 0, 1 << 16)
        if not data.startswith(b"ply") or end < 0:
            raise OutputError("not a PLY file: no 'ply ... end_header' header in its first 64 KB", source=source)
        counts = {}
        for line in data[:end].decode("ascii", "replace").splitlines():
            words = line.split()
            if len(words) == 3 and words[0] == "element" and words[1] in ("vertex", "face"):
                try:
                    counts[{"vertex": "vertices", "face": "faces"}[words[1]]] = int(words[2])
                except ValueError:
                    raise OutputError(f"PLY header line {line.strip()!r}: the count is not an integer",
                                      source=source) from None
    else:
        counts = {"faces": data.count(b"\nf ") + data.startswith(b"f "),
                  "vertices": data.count(b"\nv ") + data.startswith(b"v ")}
    for name, count in counts.items():
        if count > MAX_MESH_FACES:
            raise CaseError(f"the mesh has {count} {name}; rockslide reads at most {MAX_MESH_FACES} "
                            "(simplify the scan)", source=source)


def _source(mesh) -> str | None:
    return getattr(mesh, "metadata", {}).get("rockslide_source")


def _solid(mesh) -> None:
    """A closed mesh that encloses a volume, its faces turned outward; else CaseError."""
    source = _source(mesh)
    if not mesh.is_watertight:
        trimesh = _trimesh()
        open_edges = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
        raise CaseError(f"the mesh is not closed (watertight): {open_edges} edges belong to one triangle "
                        f"only{'' if open_edges else ' or to more than two'}; close its holes and export "
                        "it again", source=source)
    notes = mesh.metadata.setdefault("rockslide_notes", [])
    if not mesh.is_winding_consistent:
        # On a closed mesh the winding is made consistent face by face across shared edges: safe.
        _trimesh().repair.fix_winding(mesh)
        if not mesh.is_winding_consistent:
            raise CaseError("the mesh's triangles cannot be oriented consistently (a non-orientable or "
                            "self-touching surface)", source=source)
        notes.append("triangles of inconsistent winding turned to agree with their neighbours")
    scale = float(np.max(np.ptp(mesh.vertices, axis=0)))
    volume = _signed_volume(mesh)
    if volume < 0.0 and abs(volume) > 1e-9 * scale**3:
        mesh.invert()          # a consistent closed mesh inside out: every face turned, nothing else
        notes.append("faces turned outward (the file had them inward)")
        volume = -volume
    if not volume > 1e-9 * scale**3:
        raise CaseError(f"the mesh encloses no volume ({volume:.3g} m^3 in a box of {scale:.3g} m): "
                        "a flat or degenerate surface", source=source)


def _signed_volume(mesh) -> float:
    """The volume [m^3] a closed mesh encloses, negative when its faces point inward (the divergence
    theorem: a sixth of the sum of the triple products of the triangles' corners)."""
    t = np.asarray(mesh.triangles, dtype=float)
    return float(np.sum(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])))) / 6.0


# --------------------------------------------------------------------------------------------------
# Resting and measuring
# --------------------------------------------------------------------------------------------------


def _resting(mesh, tolerance: float, source: str | None) -> dict:
    """What both planes share: mass properties, the resting facet and rotation, the support polygon."""
    from scipy.spatial import ConvexHull, QhullError

    _solid(mesh)
    trimesh = _trimesh()
    props = trimesh.triangles.mass_properties(mesh.triangles, density=1.0)
    volume = float(props.volume)
    centre = np.asarray(props.center_mass, dtype=float)
    inertia = np.asarray(props.inertia, dtype=float) / volume           # per unit mass [m^2]
    vertices = np.asarray(mesh.vertices, dtype=float)
    hull = ConvexHull(vertices)
    normals, offsets = hull.equations[:, :3], hull.equations[:, 3]
    below = normals[:, 2] < 0.0
    # the vertical down from the CM leaves the hull through the facet with the smallest ray parameter
    t = np.full(len(offsets), np.inf)
    t[below] = (normals[below] @ centre + offsets[below]) / normals[below, 2]
    scale = float(np.max(np.ptp(vertices, axis=0)))
    ties = np.flatnonzero(t <= t.min() + 1e-12 * scale)
    facet = ties[np.argmin(normals[ties, 2])]          # an edge hit: the facet nearest to horizontal
    n, offset = normals[facet], offsets[facet]
    h = float(-(n @ centre + offset))
    rotation = _rotation_to_down(n)
    resting = (vertices - centre) @ rotation.T                         # CM at the origin, facet at z = -h
    near = resting[resting[:, 2] + h <= tolerance, :2]
    try:
        polygon = ConvexHull(near) if len(near) >= 3 else None
    except QhullError:
        polygon = None
    width = _min_width(near[polygon.vertices]) if polygon is not None else 0.0
    if width <= tolerance:
        extent = float(np.max(np.ptp(near, axis=0))) if len(near) else 0.0
        shape = "a point" if extent <= tolerance else "a line"
        raise CaseError(f"the body would rest on {shape}: the mesh's vertices within {tolerance * 1e3:.3g} mm of "
                        f"its resting plane span {extent * 1e3:.3g} mm x {width * 1e3:.3g} mm (the support polygon "
                        "is degenerate; a larger contact tolerance widens it)", source=source)
    if np.any(polygon.equations[:, 2] >= 0.0):
        raise CaseError("the centre of mass is outside its support polygon: the body would not stand on the "
                        f"facet of its convex hull under the centre of mass (turned {_deg(_tilt(n))} to lie on "
                        "it)", source=source)
    return {"volume": volume, "centre": centre, "inertia": rotation @ inertia @ rotation.T, "h": h,
            "rotation": rotation, "tilt": _tilt(n), "polygon": polygon.points[polygon.vertices],
            "edges": polygon.equations}


def _along(rest: dict, azimuth: float, mass, tolerance: float, source, mesh) -> PlanarBody:
    u = np.array([math.sin(azimuth), math.cos(azimuth)])
    v = np.array([math.cos(azimuth), -math.sin(azimuth)])                # azimuth + 90 deg
    m, off = rest["edges"][:, :2], rest["edges"][:, 2]

    def reach(direction):
        dot = m @ direction
        return float(np.min(-off[dot > 0.0] / dot[dot > 0.0]))

    b1, b2 = reach(-u), reach(u)
    axis = np.array([v[0], v[1], 0.0])
    k2 = float(axis @ rest["inertia"] @ axis)
    polygon = rest["polygon"]
    support = tuple((float(p @ u), float(p @ v)) for p in polygon[::-1])     # (s, t) is left-handed: reversed
    tri = (np.asarray(mesh.triangles, dtype=float) - rest["centre"]) @ rest["rotation"].T
    facing = (np.asarray(mesh.face_normals, dtype=float) @ rest["rotation"].T) @ axis > 0.0
    tri = tri[facing]
    outline = np.stack([tri[..., :2] @ u, tri[..., 2] + rest["h"]], axis=-1)
    outline.setflags(write=False)
    return PlanarBody(azimuth=float(azimuth), b1=b1, b2=b2, h=rest["h"], k2=k2, mass=mass, volume=rest["volume"],
                      centre_of_mass=tuple(float(c) for c in rest["centre"]), support=support, tilt=rest["tilt"],
                      contact_tolerance=tolerance, plane=f"azimuth {_deg(azimuth)}", source=source,
                      notes=tuple(mesh.metadata.get("rockslide_notes", ())), faces=len(mesh.faces), outline=outline)


def _rotation_to_down(n: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the unit vector ``n`` (``n_z < 0``) to ``(0, 0, -1)``
    (Rodrigues: ``R = I + [w]x + [w]x^2 / (1 + c)``, ``w = n x d``, ``c = n . d``)."""
    d = np.array([0.0, 0.0, -1.0])
    w = np.cross(n, d)
    c = float(n @ d)
    wx = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    return np.eye(3) + wx + wx @ wx / (1.0 + c)


def _tilt(n: np.ndarray) -> float:
    return float(math.atan2(math.hypot(n[0], n[1]), -n[2]))


def _min_width(points: np.ndarray) -> float:
    """The least width [m] of a convex polygon (its vertices in order): over its edges, the largest
    distance of a vertex from the edge's line."""
    best = math.inf
    for i in range(len(points)):
        a, b = points[i], points[(i + 1) % len(points)]
        edge = b - a
        length = math.hypot(*edge)
        if length == 0.0:
            continue
        rel = points - a
        best = min(best, float(np.max(np.abs(edge[0] * rel[:, 1] - edge[1] * rel[:, 0]))) / length)
    return 0.0 if best == math.inf else best


def _mass(density, mass, volume: float, source) -> float | None:
    if density is not None and mass is not None:
        raise CaseError("give a density or a mass, not both", source=source, field="mass")
    if density is None and mass is None:
        return None
    name, value = ("density", density) if density is not None else ("mass", mass)
    value = _finite(value, name, source)
    if value <= 0.0:
        raise CaseError(f"{name} must be positive, got {value!r}", source=source, field=name)
    return value * volume if name == "density" else value


def _finite(value, name: str, source) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not math.isfinite(value):
        raise CaseError(f"{name} must be a finite number (SI), got {value!r}", source=source, field=name)
    return float(value)


def _deg(angle: float) -> str:
    return f"{math.degrees(angle) % 360.0:.4g} deg"
