"""Springs tying the body to fixed points ([[spring]]): each pulls a surface region Gamma (rest area A) towards its
anchor a, its stiffness k spread over the region, every point on its own line to the anchor:
    E = k / (2 A) int_Gamma (|x - a| - L0(X))^2 dA,   L0(X) = |X - a| + (L - |Xc - a|),
x = X + u, Xc the region's centroid and L the spring's rest length (default |Xc - a|: no force at the start).
A region far smaller than its distance to the anchor pulls as one spring of stiffness k along the line; its
force is its resultant. The anchors are Constants: a new anchor, stiffness or length compiles nothing."""
from __future__ import annotations

import math

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.physics.term_integrals import Integrals, held_by_energy
from fem_forms.physics.supports import locate_facets
from fem_forms.physics.terms import Context, Term, register_terms


class Spring(Term):
    """One [[spring]] table: its region's own boundary measure, anchor, stiffness and rest length."""
    name, role = "spring", "support"
    energy_columns = ("support",)
    support_hint = "a spring holds motion along its line to the anchor"

    def __init__(self, spec, index: int, mesh: dmesh.Mesh):
        self.index, self.keys = index, ("spring", index)
        self.label = spec.name or f"spring{index}"
        self.spec = spec

        def const(v) -> fem.Constant:
            return fem.Constant(mesh, PETSc.ScalarType(v))
        self.anchor, self.k, self.offset = const(tuple(spec.anchor)), const(spec.stiffness), const(0.0)
        self.area = const(1.0)
        self.integral = Integrals(mesh.comm)

    def set_values(self, scene) -> None:
        spec = scene.spring[self.index]
        if spec.where != self.spec.where:
            raise InputError(f"spring[{self.index}].where: another surface needs a new model (new values of "
                             "anchor, stiffness and length do not)")
        self.anchor.value, self.k.value, self.spec = spec.anchor, spec.stiffness, spec
        self._rest_length()

    def prepare(self, ctx: Context) -> None:
        mesh = ctx.mesh
        if mesh.topology.cell_name() == "prism":
            raise InputError(f"spring[{self.index}]: not on a prism mesh (FFCx 0.5.0 cannot integrate over prism "
                             "facets); use tetrahedra or hexahedra")
        if ctx.rest_offset is not None:          # an inverse design (any method): the rest shape is unknown
            raise InputError(f"spring[{self.index}]: not in inverse designs yet (its rest length is taken on the "
                             "mesh, which there is the target, and FFCx 0.5 cannot compile its direct tangent)")
        facets = np.sort(locate_facets(ctx.loaded, self.spec.where)).astype(np.int32)
        tags = dmesh.meshtags(mesh, mesh.topology.dim - 1, facets, np.ones(len(facets), dtype=np.int32))
        self.ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=ctx.dx.metadata())(1)
        self.ctx = ctx
        X = ufl.SpatialCoordinate(mesh)               # the mesh as the scene gives it (the rest shape, forward)
        self.area.value = self._integral(1.0)
        self.centroid = np.array([self._integral(X[i]) for i in range(3)]) / float(self.area.value)
        self._rest_length()

    def _integral(self, density) -> float:
        form = fem.form(density * self.ds)
        return self.ctx.mesh.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM)

    def _rest_length(self) -> None:
        """offset = L - |Xc - a|: every point's rest length is its distance at the start plus this."""
        start = float(np.linalg.norm(self.centroid - np.asarray(self.spec.anchor, dtype=float)))
        if start <= 1e-9 * math.sqrt(float(self.area.value)):
            raise InputError(f"spring[{self.index}].anchor: at the centroid of the surface it pulls on (the spring "
                             "has no direction)")
        length = start if self.spec.length is None else self.spec.length
        self.offset.value = length - start

    def _stretch(self, ctx: Context):
        """(|x - a| - L0(X), (x - a) / |x - a|, the rest area element's factor)."""
        X = ufl.SpatialCoordinate(ctx.mesh)
        d = X + ctx.u - self.anchor
        if ctx.rest_offset is not None:           # the rest shape is mesh + rest_offset: x = mesh + offset + u
            d = d + ctx.rest_offset
        size = ufl.sqrt(ufl.dot(d, d))
        rest = ufl.sqrt(ufl.dot(X - self.anchor, X - self.anchor)) + self.offset
        n = ctx.rest_area_vector()
        return size - rest, d / size, ufl.sqrt(ufl.dot(n, n))

    def energy(self, ctx: Context) -> ufl.Form:
        s, _, dA = self._stretch(ctx)
        return 0.5 * self.k / self.area * s * s * dA * self.ds

    def _force(self) -> np.ndarray:
        """The spring's pull on the body (N): -int k/A (|x - a| - L0) (x - a)/|x - a| dA."""
        s, e, dA = self._stretch(self.ctx)
        return np.array([self.integral(f"F{i}", lambda i=i: -self.k / self.area * s * e[i] * dA * self.ds)
                         for i in range(3)])

    def stored_energies(self, x: PETSc.Vec) -> dict[str, float]:
        return {"support": self.integral("energy", lambda: self.energy(self.ctx))}

    def support_forces(self, x: PETSc.Vec) -> np.ndarray:
        return self._force()[None, :]

    def report(self, x: PETSc.Vec) -> dict:
        """results.json springs.NAME: force (its pull on the body, N), tension (N) and energy (J)."""
        force = self._force()
        s, _, dA = self._stretch(self.ctx)
        tension = self.integral("tension", lambda: self.k / self.area * s * dA * self.ds)
        return {"springs": {self.label: {"force": force.tolist(), "tension": tension,
                                         "energy": self.stored_energies(x)["support"]}}}

    def holds(self, model, modes: list) -> np.ndarray:
        return held_by_energy(self.energy(model.context), model.unknown, modes)


@register_terms("spring")
def spring_terms(scene, mesh) -> list[Term]:
    """One term per [[spring]] table (none without); a repeated name is refused."""
    specs = getattr(scene, "spring", None) or []
    terms = [Spring(spec, i, mesh) for i, spec in enumerate(specs)]
    names = [t.label for t in terms]
    if len(set(names)) != len(names):
        repeated = next(n for n in names if names.count(n) > 1)
        raise InputError(f"spring: the name {repeated!r} is given to two springs")
    return terms
