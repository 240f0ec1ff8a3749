"""Mesh files to MeshArrays: a gmsh .msh (with its named groups of every dimension), any other volume
mesh meshio reads, and a closed surface (STL, OBJ, PLY, OFF) filled with tetrahedra once it is known
to be closed (or repaired, `repair = true`) and to fit in memory. Coordinates given in other units
(`scale`, `units`) are multiplied into metres as the file is read.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fem_forms.errors import InputError
from fem_forms.meshes import resources, surfaces
from fem_forms.meshes.arrays import MeshArrays, compact
from fem_forms.meshes.gmsh_models import gmsh_arrays, gmsh_session
from fem_forms.meshes.repair import repair_surface


def read_surface_file(path: Path, h: float | None, limit: float, degree: int, repair: bool = False,
                      scale: float = 1.0, max_cells: int | None = None) -> MeshArrays:
    """A closed surface (STL, OBJ, PLY, OFF), its coordinates times `scale`, filled with tetrahedra of
    size h (default: the surface's mean edge length), after checking that it is closed (or, with
    `repair`, making it so with MeshFix: results.json `mesh.repair` says what changed) and that the
    mesh will fit in memory and under the scene's cap on cells."""
    key = f"mesh.file = {str(path)!r}"
    raw_points, raw_tris = surfaces.read_triangles(path)
    points, tris = surfaces.merge_points(raw_points, raw_tris)
    report = None
    if repair:      # in the file's own units: MeshFix's tolerances failed to close a scan scaled mm -> m
        points, tris, report = repair_surface(points, tris, len(raw_tris), key, scale)
    points = points * scale
    surfaces.check_closed(points, tris, key)
    h = h or surfaces.mean_edge(points, tris)
    cells, dofs = resources.tetrahedra_counts(surfaces.enclosed_volume(points, tris), h, degree)
    resources.check_cap(cells, max_cells, f"{key} at h = {h:.3g}", estimated=True)
    resources.check_fits(cells, dofs, "tetrahedron", degree, f"{key} at h = {h:.3g}", limit)
    x, tets = surfaces.tetrahedralise(points, tris, h, key)
    arrays = compact(MeshArrays(x, tets, "tetrahedron"))
    what = "repaired surface" if repair else "surface"
    arrays.info = {"source": f"{path.name} ({what}, {len(tris)} triangles) meshed by gmsh at h = {h:.4g}",
                   **surfaces.quality(arrays.points, arrays.cells)}
    if scale != 1.0:
        arrays.info["scale"] = scale
    if report is not None:
        arrays.info["repair"] = report
    return arrays


def scale_arrays(arrays: MeshArrays, scale: float) -> MeshArrays:
    """Every coordinate of a read volume mesh (points, curve and point groups) times `scale`."""
    if scale != 1.0:
        arrays.points = arrays.points * scale
        arrays.curve_groups = {n: np.asarray(c) * scale for n, c in arrays.curve_groups.items()}
        arrays.point_groups = {n: np.asarray(c) * scale for n, c in arrays.point_groups.items()}
        arrays.info["scale"] = scale
    return arrays


def read_mesh_file(path: Path) -> MeshArrays:
    """A gmsh .msh (with its named groups of every dimension) or any meshio-readable volume mesh."""
    if path.suffix == ".msh":
        gmsh = gmsh_session()
        try:
            try:
                gmsh.merge(str(path))
            except Exception as e:
                raise InputError(f"mesh.file = {str(path)!r}: gmsh cannot read it ({e})") from None
            return gmsh_arrays(gmsh)
        finally:
            gmsh.finalize()
    m = surfaces.read_meshio(path)
    kinds = {"tetra": ("tetrahedron", 4), "tetra10": ("tetrahedron", 4),
             "hexahedron": ("hexahedron", 8), "hexahedron20": ("hexahedron", 8),
             "hexahedron27": ("hexahedron", 8)}
    blocks = [(kinds[b.type], b.data) for b in m.cells if b.type in kinds]
    if not blocks or len({k[0] for k, _ in blocks}) != 1:
        found = ", ".join(sorted({b.type for b in m.cells})) or "nothing"
        raise InputError(f"mesh.file = {str(path)!r}: needs volume cells all tetrahedra or all "
                         f"hexahedra (found: {found})")
    (cell_type, nv), _ = blocks[0]
    cells = np.vstack([d[:, :nv] for _, d in blocks]).astype(np.int64)
    pts = np.asarray(m.points, dtype=np.float64)
    if pts.shape[1] != 3:
        raise InputError(f"mesh.file = {str(path)!r}: points must have 3 coordinates")
    return compact(MeshArrays(pts, cells, cell_type, {}, cell_fields=_cell_fields(m, kinds)))


def _cell_fields(m, kinds: dict) -> dict:
    """The numeric cell data of the volume blocks (meshio's cell_data: VTU, XDMF), name -> (cells, k)."""
    out = {}
    for name, per_block in m.cell_data.items():
        values = [np.asarray(v) for b, v in zip(m.cells, per_block) if b.type in kinds]
        if name.startswith("gmsh:") or not values or not all(np.issubdtype(v.dtype, np.number) for v in values):
            continue
        out[name] = np.vstack([v.reshape(len(v), -1) for v in values]).astype(float)
    return out
