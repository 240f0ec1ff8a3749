"""The one mesh loader: the built-in box, gmsh-generated solids, and volume-mesh files, all on one loader.

Non-box meshes are built on rank 0 as plain arrays (points, cells, named facet groups), checked
for degenerate and inverted cells, and then distributed by ``dolfinx.mesh.create_mesh``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from pathlib import Path

from dolfinx import cpp, mesh as dmesh
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.meshes import resources, surfaces
from fem_forms.meshes.groups import cell_groups, curve_and_point_groups, distribute_cell_groups
from fem_forms.meshes.prisms import create_prism_box
from fem_forms.scene import MeshSpec
from fem_forms.scene.spec import SURFACE_SUFFIXES


@dataclass
class MeshArrays:
    """A volume mesh on one rank: points (n, 3), cells (m, k) in gmsh/VTK vertex order."""
    points: np.ndarray
    cells: np.ndarray
    cell_type: str                                     # "tetrahedron" | "hexahedron"
    facet_groups: dict = field(default_factory=dict)   # name -> (f, 3|4) vertex indices
    cell_groups: dict = field(default_factory=dict)    # volume group name -> rows of cells
    curve_groups: dict = field(default_factory=dict)   # curve group name -> (k, 2, 3) edge end points
    point_groups: dict = field(default_factory=dict)   # point group name -> (k, 3) coordinates
    info: dict = field(default_factory=dict)           # what results.json says about the mesh


@dataclass
class LoadedMesh:
    mesh: dmesh.Mesh
    facet_tags: object | None      # MeshTags of the named groups, or None
    groups: dict                   # surface group name -> tag value
    cells: dict = field(default_factory=dict)    # volume group name -> local cell indices
    curves: dict = field(default_factory=dict)   # curve group name -> (k, 2, 3) edge end points (all ranks)
    points: dict = field(default_factory=dict)   # point group name -> (k, 3) coordinates (all ranks)
    info: dict = field(default_factory=dict)     # cell count, source, quality (results.json "mesh")

    def group_names(self) -> str:
        """The mesh's named groups by kind, for messages."""
        kinds = (("volumes", self.cells), ("surfaces", self.groups), ("curves", self.curves),
                 ("points", self.points))
        return "; ".join(f"{k} {', '.join(sorted(g))}" for k, g in kinds if g) or "none"


