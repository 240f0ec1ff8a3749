"""Staggered (alternate minimization) solve of two coupled scalar fields through the one SNES driver:
E(u, v) = int 1/2 a |grad u|^2 + 1/2 b |grad v|^2 + c u v - f u dx, u = v = 0 on the boundary. The reference
is a direct solve of the assembled block system [[aK, cM], [cM, bK]] (scipy, free dofs); the rate at which
the sweeps contract is checked against the discrete block Gauss-Seidel rate c^2 / (a b mu_min^2), mu_min the
smallest eigenvalue of K x = mu M x (the one mode that survives the sweeps)."""
import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
import ufl
from dolfinx import fem, mesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI

from fem_forms.solvers import staggered
from fem_forms.solvers.snes import NonlinearProblem

A, B, N, RTOL = 1.0, 1.0, 8, 1e-10
# measured (8 x 8 P1, mu_min 20.51): c / mu_min 0.6, 0.25, 0.08 take 24, 10, 6 sweeps; the last change
# ratios 0.3600, 0.0625, 0.0064 (predicted 0.36, 0.0625, 0.0064 to 4 digits); the answer agrees with the
# block solve to 6.7e-11, 1.6e-11, 1.2e-11 of max|u|, max|v|
RATE_RTOL, ANSWER_RTOL = 0.02, 1e-9


def two_fields(c: float, f: float = 1.0):
    domain = mesh.create_unit_square(MPI.COMM_SELF, N, N)
    V = fem.FunctionSpace(domain, ("Lagrange", 1))
    u, v = fem.Function(V, name="u"), fem.Function(V, name="v")
    energy = (0.5 * A * ufl.inner(ufl.grad(u), ufl.grad(u)) + 0.5 * B * ufl.inner(ufl.grad(v), ufl.grad(v))
              + c * u * v - f * u) * ufl.dx
    domain.topology.create_connectivity(1, 2)
    boundary = fem.locate_dofs_topological(V, 1, mesh.exterior_facet_indices(domain.topology))
    problems = []
    for w in (u, v):
        bc = fem.dirichletbc(0.0, boundary, V)
        residual = ufl.derivative(energy, w, ufl.TestFunction(V))
        problems.append(NonlinearProblem(w, residual, ufl.derivative(residual, w, ufl.TrialFunction(V)), [bc],
                                         energy=energy))
    return problems, V, boundary, f


def _scipy(form) -> sp.csr_matrix:
    A = fpetsc.assemble_matrix(fem.form(form))
    A.assemble()
    indptr, cols, vals = A.getValuesCSR()
    return sp.csr_matrix((vals, cols, indptr), shape=A.getSize())


def reference(V, boundary, c: float, f: float):
    """(u, v, mu_min) from the assembled block system on the free dofs."""
    p, q = ufl.TrialFunction(V), ufl.TestFunction(V)
    K, M = _scipy(ufl.inner(ufl.grad(p), ufl.grad(q)) * ufl.dx), _scipy(p * q * ufl.dx)
    F = fpetsc.assemble_vector(fem.form(f * q * ufl.dx)).array
    free = np.setdiff1d(np.arange(K.shape[0]), boundary)
    Kf, Mf = K[free][:, free].toarray(), M[free][:, free].toarray()
    block = np.block([[A * Kf, c * Mf], [c * Mf, B * Kf]])
    sol = np.linalg.solve(block, np.concatenate([F[free], np.zeros(len(free))]))
    u, v = np.zeros(K.shape[0]), np.zeros(K.shape[0])
    u[free], v[free] = sol[:len(free)], sol[len(free):]
    return u, v, scipy.linalg.eigh(Kf, Mf, eigvals_only=True)[0]


def test_staggered_agrees_with_the_block_solve_and_contracts_at_the_predicted_rate():
    mu_min = reference(two_fields(0.0)[1], two_fields(0.0)[2], 0.0, 1.0)[2]
    sweeps = []
    for s in (0.6, 0.25, 0.08):
        c = s * mu_min
        problems, V, boundary, f = two_fields(c)
        report = staggered.solve(problems, rtol=RTOL)
        assert report.converged, report.reason
        u_ref, v_ref, _ = reference(V, boundary, c, f)
        err = max(np.abs(problems[0].u.x.array - u_ref).max() / np.abs(u_ref).max(),
                  np.abs(problems[1].u.x.array - v_ref).max() / np.abs(v_ref).max())
        largest = [max(ch) for ch in report.changes]
        moved = [x for x in largest if x > 0.0]           # the last sweep may not move at all (SNES at atol)
        measured = moved[-1] / moved[-2]
        predicted = c ** 2 / (A * B * mu_min ** 2)
        sweeps.append(report.iterations)
        print(f"c/mu_min {s}: {report.iterations} sweeps, rate {measured:.4f} (predicted {predicted:.4f}), "
              f"error {err:.1e}, mu_min {mu_min:.2f}")
        assert err < ANSWER_RTOL
        assert measured == pytest.approx(predicted, rel=RATE_RTOL)
    assert sweeps[0] > sweeps[1] > sweeps[2]


def test_a_rejected_sub_solve_ends_the_staggered_solve():
    problems, *_ = two_fields(1.0)
    report = staggered.solve(problems, rtol=RTOL, options={"snes_max_it": 0})
    assert not report.converged and report.reason.startswith("field 0 (u), sweep 1: SNES")
    print("rejected:", report.reason)


def test_max_iterations_ends_an_unconverged_solve():
    problems, V, boundary, f = two_fields(0.6 * 20.5)
    report = staggered.solve(problems, rtol=RTOL, max_iterations=3)
    assert not report.converged and report.iterations == 3 and len(report.changes) == 3
    print("unconverged:", report.reason)
