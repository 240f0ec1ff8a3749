"""The line search's energy kept from the previous Newton iteration (solvers/energy_memo.py): every value it gives
back is the energy the form assembles at that point, also after a load changes between two solves; it saves about
one assembly per Newton iteration; the iterates are those of a solve without it."""
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
import pytest
import ufl

from fem_forms.solvers import snes
from fem_forms.solvers.energy_memo import EnergyMemo


def driver_for(name: str):
    """A nonlinear energy, 1/2 |grad u|^2 + c u^4 / 4 - f u, u = 0 on the boundary: (driver, the load f)."""
    mesh = dmesh.create_unit_cube(MPI.COMM_WORLD, 4, 4, 4)
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    u = fem.Function(V)
    c, f = fem.Constant(mesh, 50.0), fem.Constant(mesh, 20.0)
    energy = (0.5 * ufl.inner(ufl.grad(u), ufl.grad(u)) + c * u ** 4 / 4 - f * u) * ufl.dx
    residual = ufl.derivative(energy, u, ufl.TestFunction(V))
    mesh.topology.create_connectivity(2, 3)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    bc = fem.dirichletbc(0.0, fem.locate_dofs_topological(V, 2, facets), V)
    problem = snes.NonlinearProblem(u, residual, ufl.derivative(residual, u, ufl.TrialFunction(V)), [bc],
                                    energy=energy)
    return snes.SNESDriver(problem, linear_kind="direct", prefix=f"test_energy_memo_{name}_"), f


def fresh_energy(driver, x) -> float:
    saved = driver.p.u.x.array.copy()
    driver.set_state(x)
    value = driver.comm.allreduce(fem.assemble_scalar(driver.E), op=MPI.SUM)
    driver.p.u.x.array[:] = saved
    return value


@pytest.fixture
def checked(monkeypatch):
    """Every value the memo gives back compared with the form's energy at that point (exactly)."""
    given = []
    lookup = EnergyMemo.lookup

    def checking(self, snes_, x):
        value = lookup(self, snes_, x)
        if value is not None:
            given.append((value, fresh_energy(current[0], x)))
        return value
    current = []
    monkeypatch.setattr(EnergyMemo, "lookup", checking)
    return given, current


def test_kept_energies_are_the_forms_at_their_point_across_a_load_change(checked):
    given, current = checked
    driver, f = driver_for("checked")
    current.append(driver)
    first = driver.solve_step()
    f.value = 35.0                                    # a new load between two solves from the same state
    second = driver.solve_step()
    assert first.accepted and second.accepted
    assert first.iterations >= 3 and second.iterations >= 2
    assert len(given) >= first.iterations + second.iterations - 2
    for kept, fresh in given:
        assert kept == fresh
    driver.snes.destroy()


def test_the_iterates_are_those_without_it():
    with_memo, _ = driver_for("with")
    without, _ = driver_for("without")
    without.energy_memo.lookup = lambda snes_, x: None      # every energy assembled
    a, b = with_memo.solve_step(), without.solve_step()
    assert with_memo.energy_memo.hits >= a.iterations - 1 and without.energy_memo.hits == 0
    assert a.iterations == b.iterations
    np.testing.assert_array_equal(a.residuals, b.residuals)
    np.testing.assert_array_equal(with_memo.p.u.x.array, without.p.u.x.array)
    for d in (with_memo, without):
        d.snes.destroy()
