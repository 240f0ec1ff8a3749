"""Global scalar unknowns solved monolithically with the field (physics/scalars.py, solvers/bordered.py), on
the block of tests/system/scalar_block.py (mean x-displacement of the far face prescribed, the traction
resultant its multiplier): against a scipy solve of the assembled system (linear), against load control
with the resultant found by a secant iteration (neo-Hookean), under continuation with a rejected step
(the scalar rolled back), and on 2 ranks."""
import json

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI

from fem_forms.solvers import continuation
from fem_forms.solvers.snes import SNESDriver
from fem_forms.state import State
from helpers import ROOT, mpirun
from system.array_spring import by_coordinates
from system.scalar_block import K, block, constrained, loaded, mean_gradient

DELTA = 0.02                     # linear case (2% of the length)
DELTA_NH = 0.1                   # neo-Hookean case: 10% stretch


def _rel(a, b) -> float:
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(np.asarray(b)).max())


def _scipy_reference(delta: float) -> tuple[np.ndarray, float]:
    """Linearity: K u1 = g for a unit resultant (g = (1/A) int v_x dA, zero on the clamped dofs), then
    lam = delta / mean(u1) = delta / (g . u1) and u = lam u1; K assembled by dolfinx, solved by scipy."""
    V, u, v, Pi, bcs, ds = block("linear", MPI.COMM_SELF)
    Kmat = fpetsc.assemble_matrix(fem.form(ufl.derivative(ufl.derivative(Pi, u, v), u)), bcs=bcs)
    Kmat.assemble()
    indptr, cols, vals = Kmat.getValuesCSR()
    Ks = sp.csr_matrix((vals, cols, indptr), shape=Kmat.getSize())
    g = fpetsc.assemble_vector(mean_gradient(V, ds)).array.copy()
    g[np.concatenate([bc.dof_indices()[0] for bc in bcs])] = 0.0
    u1 = spla.spsolve(Ks.tocsc(), g)
    lam = delta / (g @ u1)
    u.x.array[:] = lam * u1
    return by_coordinates(V, u.x.array), lam


def test_linear_block_matches_the_scipy_solve():
    p, lam, _ = constrained("linear", DELTA, comm=MPI.COMM_SELF)
    drv = SNESDriver(p)
    assert drv.bordered is not None and drv.E is None and drv.options["snes_linesearch_type"] == "basic"
    rec = drv.solve_step()
    u = by_coordinates(p.u.function_space, p.u.x.array)
    u_ref, lam_ref = _scipy_reference(DELTA)
    eu, el = _rel(u, u_ref), abs(float(lam.value) - lam_ref) / abs(lam_ref)
    print(f"linear: {rec.iterations} Newton iteration(s) {rec.residuals}, lam {float(lam.value):.12g} "
          f"(scipy {lam_ref:.12g}), errors u {eu:.1e}, lam {el:.1e}")
    assert rec.reason.startswith("CONVERGED") and rec.iterations == 1
    assert eu < 1e-10 and el < 1e-10
    # the caller's own couplings (dR/dp as the unit resultant's virtual work, dc/dp 0) give the same answer
    q, lam2, _ = constrained("linear", DELTA, comm=MPI.COMM_SELF, given=True)
    SNESDriver(q).solve_step()
    eg = abs(float(lam2.value) - float(lam.value)) / abs(float(lam.value))
    print(f"linear, couplings given by the caller: lam differs from the derived couplings' by {eg:.1e}")
    assert eg < 1e-12


def _secant_reference(delta: float) -> tuple[np.ndarray, float, int]:
    """Load control on the resultant T (energy line search, no scalar), T found by the secant iteration on
    mean u_x(T) = delta. Returns (u by coordinates, T, secant iterations)."""
    p, T, mean_form = loaded("neo", comm=MPI.COMM_SELF)
    # full Newton steps: asked for 1e-12, the energy line search stops on the energy's round-off first
    drv = SNESDriver(p, {"snes_rtol": 1e-12, "snes_linesearch_type": "basic"})

    def mismatch(t: float) -> float:
        T.value = t
        drv.load_scale(refresh=True)
        assert drv.solve_step().reason.startswith("CONVERGED")
        return fem.assemble_scalar(mean_form) - delta

    t0, t1 = K * delta, 1.05 * K * delta
    f0, f1 = mismatch(t0), mismatch(t1)
    for it in range(30):
        if f1 == f0:                             # converged to the last bit: the secant has nothing left to do
            break
        t0, t1, f0 = t1, t1 - f1 * (t1 - t0) / (f1 - f0), f1
        f1 = mismatch(t1)
        if abs(f1) < 1e-14 * delta:
            break
    return by_coordinates(p.u.function_space, p.u.x.array), t1, it + 1


