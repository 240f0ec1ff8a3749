"""gmsh physical groups of every dimension, not only the facet groups dolfinx's gmshio brings through.

Volumes (dimension 3) become cell groups: row indices into the cell array on rank 0, distributed as
local cell indices. Curves (1) and points (0) become coordinates, the same on every rank: a support
on them fixes the dofs that lie on the curve's mesh edges or at the points, found geometrically
(dolfinx keeps no edge or vertex tags through mesh distribution). Surfaces (2) stay in gmsh_models.py.
"""
from __future__ import annotations

from dolfinx import cpp, mesh as dmesh
import numpy as np

# gmsh element types of lines (2- and 3-node) and points
_LINE_TYPES = {1: 2, 8: 3, 26: 4, 27: 5}
_POINT_TYPE = 15


def group_name(gmsh, dim: int, tag: int) -> str:
    return gmsh.model.getPhysicalName(dim, tag) or str(tag)


def cell_groups(gmsh, element_tags: np.ndarray) -> dict:
    """Volume groups: name -> rows of the cell array, whose gmsh element tags are `element_tags`
    (in cell-array order)."""
    order = np.argsort(element_tags)
    groups = {}
    for dim, tag in gmsh.model.getPhysicalGroups(3):
        rows = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            _, etags, _ = gmsh.model.mesh.getElements(3, ent)
            for t in etags:
                t = np.asarray(t)
                pos = np.searchsorted(element_tags, t, sorter=order)
                pos = np.clip(pos, 0, len(order) - 1)
                hit = element_tags[order[pos]] == t
                rows.append(order[pos[hit]])
        if rows:
            groups[group_name(gmsh, dim, tag)] = np.unique(np.concatenate(rows))
    return groups


def curve_and_point_groups(gmsh, points: np.ndarray, index: np.ndarray) -> tuple[dict, dict]:
    """Curve groups: name -> (k, 2, 3) end points of their mesh edges; point groups: name -> (k, 3)."""
    curves, pts = {}, {}
    for dim, tag in gmsh.model.getPhysicalGroups(1):
        segs = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            types, _, nodes = gmsh.model.mesh.getElements(1, ent)
            for t, n in zip(types, nodes):
                if t in _LINE_TYPES:
                    ends = index[np.asarray(n, dtype=np.int64).reshape(-1, _LINE_TYPES[t])[:, :2]]
                    segs.append(points[ends])
        if segs:
            curves[group_name(gmsh, dim, tag)] = np.concatenate(segs)
    for dim, tag in gmsh.model.getPhysicalGroups(0):
        found = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            types, _, nodes = gmsh.model.mesh.getElements(0, ent)
            for t, n in zip(types, nodes):
                if t == _POINT_TYPE:
                    found.append(points[index[np.asarray(n, dtype=np.int64)]])
        if found:
            pts[group_name(gmsh, dim, tag)] = np.concatenate(found).reshape(-1, 3)
    return curves, pts


def distribute_cell_groups(mesh: dmesh.Mesh, cells: np.ndarray | None, groups: dict | None,
                           names: list, cell_type: str) -> dict:
    """Local cell indices of each volume group (rank 0 holds the cells and the groups' rows)."""
    tdim = mesh.topology.dim
    nv = cells.shape[1] if cells is not None else (4 if cell_type == "tetrahedron" else 8)
    perm = cpp.io.perm_gmsh(dmesh.to_type(cell_type), nv)   # gmshio.cell_perm_array, without gmsh
    mesh.topology.create_connectivity(tdim, 0)
    out = {}
    for name in names:
        if cells is not None:
            ents = cells[groups[name]][:, perm].astype(np.int64)
            vals = np.ones(len(ents), dtype=np.int32)
        else:
            ents, vals = np.empty((0, nv), dtype=np.int64), np.empty(0, dtype=np.int32)
        local, lvals = cpp.io.distribute_entity_data(mesh._mesh, tdim, ents, vals)
        tags = dmesh.meshtags_from_entities(mesh, tdim, cpp.graph.AdjacencyList_int32(local),
                                            lvals.astype(np.int32))
        out[name] = np.asarray(tags.indices, dtype=np.int32)
    return out


def distance_to_segments(x: np.ndarray, segments: np.ndarray, chunk: int = 256) -> np.ndarray:
    """Distance from each point x (n, 3) to the nearest of the segments (k, 2, 3)."""
    best = np.full(len(x), np.inf)
    for s in range(0, len(segments), chunk):
        a, b = segments[s:s + chunk, 0], segments[s:s + chunk, 1]
        d = b - a
        dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
        t = np.clip(np.einsum("nij,ij->ni", x[:, None, :] - a[None], d) / dd, 0.0, 1.0)
        near = a[None] + t[..., None] * d[None]
        best = np.minimum(best, np.linalg.norm(x[:, None, :] - near, axis=2).min(axis=1))
    return best


def distance_to_points(x: np.ndarray, pts: np.ndarray, chunk: int = 256) -> np.ndarray:
    """Distance from each point x (n, 3) to the nearest of pts (k, 3)."""
    best = np.full(len(x), np.inf)
    for s in range(0, len(pts), chunk):
        best = np.minimum(best, np.linalg.norm(x[:, None, :] - pts[None, s:s + chunk], axis=2).min(axis=1))
    return best
