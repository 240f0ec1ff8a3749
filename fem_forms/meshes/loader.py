"""The one mesh loader: the built-in box (tetrahedra, hexahedra, prisms), gmsh-generated solids and
mesh files, refused before they are built when they would not fit in memory. Non-box meshes are built
on rank 0 as MeshArrays, checked for degenerate and inverted cells, and then distributed by
``dolfinx.mesh.create_mesh`` with their named groups (LoadedMesh). Also the mesh's bounding box and
size (a length scale for tolerances).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from dolfinx import cpp, mesh as dmesh
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.meshes import resources, surfaces
from fem_forms.meshes.arrays import MeshArrays, check_cells
from fem_forms.meshes.files import read_mesh_file, read_surface_file, scale_arrays
from fem_forms.meshes.cad import mesh_cad
from fem_forms.meshes.gmsh_models import generate_solid
from fem_forms.meshes.groups import distribute_cell_groups
from fem_forms.meshes.prisms import create_prism_box
from fem_forms.scene import MeshSpec
from fem_forms.scene.spec import CAD_SUFFIXES, SURFACE_SUFFIXES


@dataclass
class LoadedMesh:
    mesh: dmesh.Mesh
    facet_tags: object | None      # MeshTags of the named groups, or None
    groups: dict                   # surface group name -> tag value
    cells: dict = field(default_factory=dict)    # volume group name -> local cell indices
    curves: dict = field(default_factory=dict)   # curve group name -> (k, 2, 3) edge end points (all ranks)
    points: dict = field(default_factory=dict)   # point group name -> (k, 3) coordinates (all ranks)
    info: dict = field(default_factory=dict)     # cell count, source, quality (results.json "mesh")
    cell_fields: dict = field(default_factory=dict)   # a mesh file's cell data: name -> (local cells, k)

    def group_names(self) -> str:
        """The mesh's named groups by kind, for messages."""
        kinds = (("volumes", self.cells), ("surfaces", self.groups), ("curves", self.curves),
                 ("points", self.points))
        return "; ".join(f"{k} {', '.join(sorted(g))}" for k, g in kinds if g) or "none"


def _on_root(comm: MPI.Comm, build):
    """Run build() on rank 0; an error there is raised on every rank as one InputError line (a reader's
    or gmsh's own exception must not leave the other ranks waiting in the broadcast)."""
    result, error = None, None
    if comm.rank == 0:
        try:
            result = build()
        except InputError as e:
            error = str(e)
        except Exception as e:                            # noqa: BLE001 (a file or gmsh failure)
            error = f"mesh: cannot be built ({type(e).__name__}: {' '.join(str(e).split())[:200]})"
    error = comm.bcast(error, root=0)
    if error is not None:
        raise InputError(error)
    return result


def distribute(comm: MPI.Comm, arrays: MeshArrays | None) -> LoadedMesh:
    """Create a distributed dolfinx mesh (and facet tags of the named groups) from rank-0 arrays."""
    cell_type, names, volumes, curves, points, info, fields = comm.bcast(
        (arrays.cell_type, list(arrays.facet_groups), list(arrays.cell_groups), arrays.curve_groups,
         arrays.point_groups, arrays.info, arrays.cell_fields) if comm.rank == 0 else None, root=0)
    nv = 4 if cell_type == "tetrahedron" else 8
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell(cell_type), 1))
    dtype = dmesh.to_type(cell_type)
    perm = cpp.io.perm_gmsh(dtype, nv)       # gmshio.cell_perm_array, without importing gmsh
    if comm.rank == 0:
        cells, x = arrays.cells[:, perm], arrays.points
    else:
        cells, x = np.empty((0, nv), dtype=np.int64), np.empty((0, 3))
    mesh = dmesh.create_mesh(comm, cells, x, domain)
    cell_sets = distribute_cell_groups(
        mesh, arrays.cells if comm.rank == 0 else None, arrays.cell_groups if comm.rank == 0 else None,
        volumes, cell_type) if volumes else {}
    original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)      # each local cell's row
    extra = dict(cells=cell_sets, curves=curves, points=points, info=info,
                 cell_fields={n: np.asarray(v)[original] for n, v in fields.items()})
    if not names:
        return LoadedMesh(mesh, None, {}, **extra)
    fdim = mesh.topology.dim - 1
    fnv = 3 if cell_type == "tetrahedron" else 4
    fperm = cpp.io.perm_gmsh(cpp.mesh.cell_entity_type(dtype, fdim, 0), fnv)
    if comm.rank == 0:
        facets = np.vstack([arrays.facet_groups[n] for n in names])[:, fperm]
        values = np.concatenate([np.full(len(arrays.facet_groups[n]), i + 1, dtype=np.int32)
                                 for i, n in enumerate(names)])
    else:
        facets, values = np.empty((0, fnv), dtype=np.int64), np.empty(0, dtype=np.int32)
    ents, vals = cpp.io.distribute_entity_data(mesh._mesh, fdim, facets.astype(np.int64), values)
    mesh.topology.create_connectivity(fdim, mesh.topology.dim)
    tags = dmesh.meshtags_from_entities(mesh, fdim, cpp.graph.AdjacencyList_int32(ents),
                                        vals.astype(np.int32))
    return LoadedMesh(mesh, tags, {n: i + 1 for i, n in enumerate(names)}, **extra)


