"""Forward equilibrium of a body whose rest shape is the target mesh + d, written on the fixed target mesh."""
from __future__ import annotations

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.meshes import LoadedMesh
from fem_forms.model import _quadrature_points, build_material
from fem_forms.physics.supports import LoadFactor, load_regions, supports
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
        self.mat = build_material(scene, material)
        self.d = fem.Function(V, name="rest_minus_target")
        self.u = fem.Function(V, name="displacement")
        quad = {"quadrature_degree": scene.discretization.quadrature}
        self.dx = ufl.Measure("dx", domain=mesh, metadata=quad)
        self.load = LoadFactor(mesh)
        self.bcs = supports(V, loaded, scene.fix, self.load)
        G = ufl.Identity(3) + ufl.grad(self.d)
        Ginv = ufl.inv(G)
        jG = ufl.det(G)
        F = ufl.Identity(3) + ufl.grad(self.u) * Ginv
        tags, ids = load_regions(loaded, scene.load)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=quad)
        n = ufl.FacetNormal(mesh)
        W = 0
        for i, spec in enumerate(scene.load):
            if spec.type == "gravity":
                W = W + scene.material.rho * ufl.dot(fem.Constant(mesh, PETSc.ScalarType(spec.g)), self.u) * jG * self.dx
            elif spec.type == "traction":
                T = fem.Constant(mesh, PETSc.ScalarType(spec.value))
                dA = jG * ufl.sqrt(ufl.dot(Ginv.T * n, Ginv.T * n))
                W = W + sum(ufl.dot(T, self.u) * dA * ds(k) for k in ids[i])
            else:
                raise InputError(f"inverse.method = {scene.inverse.method!r}: follower pressure is supported "
                                 "by the direct method only")
        self.energy = self.mat.psi(F) * jG * self.dx - (self.load.constant * W if not isinstance(W, int) else 0)
        w = ufl.TestFunction(V)
        self.residual = ufl.derivative(self.energy, self.u, w)
        self.jacobian = ufl.derivative(self.residual, self.u, ufl.TrialFunction(V))
        self.dres_dd = ufl.derivative(self.residual, self.d, ufl.TrialFunction(V))
        points, _ = _quadrature_points(mesh, scene.discretization.quadrature)
        self._jexpr = fem.Expression(ufl.det(F) * jG, points)
        self.solves = 0
        self._driver: snes.SNESDriver | None = None
        self._problem: snes.NonlinearProblem | None = None
        self._u_ok = self.u.x.array.copy()

    def inadmissible(self):
        ncells = self.mesh.topology.index_map(3).size_local
        vals = self._jexpr.eval(np.arange(ncells, dtype=np.int32))
        jmin = self.mesh.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        return None if np.isfinite(jmin) and jmin > 0 else f"inverted elements (min det = {jmin:.3g})"

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

