"""Results on disk: results.json (atomic), XDMF fields for ParaView, PNG pictures, Newton history."""
from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import ufl
from dolfinx import cpp, fem, io, mesh as dmesh
from mpi4py import MPI


def _clean(obj):
    """JSON-safe copy: NaN/Inf become null, numpy scalars become Python numbers."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def write_json_atomic(path: Path, data: dict, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """Rank 0 writes to a temporary file beside `path` and renames it: complete or absent."""
    if comm.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".results-", suffix=".json")
        try:
            with os.fdopen(fd, "w") as f:
                json.dump(_clean(data), f, indent=2)
            os.chmod(tmp, 0o644)
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    comm.barrier()


def write_newton_history(path: Path, steps: list, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """CSV: step, load factor, accepted, SNES reason, Newton iteration, residual norm."""
    if comm.rank == 0:
        lines = ["step,load,accepted,reason,iteration,residual"]
        for k, s in enumerate(steps):
            for i, r in enumerate(s.residuals):
                lines.append(f"{k},{s.load:.6g},{int(s.accepted)},{s.reason},{i},{r:.6e}")
        path.write_text("\n".join(lines) + "\n")
    comm.barrier()


def p1_interpolant(f: fem.Function, name: str | None = None) -> fem.Function:
    """f on the mesh's P1 vector or scalar space (XDMF stores P1 only)."""
    mesh = f.function_space.mesh
    shape = f.ufl_shape
    V1 = fem.VectorFunctionSpace(mesh, ("Lagrange", 1)) if shape else fem.FunctionSpace(mesh, ("Lagrange", 1))
    g = fem.Function(V1, name=name or f.name)
    g.interpolate(f)
    return g


def cellwise(expr, mesh, name: str) -> fem.Function:
    """A UFL expression evaluated at cell midpoints into a DG0 function (e.g. von Mises stress)."""
    shape = expr.ufl_shape
    space = fem.FunctionSpace(mesh, ("DG", 0)) if not shape else fem.VectorFunctionSpace(mesh, ("DG", 0))
    g = fem.Function(space, name=name)
    g.interpolate(fem.Expression(expr, space.element.interpolation_points()))
    return g


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


def boundary_surface(u: fem.Function):
    """Rank 0 gets (points, triangles-or-quads, displacement at points) of the mesh's boundary;
    other ranks get None. Gathering is for the picture only."""
    mesh = u.function_space.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    nfo = mesh.topology.index_map(tdim - 1).size_local
    facets = facets[facets < nfo]
    geom = cpp.mesh.entities_to_geometry(mesh._mesh, tdim - 1, facets, False)
    if mesh.topology.cell_name() == "hexahedron" and len(geom):
        geom = geom[:, [0, 1, 3, 2]]                 # tensor-product order -> polygon order
    values = node_values(u)
    nodes = np.unique(geom)
    local = (mesh.geometry.x[nodes], values[nodes], np.searchsorted(nodes, geom))
    parts = mesh.comm.gather(local, root=0)
    if mesh.comm.rank != 0:
        return None
    pts, disp, polys, off = [], [], [], 0
    for x, d, p in parts:
        pts.append(x)
        disp.append(d)
        polys.append(p + off)
        off += len(x)
    return np.vstack(pts), np.vstack([p for p in polys if len(p)]), np.vstack(disp)


def style_axes(ax, lo: np.ndarray, hi: np.ndarray) -> None:
    """True-proportion 3D axes spanning [lo, hi], with few ticks on short axes, seen from the side."""
    import matplotlib.ticker
    ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
    span = np.maximum(hi - lo, 1e-3 * (hi - lo).max())
    ax.set_box_aspect(span)
    for axis, s in zip((ax.xaxis, ax.yaxis, ax.zaxis), span):
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(max(2, int(6 * s / span.max()))))
    ax.set_xlabel("x [m]"), ax.set_ylabel("y [m]"), ax.set_zlabel("z [m]")
    ax.view_init(elev=15, azim=-75)


def picture(path: Path, u: fem.Function, title: str, scale: float = 1.0) -> None:
    """PNG of the deformed boundary coloured by displacement magnitude, undeformed outline in grey."""
    surf = boundary_surface(u)
    if surf is None:
        u.function_space.mesh.comm.barrier()
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    X, polys, d = surf
    x = X + scale * d
    mag = np.linalg.norm(d, axis=1)
    fig = plt.figure(figsize=(9, 6))
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Poly3DCollection(X[polys], facecolor=(0.6, 0.6, 0.6, 0.08),
                                         edgecolor=(0.4, 0.4, 0.4, 0.15), linewidths=0.2))
    cmap = plt.get_cmap("viridis")
    vmax = mag.max() if mag.max() > 0 else 1.0
    faces = Poly3DCollection(x[polys], facecolors=cmap(mag[polys].mean(axis=1) / vmax),
                             edgecolor=(0, 0, 0, 0.15), linewidths=0.2)
    ax.add_collection3d(faces)
    allp = np.vstack([X, x])
    style_axes(ax, allp.min(axis=0), allp.max(axis=0))
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, vmax))
    fig.colorbar(sm, ax=ax, shrink=0.6, label="|u| [m]")
    ax.set_title(title + ("" if scale == 1.0 else f" (displacement x{scale:g})"))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    u.function_space.mesh.comm.barrier()
