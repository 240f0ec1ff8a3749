"""A volume mesh on rank 0 as plain arrays (MeshArrays: points, cells, named groups) and what every
loader path does to it before distribution: the cell checks (degenerate and inverted cells refused,
a consistently reversed orientation flipped) and compaction (points no cell uses dropped).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fem_forms.errors import InputError


@dataclass
class MeshArrays:
    """A volume mesh on one rank: points (n, 3), cells (m, k) in gmsh/VTK vertex order."""
    points: np.ndarray
    cells: np.ndarray
    cell_type: str                                     # "tetrahedron" | "hexahedron"
    facet_groups: dict = field(default_factory=dict)   # name -> (f, 3|4) vertex indices
    cell_groups: dict = field(default_factory=dict)    # volume group name -> rows of cells
    curve_groups: dict = field(default_factory=dict)   # curve group name -> (k, 2, 3) edge end points
    point_groups: dict = field(default_factory=dict)   # point group name -> (k, 3) coordinates
    info: dict = field(default_factory=dict)           # what results.json says about the mesh
    cell_fields: dict = field(default_factory=dict)    # name -> (cells, k) values per cell (a fibre direction)


def cell_volumes(points: np.ndarray, cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Signed volume of tetrahedra; for hexahedra the smallest corner Jacobian times the cell volume
    scale, so a negative value means an inverted (or self-crossing) hexahedron."""
    p = points[cells]
    if cell_type == "tetrahedron":
        a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
        return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    # hexahedron, VTK order: bottom 0-1-2-3, top 4-5-6-7; three edges at each corner, right-handed
    corners = [(0, 1, 3, 4), (1, 2, 0, 5), (2, 3, 1, 6), (3, 0, 2, 7),
               (4, 7, 5, 0), (5, 4, 6, 1), (6, 5, 7, 2), (7, 6, 4, 3)]
    dets = []
    for o, i, j, k in corners:
        a, b, c = p[:, i] - p[:, o], p[:, j] - p[:, o], p[:, k] - p[:, o]
        dets.append(np.einsum("ij,ij->i", a, np.cross(b, c)))
    d = np.array(dets)
    return np.where(d.min(axis=0) < 0, d.min(axis=0), d.mean(axis=0))


def check_cells(arrays: MeshArrays, key: str) -> None:
    """Reject meshes with degenerate (zero-volume) or inverted cells, naming how many and where."""
    if len(arrays.cells) == 0:
        raise InputError(f"{key}: the mesh has no cells")
    vol = cell_volumes(arrays.points, arrays.cells, arrays.cell_type)
    p = arrays.points[arrays.cells]
    edge = np.linalg.norm(p[:, 1] - p[:, 0], axis=1)
    scale = max(float(np.mean(edge)), 1e-300) ** 3
    if np.mean(vol) < 0:   # consistently reversed orientation: flip to the convention
        vol = -vol
        arrays.cells = arrays.cells[:, _flip(arrays.cell_type)]
    degenerate = np.abs(vol) <= 1e-10 * scale
    inverted = (vol < 0) & ~degenerate
    if degenerate.any():
        i = int(np.argmax(degenerate))
        raise InputError(f"{key}: {int(degenerate.sum())} degenerate (zero-volume) cells, the first is "
                         f"cell {i} at {np.round(p[i].mean(axis=0), 6).tolist()}")
    if inverted.any():
        i = int(np.argmax(inverted))
        raise InputError(f"{key}: {int(inverted.sum())} inverted cells, the first is cell {i} at "
                         f"{np.round(p[i].mean(axis=0), 6).tolist()}")


def _flip(cell_type: str) -> list:
    return [0, 2, 1, 3] if cell_type == "tetrahedron" else [4, 5, 6, 7, 0, 1, 2, 3]


def compact(a: MeshArrays) -> MeshArrays:
    """Drop points no cell uses (geometry points, midside nodes) and renumber."""
    used = np.unique(a.cells)
    if len(used) == len(a.points):
        return a
    new = np.full(len(a.points), -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    # facets touching unused nodes (degenerate surfaces, e.g. the revolution axis) are dropped
    groups = {n: new[f][np.all(new[f] >= 0, axis=1)] for n, f in a.facet_groups.items()}
    return MeshArrays(a.points[used], new[a.cells], a.cell_type, {n: f for n, f in groups.items() if len(f)},
                      a.cell_groups, a.curve_groups, a.point_groups, a.info, a.cell_fields)


def outward_normals(points: np.ndarray, cells: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Unit normals (n, 3) of boundary triangles (vertex indices into points) of a tetrahedral mesh given as
    arrays, pointing out of the tetrahedron each bounds (before the mesh is distributed: a CAD face's normal)."""
    if not len(facets):
        return np.zeros((0, 3))
    wanted = {tuple(sorted(f[:3].tolist())) for f in facets}
    opposite = {}
    for c in cells.tolist():                       # the boundary's facets only: one tetrahedron each
        for i in range(4):
            key = tuple(sorted(c[:i] + c[i + 1:]))
            if key in wanted:
                opposite[key] = c[i]
    tri = points[facets[:, :3]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1), np.finfo(float).tiny)[:, None]
    away = np.array([points[opposite[tuple(sorted(f[:3].tolist()))]] for f in facets]) - tri[:, 0]
    n[np.einsum("ij,ij->i", n, away) > 0] *= -1
    return n
