"""Boundary selectors, the load factor and supports (Dirichlet conditions with Constant values)."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.meshes import LoadedMesh, bounding_box, mesh_size
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
    else:
        if sel.group not in loaded.groups:
            known = ", ".join(sorted(loaded.groups)) or "none"
            raise InputError(f"{sel.key}.group = {sel.group!r}: no such boundary group (the mesh has: {known})")
        facets = loaded.facet_tags.indices[loaded.facet_tags.values == loaded.groups[sel.group]]
    if mesh.comm.allreduce(len(facets), op=MPI.SUM) == 0:
        lo, hi = bounding_box(mesh)
        raise InputError(f"{sel.key}: matches no boundary facet (mesh spans {np.round(lo, 6).tolist()} "
                         f"to {np.round(hi, 6).tolist()})")
    return np.asarray(facets, dtype=np.int32)


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


def supports(V: fem.FunctionSpace, loaded: LoadedMesh, fixes: list[Fix], load: LoadFactor,
             sign: float = 1.0, owners: list | None = None) -> list:
    """Dirichlet conditions u_i = sign * lambda * value_i on each fix's facets and components
    (sign -1 for the inverse problem, whose unknown is rest minus deformed position). If `owners` is
    given, (fix index, component) of each condition is appended to it (reactions are reported per fix)."""
    fdim = loaded.mesh.topology.dim - 1
    bcs = []
    for i, fix in enumerate(fixes):
        facets = locate_facets(loaded, fix.where)
        for c in fix.components:
            dofs = fem.locate_dofs_topological(V.sub(c), fdim, facets)
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
        if spec.where is None:
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

