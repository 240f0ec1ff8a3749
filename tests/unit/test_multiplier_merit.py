"""The merit of a volume-controlled solve (fem_forms/solvers/multiplier_merit.py) against finite differences:
along the bordered Newton direction its slope is -du.(K + rho c_u c_u^T) du, which is what makes the retries'
line search descend (and a negative curvature flip the field step). A thick eighth sphere in the displacement
formulation (an energy), inflated by volume control, taken off equilibrium by a larger prescribed volume."""
import importlib.util

import numpy as np
from mpi4py import MPI
import pytest

import fem_forms as ff
from fem_forms.analyses.static.solve import load_path
from fem_forms.model import build_model
from fem_forms.solvers import continuation
from fem_forms.solvers.snes import SNESDriver
from helpers import ROOT

_geo = importlib.util.spec_from_file_location("thick_sphere", ROOT / "verification" / "geometry" / "thick_sphere.py")
thick_sphere = importlib.util.module_from_spec(_geo)
_geo.loader.exec_module(thick_sphere)


@pytest.fixture(scope="module")
def off_equilibrium(tmp_path_factory):
    """A driver at an equilibrium with 0.5 m^3 injected, its load then raised to 0.8 m^3, with the bordered
    tangent assembled there and the Newton direction Y (SNES steps to X - lambda Y)."""
    mesh = thick_sphere.build(tmp_path_factory.mktemp("sphere") / "thick_sphere.msh", 1.0, 2.0, h=0.4)
    scene = ff.Scene.from_dict({
        "title": "merit", "analysis": "static", "mesh": {"generator": "file", "file": str(mesh)},
        "material": {"model": "neo-hookean", "E": 3.0, "nu": 0.3}, "discretization": {"degree": 1},
        "fix": [{"where": {"group": g}, "components": [g[0]]} for g in ("x0", "y0", "z0")],
        "load": [{"type": "inflation", "name": "inside", "where": {"group": "inner"}, "volume": 0.5}]})
    model = build_model(scene)
    set_load, _ = load_path(model)
    problem = model.problem(set_load)
    drv = SNESDriver(problem, {}, "direct", "merit_test_", None, False)
    assert continuation.solve(problem, {}, steps=2, driver=drv).converged
    set_load(1.6)
    b = drv.bordered
    X = b.pack(problem.u.vector).copy()
    F = X.duplicate()
    b.residual(None, X, F)
    b.jacobian(None, X, b.J, b.J)
    Y = X.duplicate()
    b.apply(None, F, Y)
    return drv, X, Y


def test_only_a_multiplier_problem_with_an_energy_has_a_merit(off_equilibrium):
    drv, _, _ = off_equilibrium
    merit = drv.bordered.merit
    assert merit is not None and merit.rho[0] > 0
    assert merit.E is not None and not merit.active            # off until a retry


def test_the_merit_falls_along_the_newton_step_as_its_curvature_says(off_equilibrium):
    drv, X, Y = off_equilibrium
    merit = drv.bordered.merit
    slope = -merit.curvature(Y)                     # dM/dlambda at lambda = 0 along X - lambda Y
    assert slope < 0
    for eps, tol in ((1e-3, 1e-2), (1e-4, 1e-3)):
        plus, minus = X.copy(), X.copy()
        plus.axpy(-eps, Y)
        minus.axpy(eps, Y)
        fd = (merit.objective(None, plus) - merit.objective(None, minus)) / (2 * eps)
        assert fd == pytest.approx(slope, rel=tol)


def test_a_negative_curvature_flips_the_field_step_only(off_equilibrium):
    drv, X, Y = off_equilibrium
    merit, b = drv.bordered.merit, drv.bordered
    Z = Y.copy()
    assert not merit.precheck(X, Z) and np.array_equal(Z.array, Y.array)   # positive curvature: as it is
    rho = merit.rho.copy()
    drv.A.scale(-1.0)                                # a tangent past a fold, the constraint's term too weak:
    merit.rho = 0.0 * rho                            # negative curvature along Y
    try:
        assert merit.curvature(Y) < 0 and merit.precheck(X, Z)
    finally:
        drv.A.scale(-1.0)
        merit.rho = rho
    assert np.array_equal(Z.array[: b.n], -Y.array[: b.n])
    assert np.array_equal(Z.array[b.n:], Y.array[b.n:])   # the multiplier part: rank 0's tail
    assert MPI.COMM_WORLD.allreduce(merit.flips) >= 1