def test_neo_hookean_block_converges_quadratically_to_the_load_control_answer():
    p, lam, _ = constrained("neo", DELTA_NH, comm=MPI.COMM_SELF)
    rec = SNESDriver(p).solve_step()
    e = np.array(rec.residuals) / rec.residuals[0]
    ratios = e[2:] / e[1:-1] ** 2
    u_ref, T_ref, secants = _secant_reference(DELTA_NH)
    eu, el = _rel(by_coordinates(p.u.function_space, p.u.x.array), u_ref), abs(float(lam.value) - T_ref) / T_ref
    print(f"neo-Hookean: {rec.iterations} Newton iterations, relative residuals {e}, e_k+1/e_k^2 {ratios}; "
          f"lam {float(lam.value):.12g}, secant reference {T_ref:.12g} ({secants} secant steps); "
          f"errors u {eu:.1e}, lam {el:.1e}")
    assert rec.reason.startswith("CONVERGED") and rec.iterations <= 5
    assert np.all(ratios < 50.0)                       # quadratic: e_k+1 <= C e_k^2 (measured C < 2)
    assert eu < 1e-8 and el < 1e-8


def test_continuation_commits_and_rolls_back_the_scalar():
    """delta ramped by the load factor; the first trial is rejected once (inadmissible): the rollback must
    return lam to its committed value, and every trial must start from the last accepted lam."""
    p, lam, target = constrained("neo", DELTA_NH, comm=MPI.COMM_SELF)
    seen, judged = [], []                            # lam at each set_load, lam at each step's end
    p.set_load = lambda f: (seen.append(float(lam.value)), setattr(target, "value", f * DELTA_NH))
    p.inadmissible = lambda: (judged.append(float(lam.value)), "test: reject once" if len(judged) == 1 else None)[1]
    report = continuation.solve(p, steps=2)
    assert report.converged and [r.accepted for r in report.steps] == [False] + [True] * (len(report.steps) - 1)
    # set_load(1.0) for the scale, then one per trial: lam 0 at the scale, the first trial and its retry
    # (the rejected trial's lam judged[0] != 0 rolled back), then the lam each accepted step committed
    assert judged[0] != 0.0 and seen[:3] == [0.0, 0.0, 0.0] and seen[3:] == judged[1:-1]
    ref, _, _ = constrained("neo", DELTA_NH, comm=MPI.COMM_SELF)
    SNESDriver(ref).solve_step()
    lam_ref = float(ref.scalars[0].value.value)
    print(f"continuation: steps {[(r.load, r.iterations, r.accepted) for r in report.steps]}, lam "
          f"{float(lam.value):.12g}, one-step lam {lam_ref:.12g}")
    assert abs(float(lam.value) - lam_ref) < 1e-9 * lam_ref
    assert _rel(p.u.x.array, ref.u.x.array) < 1e-9


def test_state_commits_and_rolls_back_scalars():
    p, lam, _ = constrained("linear", DELTA, comm=MPI.COMM_SELF)
    s = State({"u": p.u})
    s.add_scalar("resultant", lam)
    lam.value = 3.0
    s.commit()
    lam.value = 7.0
    s.rollback()
    assert float(lam.value) == 3.0


@pytest.mark.mpi
def test_two_ranks_give_the_serial_answer(tmp_path):
    out = tmp_path / "par.json"
    run = mpirun([str(ROOT / "tests" / "system" / "scalar_block.py"), str(out)])
    assert run.returncode == 0, run.stderr
    par = json.loads(out.read_text())
    p, lam, _ = constrained("linear", DELTA, comm=MPI.COMM_SELF)
    SNESDriver(p).solve_step()
    eu = _rel(par["u"], by_coordinates(p.u.function_space, p.u.x.array))
    el = abs(par["lam"] - float(lam.value)) / abs(float(lam.value))
    print(f"2 ranks: {par['iterations']} iteration(s), errors against serial u {eu:.1e}, lam {el:.1e}")
    assert par["reason"].startswith("CONVERGED") and eu < 1e-10 and el < 1e-10


def test_an_iterative_k_solve_gives_the_direct_answer():
    """The driver's iterative kind (GAMG) on the inner K solve, its tolerance tightened to 1e-12: the same
    Newton iterations and answer as MUMPS LU."""
    answers = {}
    for kind in ("direct", "iterative"):
        p, lam, _ = constrained("neo", DELTA_NH, comm=MPI.COMM_SELF)
        drv = SNESDriver(p, linear_kind=kind)
        rec = drv.solve_step()
        answers[kind] = (rec.iterations, p.u.x.array.copy(), float(lam.value))
    assert drv.options["K_ksp_rtol"] <= 1e-12 and drv.options["ksp_type"] == "preonly"
    (n_d, u_d, l_d), (n_i, u_i, l_i) = answers["direct"], answers["iterative"]
    print(f"iterative K: {n_i} Newton iterations (direct {n_d}), u {_rel(u_i, u_d):.1e}, "
          f"lam {abs(l_i - l_d) / l_d:.1e}")
    assert n_i == n_d and _rel(u_i, u_d) < 1e-10 and abs(l_i - l_d) < 1e-10 * l_d


def test_a_problem_s_own_state_takes_its_scalars():
    p, lam, _ = constrained("linear", DELTA, comm=MPI.COMM_SELF)
    p.state = State({"u": p.u})
    SNESDriver(p)
    assert p.state.scalars == {"resultant": lam}
