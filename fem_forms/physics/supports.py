"""Selectors, the load factor and supports (Dirichlet conditions with Constant values).

The one selector mechanism: boundary facets (plane, box, surface group, a CAD face, the facets facing a direction,
on a plane of any orientation or around a cavity) for loads and supports;
for supports also cells (volume group) and positions (the nearest node to a point, nodes on a line
segment, on a gmsh curve group's edges or at a point group's points)."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.meshes import LoadedMesh, bounding_box, mesh_size
from fem_forms.meshes.facet_geometry import boundary_facets, cavities, outward_geometry
from fem_forms.meshes.groups import distance_to_points, distance_to_segments
from fem_forms.progress import report

CONE_ROUNDOFF = 1e-12          # a facet exactly on the cone's edge (within_deg = 90 takes the faces square to it)
from fem_forms.scene import Fix, Load, Selector


def locate_facets(loaded: LoadedMesh, sel: Selector) -> np.ndarray:
    """Local indices of the boundary facets a selector picks; an error if it picks none anywhere."""
    mesh = loaded.mesh
    fdim = mesh.topology.dim - 1
    tol = 1e-6 * mesh_size(mesh)
    if sel.kind == "plane":
        facets = dmesh.locate_entities_boundary(mesh, fdim, lambda x: np.abs(x[sel.axis] - sel.at) <= tol)
    elif sel.kind == "box":
        lo, hi = np.array(sel.lo)[:, None] - tol, np.array(sel.hi)[:, None] + tol
        facets = dmesh.locate_entities_boundary(
            mesh, fdim, lambda x: np.all((x >= lo) & (x <= hi), axis=0))
    elif sel.kind in ("group", "face"):
        kind = _group(loaded, sel)
        if kind != "surface":
            raise InputError(f"{sel.key}.group = {sel.group!r}: a {kind} group; a traction or pressure "
                             "needs a surface group")
        tags = [loaded.groups[name] for name in _surface_groups(loaded, sel)]
        facets = loaded.facet_tags.indices[np.isin(loaded.facet_tags.values, tags)]
    elif sel.kind in ("normal", "oblique", "cavity"):
        facets = _facets_by_geometry(mesh, sel)
    else:
        raise InputError(f"{sel.key}: a {sel.kind} has no area; select facets with axis/at, box, group, normal, "
                         "plane, cavity or face")
    found = mesh.comm.allreduce(len(_owned(mesh, facets)), op=MPI.SUM)
    if found == 0:
        lo, hi = bounding_box(mesh)
        raise InputError(f"{sel.key}: matches no boundary facet (mesh spans {np.round(lo, 6).tolist()} "
                         f"to {np.round(hi, 6).tolist()})")
    report("selected", key=sel.key, facets=found)
    return np.asarray(facets, dtype=np.int32)


def _owned(mesh: dmesh.Mesh, facets: np.ndarray) -> np.ndarray:
    """The facets this rank owns (the others are ghosts another rank counts)."""
    return facets[facets < mesh.topology.index_map(mesh.topology.dim - 1).size_local]


def _facets_by_geometry(mesh: dmesh.Mesh, sel: Selector) -> np.ndarray:
    """Boundary facets facing a direction (normal), on a plane of any orientation (oblique), or a cavity's walls."""
    if mesh.topology.cell_type == dmesh.CellType.prism:
        raise InputError(f"{sel.key}: normal, plane and cavity take the facets of tetrahedra and hexahedra (this "
                         "mesh has prisms); use axis/at, box or group")
    if sel.kind == "oblique":
        tol = sel.tolerance if sel.tolerance is not None else 1e-6 * mesh_size(mesh)
        p, n = np.array(sel.origin)[:, None], np.array(sel.direction)
        return dmesh.locate_entities_boundary(mesh, mesh.topology.dim - 1, lambda x: np.abs(n @ (x - p)) <= tol)
    if sel.kind == "normal":
        facets = boundary_facets(mesh)
        normal, _, _ = outward_geometry(mesh, facets)
        return facets[normal @ np.array(sel.direction) >= np.cos(np.radians(sel.within_deg)) - CONE_ROUNDOFF]
    found = cavities(mesh)
    volumes = ", ".join(f"{v:.4g}" for v, _ in found[:6]) + (", ..." if len(found) > 6 else "")
    if not found:
        raise InputError(f"{sel.key}.cavity: the mesh has no cavity (no closed surface inside the part)")
    if sel.cavity == "all":
        return np.concatenate([f for _, f in found])
    if sel.cavity > len(found):
        raise InputError(f"{sel.key}.cavity = {sel.cavity}: the mesh has {len(found)} cavit"
                         f"{'y' if len(found) == 1 else 'ies'} (enclosing {volumes} m^3, largest first)")
    return found[sel.cavity - 1][1]