# ----------------------------------------------------------------------------- quality checks
def cell_volumes(points: np.ndarray, cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Signed volume of tetrahedra; for hexahedra the smallest corner Jacobian times the cell volume
    scale, so a negative value means an inverted (or self-crossing) hexahedron."""
    p = points[cells]
    if cell_type == "tetrahedron":
        a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
        return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    # hexahedron, VTK order: bottom 0-1-2-3, top 4-5-6-7; three edges at each corner, right-handed
    corners = [(0, 1, 3, 4), (1, 2, 0, 5), (2, 3, 1, 6), (3, 0, 2, 7),
               (4, 7, 5, 0), (5, 4, 6, 1), (6, 5, 7, 2), (7, 6, 4, 3)]
    dets = []
    for o, i, j, k in corners:
        a, b, c = p[:, i] - p[:, o], p[:, j] - p[:, o], p[:, k] - p[:, o]
        dets.append(np.einsum("ij,ij->i", a, np.cross(b, c)))
    d = np.array(dets)
    return np.where(d.min(axis=0) < 0, d.min(axis=0), d.mean(axis=0))


def check_cells(arrays: MeshArrays, key: str) -> None:
    """Reject meshes with degenerate (zero-volume) or inverted cells, naming how many and where."""
    if len(arrays.cells) == 0:
        raise InputError(f"{key}: the mesh has no cells")
    vol = cell_volumes(arrays.points, arrays.cells, arrays.cell_type)
    p = arrays.points[arrays.cells]
    edge = np.linalg.norm(p[:, 1] - p[:, 0], axis=1)
    scale = max(float(np.mean(edge)), 1e-300) ** 3
    if np.mean(vol) < 0:   # consistently reversed orientation: flip to the convention
        vol = -vol
        arrays.cells = arrays.cells[:, _flip(arrays.cell_type)]
    degenerate = np.abs(vol) <= 1e-10 * scale
    inverted = (vol < 0) & ~degenerate
    if degenerate.any():
        i = int(np.argmax(degenerate))
        raise InputError(f"{key}: {int(degenerate.sum())} degenerate (zero-volume) cells, the first is "
                         f"cell {i} at {np.round(p[i].mean(axis=0), 6).tolist()}")
    if inverted.any():
        i = int(np.argmax(inverted))
        raise InputError(f"{key}: {int(inverted.sum())} inverted cells, the first is cell {i} at "
                         f"{np.round(p[i].mean(axis=0), 6).tolist()}")


def _flip(cell_type: str) -> list:
    return [0, 2, 1, 3] if cell_type == "tetrahedron" else [4, 5, 6, 7, 0, 1, 2, 3]


# ----------------------------------------------------------------------------- gmsh generators
def _gmsh_session():
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("fem_forms")
    return gmsh


def _gmsh_arrays(gmsh) -> MeshArrays:
    """Linear tetrahedra or hexahedra of the current gmsh model, with its named surface groups."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    tags, points = tags[order], coords.reshape(-1, 3)[order]
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags] = np.arange(len(tags))
    types, element_tags, nodes = gmsh.model.mesh.getElements(3)
    kinds = {4: ("tetrahedron", 4), 5: ("hexahedron", 8), 11: ("tetrahedron", 4), 12: ("hexahedron", 8)}
    found = [gmsh.model.mesh.getElementProperties(t)[0] for t in types]
    usable = [(t, n) for t, n in zip(types, nodes) if t in kinds]
    if not usable or len({kinds[t][0] for t, _ in usable}) != 1 or len(usable) != len(types):
        raise InputError(f"mesh: needs volume cells all tetrahedra or all hexahedra (found: "
                         f"{', '.join(found) or 'no volume cells'})")
    cell_type = kinds[usable[0][0]][0]
    nv = kinds[usable[0][0]][1]
    per = [gmsh.model.mesh.getElementProperties(t)[3] for t, _ in usable]
    cells = np.vstack([index[n.reshape(-1, k)[:, :nv]] for (t, n), k in zip(usable, per)])
    volumes = cell_groups(gmsh, np.concatenate([np.asarray(t) for t in element_tags]))
    curves, points_named = curve_and_point_groups(gmsh, points, index)
    groups = {}
    for dim, tag in gmsh.model.getPhysicalGroups(2):
        name = gmsh.model.getPhysicalName(dim, tag) or str(tag)
        facets = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            ftypes, _, fnodes = gmsh.model.mesh.getElements(2, ent)
            for ft, fn in zip(ftypes, fnodes):
                k = gmsh.model.mesh.getElementProperties(ft)[3]
                corner = 3 if cell_type == "tetrahedron" else 4
                facets.append(index[fn.reshape(-1, k)[:, :corner]])
        if facets:
            groups[name] = np.vstack(facets)
    return _compact(MeshArrays(points, cells, cell_type, groups, volumes, curves, points_named))


def _compact(a: MeshArrays) -> MeshArrays:
    """Drop points no cell uses (geometry points, midside nodes) and renumber."""
    used = np.unique(a.cells)
    if len(used) == len(a.points):
        return a
    new = np.full(len(a.points), -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    # facets touching unused nodes (degenerate surfaces, e.g. the revolution axis) are dropped
    groups = {n: new[f][np.all(new[f] >= 0, axis=1)] for n, f in a.facet_groups.items()}
    return MeshArrays(a.points[used], new[a.cells], a.cell_type, {n: f for n, f in groups.items() if len(f)},
                      a.cell_groups, a.curve_groups, a.point_groups, a.info)


def _generate(spec: MeshSpec) -> MeshArrays:
    gmsh = _gmsh_session()
    try:
        occ = gmsh.model.occ
        ox, oy, oz = spec.origin
        if spec.generator == "cylinder":
            vol = occ.addCylinder(ox, oy, oz, 0, 0, spec.height, spec.radius)
        elif spec.generator == "sphere":
            vol = occ.addSphere(ox, oy, oz, spec.radius)
        else:
            vol = _revolved_profile(occ, spec)
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [vol], 1)
        _name_surfaces(gmsh, spec)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", spec.h)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMin", spec.h / 4)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.model.mesh.generate(3)
        return _gmsh_arrays(gmsh)
    finally:
        gmsh.finalize()


def _revolved_profile(occ, spec: MeshSpec) -> int:
    """Revolve a closed r-z outline about the z axis through the origin into a solid."""
    pts = spec.profile
    if pts[0] == pts[-1]:
        pts = pts[:-1]
    ox, oy, oz = spec.origin
    tags = [occ.addPoint(ox + r, oy, oz + z) for r, z in pts]
    lines = [occ.addLine(tags[i], tags[(i + 1) % len(tags)]) for i in range(len(tags))]
    surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    out = occ.revolve([(2, surf)], ox, oy, oz, 0, 0, 1, 2 * math.pi)
    vols = [t for d, t in out if d == 3]
    if len(vols) != 1:
        raise InputError("mesh.profile: revolving the outline did not give one solid")
    return vols[0]


