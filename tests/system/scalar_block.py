"""The global-scalar test problem: a block clamped at x = 0 whose far face x = L must move, on average, by
delta in x; the multiplier lam is the resultant of a uniform dead traction on that face (lam / A per area).
Field residual R(u) - lam (1/A) int_far v_x dA, equation c = k (mean u_x - delta) with k = E A / L (so c is
a force, like R). Linear elastic or neo-Hookean. Run as a script (under mpirun) it solves the linear case
and writes the answer to a JSON file: `python tests/system/scalar_block.py out.json`."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from fem_forms.physics.scalars import GlobalScalar  # noqa: E402
from fem_forms.solvers.snes import NonlinearProblem  # noqa: E402
from system.array_spring import by_coordinates  # noqa: E402

E, NU, L, W = 1e4, 0.3, 1.0, 0.2
A, K = W * W, E * W * W / L
CELLS = (8, 3, 3)                                     # 432 P1 dofs


def block(material: str = "linear", comm=MPI.COMM_WORLD, cells=CELLS):
    """(V, u, v, Pi, bcs, the far face's measure)."""
    msh = mesh.create_box(comm, [[0, 0, 0], [L, W, W]], list(cells), mesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    u, v = fem.Function(V), ufl.TestFunction(V)
    mu, lmbda = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    if material == "linear":
        eps = ufl.sym(ufl.grad(u))
        psi = mu * ufl.inner(eps, eps) + lmbda / 2 * ufl.tr(eps) ** 2
    else:
        F = ufl.Identity(3) + ufl.grad(u)
        J = ufl.det(F)
        psi = mu / 2 * (ufl.tr(F.T * F) - 3) - mu * ufl.ln(J) + lmbda / 2 * ufl.ln(J) ** 2
    far = mesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[0], L))
    tags = mesh.meshtags(msh, 2, far, np.ones(len(far), dtype=np.int32))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)(1)
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                         fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0)), V)
    return V, u, v, psi * ufl.dx, [bc], ds


def mean_gradient(V: fem.FunctionSpace, ds: ufl.Measure) -> fem.Form:
    """g = (1/A) int_far v_x dA: the gradient of the face's mean x-displacement (the unit resultant's load)."""
    return fem.form(ufl.TestFunction(V)[0] / A * ds)


def constrained(material: str = "linear", delta: float = 0.02, comm=MPI.COMM_WORLD, given: bool = False):
    """The block with the mean-displacement constraint as a global scalar: (problem, lam, delta Constant).
    `given`: the caller writes the couplings (dR/dp, dc/du, dc/dp 0) instead of letting them be derived."""
    V, u, v, Pi, bcs, ds = block(material, comm)
    msh = V.mesh
    lam = fem.Constant(msh, PETSc.ScalarType(0.0))
    target = fem.Constant(msh, PETSc.ScalarType(delta))
    R = ufl.derivative(Pi, u, v) - lam / A * v[0] * ds
    c = K * (u[0] / A - target / A) * ds            # k (mean u_x - delta): int over the face of 1/A is 1
    kw = dict(coupling=-1.0 / A * v[0] * ds, gradient=K / A * v[0] * ds, slope=0.0) if given else {}
    scalar = GlobalScalar("resultant", lam, c, **kw)
    p = NonlinearProblem(u, R, ufl.derivative(R, u, ufl.TrialFunction(V)), bcs, energy=Pi, scalars=[scalar])
    return p, lam, target


def loaded(material: str, comm=MPI.COMM_WORLD):
    """The same block under a given resultant T (a Constant), no scalar: (problem, T, mean-u_x form)."""
    V, u, v, Pi, bcs, ds = block(material, comm)
    T = fem.Constant(V.mesh, PETSc.ScalarType(0.0))
    Pi_T = Pi - T / A * u[0] * ds
    R = ufl.derivative(Pi_T, u, v)
    p = NonlinearProblem(u, R, ufl.derivative(R, u, ufl.TrialFunction(V)), bcs, energy=Pi_T)
    return p, T, fem.form(u[0] / A * ds)


if __name__ == "__main__":
    from fem_forms.solvers.snes import SNESDriver
    problem, lam, _ = constrained("linear")
    rec = SNESDriver(problem).solve_step()
    u_sorted = by_coordinates(problem.u.function_space, problem.u.x.array)
    if MPI.COMM_WORLD.rank == 0:
        Path(sys.argv[1]).write_text(json.dumps({"lam": float(lam.value), "iterations": rec.iterations,
                                                 "reason": rec.reason, "u": u_sorted.tolist()}))