def _surface_groups(loaded: LoadedMesh, sel: Selector) -> list[str]:
    """The surface groups a selector names: its group; a CAD file's face by number (face<N>); or every CAD face
    the file gives the name `group`."""
    faces = loaded.info.get("faces")
    if sel.kind == "face":
        if faces is None:
            raise InputError(f"{sel.key}.face: only for a mesh made from a CAD file (.step, .iges, .brep)")
        if not any(f["face"] == sel.face for f in faces):
            raise InputError(f"{sel.key}.face = {sel.face}: the CAD file has faces {faces[0]['face']}.."
                             f"{faces[-1]['face']} (`fem-forms faces FILE` lists them)")
        return [f"face{sel.face}"]
    if sel.group not in loaded.groups and faces is not None:
        named = [f["group"] for f in faces if f.get("name") == sel.group]
        if named:
            return named
    return [sel.group]


def _group(loaded: LoadedMesh, sel: Selector) -> str:
    name = _surface_groups(loaded, sel)[0]
    for kind, groups in (("surface", loaded.groups), ("volume", loaded.cells), ("curve", loaded.curves),
                         ("point", loaded.points)):
        if name in groups:
            return kind
    raise InputError(f"{sel.key}.group = {sel.group!r}: no such group (the mesh has: {loaded.group_names()})")


def nearest_node(mesh: dmesh.Mesh, point) -> np.ndarray:
    """The mesh vertex nearest `point` over all ranks; ties go to the lexicographically smallest
    coordinates, so every rank count picks the same node."""
    x = mesh.geometry.x
    d = np.linalg.norm(x - np.asarray(point, dtype=float), axis=1) if len(x) else np.empty(0)
    dmin = mesh.comm.allreduce(float(d.min()) if len(d) else np.inf, op=MPI.MIN)
    tie = 1e-12 * mesh_size(mesh)
    local = x[d <= dmin + tie] if len(d) else np.empty((0, 3))
    candidates = np.vstack([c for c in mesh.comm.allgather(local) if len(c)])
    return candidates[np.lexsort(candidates.T[::-1])][0]


def _geometric_marker(loaded: LoadedMesh, sel: Selector):
    """A marker x (3, n) -> bool for selectors resolved by position (point, line, curve and point
    groups), with a description of what it selects for the nothing-found message."""
    mesh = loaded.mesh
    tol = 1e-6 * mesh_size(mesh)
    if sel.kind == "point":
        lo, hi = bounding_box(mesh)
        p = np.asarray(sel.point)
        if np.any(p < lo - tol) or np.any(p > hi + tol):
            raise InputError(f"{sel.key}.point = {list(sel.point)}: lies outside the mesh (which spans "
                             f"{np.round(lo, 6).tolist()} to {np.round(hi, 6).tolist()}), selects no node")
        node = nearest_node(mesh, p)
        close = 1e-9 * mesh_size(mesh)                  # collective: outside the marker
        return lambda x: np.linalg.norm(x.T - node, axis=1) <= close
    if sel.kind == "line":
        seg = np.array([sel.line])
        return lambda x: distance_to_segments(x.T, seg) <= tol
    if sel.group in loaded.curves:
        segs = loaded.curves[sel.group]
        return lambda x: distance_to_segments(x.T, segs) <= tol
    pts = loaded.points[sel.group]
    return lambda x: distance_to_points(x.T, pts) <= tol


def support_dofs(V: fem.FunctionSpace, loaded: LoadedMesh, sel: Selector, components: list) -> list:
    """For each component c, the dofs of V.sub(c) (in V's numbering) the selector holds: on facets
    (plane, box, surface group), in cells (volume group) or at positions (point, line, curve and point
    groups); an error when nothing is selected on any rank."""
    mesh = loaded.mesh
    tdim = mesh.topology.dim
    kind = _group(loaded, sel) if sel.kind in ("group", "face") else sel.kind
    if kind in ("plane", "box", "surface", "normal", "oblique", "cavity"):
        facets = locate_facets(loaded, sel)
        return [fem.locate_dofs_topological(V.sub(c), tdim - 1, facets) for c in components]
    if kind == "volume":
        cells = loaded.cells[sel.group]
        if mesh.comm.allreduce(len(cells), op=MPI.SUM) == 0:
            raise InputError(f"{sel.key}.group = {sel.group!r}: the volume group has no cells")
        return [fem.locate_dofs_topological(V.sub(c), tdim, cells) for c in components]
    marker = _geometric_marker(loaded, sel)
    out = []
    for c in components:
        sub = V.sub(c)
        collapsed, _ = sub.collapse()
        out.append(np.asarray(fem.locate_dofs_geometrical((sub, collapsed), marker)[0], dtype=np.int32))
    if mesh.comm.allreduce(len(out[0]), op=MPI.SUM) == 0:
        what = (f"the line from {list(sel.line[0])} to {list(sel.line[1])}" if sel.kind == "line"
                else f"the {kind} group {sel.group!r}")
        raise InputError(f"{sel.key}: {what} passes through no mesh node (tolerance {tol_text(mesh)})")
    return out