def _name_surfaces(gmsh, spec: MeshSpec) -> None:
    """Physical groups for generated surfaces: flat horizontal faces at the lowest/highest z are
    'bottom'/'top' and the rest 'side' (cylinder, revolve); a sphere has one group 'surface'."""
    surfaces = [t for _, t in gmsh.model.getEntities(2)]
    if spec.generator == "sphere":
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, surfaces, 10), "surface")
        return
    boxes = {s: gmsh.model.getBoundingBox(2, s) for s in surfaces}
    zlo = min(b[2] for b in boxes.values())
    zhi = max(b[5] for b in boxes.values())
    tol = 1e-4 * (zhi - zlo)              # OCC pads bounding boxes by its tolerance
    named = {"bottom": [], "top": [], "side": []}
    for s, b in boxes.items():
        flat = b[5] - b[2] < tol
        if flat and abs(b[2] - zlo) < tol:
            named["bottom"].append(s)
        elif flat and abs(b[5] - zhi) < tol:
            named["top"].append(s)
        else:
            named["side"].append(s)
    for i, (n, ss) in enumerate(named.items()):
        if ss:
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, ss, 10 + i), n)


# ----------------------------------------------------------------------------- files
def read_surface_file(path: Path, h: float | None, limit: float, degree: int) -> MeshArrays:
    """A closed surface (STL, OBJ, PLY, OFF) filled with tetrahedra of size h (default: the surface's
    mean edge length), after checking that it is closed and that the mesh will fit in memory."""
    key = f"mesh.file = {str(path)!r}"
    points, tris = surfaces.read_surface(path)
    surfaces.check_closed(points, tris, key)
    h = h or surfaces.mean_edge(points, tris)
    cells, dofs = resources.tetrahedra_counts(surfaces.enclosed_volume(points, tris), h, degree)
    resources.check_fits(cells, dofs, "tetrahedron", degree, f"{key} at h = {h:.3g}", limit)
    x, tets = surfaces.tetrahedralise(points, tris, h, key)
    arrays = _compact(MeshArrays(x, tets, "tetrahedron"))
    arrays.info = {"source": f"{path.name} (surface, {len(tris)} triangles) meshed by gmsh at h = {h:.4g}",
                   **surfaces.quality(arrays.points, arrays.cells)}
    return arrays


def read_mesh_file(path: Path) -> MeshArrays:
    """A gmsh .msh (with its named groups of every dimension) or any meshio-readable volume mesh."""
    if path.suffix == ".msh":
        gmsh = _gmsh_session()
        try:
            try:
                gmsh.merge(str(path))
            except Exception as e:
                raise InputError(f"mesh.file = {str(path)!r}: gmsh cannot read it ({e})") from None
            return _gmsh_arrays(gmsh)
        finally:
            gmsh.finalize()
    m = surfaces.read_meshio(path)
    kinds = {"tetra": ("tetrahedron", 4), "tetra10": ("tetrahedron", 4),
             "hexahedron": ("hexahedron", 8), "hexahedron20": ("hexahedron", 8),
             "hexahedron27": ("hexahedron", 8)}
    blocks = [(kinds[b.type], b.data) for b in m.cells if b.type in kinds]
    if not blocks or len({k[0] for k, _ in blocks}) != 1:
        found = ", ".join(sorted({b.type for b in m.cells})) or "nothing"
        raise InputError(f"mesh.file = {str(path)!r}: needs volume cells all tetrahedra or all "
                         f"hexahedra (found: {found})")
    (cell_type, nv), _ = blocks[0]
    cells = np.vstack([d[:, :nv] for _, d in blocks]).astype(np.int64)
    pts = np.asarray(m.points, dtype=np.float64)
    if pts.shape[1] != 3:
        raise InputError(f"mesh.file = {str(path)!r}: points must have 3 coordinates")
    return _compact(MeshArrays(pts, cells, cell_type, {}))


# ----------------------------------------------------------------------------- distribution
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
    cell_type, names, volumes, curves, points, info = comm.bcast(
        (arrays.cell_type, list(arrays.facet_groups), list(arrays.cell_groups), arrays.curve_groups,
         arrays.point_groups, arrays.info) if comm.rank == 0 else None, root=0)
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
    extra = dict(cells=cell_sets, curves=curves, points=points, info=info)
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
        if spec.generator == "file" and spec.file.suffix.lower() in SURFACE_SUFFIXES:
            arrays = read_surface_file(spec.file, spec.h, limit, degree)
        elif spec.generator == "file":
            arrays = read_mesh_file(spec.file)
            arrays.info = {"source": spec.file.name, "cells": len(arrays.cells)}
        else:
            resources.check_fits(*resources.tetrahedra_counts(resources.solid_volume(spec), spec.h, degree),
                                 "tetrahedron", degree, f"mesh.h = {spec.h}", limit)
            arrays = _generate(spec)
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
