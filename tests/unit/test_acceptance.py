"""The one step acceptance (solvers/acceptance.py): a step SNES converged is still rejected for NaN or Inf in
the state, an inadmissible state (with its reason) and a residual above its threshold; a residual at the
round-off floor passes whatever its relative size."""
import math

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
import pytest
import ufl

from fem_forms.solvers import acceptance, snes


@pytest.fixture(scope="module")
def solved():
    """A Poisson problem (u = 0 on the boundary, unit source) solved by the driver: (driver, record, u)."""
    mesh = dmesh.create_unit_cube(MPI.COMM_WORLD, 3, 3, 3)
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    u, v = fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx - v * ufl.dx
    mesh.topology.create_connectivity(2, 3)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    bc = fem.dirichletbc(0.0, fem.locate_dofs_topological(V, 2, facets), V)
    problem = snes.NonlinearProblem(u, F, ufl.derivative(F, u, ufl.TrialFunction(V)), [bc])
    driver = snes.SNESDriver(problem, linear_kind="direct", prefix="test_acceptance_")
    record = driver.solve_step()
    assert record.accepted
    yield driver, record, u
    driver.snes.destroy()


def test_a_converged_step_at_equilibrium_is_accepted(solved):
    driver, record, _ = solved
    assert acceptance.why_rejected(driver, record, load_scale=driver.load_scale()) is None
    assert record.checked_residual <= acceptance.ACCEPTED * driver.load_scale()


def test_what_snes_refused_is_rejected_with_its_reason(solved):
    driver, _, _ = solved
    failed = snes.StepRecord(1.0, 3, [1.0, 0.5], "DIVERGED_LINE_SEARCH", False)
    assert acceptance.why_rejected(driver, failed) == "SNES DIVERGED_LINE_SEARCH"


def test_a_nan_state_is_rejected(solved):
    driver, record, u = solved
    saved = u.x.array.copy()
    try:
        u.x.array[0] = math.nan
        assert acceptance.why_rejected(driver, record) == "NaN or Inf in the solution"
    finally:
        u.x.array[:] = saved


def test_an_inadmissible_state_is_rejected_with_its_reason(solved):
    driver, record, _ = solved
    try:
        driver.p.inadmissible = lambda: "inverted elements (min det = -0.5)"
        assert acceptance.why_rejected(driver, record) == "inverted elements (min det = -0.5)"
    finally:
        driver.p.inadmissible = None


def test_a_residual_above_its_threshold_is_rejected(solved):
    driver, record, u = solved
    saved = u.x.array.copy()
    try:
        u.x.array[:] *= 1.01                     # 1 % off equilibrium: a residual 1e-2 of the load's
        why = acceptance.why_rejected(driver, record, load_scale=driver.load_scale())
        assert why is not None and why.startswith("residual ") and "left, above" in why
        assert record.checked_residual > acceptance.ACCEPTED * driver.load_scale()
    finally:
        u.x.array[:] = saved
    # SNES's own last residual (reassemble False) is tested against the step's first one
    stalled = snes.StepRecord(1.0, 2, [1.0, 1e-3], "CONVERGED_SNORM_RELATIVE", True)
    assert acceptance.why_rejected(driver, stalled, rtol=acceptance.LINEAR_DROP, reassemble=False) is not None
    assert stalled.checked_residual == 1e-3


def test_a_residual_at_the_round_off_floor_is_accepted(solved):
    driver, record, _ = solved
    # asked for 0 relative residual, a step at equilibrium still passes: its residual is round-off
    assert acceptance.why_rejected(driver, record, rtol=0.0) is None
    assert 0.0 < record.checked_residual <= driver.roundoff_floor(acceptance.ROUNDOFF_SAFETY)
    # no residual test at all with rtol None (Newton heat steps)
    assert acceptance.why_rejected(driver, snes.StepRecord(1.0, 1, [1.0, 1.0], "CONVERGED_FNORM_ABS", True),
                                   rtol=None) is None


def test_the_scale_is_the_larger_of_the_load_scale_and_the_first_residual():
    rec = snes.StepRecord(1.0, 2, [3.0, 1e-9], "CONVERGED_FNORM_RELATIVE", True)
    assert acceptance.step_scale(rec) == 3.0
    assert acceptance.step_scale(rec, load_scale=5.0) == 5.0
    assert acceptance.step_scale(snes.StepRecord(1.0, 0, [], "CONVERGED_ITS", True)) == 0.0
    assert np.isclose(acceptance.ACCEPTED, 1e-6) and np.isclose(acceptance.LINEAR_DROP, 1e-5)
