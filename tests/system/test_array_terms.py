"""Array terms (energies given as arrays, not UFL) join the Newton solve, the energy line search and the
step cap: a spring written as an array term solves exactly as the same spring written in UFL (serial and
2 ranks, BAIJ and AIJ tangents), the Dirichlet rows stay the UFL assembly's, and max_step caps the first
trial of the line search (sign of PETSc's step checked). The spring problem is tests/system/array_spring.py."""
import json

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from petsc4py import PETSc

from fem_forms.physics.array_term import ArrayTerm
from fem_forms.solvers import acceptance
from fem_forms.solvers.snes import NonlinearProblem, SNESDriver
from helpers import ROOT, mpirun
from system.array_spring import AIJ, CASES, by_coordinates, run, solve, spring_problem

# measured (serial): the clamped P1 case takes 20 Newton iterations with backtracking (lambda 0.5, 0.1)
# on a nonconvex path that doubles round-off per iteration: iterates agree to 1.2e-11 of the largest
# displacement, residual norms to 1.7e-10 of the first residual (2e-15 and 4e-14 in the free P2 case)
ITERATES_RTOL, HISTORY_RTOL = 1e-10, 1e-9


def _agree(a: dict, b: dict) -> tuple[float, float]:
    """(largest iterate difference / largest displacement, largest residual difference / first residual)
    between two runs that must take the same iterations."""
    assert a["reason"] == b["reason"] and a["iterations"] == b["iterations"]
    ha, hb = np.array(a["history"]), np.array(b["history"])
    ia, ib = np.array(a["iterates"]), np.array(b["iterates"])
    assert ia.shape == ib.shape
    return float(np.abs(ia - ib).max() / np.abs(ia[-1]).max()), float(np.abs(ha - hb).max() / ha[0])


@pytest.mark.parametrize("tangent", ["baij", "aij"])
@pytest.mark.parametrize("case", list(CASES))
def test_array_spring_solves_as_the_ufl_spring(case, tangent):
    r = run(case, AIJ if tangent == "aij" else None)
    assert r["ufl"]["reason"].startswith("CONVERGED")
    du, dr = _agree(r["ufl"], r["array"])
    print(f"{case} {tangent}: {r['ufl']['iterations']} Newton iterations, iterates {du:.1e}, residuals {dr:.1e}")
    assert du < ITERATES_RTOL and dr < HISTORY_RTOL


def test_dirichlet_rows_stay_the_ufl_assembly_s():
    """At a deformed state off the Dirichlet values the array spring's residual and tangent equal the UFL
    spring's, on the clamped rows (which the spring's facets share) too: identity rows and columns,
    set_bc's residual x - g, and the lifting of the free rows by the spring's Hessian."""
    drivers = []
    for as_array in (False, True):
        p = spring_problem(as_array, **CASES["clamped P1"])
        p.u.interpolate(lambda x: np.vstack([0.01 * x[1], -0.02 * x[0] * x[2], -0.1 * x[0] ** 2]))
        drivers.append(SNESDriver(p))
    (d_u, d_a) = drivers
    x = d_u.p.u.vector.copy()
    x.array[:] += 1e-3                          # constrained dofs off their value: set_bc's rows are x - g
    mats, vecs = [], []
    for d in drivers:
        b = d.b.duplicate()
        d._residual(None, x, b)
        d._jacobian(None, x, d.A, d.A)
        mats.append(d.A.copy())
        vecs.append(b)
    assert (vecs[1] - vecs[0]).norm() < 1e-12 * vecs[0].norm()
    diff = mats[1].copy()
    diff.axpy(-1.0, mats[0])
    assert diff.norm() < 1e-12 * mats[0].norm()
    clamped = d_a.arrays.constrained
    assert len(clamped) == 3 * 9
    lo, hi = mats[1].getOwnershipRange()
    for r in clamped[(clamped >= lo) & (clamped < hi)]:
        cols, vals = mats[1].getRow(int(r))
        assert np.array_equal(vals[cols == r], [1.0]) and not np.any(vals[cols != r])
        assert vecs[1].getValue(int(r)) == x.getValue(int(r))           # x - g, g = 0


class HalfStep(ArrayTerm):
    """No energy; halves every step that lowers the tip (a stand-in for a collision step bound), and keeps
    the steps it was asked about."""

    def __init__(self, tip: np.ndarray):
        self.tip, self.steps = tip, []

    def energy_value(self, x):
        return 0.0

    def add_gradient(self, x, b):
        pass

    def add_hessian(self, x, A, constrained):
        pass

    def max_step(self, x, dx):
        self.steps.append(dx.array.copy())
        return 0.5 if dx.array[self.tip].sum() < 0 else 1.0


class Inert(HalfStep):
    max_step = ArrayTerm.max_step                # cannot cap: no pre-check installed


