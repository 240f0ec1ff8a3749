"""Forward equilibrium of a body whose rest shape is the target mesh + d, written on the fixed target mesh."""
from __future__ import annotations

import ufl

from fem_forms.meshes import LoadedMesh
from fem_forms.physics.admissibility import SmallestValue
from fem_forms.physics.contact.on_rest import StandingRest
from fem_forms.model import build_model
from fem_forms.scene import Scene
from fem_forms.solvers import continuation, snes
from fem_forms.solvers.reports import SolveReport


class ForwardOnRest:
    """Forward equilibrium of the body whose rest shape is (target mesh + d), written on the fixed
    target mesh: X = x + d(x), G = dX/dx = I + grad d, F = I + grad u G^-1, dX = det G dx.
    Provides the energy, its derivatives in u and in d (ufl.derivative), and warm-started solves. A part standing
    on obstacles ([contact]) has the contact term beside the forms (physics/contact/on_rest.py)."""

    def __init__(self, scene: Scene, material, loaded: LoadedMesh):
        model = build_model(scene, material, loaded=loaded, rest="designed")
        model.terms.only_ufl("inverse design", but=("contact",))
        self.scene, self.loaded, self.V, self.mesh = scene, loaded, model.V, loaded.mesh
        self.d, self.u = model.rest_offset, model.u
        self.scalars = model.global_scalars()     # a volume-controlled cavity's pressure, solved with u
        self.load, self.bcs, self.dx = model.load, model.bcs, model.dx
        # a follower pressure has no energy: its solves search along the residual, its adjoint solves with K^T
        self.energy = model.energy if model.conservative else None
        self.residual, self.jacobian = model.residual, model.jacobian
        self.dres_dd = ufl.derivative(self.residual, self.d, ufl.TrialFunction(self.V))
        self.physics, self.terms = model.physics, model.terms
        self.arrays = model.terms.arrays
        contact = next((t for t in self.arrays if t.role == "contact"), None)
        self.standing = StandingRest.of(contact) if contact is not None else None
        G = model.context.rest_map
        self._volume_ratio = SmallestValue(ufl.det(model.context.F) * ufl.det(G), self.mesh,
                                           self.dx.metadata()["quadrature_degree"])
        self.solves = 0
        self._driver: snes.SNESDriver | None = None
        self._problem: snes.NonlinearProblem | None = None
        self._u_ok = self.u.x.array.copy()
        self._d_ok = self.d.x.array.copy()
        self._p_ok = [0.0] * len(self.scalars)

    def inadmissible(self):
        return self._volume_ratio.positive_or("inverted elements (min det = {value:.3g})")

    def solve(self, fallback: bool = True) -> snes.SolveReport:
        """Equilibrium for the current d, warm-started from the current u; if that fails and
        `fallback`, load continuation from zero (costly: trial steps of an optimiser skip it)."""
        self.solves += 1
        if self._driver is None:          # forms compiled and matrix created once for all solves
            self._problem = snes.NonlinearProblem(self.u, self.residual, self.jacobian, self.bcs,
                                                    energy=self.energy, set_load=None,
                                                    inadmissible=self.inadmissible, array_terms=self.arrays,
                                                    scalars=self.scalars)
            self._driver = snes.SNESDriver(self._problem, dict(self.scene.solver.petsc),
                                             self.scene.solver.linear, "fem_forms_fwd_")
        problem = self._problem
        problem.set_load = None
        self.load.set(1.0)
        if self.standing is not None and (failed := self._start_standing(fallback)) is not None:
            return self._keep(failed)
        rep = continuation.solve(problem, driver=self._driver)
        if not rep.converged and fallback:
            self.u.x.array[:] = 0.0
            self.u.x.scatter_forward()
            self._set_scalars([0.0] * len(self.scalars))
            problem.set_load = self._set_load
            rep = continuation.solve(problem, steps=max(self.scene.solver.steps, 4),
                                     max_cutbacks=self.scene.solver.max_cutbacks, driver=self._driver)
            problem.set_load = None
        return self._keep(rep)

    def _set_load(self, lam: float) -> None:
        """The load factor of the fallback's steps; standing on obstacles, each step's friction anchored at rest."""
        self.load.set(lam)
        if self.standing is not None:
            self.standing.lag()

    @property
    def driver(self) -> snes.SNESDriver | None:
        """The SNES driver of the forward solves (its array terms' Hessian: the adjoint's K), after the first."""
        return self._driver

    def _keep(self, rep: SolveReport) -> SolveReport:
        """The state of a converged solve kept as the next one's fallback; a failed one's undone."""
        if rep.converged:
            self._u_ok, self._d_ok = self.u.x.array.copy(), self.d.x.array.copy()
            self._p_ok = [float(sc.value.value) for sc in self.scalars]
        else:
            self.u.x.array[:] = self._u_ok
            self._set_scalars(self._p_ok)
        return rep

    def _set_scalars(self, values: list) -> None:
        for scalar, value in zip(self.scalars, values):
            scalar.value.value = value

    def _start_standing(self, fallback: bool) -> SolveReport | None:
        """Before a solve on the obstacles: the rest shape mesh + d (through an obstacle: no equilibrium, a failed
        report), a start that crosses no obstacle (else the last deformed shape kept; else, with `fallback`, rest)
        and friction anchored at the rest shape (the continuation re-lags it at the equilibrium until its normal
        forces settle); None when the solve may go on."""
        standing, x = self.standing, self.u.vector
        if (gap := standing.follow_rest()) <= 0.0:
            why = f"the rest shape crosses an obstacle (smallest distance {gap:.3g} m)"
            return SolveReport(False, 0.0, 0, float("nan"), message=why)
        if standing.term.inadmissible(x) is not None:       # the last deformed shape, kept
            self.u.x.array[:] = self._u_ok - (self.d.x.array - self._d_ok)
            self.u.x.scatter_forward()
        if fallback and standing.term.inadmissible(x) is not None:
            self.u.x.array[:] = 0.0
            self.u.x.scatter_forward()
        standing.lag()
        return None
