"""Whether a set of boundary facets encloses a volume: every edge shared by exactly two of the facets, except
edges lying in a symmetry plane through the origin (x = 0, y = 0 or z = 0), which close the surface there.
The facets may be spread over ranks (and repeated as ghosts): each rank sends its facets' edges as pairs of
global vertex numbers, and every rank counts them all, so every rank reaches the same verdict."""
from __future__ import annotations

from dolfinx import cpp, mesh as dmesh
import numpy as np

# a vertex lies in a symmetry plane x_i = 0 when |x_i| is below this fraction of the facets' extent
PLANE_TOLERANCE = 1e-6


def _local_edges(mesh: dmesh.Mesh, facets: np.ndarray) -> tuple[list, dict]:
    """(facet key, its edge keys) of each local facet, keys as sorted global vertex numbers, and the
    coordinates of every vertex they name."""
    top = mesh.topology
    fdim = top.dim - 1
    for a, b in ((fdim, 1), (1, 0), (fdim, 0)):
        top.create_connectivity(a, b)
    f2e, e2v, f2v = top.connectivity(fdim, 1), top.connectivity(1, 0), top.connectivity(fdim, 0)
    imap = top.index_map(0)
    vertices = np.unique(np.concatenate([f2v.links(f) for f in facets])) if len(facets) else np.zeros(0, np.int32)
    glob = dict(zip(vertices.tolist(), imap.local_to_global(vertices.astype(np.int32)).tolist()))
    nodes = cpp.mesh.entities_to_geometry(mesh._mesh, 0, vertices.astype(np.int32), False).ravel()
    coords = {glob[v]: mesh.geometry.x[n] for v, n in zip(vertices.tolist(), nodes.tolist())}
    entries = []
    for f in facets:
        edges = [tuple(sorted(glob[v] for v in e2v.links(e))) for e in f2e.links(f)]
        entries.append((tuple(sorted(glob[v] for v in f2v.links(f))), edges))
    return entries, coords


def enclosure_problem(mesh: dmesh.Mesh, facets: np.ndarray) -> str | None:
    """Why the facets (local indices on this rank) enclose no volume, or None when they do (closed, or closed
    by symmetry planes through the origin). The same answer on every rank."""
    entries, coords = _local_edges(mesh, np.asarray(facets, dtype=np.int32))
    all_entries = mesh.comm.allgather(entries)
    all_coords = {}
    for c in mesh.comm.allgather(coords):
        all_coords.update(c)
    facets_seen, count = set(), {}
    for rank_entries in all_entries:
        for key, edges in rank_entries:
            if key in facets_seen:                    # a ghost copy of a facet another rank also has
                continue
            facets_seen.add(key)
            for e in edges:
                count[e] = count.get(e, 0) + 1
    if not facets_seen:
        return "it selects no boundary facet"
    branching = [e for e, n in count.items() if n > 2]
    if branching:
        return f"{len(branching)} of its edges are shared by more than two of its facets (not a surface)"
    X = np.array(list(all_coords.values()))
    tol = PLANE_TOLERANCE * float(np.ptp(X, axis=0).max() or 1.0)
    open_edges = [e for e, n in count.items() if n == 1]
    loose = []
    for a, b in open_edges:
        xa, xb = all_coords[a], all_coords[b]
        if not any(abs(xa[i]) <= tol and abs(xb[i]) <= tol for i in range(3)):
            loose.append((xa, xb))
    if loose:
        xa, xb = loose[0]
        return (f"{len(loose)} of its edges are open and lie in no symmetry plane through the origin (x = 0, "
                f"y = 0 or z = 0), e.g. the edge from ({', '.join(f'{v:.4g}' for v in xa)}) to "
                f"({', '.join(f'{v:.4g}' for v in xb)})")
    return None
