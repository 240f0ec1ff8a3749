"""The part's outer surface as triangles on the displacement's nodes, the same on every rank: what contact
measures distances on and what deformed.stl shows. The surface is small next to the volume, so it is gathered
whole; each rank remembers which of its nodes it owns, to read displacements and to add forces."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError


@dataclass
class BoundarySurface:
    """Surface nodes (global dof blocks of a vector Lagrange space), their rest positions, outward triangles and
    lumped rest areas; identical on every rank. `owned` indexes the nodes this rank owns, `owned_local` gives
    their local block numbers."""
    blocks: np.ndarray          # (n,) global block index of each surface node
    rest: np.ndarray            # (n, 3) rest positions
    faces: np.ndarray           # (m, 3) triangles, indices into blocks, outward by the right-hand rule
    area: np.ndarray            # (n,) a third of the rest area of the triangles around each node
    owned: np.ndarray           # indices into blocks of the nodes this rank owns
    owned_local: np.ndarray     # their local block numbers
    comm: MPI.Comm

    @property
    def size(self) -> int:
        return len(self.blocks)

    def displacement(self, x: PETSc.Vec) -> np.ndarray:
        """(n, 3) displacement of every surface node from the owned entries of x (a collective call)."""
        mine = x.array_r.reshape(-1, 3)[self.owned_local]
        parts = self.comm.allgather((self.owned, mine))
        u = np.empty((self.size, 3))
        for idx, vals in parts:
            u[idx] = vals
        return u

    def positions(self, x: PETSc.Vec) -> np.ndarray:
        """(n, 3) current positions rest + u of the surface nodes."""
        return self.rest + self.displacement(x)

    def face_areas(self) -> np.ndarray:
        """(m,) rest area of each triangle."""
        p = self.rest[self.faces]
        return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)

    def edges(self) -> np.ndarray:
        """(k, 2) the triangles' edges, each once (sorted node pairs)."""
        e = np.sort(np.concatenate([self.faces[:, [0, 1]], self.faces[:, [1, 2]], self.faces[:, [2, 0]]]), axis=1)
        return np.unique(e, axis=0)


def _pair(coords: np.ndarray, corners: list, k: int) -> tuple:
    """The two corners whose midpoint lies nearest to node k (the edge node k sits on)."""
    pairs = [(a, b) for i, a in enumerate(corners) for b in corners[i + 1:]]
    return min(pairs, key=lambda ab: np.linalg.norm(coords[k] - (coords[ab[0]] + coords[ab[1]]) / 2))


