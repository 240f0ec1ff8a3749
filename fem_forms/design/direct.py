"""Inverse elastostatics: equilibrium written on the known target shape with the rest positions as unknowns."""
from __future__ import annotations

import time

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.design.parameters import InverseResult, target_scene
from fem_forms.materials.stresses import first_piola_kirchhoff
from fem_forms.meshes import LoadedMesh, load_mesh
from fem_forms.model import _quadrature_points, build_material
from fem_forms.physics.supports import LoadFactor, load_regions, supports
from fem_forms.scene import Scene
from fem_forms.solvers import continuation, snes
from fem_forms.solvers.linear import rigid_body_modes


def _pulled_back_loads(scene: Scene, loaded: LoadedMesh, eta, F, j, dx, quad: dict):
    """External virtual work of the scene's loads written on the target (deformed) configuration."""
    mesh = loaded.mesh
    tags, ids = load_regions(loaded, scene.load)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=quad)
    n = ufl.FacetNormal(mesh)
    rho = scene.material.rho
    ext = 0
    for i, spec in enumerate(scene.load):
        if spec.type == "gravity":                      # rho per rest volume: rho dX = rho j dx
            ext = ext + rho * j * ufl.dot(fem.Constant(mesh, PETSc.ScalarType(spec.g)), eta) * dx
        elif spec.type == "traction":                   # per rest area: dA = j |F^T n| da
            T = fem.Constant(mesh, PETSc.ScalarType(spec.value))
            dA = j * ufl.sqrt(ufl.dot(F.T * n, F.T * n))
            ext = ext + sum(dA * ufl.dot(T, eta) * ds(k) for k in ids[i])
        else:                                           # follower pressure acts on the known surface
            ext = ext - sum(spec.pressure * ufl.dot(n, eta) * ds(k) for k in ids[i])
    return ext


def solve_direct(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Inverse elastostatics with load continuation (secant predictor, automatic cut-back)."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    mesh = loaded.mesh
    mat = build_material(scene, material)
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", scene.discretization.degree))
    v = fem.Function(V, name="rest_minus_target")
    quad = {"quadrature_degree": scene.discretization.quadrature}
    dx = ufl.Measure("dx", domain=mesh, metadata=quad)
    load = LoadFactor(mesh)
    bcs = supports(V, loaded, scene.fix, load, sign=-1.0)
    eta = ufl.TestFunction(V)
    Finv = ufl.Identity(3) + ufl.grad(v)                 # dX/dx
    F = ufl.inv(Finv)
    j = ufl.det(Finv)
    P = first_piola_kirchhoff(mat, F)
    residual = ufl.inner(P, ufl.grad(eta) * F) * j * dx \
        - load.constant * _pulled_back_loads(scene, loaded, eta, F, j, dx, quad)
    jacobian = ufl.derivative(residual, v, ufl.TrialFunction(V))
    points, _ = _quadrature_points(mesh, scene.discretization.quadrature)
    jexpr = fem.Expression(j, points)
    ncells = mesh.topology.index_map(3).size_local

    def inadmissible():
        vals = jexpr.eval(np.arange(ncells, dtype=np.int32))
        jmin = mesh.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        return None if np.isfinite(jmin) and jmin > 0 else f"inverted rest-shape elements (min det = {jmin:.3g})"

    problem = snes.NonlinearProblem(v, residual, jacobian, bcs, energy=None, set_load=load.set,
                                      inadmissible=inadmissible)
    options = {"snes_linesearch_type": "basic", **scene.solver.petsc}
    report = continuation.solve(problem, options, steps=scene.solver.steps, max_cutbacks=scene.solver.max_cutbacks,
                          linear_kind=scene.solver.linear, near_nullspace=lambda: rigid_body_modes(V),
                          prefix="fem_forms_inverse_", reuse_factor=True)
    res = InverseResult("direct", v, loaded, report.converged, report.newton_iterations, report.message,
                        history=[{"load": s.load, "iterations": s.iterations, "accepted": s.accepted,
                                  "reason": s.reason, "note": s.note} for s in report.steps])
    res.solve_time = time.perf_counter() - t0
    return res

