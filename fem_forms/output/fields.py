"""Fields for ParaView (XDMF, P1 and DG0) and gathering of mesh and fields on rank 0 for output."""
from __future__ import annotations

from pathlib import Path

from dolfinx import cpp, fem, io, mesh as dmesh
import numpy as np

from fem_forms.meshes import prisms


def p1_interpolant(f: fem.Function, name: str | None = None) -> fem.Function:
    """f on the mesh's P1 vector or scalar space (XDMF stores P1 only)."""
    mesh = f.function_space.mesh
    shape = f.ufl_shape
    V1 = fem.VectorFunctionSpace(mesh, ("Lagrange", 1)) if shape else fem.FunctionSpace(mesh, ("Lagrange", 1))
    g = fem.Function(V1, name=name or f.name)
    g.interpolate(f)
    return g


def cell_function(mesh, values: np.ndarray, name: str) -> fem.Function:
    """A DG0 Function holding `values` on the mesh's first len(values) local cells (owned, maybe ghosts too);
    ghosts then take their owners' values."""
    f = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name=name)
    f.x.array[f.function_space.dofmap.list.array[:len(values)]] = values
    f.x.scatter_forward()
    return f


def write_fields(path: Path, mesh, functions: list) -> None:
    """One XDMF file (+ .h5) with the mesh and the given P1/DG0 functions, for ParaView."""
    with io.XDMFFile(mesh.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        for f in functions:
            xdmf.write_function(f)


def node_values(f: fem.Function) -> np.ndarray:
    """Values of f (through its P1 interpolant) at this rank's geometry nodes, shape (nodes, bs)."""
    mesh = f.function_space.mesh
    f1 = p1_interpolant(f) if f.function_space.ufl_element().degree() != 1 else f
    gdofs = mesh.geometry.dofmap.array.reshape(-1, len(mesh.geometry.dofmap.links(0)))
    vdofs = f1.function_space.dofmap.list.array.reshape(gdofs.shape)
    node_to_dof = np.empty(len(mesh.geometry.x), dtype=np.int64)
    node_to_dof[gdofs.ravel()] = vdofs.ravel()
    bs = f1.function_space.dofmap.index_map_bs
    return f1.x.array.reshape(-1, bs)[node_to_dof]


def gather_facet_groups(loaded) -> dict | None:
    """Named facet groups of a LoadedMesh on rank 0 as {name: faces (global node indices, gmsh order)}."""
    mesh = loaded.mesh
    groups = {}
    if loaded.facet_tags is not None:
        imap = mesh.geometry.index_map()
        fdim = mesh.topology.dim - 1
        nown = mesh.topology.index_map(fdim).size_local
        for name, tag in loaded.groups.items():
            facets = loaded.facet_tags.indices[loaded.facet_tags.values == tag]
            facets = facets[facets < nown]
            nodes = cpp.mesh.entities_to_geometry(mesh._mesh, fdim, facets, False)
            if mesh.topology.cell_name() == "hexahedron" and len(nodes):
                nodes = nodes[:, [0, 1, 3, 2]]
            groups[name] = imap.local_to_global(nodes.ravel()).reshape(nodes.shape) if len(nodes) \
                else np.empty((0, nodes.shape[1] if nodes.ndim == 2 else 3), dtype=np.int64)
    parts = mesh.comm.gather(groups, root=0)
    if mesh.comm.rank != 0:
        return None
    return {n: np.vstack([p[n] for p in parts if len(p[n])]) for n in loaded.groups}


def gather_mesh(mesh, point_shift: np.ndarray | None = None):
    """The whole mesh on rank 0 as (points, cells in VTK/gmsh vertex order, cell type name), with
    points moved by point_shift (per local geometry node) if given; None on other ranks."""
    imap = mesh.geometry.index_map()
    nown = imap.size_local
    x = mesh.geometry.x + (0.0 if point_shift is None else point_shift)
    glob = imap.local_to_global(np.arange(len(x), dtype=np.int32))
    tdim = mesh.topology.dim
    ncells = mesh.topology.index_map(tdim).size_local
    gdofs = mesh.geometry.dofmap.array.reshape(-1, len(mesh.geometry.dofmap.links(0)))[:ncells]
    cells = glob[gdofs]
    name = mesh.topology.cell_name()
    if name == "hexahedron":
        cells = cells[:, [0, 1, 3, 2, 4, 5, 7, 6]]            # dolfinx tensor order -> VTK order
    parts = mesh.comm.gather((glob[:nown], x[:nown], cells), root=0)
    if mesh.comm.rank != 0:
        return None
    points = np.empty((imap.size_global, 3))
    for g, p, _ in parts:
        points[g] = p
    return points, np.vstack([c for _, _, c in parts]), name


def gather_cell_values(mesh, values: np.ndarray) -> np.ndarray | None:
    """One value per owned cell of every rank, on rank 0 in gather_mesh's cell order (None elsewhere)."""
    ncells = mesh.topology.index_map(mesh.topology.dim).size_local
    parts = mesh.comm.gather(np.asarray(values)[:ncells], root=0)
    return np.concatenate(parts) if mesh.comm.rank == 0 else None


def boundary_surface(u: fem.Function, scalar: fem.Function | list | None = None, marks: list | None = None):
    """Rank 0 gets (points, triangles-or-quads, displacement at points) of the mesh's boundary, and a scalar
    field's values at those points as a fourth entry when `scalar` is given (the damage of a crack picture; a
    list of P1 fields: their values as the columns of an (n, k) array), and
    each polygon's marks as a last entry when `marks` (local facet index arrays) are given: bit i set when the
    polygon's facet is in marks[i] (a support's or a load's facets in the report); other ranks get None.
    Gathering is for pictures and the report only."""
    mesh = u.function_space.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    nfo = mesh.topology.index_map(tdim - 1).size_local
    facets = facets[facets < nfo]
    if mesh.topology.cell_name() == "prism":
        geom = prisms.boundary_triangles(mesh, facets)
    else:
        geom = cpp.mesh.entities_to_geometry(mesh._mesh, tdim - 1, facets, False)
    if mesh.topology.cell_name() == "hexahedron" and len(geom):
        geom = geom[:, [0, 1, 3, 2]]                 # tensor-product order -> polygon order
    values = node_values(u)
    nodes = np.unique(geom)
    if isinstance(scalar, list):
        extra = np.column_stack([node_values(f)[nodes, 0] for f in scalar]) if scalar else np.zeros((len(nodes), 0))
    else:
        extra = node_values(scalar)[nodes, 0] if scalar is not None else np.zeros(len(nodes))
    bits = np.zeros(len(facets), dtype=np.int64)
    for i, m in enumerate(marks or []):
        bits |= np.isin(facets, m).astype(np.int64) << i
    if len(geom) != len(facets):                     # prisms: quadrilateral facets in two triangles: unmarked
        bits = np.zeros(len(geom), dtype=np.int64)
    local = (mesh.geometry.x[nodes], values[nodes], np.searchsorted(nodes, geom), extra, bits)
    parts = mesh.comm.gather(local, root=0)
    if mesh.comm.rank != 0:
        return None
    pts, disp, polys, scalars, marked, off = [], [], [], [], [], 0
    for x, d, p, e, b in parts:
        pts.append(x)
        disp.append(d)
        polys.append(p + off)
        scalars.append(e)
        marked.append(b)
        off += len(x)
    out = np.vstack(pts), np.vstack([p for p in polys if len(p)]), np.vstack(disp)
    out = out if scalar is None else (*out, np.concatenate(scalars))
    return out if marks is None else (*out, np.concatenate(marked))

