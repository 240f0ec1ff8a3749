"""CAD files (STEP, IGES, BREP) meshed by gmsh through OpenCASCADE: the solids of the file filled with tetrahedra of
size h (h_min, h_max, and finer near given points), every CAD face a surface group face<N>, so a support or a load
can take it (`where = { face = N }`; faces the file names: `{ group = NAME }`, all of that name), every solid a
volume group named by the CAD (solids of one name together). A STEP or IGES file declares its length unit: OpenCASCADE converts to the unit the
scene names (`units`, metres by default) and the coordinates are then scaled into metres, so the part comes in at
its true size; a BREP declares none, so `units` or `scale` says it as for an STL."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fem_forms.errors import InputError
from fem_forms.meshes import resources
from fem_forms.meshes.arrays import MeshArrays, outward_normals
from fem_forms.meshes.gmsh_models import gmsh_arrays, gmsh_session
from fem_forms.scene import MeshSpec
from fem_forms.scene.spec import UNIT_SCALES

OCC_UNITS = {"m": "M", "mm": "MM", "cm": "CM", "in": "INCH"}
H_PER_DIAGONAL = 20            # the default h: the part's bounding-box diagonal over this
LISTING_CELLS = 15             # `fem-forms faces` meshes at the diagonal over this (enough to draw and orient)
MIN_FRACTION = 0.25            # the default h_min: this fraction of h
FLAT = 1e-9                    # a face is flat when its facets' normals agree to this (1 - cosine)


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


def _group_solids(gmsh, solids: list) -> None:
    """One volume group per CAD name (solids sharing a name together), solid<i> for a solid without one."""
    named: dict = {}
    for i, (_, tag) in enumerate(solids):
        named.setdefault(_cad_name(gmsh, 3, tag) or f"solid{i + 1}", []).append(tag)
    for name, tags in named.items():
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, tags), name)


def _group_faces(gmsh) -> list[int]:
    """Every CAD face a surface group face<N> (N its number); its CAD name is kept in the face table."""
    faces = [tag for _, tag in gmsh.model.getEntities(2)]
    for tag in faces:
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [tag], tag), f"face{tag}")
    return faces


def face_table(gmsh, arrays: MeshArrays, scale: float) -> list[dict]:
    """Every CAD face: its number, its group (face<N>), its CAD name where the file gives one, its area (m^2),
    centroid (m) and, when flat, its outward normal (from its mesh facets and the tetrahedra they bound)."""
    groups = {name: f for name, f in arrays.facet_groups.items() if len(f)}
    every = np.vstack(list(groups.values())) if groups else np.zeros((0, 3), dtype=np.int64)
    normals = outward_normals(arrays.points, arrays.cells, every)      # one pass over the cells for every face
    starts = np.cumsum([0] + [len(f) for f in groups.values()])
    by_group = {name: normals[a:b] for name, a, b in zip(groups, starts[:-1], starts[1:])}
    rows = []
    for tag in sorted(t for _, t in gmsh.model.getEntities(2)):
        row = {"face": tag, "group": f"face{tag}", "area": gmsh.model.occ.getMass(2, tag) * scale**2,
               "centroid": [c * scale for c in gmsh.model.occ.getCenterOfMass(2, tag)]}
        name = _cad_name(gmsh, 2, tag)
        if name:
            row["name"] = name
        n = by_group.get(f"face{tag}")
        if n is not None:
            mean = n.mean(axis=0) / np.linalg.norm(n.mean(axis=0))
            if np.all(n @ mean >= 1.0 - FLAT):
                row["normal"] = [round(float(c), 12) + 0.0 for c in mean]
        rows.append(row)
    return rows


def _sizes(spec: MeshSpec, h: float) -> tuple[float, float]:
    """(smallest, largest) cell gmsh may make: h_min (default a quarter of h, or the smallest near h), and h capped
    by h_max."""
    largest = min(h, spec.h_max) if spec.h_max else h
    smallest = spec.h_min or min([largest * MIN_FRACTION] + [row[4] for row in spec.near or []])
    return smallest, largest


def _size_fields(gmsh, spec: MeshSpec, h: float, scale: float) -> None:
    """Cells of size h (between h_min and h_max), finer within r of each near point (the scene's metres)."""
    smallest, largest = _sizes(spec, h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", largest / scale)
    gmsh.option.setNumber("Mesh.MeshSizeMin", smallest / scale)
    if not spec.near:
        return
    field = gmsh.model.mesh.field
    balls = []
    for x, y, z, r, h_near in spec.near:
        b = field.add("Ball")
        for name, value in (("XCenter", x), ("YCenter", y), ("ZCenter", z), ("Radius", r), ("Thickness", r),
                            ("VIn", h_near), ("VOut", largest)):
            field.setNumber(b, name, value / scale)
        balls.append(b)
    least = field.add("Min")
    field.setNumbers(least, "FieldsList", balls)
    field.setAsBackgroundMesh(least)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)


def _estimated_cells(volume: float, spec: MeshSpec, h: float) -> int:
    cells = resources.tetrahedra_counts(volume, _sizes(spec, h)[1], 1)[0]
    for _, _, _, r, h_near in spec.near or []:
        cells += resources.tetrahedra_counts(4 / 3 * math.pi * (2 * r) ** 3, h_near, 1)[0]
    return cells


def _generate(gmsh, key: str, h: float) -> MeshArrays:
    try:
        gmsh.model.mesh.generate(3)
    except Exception as e:                       # noqa: BLE001 (gmsh raises Exception with its log line)
        raise InputError(f"{key}: gmsh could not mesh it at h = {h:.3g} ({str(e).strip()[:120]})") from None
    return gmsh_arrays(gmsh)


def mesh_cad(spec: MeshSpec, limit: float, degree: int) -> MeshArrays:
    """The CAD file of `spec` meshed with tetrahedra, refused first when its estimated size exceeds the scene's cap
    on cells or the machine's memory (and after meshing, by its count); info lists its faces (results.json
    mesh.faces)."""
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
        _group_faces(gmsh)
        _group_solids(gmsh, solids)
        _size_fields(gmsh, spec, h, scale)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        arrays = _generate(gmsh, key, h)
        resources.check_cap(len(arrays.cells), spec.max_cells, f"{key} at h = {h:.3g}")
        faces = face_table(gmsh, arrays, 1.0)
    finally:
        gmsh.finalize()
    if scale != 1.0:
        arrays.points = arrays.points * scale
        for row in faces:
            row["area"], row["centroid"] = row["area"] * scale**2, [c * scale for c in row["centroid"]]
    arrays.info = {"source": f"{spec.file.name} (CAD, {len(solids)} solid{'s' * (len(solids) > 1)}, {len(faces)} "
                             f"faces) meshed by gmsh at h = {h:.4g}", "faces": faces}
    return arrays


def cad_faces(path: Path, units: str | None) -> tuple[list[dict], dict]:
    """The faces of a CAD file (face_table, in metres) and each face's surface triangles (face number -> (m, 3, 3)
    corners), from a coarse mesh, for listing and drawing them before a scene picks one."""
    key = f"faces {str(path)!r}"
    gmsh = gmsh_session()
    try:
        solids = import_cad(gmsh, path, units, key)
        scale = UNIT_SCALES[units] if units else 1.0      # into metres from the unit OpenCASCADE gave
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(-1, -1)
        _group_faces(gmsh)
        _group_solids(gmsh, solids)
        gmsh.option.setNumber("Mesh.MeshSizeMax", math.dist((x0, y0, z0), (x1, y1, z1)) / LISTING_CELLS)
        arrays = _generate(gmsh, key, math.dist((x0, y0, z0), (x1, y1, z1)) * scale / LISTING_CELLS)
        faces = face_table(gmsh, arrays, scale)
    finally:
        gmsh.finalize()
    triangles = {row["face"]: (arrays.points[arrays.facet_groups[row["group"]][:, :3]] * scale).tolist()
                 for row in faces if row["group"] in arrays.facet_groups}
    return faces, triangles
