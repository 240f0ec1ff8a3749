"""The contact pressure at the surface's corner nodes (the mesh's vertices), from the barriers' nodal pushes.
On degree 2 the pushes follow the consistent nodal loads (corners carry almost nothing, edge nodes a third of
a triangle's load each): push per node area would zigzag from node to node. Each other node's push and
touching area are handed to its corner neighbours (half to each end of an edge, a quarter to each corner of
a quadrilateral: the P1 hat functions' values there) before the division."""
from __future__ import annotations

from mpi4py import MPI
import numpy as np

from fem_forms.meshes.boundary_surface import BoundarySurface


def vertex_pressure(surface: BoundarySurface, push: np.ndarray, corner: np.ndarray) -> np.ndarray:
    """(n,) the pressure (Pa) at the corner nodes (`corner` marks them), 0 at the others: the pushes (N, (n,))
    over the rest area of the surface triangles whose nodes all push, both gathered onto the corners."""
    touching = push > 0.0
    whole = touching[surface.faces].all(axis=1)         # triangles whose nodes all push
    area = np.zeros(surface.size)
    for k in range(3):
        np.add.at(area, surface.faces[whole, k], surface.face_areas()[whole] / 3.0)
    e = surface.edges()
    share = {}                                  # other node -> its corner neighbours
    for a, b in e:
        if corner[a] and not corner[b]:
            share.setdefault(b, []).append(a)
        elif corner[b] and not corner[a]:
            share.setdefault(a, []).append(b)
    force, held = np.where(corner, push, 0.0), np.where(corner, area, 0.0)
    for node, corners in share.items():
        np.add.at(force, corners, push[node] / len(corners))
        np.add.at(held, corners, area[node] / len(corners))
    out = np.zeros(surface.size)
    ok = corner & (held > 0.0)
    out[ok] = force[ok] / held[ok]
    return out


def add_pressure_field(term, f) -> None:
    """Add the contact term's pressure (Pa) at the mesh's vertices into the P1 Function f, zero off the contact:
    the barriers' pushes per touching area, gathered onto the corner nodes."""
    from scipy.spatial import cKDTree
    s = term.surface
    xyz = f.function_space.tabulate_dof_coordinates()
    dist, node = cKDTree(s.rest).query(xyz)
    mine = dist <= 1e-9 * term.diagonal                  # this rank's vertices on the surface
    corner = np.zeros(s.size, np.int32)
    corner[node[mine]] = 1
    f.function_space.mesh.comm.Allreduce(MPI.IN_PLACE, corner, op=MPI.MAX)      # a vertex of any rank
    push = term.nodal_pressure(term.state) * s.area
    f.x.array[mine] += vertex_pressure(s, push, corner.astype(bool))[node[mine]]
