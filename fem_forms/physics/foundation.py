"""An elastic (Winkler) foundation under a surface: [[load]] type = "foundation" with `stiffness` k (Pa/m) on the
selected facets. Each point of the surface rests on its own spring along the rest normal N:
    E = k/2 int (u . N)^2 dA,
so the ground pushes back k (u . N) per area, in tension as in compression (a bonded bed, as in Hetenyi's
beams on elastic foundations). A support, not a load: the load factor does not scale it, its reaction is
reported with the supports', and its stored energy is the dynamic account's `support` column."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.physics.term_integrals import Integrals, held_by_energy
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
        self.integral = Integrals(mesh.comm)

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

    def stored_energies(self, x: PETSc.Vec) -> dict[str, float]:
        return {"support": self.integral("energy", lambda: self.energy(self.ctx))}

    def support_forces(self, x: PETSc.Vec) -> np.ndarray:
        """(1, 3): the foundation's push on the body, -int k (u . N) N dA."""
        w, N = self._normal_motion(self.ctx)
        return np.array([[self.integral(f"F{i}", lambda i=i: sum(self.ctx.area(-self.k * w * N[i], r)
                                                                 for r in self.ctx.regions[self.index]))
                          for i in range(3)]])

    def report(self, x: PETSc.Vec) -> dict:
        return {"foundations": {f"load[{self.index}]": {"force": self.support_forces(x)[0].tolist(),
                                                        "energy": self.stored_energies(x)["support"]}}}

    def holds(self, model, modes: list) -> np.ndarray:
        return held_by_energy(self.energy(model.context), model.unknown, modes)
