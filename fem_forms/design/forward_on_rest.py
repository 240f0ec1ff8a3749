"""Forward equilibrium of a body whose rest shape is the target mesh + d, written on the fixed target mesh."""
from __future__ import annotations

import ufl

from fem_forms.errors import InputError
from fem_forms.meshes import LoadedMesh
from fem_forms.physics.admissibility import SmallestValue
from fem_forms.model import build_model
from fem_forms.scene import Scene
from fem_forms.solvers import continuation, snes


class ForwardOnRest:
    """Forward equilibrium of the body whose rest shape is (target mesh + d), written on the fixed
    target mesh: X = x + d(x), G = dX/dx = I + grad d, F = I + grad u G^-1, dX = det G dx.
    Provides the energy, its derivatives in u and in d (ufl.derivative), and warm-started solves."""

    def __init__(self, scene: Scene, material, loaded: LoadedMesh):
        model = build_model(scene, material, loaded=loaded, rest="designed")
        model.only_ufl_terms("inverse design")
        if not model.conservative:
            raise InputError(f"inverse.method = {scene.inverse.method!r}: follower pressure is supported "
                             "by the direct method only")
        if model.global_scalars():                # the scene refuses it; a script's call would leave p at 0
            raise InputError(f"inverse.method = {scene.inverse.method!r}: volume control is designed by the "
                             "direct method only")
        self.scene, self.loaded, self.V, self.mesh = scene, loaded, model.V, loaded.mesh
        self.d, self.u = model.rest_offset, model.u
        self.load, self.bcs, self.dx = model.load, model.bcs, model.dx
        self.energy, self.residual, self.jacobian = model.energy, model.residual, model.jacobian
        self.dres_dd = ufl.derivative(self.residual, self.d, ufl.TrialFunction(self.V))
        self.physics = model.physics
        G = model.context.rest_map
        self._volume_ratio = SmallestValue(ufl.det(model.context.F) * ufl.det(G), self.mesh,
                                           self.dx.metadata()["quadrature_degree"])
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