def tol_text(mesh: dmesh.Mesh) -> str:
    return f"{1e-6 * mesh_size(mesh):.3g} m"


class LoadFactor:
    """The continuation parameter lambda in [0, 1]: scales every load and prescribed displacement."""

    def __init__(self, mesh: dmesh.Mesh):
        self.constant = fem.Constant(mesh, PETSc.ScalarType(1.0))
        self._scaled: dict = {}                      # key -> [Constant, full value]

    def scaled(self, mesh: dmesh.Mesh, value: float, key=None) -> fem.Constant:
        """A Constant that equals lambda * value (`key` names it for rescale)."""
        c = fem.Constant(mesh, PETSc.ScalarType(self.value * value))
        self._scaled[key if key is not None else len(self._scaled)] = [c, value]
        return c

    def rescale(self, key, value: float) -> None:
        """A new full value for a scaled Constant (e.g. a support's prescribed displacement)."""
        entry = self._scaled[key]
        entry[1] = value
        entry[0].value = self.value * value

    @property
    def value(self) -> float:
        return float(self.constant.value)

    def set(self, lam: float) -> None:
        self.constant.value = lam
        for c, v in self._scaled.values():
            c.value = lam * v

    def set_one(self, key, factor: float) -> None:
        """One scaled Constant at factor x its full value (a support following its own history)."""
        c, v = self._scaled[key]
        c.value = factor * v


def supports(V: fem.FunctionSpace, loaded: LoadedMesh, fixes: list[Fix], load: LoadFactor,
             sign: float = 1.0, owners: list | None = None) -> list:
    """Dirichlet conditions u_i = sign * lambda * value_i on each fix's selection and components
    (sign -1 for the inverse problem, whose unknown is rest minus deformed position). If `owners` is
    given, (fix index, component) of each condition is appended to it (reactions are reported per fix)."""
    bcs = []
    for i, fix in enumerate(fixes):
        held = support_dofs(V, loaded, fix.where, fix.components)
        for c, dofs in zip(fix.components, held):
            value = load.scaled(loaded.mesh, sign * fix.value[c], key=(i, c))
            bcs.append(fem.dirichletbc(value, dofs, V.sub(c)))
            if owners is not None:
                owners.append((i, c))
    return bcs


def load_regions(loaded: LoadedMesh, loads: list[Load]):
    """One facet MeshTags for all surface loads: each distinct set of loads sharing a facet gets an id."""
    mesh = loaded.mesh
    fdim = mesh.topology.dim - 1
    owner: dict[int, frozenset] = {}
    for i, spec in enumerate(loads):
        if spec.where is None or spec.type == "gravity":       # body loads act on cells, not facets
            continue
        for f in locate_facets(loaded, spec.where):
            owner[int(f)] = owner.get(int(f), frozenset()) | {i}
    combos = sorted({c for c in owner.values()}, key=sorted)
    # the same set of combinations on every rank, so ids agree
    combos = sorted({c for cs in mesh.comm.allgather(combos) for c in cs}, key=sorted)
    cid = {c: k + 1 for k, c in enumerate(combos)}
    ids = {i: [cid[c] for c in combos if i in c] for i in range(len(loads))}
    facets = np.array(sorted(owner), dtype=np.int32)
    values = np.array([cid[owner[f]] for f in facets], dtype=np.int32)
    return dmesh.meshtags(mesh, fdim, facets, values), ids


def body_regions(loaded: LoadedMesh, loads: list[Load]):
    """One cell MeshTags for the body loads restricted to gmsh volume groups (`where = { group = ... }`):
    each distinct set of loads sharing a cell gets an id (the same on every rank)."""
    mesh = loaded.mesh
    owner: dict[int, frozenset] = {}
    for i, spec in enumerate(loads):
        if spec.type != "gravity" or spec.where is None:
            continue
        name = spec.where.group
        if name not in loaded.cells:
            raise InputError(f"{spec.where.key}.group = {name!r}: no such volume group (the mesh has: "
                             f"{loaded.group_names()})")
        for c in loaded.cells[name]:
            owner[int(c)] = owner.get(int(c), frozenset()) | {i}
    combos = sorted({c for cs in mesh.comm.allgather(sorted(set(owner.values()), key=sorted)) for c in cs},
                    key=sorted)
    cid = {c: k + 1 for k, c in enumerate(combos)}
    ids = {i: [cid[c] for c in combos if i in c] for i in range(len(loads))}
    cells = np.array(sorted(owner), dtype=np.int32)
    values = np.array([cid[owner[c]] for c in cells], dtype=np.int32)
    return dmesh.meshtags(mesh, mesh.topology.dim, cells, values), ids