def _pattern(coords: np.ndarray, kinds: np.ndarray) -> tuple[list, list]:
    """One facet's corners and its triangles, as positions among its nodes: a triangle (3 corners) itself, a
    quadrilateral split along a diagonal; degree 2 facets into 4 (triangle) or 8 (quadrilateral, around its
    centre node) triangles on the corner, edge and centre nodes. `kinds` holds each node's entity dimension (0
    corner, 1 edge, 2 face). The same for every facet at the same place in its cell (the dof layout's)."""
    corners = [int(i) for i in np.flatnonzero(kinds == 0)]
    edge = {_pair(coords, corners, int(k)): int(k) for k in np.flatnonzero(kinds == 1)}
    local = []
    if len(corners) == 3 and not edge:
        local = [corners]
    elif len(corners) == 4 and not edge:       # along the diagonal from corner 0 to its opposite corner
        a, i, j, opp = corners                     # a quadrilateral's corners in tensor order: 3 faces 0
        local = [[a, i, opp], [a, opp, j]]
    elif len(corners) == 3:
        a, b, c = corners
        ab, bc, ca = (edge[tuple(sorted(p, key=corners.index))] for p in ((a, b), (b, c), (a, c)))
        local = [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
    else:
        centre = int(np.flatnonzero(kinds == 2)[0])
        for v in corners:
            ea, eb = [k for pair, k in edge.items() if v in pair]
            local += [[v, ea, centre], [v, centre, eb]]
    return corners, local


def _outward(nodes: np.ndarray, coords: np.ndarray, corners: list, local: list, inside: np.ndarray) -> np.ndarray:
    """(facets, triangles, 3) the triangles `local` of facets whose nodes are `nodes` (facets, k) at `coords`
    (facets, k, 3), each turned so that its normal points away from its cell's centroid `inside` (facets, 3)."""
    p = coords[:, corners]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    normal[np.einsum("ij,ij->i", normal, p.mean(axis=1) - inside) < 0] *= -1.0
    tri = np.asarray(local)
    q = coords[:, tri]                                   # (facets, triangles, 3 corners, 3)
    flip = np.einsum("fti,fi->ft", np.cross(q[:, :, 1] - q[:, :, 0], q[:, :, 2] - q[:, :, 0]), normal) < 0
    out = nodes[:, tri]
    out[flip] = out[flip][:, [0, 2, 1]]
    return out


def boundary_surface(V: fem.FunctionSpace) -> BoundarySurface:
    """The outer surface of V's mesh on V's nodes (a vector Lagrange space of degree 1 or 2 on tetrahedra or
    hexahedra: degree 2 facets are split into triangles on their corner, edge and centre nodes), gathered on
    every rank."""
    mesh = V.mesh
    degree = V.ufl_element().degree()
    if degree > 2:
        raise InputError(f"contact: elements of degree 1 or 2 (this space's is {degree})")
    tdim, fdim = mesh.topology.dim, mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, tdim)
    mesh.topology.create_connectivity(tdim, fdim)
    f2c, c2f = mesh.topology.connectivity(fdim, tdim), mesh.topology.connectivity(tdim, fdim)
    imap = V.dofmap.index_map
    layout = V.dofmap.dof_layout
    xyz = V.tabulate_dof_coordinates()
    owned_facets = dmesh.exterior_facet_indices(mesh.topology)
    owned_facets = owned_facets[owned_facets < mesh.topology.index_map(fdim).size_local]
    cell = mesh.topology.cell_name()
    if cell not in ("tetrahedron", "hexahedron"):
        raise InputError(f"contact: tetrahedra or hexahedra only (this mesh has {cell} cells)")
    n_corners, n_edges, per_cell = {"tetrahedron": (4, 6, 4), "hexahedron": (8, 12, 6)}[cell]   # per_cell: facets
    cells = f2c.array[f2c.offsets[owned_facets]]                      # an exterior facet's one cell
    place = np.argmax(c2f.array.reshape(-1, per_cell)[cells] == owned_facets[:, None], axis=1)
    cell_dofs = V.dofmap.list.array.reshape(-1, layout.num_dofs)[cells]
    closures = np.array([layout.entity_closure_dofs(fdim, j) for j in range(per_cell)])
    nodes = np.take_along_axis(cell_dofs, closures[place], axis=1)   # (facets, nodes of a facet), local
    glob = imap.local_to_global(nodes.ravel()).astype(np.int64).reshape(nodes.shape)
    inside = xyz[cell_dofs[:, :n_corners]].mean(axis=1)
    tris = None
    for j in np.unique(place):                          # facets at the same place in their cells: one pattern
        at = np.flatnonzero(place == j)
        kinds = (closures[j] >= n_corners).astype(int) + (closures[j] >= n_corners + n_edges)
        corners, local = _pattern(xyz[nodes[at[0]]], kinds)
        if tris is None:
            tris = np.empty((len(place), len(local), 3), dtype=np.int64)
        tris[at] = _outward(glob[at], xyz[nodes[at]], corners, local, inside[at])
    tris = np.zeros((0, 3), dtype=np.int64) if tris is None else tris.reshape(-1, 3)
    blocks_local, first = np.unique(glob.ravel(), return_index=True)
    coords = xyz[nodes.ravel()[first]]
    gathered = mesh.comm.allgather((tris, blocks_local, coords))
    faces = np.concatenate([g[0] for g in gathered])
    blocks = np.concatenate([g[1] for g in gathered])
    rest_all = np.concatenate([g[2].reshape(-1, 3) for g in gathered])
    blocks, first = np.unique(blocks, return_index=True)
    rest = rest_all[first]
    faces = np.searchsorted(blocks, faces)
    lo, hi = imap.local_range
    owned = np.flatnonzero((blocks >= lo) & (blocks < hi))
    surface = BoundarySurface(blocks, rest, faces, np.zeros(len(blocks)), owned,
                              (blocks[owned] - lo).astype(np.int32), mesh.comm)
    for k in range(3):
        np.add.at(surface.area, faces[:, k], surface.face_areas() / 3.0)
    return surface
