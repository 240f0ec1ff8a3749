"""The one KSP/TAO factory (solvers/linear.py): each kind gives its solver types and options, a caller's
options override the kind's defaults, and an option already in PETSc's database under the prefix wins over
both; the defaults written are not left behind for other objects."""
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import pytest

from fem_forms.solvers import linear


def diagonal(values) -> PETSc.Mat:
    """A diagonal AIJ matrix with the given diagonal (split over the ranks)."""
    n = len(values)
    A = PETSc.Mat().createAIJ((n, n), nnz=1, comm=MPI.COMM_WORLD)
    lo, hi = A.getOwnershipRange()
    for i in range(lo, hi):
        A.setValue(i, i, values[i])
    A.assemble()
    return A


@pytest.fixture
def db():
    """PETSc's options database, with every test_factory_* option this test set removed afterwards."""
    opts = PETSc.Options()
    yield opts
    for k in list(opts.getAll()):
        if k.startswith("test_factory_"):
            opts.delValue(k)


def test_lu_is_mumps_lu():
    A = diagonal(np.arange(1.0, 11.0))
    ksp = linear.make_ksp(A, "lu", prefix="test_factory_lu_")
    assert ksp.getType() == "preonly" and ksp.getOptionsPrefix() == "test_factory_lu_"
    pc = ksp.getPC()
    assert pc.getType() == "lu" and pc.getFactorSolverType() == "mumps"
    x, b = A.createVecs()
    b.set(1.0)
    ksp.solve(b, x)
    assert np.allclose(x.array, 1.0 / np.arange(1.0, 11.0)[slice(*A.getOwnershipRange())])
    ksp.destroy()


def test_inertia_counts_the_negative_pivots():
    A = diagonal([3.0, -1.0, 2.0, -4.0, 5.0, 1.0])
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = linear.make_ksp(A, "inertia")
    pc = ksp.getPC()
    assert ksp.getType() == "preonly" and pc.getType() == "cholesky" and pc.getFactorSolverType() == "mumps"
    F = pc.getFactorMatrix()
    pc.setUp()                                   # MUMPS takes the controls set before it starts here
    assert F.getMumpsIcntl(13) == 1 and F.getMumpsIcntl(24) == 1
    assert F.getMumpsInfog(12) == 2 and F.getMumpsInfog(28) == 0
    ksp.destroy()


def test_mass_is_cg_jacobi_with_the_callers_tolerances():
    A = diagonal(np.full(8, 2.0))
    ksp = linear.make_ksp(A, "mass", "test_factory_mass_", {"ksp_rtol": 1e-12, "ksp_atol": 1e-300,
                                                            "ksp_max_it": 2000})
    assert ksp.getType() == "cg" and ksp.getPC().getType() == "jacobi"
    rtol, atol, _, max_it = ksp.getTolerances()
    assert (rtol, atol, max_it) == (1e-12, 1e-300, 2000)
    ksp.destroy()


def test_cg_python_takes_the_callers_preconditioner():
    class Halve:
        calls = 0

        def apply(self, pc, x, y):
            Halve.calls += 1
            x.copy(y)
            y.scale(0.5)
    A = diagonal(np.full(4, 2.0))
    ksp = linear.make_ksp(A, "cg-python", "test_factory_gn_", {"ksp_rtol": 1e-3, "ksp_max_it": 200},
                          python_pc=Halve())
    assert ksp.getType() == "cg" and ksp.getPC().getType() == "python"
    assert ksp.getTolerances()[0] == 1e-3 and ksp.getTolerances()[3] == 200
    x, b = A.createVecs()
    b.set(1.0)
    ksp.solve(b, x)
    assert Halve.calls > 0 and np.allclose(x.array, 0.5)
    ksp.destroy()


def test_an_option_under_the_prefix_wins_and_defaults_are_not_left_behind(db):
    A = diagonal(np.full(6, 4.0))
    db["test_factory_user_ksp_type"] = "gmres"        # the user's (command line) choice
    db["test_factory_user_ksp_rtol"] = 1e-4
    ksp = linear.make_ksp(A, "mass", "test_factory_user_", {"ksp_rtol": 1e-12, "ksp_max_it": 77})
    assert ksp.getType() == "gmres"                   # the database beats the kind's cg
    assert ksp.getTolerances()[0] == 1e-4             # and the caller's options
    assert ksp.getTolerances()[3] == 77               # the caller's option beats PETSc's default
    assert ksp.getPC().getType() == "jacobi"          # the kind's default where nobody said otherwise
    # the user's values stay; the factory's own are gone once read
    assert db.getString("test_factory_user_ksp_type") == "gmres"
    assert not db.hasName("test_factory_user_pc_type") and not db.hasName("test_factory_user_ksp_max_it")
    ksp.destroy()
    db["test_factory_icntl_mat_mumps_icntl_24"] = 0   # MUMPS controls too
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = linear.make_ksp(A, "inertia", "test_factory_icntl_")
    ksp.getPC().setUp()
    assert ksp.getPC().getFactorMatrix().getMumpsIcntl(24) == 0
    assert ksp.getPC().getFactorMatrix().getMumpsIcntl(13) == 1
    ksp.destroy()


def test_tao_kind_and_a_user_type(db):
    tao = linear.make_tao(MPI.COMM_WORLD, "blmvm", "test_factory_tao_")
    assert tao.getType() == "blmvm" and not db.hasName("test_factory_tao_tao_type")
    tao.destroy()
    db["test_factory_tao2_tao_type"] = "lmvm"
    tao = linear.make_tao(MPI.COMM_WORLD, "blmvm", "test_factory_tao2_")
    assert tao.getType() == "lmvm"
    tao.destroy()


def test_an_unknown_kind_is_refused():
    with pytest.raises(KeyError):
        linear.make_ksp(diagonal([1.0]), "spooky")