def load_mesh(spec: MeshSpec, comm: MPI.Comm = MPI.COMM_WORLD, degree: int = 1) -> LoadedMesh:
    """The one mesh loader every analysis uses. A mesh whose estimated memory (with elements of
    `degree`) exceeds the machine's is refused before it is built."""
    limit = resources.machine_memory(comm)
    if spec.generator == "box":
        counts = resources.box_counts(spec.cells, spec.cell, degree)
        resources.check_cap(counts[0], spec.max_cells, f"mesh.cells = {list(spec.cells)}")
        resources.check_fits(*counts, spec.cell, degree, f"mesh.cells = {list(spec.cells)}", limit)
        lo = np.array(spec.origin, dtype=float)
        hi = lo + np.array(spec.size, dtype=float)
        if spec.cell == "prism":
            loaded = LoadedMesh(create_prism_box(comm, lo, hi, list(spec.cells)), None, {})
        else:
            ct = dmesh.CellType.tetrahedron if spec.cell == "tetrahedron" else dmesh.CellType.hexahedron
            box = dmesh.create_box(comm, [lo, hi], list(spec.cells), cell_type=ct)
            loaded = LoadedMesh(box, None, {}, info={"source": "box", "cells": counts[0]})
        settle_coordinate_element(loaded.mesh)
        return loaded
    key = "mesh.file" if spec.generator == "file" else f"mesh ({spec.generator})"

    def build():
        if spec.generator == "file" and spec.file.suffix.lower() in CAD_SUFFIXES:
            arrays = mesh_cad(spec, limit, degree)
        elif spec.generator == "file" and spec.file.suffix.lower() in SURFACE_SUFFIXES:
            arrays = read_surface_file(spec.file, spec.h, limit, degree, spec.repair, spec.length_scale,
                                       spec.max_cells)
        elif spec.generator == "file":
            arrays = read_mesh_file(spec.file)
            resources.check_cap(len(arrays.cells), spec.max_cells, f"mesh.file = {spec.file.name!r}")
            arrays.info = {"source": spec.file.name, "cells": len(arrays.cells)}
            scale_arrays(arrays, spec.length_scale)
        else:
            counts = resources.tetrahedra_counts(resources.solid_volume(spec), spec.h, degree)
            resources.check_cap(counts[0], spec.max_cells, f"mesh.h = {spec.h}", estimated=True)
            resources.check_fits(*counts, "tetrahedron", degree, f"mesh.h = {spec.h}", limit)
            arrays = generate_solid(spec)
            arrays.info = {"source": f"{spec.generator} meshed by gmsh at h = {spec.h:.4g}",
                           **surfaces.quality(arrays.points, arrays.cells)}
        check_cells(arrays, key)
        return arrays

    return from_arrays(comm, build)


def from_arrays(comm: MPI.Comm, build) -> LoadedMesh:
    """The distributed mesh of the arrays build() makes on rank 0 (its errors: one InputError on every
    rank). Also how a mesh the package wrote itself (a designed rest shape) is loaded again."""
    loaded = distribute(comm, _on_root(comm, build))
    settle_coordinate_element(loaded.mesh)
    return loaded


def settle_coordinate_element(mesh: dmesh.Mesh) -> None:
    """Give the mesh's coordinate element the "equispaced" variant now. FFCx sets it the first time it
    compiles a form on the mesh (ffcx/analysis.py), which changes the mesh's repr and so the signature
    of every form built on that mesh afterwards: without this, forms of the second model in a process
    and of the next run carry other signatures than the first's and compile again (measured: the
    tangent and the energy of a neo-Hookean beam compiled twice)."""
    domain = mesh.ufl_domain()
    element = domain._ufl_coordinate_element
    if element._sub_element._variant is None:
        sub = ufl.FiniteElement(element.family(), element.cell(), element.degree(),
                                element.quadrature_scheme(), variant="equispaced")
        domain._ufl_coordinate_element = ufl.VectorElement(sub)


def mesh_size(mesh: dmesh.Mesh) -> float:
    """The diagonal of the mesh's bounding box (a length scale for tolerances)."""
    lo, hi = bounding_box(mesh)
    return float(np.linalg.norm(hi - lo))


def bounding_box(mesh: dmesh.Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Global (lower, upper) corners of the mesh."""
    x = mesh.geometry.x
    lo = x.min(axis=0) if len(x) else np.full(3, np.inf)
    hi = x.max(axis=0) if len(x) else np.full(3, -np.inf)
    glo, ghi = np.empty(3), np.empty(3)
    mesh.comm.Allreduce(np.ascontiguousarray(lo), glo, op=MPI.MIN)
    mesh.comm.Allreduce(np.ascontiguousarray(hi), ghi, op=MPI.MAX)
    return glo, ghi
