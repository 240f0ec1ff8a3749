"""The FEniCSx tutorial's hyperelastic beam, solved the tutorial's way with bare dolfinx 0.5.2 (no
fem_forms): the reference for the `tutorial_beam` case.

Problem (J. S. Dokken, "The FEniCSx tutorial", chapter 2, Hyperelasticity,
https://jsdokken.com/dolfinx-tutorial/chapter2/hyperelasticity.html, version v0.5.0 for dolfinx 0.5):
box [0, 20] x [0, 1] x [0, 1], 20 x 5 x 5 hexahedra, Q2 displacement (14,883 dofs), compressible
neo-Hookean psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 with E = 1e4, nu = 0.3, clamped at x = 0,
dead (first Piola-Kirchhoff) traction (0, 0, -1.5 n) on x = 20 for n = 1..9, quadrature degree 4,
dolfinx's NewtonSolver (full Newton, no line search, incremental criterion, rtol = atol = 1e-8), direct
linear solves. The published notebook prints 8, 9, 10, 9, 8, 7, 6, 6, 6 Newton iterations per step.

This script is written from that description (not copied); it prints one JSON line: the Newton
iterations per load step and the displacement at the tip centre (20, 0.5, 0.5) after the last step.
"""
import json
import logging
import time

import numpy as np
import ufl
from dolfinx import fem, geometry, mesh as dmesh
from dolfinx.fem.petsc import NonlinearProblem
from dolfinx.nls.petsc import NewtonSolver
from mpi4py import MPI
from petsc4py import PETSc

L, E, NU, STEP = 20.0, 1.0e4, 0.3, -1.5
TIP = np.array([L, 0.5, 0.5])


def main() -> dict:
    t0 = time.perf_counter()
    domain = dmesh.create_box(MPI.COMM_WORLD, [[0.0, 0.0, 0.0], [L, 1.0, 1.0]], [20, 5, 5],
                              dmesh.CellType.hexahedron)
    V = fem.VectorFunctionSpace(domain, ("Lagrange", 2))
    fdim = domain.topology.dim - 1
    clamped = dmesh.locate_entities_boundary(domain, fdim, lambda x: np.isclose(x[0], 0.0))
    loaded = dmesh.locate_entities_boundary(domain, fdim, lambda x: np.isclose(x[0], L))
    tags = dmesh.meshtags(domain, fdim, loaded, np.full(len(loaded), 2, dtype=np.int32))
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                         fem.locate_dofs_topological(V, fdim, clamped), V)
    traction = fem.Constant(domain, PETSc.ScalarType((0.0, 0.0, 0.0)))
    u, v = fem.Function(V), ufl.TestFunction(V)
    F = ufl.variable(ufl.Identity(3) + ufl.grad(u))
    J = ufl.det(F)
    mu, lmbda = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    psi = mu / 2 * (ufl.tr(F.T * F) - 3) - mu * ufl.ln(J) + lmbda / 2 * ufl.ln(J) ** 2
    P = ufl.diff(psi, F)
    md = {"quadrature_degree": 4}
    residual = (ufl.inner(ufl.grad(v), P) * ufl.dx(metadata=md)
                - ufl.inner(v, traction) * ufl.ds(subdomain_data=tags, subdomain_id=2, metadata=md))
    problem = NonlinearProblem(residual, u, [bc])
    solver = NewtonSolver(domain.comm, problem)
    solver.atol, solver.rtol, solver.convergence_criterion = 1e-8, 1e-8, "incremental"
    ksp = solver.krylov_solver
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    its = []
    for n in range(1, 10):
        traction.value[2] = n * STEP
        k, converged = solver.solve(u)
        assert converged
        its.append(int(k))
    tree = geometry.BoundingBoxTree(domain, domain.topology.dim)
    cells = geometry.compute_colliding_cells(domain, geometry.compute_collisions(tree, TIP.reshape(1, 3)),
                                             TIP.reshape(1, 3)).links(0)
    tip = u.eval(TIP, cells[:1]).tolist()
    return {"newton_per_step": its, "tip_displacement": tip,
            "dofs": V.dofmap.index_map.size_global * 3, "time_s": time.perf_counter() - t0}


if __name__ == "__main__":
    logging.getLogger().setLevel(logging.ERROR)
    print(json.dumps(main()))
