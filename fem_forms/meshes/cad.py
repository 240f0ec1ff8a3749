"""CAD files (STEP, IGES, BREP) meshed by gmsh through OpenCASCADE: the solids of the file filled with tetrahedra of
size h (h_min, h_max, and finer near given points), every CAD face a surface group - its CAD name where the file
carries one, else face<N> - so a support or a load can take it (`where = { face = N }` or `{ group = ... }`), every
named solid a volume group. A STEP or IGES file declares its length unit: OpenCASCADE converts to the unit the
scene names (`units`, metres by default) and the coordinates are then scaled into metres, so the part comes in at
its true size; a BREP declares none, so `units` or `scale` says it as for an STL."""
from __future__ import annotations

import math
from pathlib import Path

from fem_forms.errors import InputError
from fem_forms.meshes import resources
from fem_forms.meshes.arrays import MeshArrays
from fem_forms.meshes.gmsh_models import gmsh_arrays, gmsh_session
from fem_forms.scene import MeshSpec
from fem_forms.scene.spec import UNIT_SCALES

OCC_UNITS = {"m": "M", "mm": "MM", "cm": "CM", "in": "INCH"}
H_PER_DIAGONAL = 20            # the default h: the part's bounding-box diagonal over this


def import_cad(gmsh, path: Path, units: str | None, key: str) -> list:
    """The file's solids in the current gmsh model (coordinates in `units`, or metres), fragmented so that
    solids that touch share their faces' nodes; their (3, tag) list. One line when gmsh cannot read it or it
    holds no solid."""
    declares_unit = path.suffix.lower() in (".step", ".stp", ".iges", ".igs")
    if declares_unit:
        gmsh.option.setString("Geometry.OCCTargetUnit", OCC_UNITS[units or "m"])
    try:
        gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
    except Exception as e:                       # noqa: BLE001 (gmsh raises Exception with its log line)
        raise InputError(f"{key}: gmsh cannot read it ({str(e).strip().splitlines()[-1] if str(e) else e})") from None
    solids = gmsh.model.getEntities(3)
    if not solids:
        found = len(gmsh.model.getEntities(2))
        raise InputError(f"{key}: holds no solid ({found} surfaces and no volume: export the part as a solid body)")
    if len(solids) > 1:
        gmsh.model.occ.fragment(solids[:1], solids[1:])
        gmsh.model.occ.synchronize()
        solids = gmsh.model.getEntities(3)
    return solids


def _cad_name(gmsh, dim: int, tag: int) -> str:
    """The entity's name in the CAD file (its last path part: gmsh names imported entities Shapes/.../name)."""
    return gmsh.model.getEntityName(dim, tag).rsplit("/", 1)[-1].strip()


def face_table(gmsh, scale: float = 1.0) -> list[dict]:
    """Every CAD face: its number, its group (CAD name or face<N>), its area (m^2), centroid (m) and, when flat,
    its normal (out of the solid it bounds)."""
    faces, seen = [], {}
    for _, tag in gmsh.model.getEntities(2):
        name = _cad_name(gmsh, 2, tag)
        group = name if name and name not in seen else f"face{tag}"
        seen[group] = tag
        centroid = [c * scale for c in gmsh.model.occ.getCenterOfMass(2, tag)]
        row = {"face": tag, "group": group, "area": gmsh.model.occ.getMass(2, tag) * scale**2, "centroid": centroid}
        if gmsh.model.getType(2, tag) == "Plane":
            u0, u1 = gmsh.model.getParametrizationBounds(2, tag)
            n = gmsh.model.getNormal(tag, [(u0[0] + u1[0]) / 2, (u0[1] + u1[1]) / 2])
            row["normal"] = [round(float(c), 12) + 0.0 for c in _outward(gmsh, tag, list(n))]
        faces.append(row)
    return faces


def _outward(gmsh, tag: int, n: list) -> list:
    """A flat face's normal n turned to point out of the solid it bounds (a point just off the face along n lies
    inside the solid: n points in)."""
    solids = gmsh.model.getAdjacencies(2, tag)[0]
    if not len(solids):
        return n
    x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(3, int(solids[0]))
    step = 1e-6 * math.dist((x0, y0, z0), (x1, y1, z1))
    inside = gmsh.model.getClosestPoint(2, tag, list(gmsh.model.occ.getCenterOfMass(2, tag)))[0]
    probe = [c + step * v for c, v in zip(inside, n)]
    return [-v for v in n] if gmsh.model.isInside(3, int(solids[0]), probe) else n