def linear_block(terms_of=lambda V: []):
    """A clamped linear-elastic block under gravity (Newton converges in one step); its tip's z dofs."""
    msh = mesh.create_box(MPI.COMM_SELF, [[0, 0, 0], [1, 0.2, 0.2]], [6, 2, 2], mesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    u, v, du = fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    eps = ufl.sym(ufl.grad(u))
    Pi = (1e4 * ufl.inner(eps, eps) + 5e3 * ufl.tr(eps) ** 2 + 1e3 * 9.81 * u[2]) * ufl.dx
    R = ufl.derivative(Pi, u, v)
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                         fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0)), V)
    tip = 3 * fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 1.0)) + 2
    terms = terms_of(tip)
    return NonlinearProblem(u, R, ufl.derivative(R, u, du), [bc], energy=Pi, array_terms=terms), terms


def test_max_step_caps_the_first_trial_with_petsc_s_sign():
    plain, _ = linear_block()
    drv, rec, its = solve(plain)
    assert rec.iterations == 1
    exact = plain.u.x.array.copy()
    # no capping term: no pre-check, the same single step, bit for bit
    inert, _ = linear_block(lambda tip: [Inert(tip)])
    _, rec_i, _ = solve(inert)
    assert rec_i.iterations == 1 and np.array_equal(inert.u.x.array, exact)
    capped, (term,) = linear_block(lambda tip: [HalfStep(tip)])
    drv, rec, its = solve(capped)
    # max_step saw the step x -> x + dx with dx the full Newton step (newtonls tries x - lambda y, dx = -y):
    # downward at the tip, so halved; the energy line search takes the halved step whole (lambda = 1)
    np.testing.assert_allclose(term.steps[0], exact, rtol=0, atol=1e-12 * np.abs(exact).max())
    np.testing.assert_allclose(its[1].ravel(), 0.5 * by_coordinates(capped.u.function_space, exact).ravel(),
                               rtol=0, atol=1e-12 * np.abs(exact).max())      # the first iterate: half
    assert rec.iterations > 20 and drv.arrays.last_cap == 0.5     # halving the error each iteration
    np.testing.assert_allclose(capped.u.x.array, exact, rtol=0, atol=1e-7 * np.abs(exact).max())
    # the cap survives the line-search switch of the polish (petsc4py has no getLineSearch)
    drv.set_line_search("basic")
    capped.u.x.array[:] = 0.0
    term.steps.clear()
    drv.solve_step()
    assert len(term.steps) > 1 and np.allclose(term.steps[0], exact, atol=1e-12 * np.abs(exact).max())


@pytest.mark.mpi
def test_two_ranks_give_the_serial_iterates(tmp_path):
    out = tmp_path / "par.json"
    p = mpirun([str(ROOT / "tests" / "system" / "array_spring.py"), str(out)])
    assert p.returncode == 0, p.stderr
    par = json.loads(out.read_text())
    for key, runs in par.items():
        case, tangent = key.split("|")
        serial = run(case, AIJ if tangent == "aij" else None)
        for kind in ("ufl", "array"):
            du, dr = _agree(serial[kind], runs[kind])
            print(f"{key} {kind}: 2 ranks vs serial: iterates {du:.1e}, residuals {dr:.1e}")
            assert du < ITERATES_RTOL and dr < HISTORY_RTOL
        du, dr = _agree(runs["ufl"], runs["array"])
        print(f"{key}: 2 ranks, array vs UFL: iterates {du:.1e}, residuals {dr:.1e}")
        assert du < ITERATES_RTOL and dr < HISTORY_RTOL


class RoundOffEnergy(HalfStep):
    """HalfStep (a step bound that makes Newton converge linearly, as contact's PSD-projected Hessians do) whose
    energy grows by `noise` at every evaluation: a stand-in for the energy's round-off, on which the energy line
    search fails once a step's true decrease falls below it."""

    def __init__(self, tip: np.ndarray, noise: float):
        super().__init__(tip)
        self.noise, self.calls = noise, 0

    def energy_value(self, x):
        self.calls += 1
        return self.noise * self.calls


def test_a_line_search_that_fails_on_round_off_at_an_equilibrium_is_accepted():
    """The line search stops on the energy's noise with the residual far below acceptance's bar, and the polish
    (3 capped full steps) does not reach SNES's tolerance: the step is an equilibrium and is accepted. Rejecting
    it cut the step back and sent a frictional ring on two ranks down another path than on one (-4.95 / -4.93 N)."""
    plain, _ = linear_block()
    SNESDriver(plain).solve_step()
    exact = plain.u.x.array.copy()
    energy = abs(fem.assemble_scalar(fem.form(plain.energy)))
    noisy, (term,) = linear_block(lambda tip: [RoundOffEnergy(tip, 1e-13 * energy)])
    drv = SNESDriver(noisy)
    scale = drv.load_scale()
    rec = drv.solve_step()
    assert rec.reason == "DIVERGED_LINE_SEARCH" and rec.accepted
    assert 10 * drv.base_atol() < rec.residuals[-1] < 1e-6 * scale     # 2.4e-7 of scale: the polish did not converge
    assert acceptance.why_rejected(drv, rec, load_scale=scale) is None
    np.testing.assert_allclose(noisy.u.x.array, exact, rtol=0, atol=1e-6 * np.abs(exact).max())   # 2.4e-7 of max |u|
