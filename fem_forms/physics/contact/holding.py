"""What of the part touches and holds: the surface points [contact] where leaves to the obstacles, and the parts of a
rigid motion the obstacles resist at rest (the supports' check of a static scene held by contact alone)."""
from __future__ import annotations

from dolfinx import fem
import numpy as np


def surface_points(surface, V, loaded, where) -> np.ndarray:
    """(n,) bool: the surface's points on the boundary facets `where` selects (their corner and, on P2, edge nodes:
    the displacement's dofs there; any rank's), the same on every rank."""
    from fem_forms.physics.supports import locate_facets
    mesh = loaded.mesh
    facets = locate_facets(loaded, where)
    local = fem.locate_dofs_topological(V, mesh.topology.dim - 1, facets)
    imap = V.dofmap.index_map
    chosen = imap.local_to_global(np.asarray(local, dtype=np.int32)).astype(np.int64)
    chosen = np.unique(np.concatenate(mesh.comm.allgather(chosen)))
    return np.isin(surface.blocks, chosen)


def held_motion(term, values: np.ndarray) -> np.ndarray:
    """The parts of a motion (its values at the surface nodes, (n, 3)) the contact term's obstacles resist at rest,
    at the nodes nearest each: all of it with friction, its normal component without (no hold on sliding); an
    obstacle farther than dhat resists nothing (a static solve's first Newton step would be singular)."""
    rows = []
    for ob in term.obstacles:
        d, g = ob.derivatives(term.surface.rest, order=1)
        if d.min() >= term.dhat:
            continue                           # beyond the barrier's reach: it holds nothing at the start
        near = d <= d.min() + 0.5 * term.dhat
        rows.append(values[near].ravel() if ob.friction > 0 else np.einsum("ij,ij->i", g[near], values[near]))
    for k, ob in enumerate(term.files):            # a file: the nodes it pushes at rest, along the push
        push = term.filec.only(term.surface.rest, k)
        near = np.linalg.norm(push, axis=1) > 0.0
        n = push[near] / np.linalg.norm(push[near], axis=1)[:, None]
        rows.append(values[near].ravel() if ob.friction > 0 else np.einsum("ij,ij->i", n, values[near]))
    return np.concatenate(rows) if rows else np.zeros(0)
