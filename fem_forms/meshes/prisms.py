"""Prism (wedge) meshes. dolfinx 0.5.2 assembles cell integrals on prisms, but its python
``dolfinx.mesh.create_mesh`` has no entry for them (KeyError: 'prism'), so the mesh is made through the
C++ layer; and FFCx 0.5.0 refuses facet integrals on cells with two facet types ("Cell type prism not
supported for integral type exterior_facet"), so surface loads (traction, pressure) cannot be applied
on prism meshes; body loads and supports work. Serial only: with 2 ranks dolfinx 0.5.2 hangs in
``mesh.topology.create_entities(2)`` (the facets of a distributed prism mesh), which every support needs."""
from __future__ import annotations

from dolfinx import cpp, mesh as dmesh
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.errors import InputError

SURFACE_LOADS_UNSUPPORTED = ("FFCx 0.5.0 (dolfinx 0.5.2) cannot integrate over the facets of prisms "
                             "(\"Cell type prism not supported for integral type exterior_facet\")")


def create_prism_mesh(comm: MPI.Comm, cells: np.ndarray, points: np.ndarray) -> dmesh.Mesh:
    """A distributed mesh of linear prisms from rank-0 arrays in dolfinx order (triangle a b c, then
    the triangle a' b' c' above it); other ranks pass empty arrays."""
    cmap = cpp.fem.CoordinateElement(dmesh.CellType.prism, 1)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell("prism"), 1))
    topology = cpp.graph.AdjacencyList_int64(np.ascontiguousarray(cells, dtype=np.int64))
    m = cpp.mesh.create_mesh(comm, topology, cmap, np.ascontiguousarray(points, dtype=np.float64),
                             dmesh.GhostMode.shared_facet, cpp.mesh.create_cell_partitioner())
    return dmesh.Mesh(m, domain)


def prism_box_arrays(lo, hi, n) -> tuple[np.ndarray, np.ndarray]:
    """Points and cells of a box of nx x ny x nz hexahedral blocks, each split into two prisms whose
    triangles lie in x-y planes (extruded along z), as gmsh makes by extruding a triangulated face."""
    nx, ny, nz = (int(k) for k in n)
    axes = [np.linspace(lo[i], hi[i], n[i] + 1) for i in range(3)]
    Z, Y, X = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])

    def v(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i

    cells = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                a, b, c, d = v(i, j, k), v(i + 1, j, k), v(i + 1, j + 1, k), v(i, j + 1, k)
                up = (ny + 1) * (nx + 1)
                cells.append([a, b, c, a + up, b + up, c + up])
                cells.append([a, c, d, a + up, c + up, d + up])
    return points, np.array(cells, dtype=np.int64)


def create_prism_box(comm: MPI.Comm, lo, hi, n) -> dmesh.Mesh:
    """The box [lo, hi] as prisms (see prism_box_arrays); serial only (see the module's docstring)."""
    if comm.size > 1:
        raise InputError("mesh.cell = 'prism': serial runs only (with MPI, dolfinx 0.5.2 hangs creating "
                         "the facets of a distributed prism mesh)")
    if comm.rank == 0:
        points, cells = prism_box_arrays(lo, hi, n)
    else:
        points, cells = np.empty((0, 3)), np.empty((0, 6), dtype=np.int64)
    return create_prism_mesh(comm, cells, points)


def boundary_triangles(mesh: dmesh.Mesh, facets: np.ndarray) -> np.ndarray:
    """Geometry node indices (n, 3) of the given facets of a prism mesh as triangles, quadrilateral
    facets split in two (dolfinx's entities_to_geometry stops with "More work needed for prism cells")."""
    topology = mesh.topology
    topology.create_connectivity(2, 0)
    c2v = topology.connectivity(3, 0).array
    nodes = mesh.geometry.dofmap.array                    # P1 geometry: same order as the cell's vertices
    vertex_node = np.empty(topology.index_map(0).size_local + topology.index_map(0).num_ghosts, dtype=np.int64)
    vertex_node[c2v] = nodes
    f2v = topology.connectivity(2, 0)
    triangles = []
    for f in facets:
        v = vertex_node[f2v.links(f)]
        if len(v) == 3:
            triangles.append(v)
        else:                                             # tensor-product order 0 1 / 2 3
            triangles += [v[[0, 1, 3]], v[[0, 3, 2]]]
    return np.array(triangles, dtype=np.int64).reshape(-1, 3)
