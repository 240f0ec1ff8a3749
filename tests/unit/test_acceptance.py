"""The one step acceptance (solvers/acceptance.py): a step SNES converged is still rejected for NaN or Inf in
the state, an inadmissible state (with its reason) and a residual above its threshold; a residual at the
round-off floor passes whatever its relative size. A line search that fails on the energy's round-off near
the answer is finished by full Newton steps (solvers/polish.py) unless they move the answer; far from it, it
fails."""
import math

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import pytest
import ufl

from fem_forms.solvers import acceptance, polish, snes


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


class NoisyEnergyDriver(snes.SNESDriver):
    """A driver whose energy is noise (growing at every evaluation) once the residual is below `noisy_below`: a
    stand-in for the energy's round-off, on which the line search fails near the answer (the README's first scene
    on one CPU's BLAS kernels: at 3.9e-10 of its 4.2e-2 scale, then cut back: 35 Newton iterations for 17)."""
    noisy_below = 0.0
    noise_seen = False

    def _objective(self, snes_, x):
        value = super()._objective(snes_, x)
        if self.history and self.history[-1] < self.noisy_below:
            self.noise_seen, self.calls = True, getattr(self, "calls", 0) + 1
            value += self.calls
        return value


def slow_newton_driver(noisy_below: float) -> NoisyEnergyDriver:
    """Poisson as an energy, its tangent 1.05x too stiff: Newton converges linearly (x 0.048 a step), so the
    residual passes through every decade and meets the noise where `noisy_below` (relative to the scale) says."""
    mesh = dmesh.create_unit_cube(MPI.COMM_WORLD, 3, 3, 3)
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    u, v = fem.Function(V), ufl.TestFunction(V)
    energy = (0.5 * ufl.inner(ufl.grad(u), ufl.grad(u)) - u) * ufl.dx
    R = ufl.derivative(energy, u, v)
    mesh.topology.create_connectivity(2, 3)
    bc = fem.dirichletbc(0.0, fem.locate_dofs_topological(V, 2, dmesh.exterior_facet_indices(mesh.topology)), V)
    problem = snes.NonlinearProblem(u, R, 1.05 * ufl.derivative(R, u, ufl.TrialFunction(V)), [bc], energy=energy)
    driver = NoisyEnergyDriver(problem, linear_kind="direct", prefix="test_noisy_energy_")
    driver.noisy_below = noisy_below * driver.load_scale()
    return driver


def polished_after(monkeypatch) -> list:
    """The reasons SNES stopped with before each polish (fem_forms/solvers/polish.py) from now on."""
    seen, original = [], polish.polish

    def recording(driver, reason):
        seen.append(reason)
        return original(driver, reason)
    monkeypatch.setattr(polish, "polish", recording)
    return seen


def test_a_line_search_that_fails_on_round_off_near_the_answer_is_finished_by_full_newton_steps(monkeypatch):
    seen = polished_after(monkeypatch)
    driver = slow_newton_driver(1e-6)
    record = driver.solve_step()
    assert driver.noise_seen and seen == [PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH]   # failed at 2.5e-7 ...
    assert record.reason.startswith("CONVERGED") and record.accepted      # ... and the polish converged
    assert record.residuals[-1] <= 1e-9 * driver.load_scale()
    assert acceptance.why_rejected(driver, record, load_scale=driver.load_scale()) is None
    driver.destroy()


def test_without_a_load_scale_the_polish_measures_near_against_the_first_residual(monkeypatch):
    """A time step measures no load scale: a line search failing near its answer (here at 2.5e-7 of the first
    residual) is finished by full Newton steps all the same (it used to redo the step from its start)."""
    seen = polished_after(monkeypatch)
    driver = slow_newton_driver(1e-6)
    scale, driver._load_scale = driver.load_scale(), None   # unmeasured, as in a time step
    driver.user_options["snes_atol"] = 1e-10 * scale          # what 3 polish steps of this slow Newton reach
    record = driver.solve_step()
    assert driver.known_load_scale is None and seen == [PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH]
    assert record.reason.startswith("CONVERGED") and record.accepted
    assert record.residuals[-1] <= 1e-9 * record.residuals[0]
    driver.destroy()


def test_a_polish_that_moves_the_answer_is_not_kept(monkeypatch):
    """The same solve with polish.FINISH_MOVE = 0: the polish's move counts as a jump to another equilibrium (past a
    limit load), so the failed line search stands and the step is rejected."""
    monkeypatch.setattr(polish, "FINISH_MOVE", 0.0)
    driver = slow_newton_driver(1e-6)
    record = driver.solve_step()
    assert driver.noise_seen and record.reason == "DIVERGED_LINE_SEARCH" and not record.accepted
    driver.destroy()


def test_a_line_search_that_fails_far_from_the_answer_is_a_failed_step():
    driver = slow_newton_driver(1e-2)            # noise from the first residual below 1e-2 of the scale on
    record = driver.solve_step()
    assert driver.noise_seen and record.reason == "DIVERGED_LINE_SEARCH" and not record.accepted
    assert record.residuals[-1] > 1e-6 * driver.load_scale()
    driver.destroy()
