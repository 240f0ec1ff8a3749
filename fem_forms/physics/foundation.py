"""An elastic (Winkler) foundation under a surface: [[load]] type = "foundation" with `stiffness` k (Pa/m) on the
selected facets. Each point of the surface rests on its own spring along the rest normal N:
    E = k/2 int (u . N)^2 dA,
so the ground pushes back k (u . N) per area, in tension as in compression (a bonded bed, as in Hetenyi's
beams on elastic foundations). A support, not a load: the load factor does not scale it, its reaction is
reported with the supports', and its stored energy is the dynamic account's `support` column."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.physics.terms import Context, Term, register_load


@register_load("foundation")
class Foundation(Term):
    """k/2 int (u . N)^2 dA over one [[load]] table's facets (N the rest shape's unit outward normal)."""
    name, role = "elastic foundation (Winkler)", "support"
    energy_columns = ("support",)
    support_hint = "a foundation holds motion along its surface's normal only"

    def __init__(self, spec, index: int, mesh: dmesh.Mesh):
        if spec.history:
            raise InputError(f"load[{index}].history: a foundation is a support; it has no history")
        self.index, self.keys = index, ("load", index)
        self.k = fem.Constant(mesh, PETSc.ScalarType(spec.stiffness))   # a new stiffness compiles nothing
        self._forms: dict = {}

    def set_values(self, scene) -> None:
        self.k.value = scene.load[self.index].stiffness

    def prepare(self, ctx: Context) -> None:
        self.ctx = ctx

    def _normal_motion(self, ctx: Context):
        n = ctx.rest_area_vector()
        return ufl.dot(ctx.u, n) / ufl.sqrt(ufl.dot(n, n)), n / ufl.sqrt(ufl.dot(n, n))

    def energy(self, ctx: Context) -> ufl.Form:
        w, _ = self._normal_motion(ctx)
        return sum(ctx.area(0.5 * self.k * w * w, r) for r in ctx.regions[self.index])

    def _value(self, name: str, make) -> float:
        if name not in self._forms:
            self._forms[name] = fem.form(make())
        comm = self.ctx.mesh.comm
        return comm.allreduce(fem.assemble_scalar(self._forms[name]), op=MPI.SUM)

    def stored_energies(self, x: PETSc.Vec) -> dict[str, float]:
        return {"support": self._value("energy", lambda: self.energy(self.ctx))}

    def support_forces(self, x: PETSc.Vec) -> np.ndarray:
        """(1, 3): the foundation's push on the body, -int k (u . N) N dA."""
        w, N = self._normal_motion(self.ctx)
        return np.array([[self._value(f"F{i}", lambda i=i: sum(self.ctx.area(-self.k * w * N[i], r)
                                                                 for r in self.ctx.regions[self.index]))
                          for i in range(3)]])

    def report(self, x: PETSc.Vec) -> dict:
        return {"foundations": {f"load[{self.index}]": {"force": self.support_forces(x)[0].tolist(),
                                                        "energy": self.stored_energies(x)["support"]}}}

    def holds(self, model, modes: list) -> np.ndarray:
        return held_by_energy(self.energy(model.context), model.unknown, modes)


def held_by_energy(energy: ufl.Form, unknown: fem.Function, modes: list) -> np.ndarray:
    """Rows R with R^T R = the Gram matrix of the support's restoring forces d2E[m_i] . d2E[m_j] for the rigid
    modes m_i, scaled to its largest entry (1: held as firmly as the most held mode; 0: free)."""
    V = unknown.function_space
    w = fem.Function(V)
    form = fem.form(ufl.derivative(ufl.derivative(energy, unknown, ufl.TestFunction(V)), unknown, w))
    forces = []
    for m in modes:
        w.vector.array[:] = m.array
        w.x.scatter_forward()
        b = fpetsc.assemble_vector(form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        forces.append(b)
    gram = np.array([[a.dot(b) for b in forces] for a in forces])
    for b in forces:
        b.destroy()
    gram /= max(float(np.abs(gram).max()), 1e-300)
    values, vectors = np.linalg.eigh(gram)
    return (vectors * np.sqrt(np.clip(values, 0.0, None))).T
