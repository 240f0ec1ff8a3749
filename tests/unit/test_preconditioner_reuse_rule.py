"""The rule that keeps a multigrid preconditioner across Newton steps: rebuild exactly when the extra
iterations cost more than a build, and always on the first Jacobian of a solve."""
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from fem_forms.solvers import preconditioner_reuse as pr


@pytest.mark.parametrize("extra_its, rebuild", [(0, False), (40, False), (60, True)])
def test_rebuild_exactly_when_extra_iterations_cost_more_than_a_build(extra_its, rebuild):
    snes = PETSc.SNES().create(MPI.COMM_SELF)
    reuse = pr.PreconditionerReuse(snes, MPI.COMM_SELF)
    # a build took 0.5 s; one iteration costs 0.01 s: break-even at 50 extra iterations
    reuse._fresh = (0.5, 0.01, 30)
    reuse._last = (0.0, 0.01, 30 + extra_its)
    assert reuse.decide() is rebuild
    assert reuse.last_solve_reused is (not rebuild)
    snes.destroy()


def test_first_jacobian_of_a_solve_always_rebuilds():
    snes = PETSc.SNES().create(MPI.COMM_SELF)
    reuse = pr.PreconditionerReuse(snes, MPI.COMM_SELF)
    reuse._fresh = (0.5, 0.01, 30)
    reuse._last = (0.0, 0.01, 30)
    reuse.start_solve()
    assert reuse.decide() is True
    snes.destroy()