def _size_fields(gmsh, spec: MeshSpec, h: float, scale: float) -> None:
    """Cells of size h (between h_min and h_max), finer within r of each near point (the scene's metres)."""
    gmsh.option.setNumber("Mesh.MeshSizeMax", (spec.h_max or h) / scale)
    gmsh.option.setNumber("Mesh.MeshSizeMin", (spec.h_min or min(h, spec.h_max or h) / 4) / scale)
    if not spec.near:
        return
    field = gmsh.model.mesh.field
    balls = []
    for x, y, z, r, h_near in spec.near:
        b = field.add("Ball")
        for name, value in (("XCenter", x), ("YCenter", y), ("ZCenter", z), ("Radius", r), ("Thickness", r),
                            ("VIn", h_near), ("VOut", spec.h_max or h)):
            field.setNumber(b, name, value / scale)
        balls.append(b)
    least = field.add("Min")
    field.setNumbers(least, "FieldsList", balls)
    field.setAsBackgroundMesh(least)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)


def _estimated_cells(volume: float, spec: MeshSpec, h: float) -> int:
    cells = resources.tetrahedra_counts(volume, spec.h_max or h, 1)[0]
    for _, _, _, r, h_near in spec.near or []:
        cells += resources.tetrahedra_counts(4 / 3 * math.pi * (2 * r) ** 3, h_near, 1)[0]
    return cells


def mesh_cad(spec: MeshSpec, limit: float, degree: int) -> MeshArrays:
    """The CAD file of `spec` meshed with tetrahedra, refused first when its estimated size exceeds the scene's cap
    on cells or the machine's memory; info lists its faces (results.json mesh.faces)."""
    key = f"mesh.file = {str(spec.file)!r}"
    gmsh = gmsh_session()
    try:
        solids = import_cad(gmsh, spec.file, spec.units, key)
        scale = spec.length_scale           # STEP, IGES: OpenCASCADE gave `units` (default m); BREP: as written
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(-1, -1)
        h = spec.h or math.dist((x0, y0, z0), (x1, y1, z1)) * scale / H_PER_DIAGONAL
        volume = sum(gmsh.model.occ.getMass(3, t) for _, t in solids) * scale**3
        cells = _estimated_cells(volume, spec, h)
        resources.check_cap(cells, spec.max_cells, f"{key} at h = {h:.3g}", estimated=True)
        resources.check_fits(cells, resources.tetrahedra_dofs(cells, degree), "tetrahedron", degree,
                             f"{key} at h = {h:.3g}", limit)
        faces = face_table(gmsh, scale)
        for row in faces:
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [row["face"]], row["face"]), row["group"])
        for i, (_, tag) in enumerate(solids):
            name = _cad_name(gmsh, 3, tag) or f"solid{i + 1}"
            gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [tag], tag), name)
        _size_fields(gmsh, spec, h, scale)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as e:                   # noqa: BLE001
            raise InputError(f"{key}: gmsh could not mesh it at h = {h:.3g} ({str(e).strip()[:120]})") from None
        arrays = gmsh_arrays(gmsh)
    finally:
        gmsh.finalize()
    if scale != 1.0:
        arrays.points = arrays.points * scale
    arrays.info = {"source": f"{spec.file.name} (CAD, {len(solids)} solid{'s' * (len(solids) > 1)}, {len(faces)} "
                             f"faces) meshed by gmsh at h = {h:.4g}", "faces": faces}
    return arrays


def cad_faces(path: Path, units: str | None) -> tuple[list[dict], dict]:
    """The faces of a CAD file (face_table, in metres) and each face's surface triangles (face number -> (m, 3, 3)
    corners, from a coarse surface mesh), for listing and drawing them before a scene picks one."""
    key = f"{str(path)!r}"
    gmsh = gmsh_session()
    try:
        import_cad(gmsh, path, units, key)
        scale = UNIT_SCALES[units] if units else 1.0      # into metres from the unit OpenCASCADE gave
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(-1, -1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", math.dist((x0, y0, z0), (x1, y1, z1)) / 30)
        faces = face_table(gmsh, scale)
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        position = dict(zip(tags.tolist(), (coords.reshape(-1, 3) * scale).tolist()))
        triangles = {}
        for row in faces:
            types, _, nodes = gmsh.model.mesh.getElements(2, row["face"])
            corners = [n.reshape(-1, gmsh.model.mesh.getElementProperties(t)[3])[:, :3]
                       for t, n in zip(types, nodes)]
            flat = [c for block in corners for c in block.tolist()]
            triangles[row["face"]] = [[position[v] for v in tri] for tri in flat]
    finally:
        gmsh.finalize()
    return faces, triangles
