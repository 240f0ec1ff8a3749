"""The part as the balance design sees it, on each rank: owned cells (global ids, corners, moment
integrals on the current shape), which of them may be carved, and the geometry nodes (for contact)."""
from __future__ import annotations

from dataclasses import dataclass
import time

from dolfinx import cpp, fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from scipy.spatial import cKDTree

from fem_forms.design.mass_properties import cell_moments
from fem_forms.output.fields import node_values


def _cell_nodes(mesh) -> np.ndarray:
    n = mesh.topology.index_map(3).size_local
    dofs = mesh.geometry.dofmap.array.reshape(-1, len(mesh.geometry.dofmap.links(0)))
    return dofs[:n]


def surface_points(mesh) -> np.ndarray:
    """Points sampled on the boundary (facet corners, edge midpoints, facet centroids) of all ranks, each
    corner and edge once per rank (repeated points make a k-d tree's leaves big and its queries slow)."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    nodes = cpp.mesh.entities_to_geometry(mesh._mesh, tdim - 1, facets, False)
    x = mesh.geometry.x
    if len(nodes):
        k = nodes.shape[1]
        edges = np.sort(np.concatenate([nodes[:, [i, (i + 1) % k]] for i in range(k)]), axis=1)
        edges = np.unique(edges[:, 0] * len(x) + edges[:, 1])
        local = np.vstack([x[np.unique(nodes)], (x[edges // len(x)] + x[edges % len(x)]) / 2,
                           x[nodes].mean(axis=1)])
    else:
        local = np.empty((0, 3))
    return np.vstack(mesh.comm.allgather(local))


def _beyond(x: np.ndarray, cell_nodes: np.ndarray, surface: np.ndarray, shell: float) -> np.ndarray:
    """Cells whose nodes all lie farther than `shell` from every surface point. Each node is asked once
    (not once per cell it belongs to) and the search stops at the shell (distance_upper_bound): finding an
    interior point's nearest point on a 2-D sheet of points is what costs."""
    if not len(cell_nodes):
        return np.zeros(0, bool)
    bound = np.nextafter(shell, np.inf)                   # a node at exactly `shell` stays in the wall
    dist, _ = cKDTree(surface).query(x, distance_upper_bound=bound)
    return (dist[cell_nodes] > shell).all(axis=1)


def _boundary_nodes(mesh) -> np.ndarray:
    """Owned geometry nodes on the boundary: only they can touch the ground (an interior node near the
    bottom would bend a rocking surface's sphere fit inwards)."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    idx = np.unique(cpp.mesh.entities_to_geometry(mesh._mesh, tdim - 1, facets, False).ravel())
    return idx[idx < mesh.geometry.index_map().size_local]


@dataclass
class Body:
    """One rank's share of the part on one shape (rest, or deformed by u)."""
    mesh: object
    ids: np.ndarray              # global (input) index of each owned cell
    carvable: np.ndarray         # owned cells that may be carved
    moments: np.ndarray          # (owned cells, 10) on this shape
    corners: np.ndarray          # (owned cells, 4 or 8, 3) on this shape
    nodes: np.ndarray            # owned boundary geometry nodes on this shape
    node_index: np.ndarray       # their local geometry indices

    @classmethod
    def rest(cls, mesh, shell: float, timing: dict | None = None) -> "Body":
        """The part on its rest shape; `timing` (if given) gets shell_s and moments_s (wall seconds)."""
        t0 = time.perf_counter()
        n = mesh.topology.index_map(3).size_local
        cn = _cell_nodes(mesh)
        corners = mesh.geometry.x[cn]
        carvable = _beyond(mesh.geometry.x, cn, surface_points(mesh), shell)
        t1 = time.perf_counter()
        moments = cell_moments(mesh)
        if timing is not None:
            timing.update(shell_s=t1 - t0, moments_s=time.perf_counter() - t1)
        ids = np.asarray(mesh.topology.original_cell_index[:n], dtype=np.int64)
        surface = _boundary_nodes(mesh)
        return cls(mesh, ids, carvable, moments, corners, mesh.geometry.x[surface].copy(), surface)

    def deformed(self, u: fem.Function) -> "Body":
        """The same cells on the shape X + u."""
        d = node_values(u)
        x = self.mesh.geometry.x + d
        return Body(self.mesh, self.ids, self.carvable, cell_moments(self.mesh, u), x[_cell_nodes(self.mesh)],
                    x[self.node_index], self.node_index)

    def centroids(self) -> np.ndarray:
        return self.corners.mean(axis=1)

    def contact_points(self, up: np.ndarray, tolerance: float) -> np.ndarray:
        """Nodes of all ranks within `tolerance` of the lowest point along -up."""
        h = self.nodes @ up
        low = self.mesh.comm.allreduce(float(h.min()) if len(h) else np.inf, op=MPI.MIN)
        return np.vstack(self.mesh.comm.allgather(self.nodes[h <= low + tolerance]))

    def lowest(self, direction: np.ndarray) -> float:
        h = self.nodes @ direction
        return self.mesh.comm.allreduce(float(h.min()) if len(h) else np.inf, op=MPI.MIN)

    def density(self, solid: np.ndarray, rho, fill: float) -> np.ndarray:
        """Density per owned cell for the solid fractions of the carvable ones (`rho`: one density, or one
        per owned cell)."""
        d = np.broadcast_to(np.asarray(rho, dtype=float), self.ids.shape).copy()
        d[self.carvable] = fill + (d[self.carvable] - fill) * solid
        return d
