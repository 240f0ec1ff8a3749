"""Forward equilibrium of a body whose rest shape is the target mesh + d, written on the fixed target mesh."""
from __future__ import annotations

from dolfinx import fem
import ufl

from fem_forms.errors import InputError
from fem_forms.meshes import LoadedMesh
from fem_forms.physics.admissibility import SmallestValue
from fem_forms.physics.assemble import equilibrium_forms, scene_physics
from fem_forms.scene import Scene
from fem_forms.solvers import continuation, snes


class ForwardOnRest:
    """Forward equilibrium of the body whose rest shape is (target mesh + d), written on the fixed
    target mesh: X = x + d(x), G = dX/dx = I + grad d, F = I + grad u G^-1, dX = det G dx.
    Provides the energy, its derivatives in u and in d (ufl.derivative), and warm-started solves."""

    def __init__(self, scene: Scene, material, loaded: LoadedMesh, V: fem.FunctionSpace):
        self.scene, self.loaded, self.V = scene, loaded, V
        mesh = loaded.mesh
        self.mesh = mesh
        self.d = fem.Function(V, name="rest_minus_target")
        self.u = fem.Function(V, name="displacement")
        G = ufl.Identity(3) + ufl.grad(self.d)
        physics = scene_physics(scene, loaded, self.u, V, material, rest_map=G, rest_offset=self.d)
        physics.terms.only_ufl("inverse design")
        self.load, self.bcs = physics.load, physics.bcs
        ctx, terms = physics.context, physics.terms
        if not all(t.conservative for t in terms):
            raise InputError(f"inverse.method = {scene.inverse.method!r}: follower pressure is supported "
                             "by the direct method only")
        self.dx = ctx.dx
        forms = equilibrium_forms(terms, ctx, self.u, ufl.TestFunction(V))
        self.energy, self.residual, self.jacobian = forms.energy, forms.residual, forms.jacobian
        self.dres_dd = ufl.derivative(self.residual, self.d, ufl.TrialFunction(V))
        self.physics = [t.name for t in terms]
        self._volume_ratio = SmallestValue(ufl.det(ctx.F) * ufl.det(G), mesh, scene.discretization.quadrature)
        self.solves = 0
        self._driver: snes.SNESDriver | None = None
        self._problem: snes.NonlinearProblem | None = None
        self._u_ok = self.u.x.array.copy()

    def inadmissible(self):
        return self._volume_ratio.positive_or("inverted elements (min det = {value:.3g})")

    def solve(self, fallback: bool = True) -> snes.SolveReport:
        """Equilibrium for the current d, warm-started from the current u; if that fails and
        `fallback`, load continuation from zero (costly: trial steps of an optimiser skip it)."""
        self.solves += 1
        if self._driver is None:          # forms compiled and matrix created once for all solves
            self._problem = snes.NonlinearProblem(self.u, self.residual, self.jacobian, self.bcs,
                                                    energy=self.energy, set_load=None,
                                                    inadmissible=self.inadmissible)
            self._driver = snes.SNESDriver(self._problem, dict(self.scene.solver.petsc),
                                             self.scene.solver.linear, "fem_forms_fwd_")
        problem = self._problem
        problem.set_load = None
        self.load.set(1.0)
        rep = continuation.solve(problem, driver=self._driver)
        if not rep.converged and fallback:
            self.u.x.array[:] = 0.0
            problem.set_load = self.load.set
            rep = continuation.solve(problem, steps=max(self.scene.solver.steps, 4),
                               max_cutbacks=self.scene.solver.max_cutbacks, driver=self._driver)
        if rep.converged:
            self._u_ok = self.u.x.array.copy()
        else:
            self.u.x.array[:] = self._u_ok
        return rep

