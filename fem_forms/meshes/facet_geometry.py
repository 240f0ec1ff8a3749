"""The boundary facets' geometry, for selecting them by where they face and by the closed surface they belong to:
outward unit normals, areas and centroids (local to each rank), and the part's cavities, the closed interior
surfaces, found from the whole boundary gathered on every rank (the boundary is small next to the volume), so
that every rank orders them the same way (by the volume each encloses, largest first)."""
from __future__ import annotations

from dolfinx import cpp, mesh as dmesh
import numpy as np

from fem_forms.meshes.loader import bounding_box

SYMMETRY_TOLERANCE = 1e-6     # a facet lies in a symmetry plane x_i = 0 within this fraction of the part's size
VOLUME_ROUNDOFF = 1e-12       # a surface enclosing less than this fraction of the largest is no cavity


def boundary_facets(mesh: dmesh.Mesh) -> np.ndarray:
    """Local indices of the facets on the part's boundary (the exterior facets)."""
    fdim = mesh.topology.dim - 1
    return np.asarray(dmesh.locate_entities_boundary(mesh, fdim, lambda x: np.full(x.shape[1], True)),
                      dtype=np.int32)


def outward_geometry(mesh: dmesh.Mesh, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(unit outward normals (n, 3), areas (n,), centroids (n, 3)) of boundary facets (local indices). A
    triangle's normal is its edges' cross product; a quadrilateral's its diagonals' (a warped one's mean plane);
    outward: away from the centroid of the one cell the facet bounds."""
    top = mesh.topology
    tdim, fdim = top.dim, top.dim - 1
    facets = np.asarray(facets, dtype=np.int32)
    if not len(facets):
        return np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3))
    top.create_connectivity(fdim, tdim)
    f2c = top.connectivity(fdim, tdim)
    x = mesh.geometry.x
    nodes = cpp.mesh.entities_to_geometry(mesh._mesh, fdim, facets, False)
    corners = x[nodes[:, :4] if nodes.shape[1] >= 4 else nodes[:, :3]]
    if nodes.shape[1] == 3:
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    else:                       # dolfinx's quadrilateral: vertices 0 and 3, 1 and 2 are opposite
        cross = np.cross(corners[:, 3] - corners[:, 0], corners[:, 2] - corners[:, 1])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / np.maximum(2.0 * area, np.finfo(float).tiny)[:, None]
    centroid = corners.mean(axis=1)
    cells = f2c.array[f2c.offsets[facets]]
    dofmap = mesh.geometry.dofmap
    cell_nodes = dofmap.array.reshape(-1, dofmap.offsets[1] - dofmap.offsets[0])[cells]
    inward = x[cell_nodes].mean(axis=1) - centroid
    flip = np.einsum("ij,ij->i", normal, inward) > 0
    normal[flip] *= -1
    return normal, area, centroid


def cavities(mesh: dmesh.Mesh) -> list[tuple[float, np.ndarray]]:
    """The part's cavities: each closed interior surface as (the volume it encloses, the local indices of its
    facets on this rank), largest volume first; the same list (and volumes) on every rank. A surface is a set of
    boundary facets connected through their vertices; it bounds a cavity when its outward normals (out of the
    material) point into what it encloses: the divergence theorem then gives it a negative volume. Facets in a
    symmetry plane through the origin (x = 0, y = 0 or z = 0) are left out: they add no volume, and a cavity cut
    by the plane (a half or quarter model) would otherwise join the outer surface through them."""
    facets = boundary_facets(mesh)
    normal, area, centroid = outward_geometry(mesh, facets)
    top = mesh.topology
    fdim = top.dim - 1
    top.create_connectivity(fdim, 0)
    f2v = top.connectivity(fdim, 0)
    imap = top.index_map(0)
    lo, hi = bounding_box(mesh)
    tol = SYMMETRY_TOLERANCE * float((hi - lo).max())
    in_plane = np.any((np.abs(centroid) <= tol) & (np.abs(np.abs(normal) - 1.0) <= SYMMETRY_TOLERANCE), axis=1)
    keys = [tuple(sorted(imap.local_to_global(f2v.links(f)).tolist())) for f in facets]
    volume = np.einsum("ij,ij->i", centroid, normal) * area / 3.0
    mine = [(k, v, tuple(c)) for k, v, c, skip in zip(keys, volume.tolist(), centroid.tolist(), in_plane) if not skip]
    seen: dict = {}
    for part in mesh.comm.allgather(mine):
        for key, v, c in part:
            seen.setdefault(key, (v, c))            # a facet on two ranks (a ghost) counts once
    parent: dict = {}

    def root(a):
        while parent.setdefault(a, a) != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for key in sorted(seen):
        r = root(key[0])
        for v in key[1:]:
            parent[root(v)] = r
    enclosed: dict = {}
    corner: dict = {}
    for key, (v, c) in seen.items():
        r = root(key[0])
        enclosed[r] = enclosed.get(r, 0.0) + v
        corner[r] = min(corner.get(r, c), c)     # ties in volume: the lowest corner first, on any partition
    scale = max(abs(v) for v in enclosed.values()) if enclosed else 1.0
    order = sorted((r for r, v in enclosed.items() if v < -VOLUME_ROUNDOFF * scale),
                   key=lambda r: (round(enclosed[r] / scale, 9), corner[r]))
    local_root = np.array([root(k[0]) if k in seen else -1 for k in keys]) if keys else np.zeros(0)
    return [(-enclosed[r], facets[local_root == r]) for r in order]
