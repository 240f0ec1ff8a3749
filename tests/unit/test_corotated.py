"""Unit tests of the corotated material and the polar decomposition it rests on: closed forms at
homogeneous deformations (scipy.linalg.polar as the reference), repeated stretches, rotation invariance
at quadrature points, small-strain agreement with linear elasticity, parameters as Constants."""
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from scipy.linalg import polar
from scipy.spatial.transform import Rotation

import fem_forms as ff
from fem_forms.kinematics import biot_invariants, deformation_gradient, polar_rotation
from fem_forms.materials import lame_from_young_poisson, mixed_energy
from fem_forms.materials.constants import bind_constants, parameter_value, set_parameters

MU, LMBDA = lame_from_young_poisson(2.0e6, 0.3)
Q = Rotation.from_rotvec([0.4, -1.3, 2.1]).as_matrix()          # a large rotation (about 143 degrees)


@pytest.fixture(scope="module")
def unit_cube():
    return mesh.create_unit_cube(MPI.COMM_WORLD, 2, 2, 2)


def value(domain, expr) -> np.ndarray:
    """A constant UFL expression evaluated once, through one compiled kernel."""
    one = fem.Constant(domain, 1.0)
    e = fem.Expression(expr * one, np.array([[0.25, 0.25, 0.25]]))
    return e.eval(np.array([0], dtype=np.int32)).reshape(expr.ufl_shape)


def stretched(stretches, rotation=Q, axes_seed=3) -> np.ndarray:
    """F = Q V diag(stretches) V^T with random principal axes V."""
    V = Rotation.random(random_state=axes_seed).as_matrix()
    return rotation @ V @ np.diag(stretches) @ V.T


def corotated_pk1(F: np.ndarray) -> np.ndarray:
    """P = 2 mu (F - R) + lambda (tr U - 3) R, from scipy's polar decomposition."""
    R, U = polar(F)
    return 2 * MU * (F - R) + LMBDA * (np.trace(U) - 3) * R


# stretches include the repeated cases where eigenvalue formulas divide by zero
CASES = {
    "rest": np.eye(3),
    "isotropic": 1.2 * Q,
    "uniaxial (two equal)": stretched([1.3, 0.9, 0.9]),
    "nearly equal": stretched([1 + 1e-9, 1.0, 1 - 1e-9]),
    "general": stretched([1.25, 0.8, 1.05]),
    "large": stretched([2.5, 0.45, 1.1]),
    "sheared": np.array([[1.10, 0.35, 0.00], [0.02, 0.95, 0.03], [0.00, -0.24, 1.02]]),
}


@pytest.mark.parametrize("name", list(CASES))
def test_polar_rotation_and_biot_invariants_match_scipy(unit_cube, name):
    F0 = CASES[name]
    R_ref, U_ref = polar(F0)
    F = ufl.as_matrix(F0.tolist())
    R = value(unit_cube, polar_rotation(F))
    np.testing.assert_allclose(R, R_ref, atol=1e-13)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-13)
    trace, norm2 = biot_invariants(F)
    B = U_ref - np.eye(3)
    assert value(unit_cube, trace) == pytest.approx(np.trace(B), abs=1e-14)
    assert value(unit_cube, norm2) == pytest.approx(np.sum(B * B), rel=1e-10, abs=1e-15)


@pytest.mark.parametrize("name", list(CASES))
def test_stress_from_ufl_diff_matches_closed_form_at_repeated_stretches(unit_cube, name):
    """P = d psi/dF through the scalar Newton steps equals 2 mu (F - R) + lambda (tr U - 3) R, finite
    at F = I and wherever stretches coincide (no division by eigenvalue differences)."""
    F0 = CASES[name]
    P = value(unit_cube, ff.first_piola_kirchhoff(ff.Corotated(MU, LMBDA), ufl.as_matrix(F0.tolist())))
    assert np.all(np.isfinite(P))
    np.testing.assert_allclose(P, corotated_pk1(F0), rtol=1e-10, atol=1e-8 * MU)


def test_energy_written_with_explicit_rotation_is_the_same(unit_cube):
    """mu |F - R|^2 + lambda/2 (tr(R^T F) - 3)^2 with R from polar_rotation equals the material's psi."""
    for F0 in CASES.values():
        F = ufl.as_matrix(F0.tolist())
        R = polar_rotation(F)
        explicit = MU * ufl.inner(F - R, F - R) + 0.5 * LMBDA * (ufl.tr(R.T * F) - 3) ** 2
        psi = ff.Corotated(MU, LMBDA).psi(F)
        assert value(unit_cube, psi) == pytest.approx(value(unit_cube, explicit), rel=1e-9, abs=1e-9 * MU)


def _at_quadrature_points(domain, expr, degree=2) -> np.ndarray:
    """expr at the points of the degree-2 rule of every local cell."""
    import basix
    points, _ = basix.make_quadrature(basix.CellType.tetrahedron, degree)
    cells = np.arange(domain.topology.index_map(3).size_local, dtype=np.int32)
    return fem.Expression(expr, points).eval(cells)


def test_energy_is_rotation_invariant_at_quadrature_points(unit_cube):
    """psi(Q F) = psi(F) at every quadrature point of a non-uniform deformation, Q a large rotation."""
    V = fem.VectorFunctionSpace(unit_cube, ("Lagrange", 2))
    u = fem.Function(V)
    u.interpolate(lambda X: np.vstack([0.1 * X[0] * X[1], -0.05 * X[2] ** 2, 0.08 * X[0] - 0.1 * X[1] * X[2]]))
    F = deformation_gradient(u)
    mat = ff.Corotated(MU, LMBDA)
    a = _at_quadrature_points(unit_cube, mat.psi(F))
    b = _at_quadrature_points(unit_cube, mat.psi(ufl.as_matrix(Q.tolist()) * F))
    assert np.abs(a).max() > 1e3                       # a real deformation
    np.testing.assert_allclose(b, a, rtol=1e-10, atol=1e-10 * MU)


def test_rigid_rotation_has_zero_stress_and_energy_unlike_linear(unit_cube):
    """u = (Q - I) X: corotated psi and P vanish at every quadrature point; linear elasticity
    stores a large energy (it sees the rotation as strain)."""
    V = fem.VectorFunctionSpace(unit_cube, ("Lagrange", 1))
    u = fem.Function(V)
    u.interpolate(lambda X: (Q - np.eye(3)) @ X)
    F = deformation_gradient(u)
    corot = ff.Corotated(MU, LMBDA)
    psi = _at_quadrature_points(unit_cube, corot.psi(F))
    P = _at_quadrature_points(unit_cube, ff.first_piola_kirchhoff(corot, F))
    assert np.abs(psi).max() < 1e-9 * MU
    assert np.abs(P).max() < 1e-9 * MU
    linear = _at_quadrature_points(unit_cube, ff.LinearElastic(MU, LMBDA).psi(F))
    assert linear.min() > 0.1 * MU


def test_small_strain_agrees_with_linear_elasticity(unit_cube):
    """P_corotated - P_linear = O(|grad u|^2): halving the displacement gradient quarters the gap."""
    G = np.array([[0.3, 1.0, -0.4], [0.2, -0.5, 0.7], [-0.6, 0.1, 0.4]])
    gaps = []
    for d in (1e-3, 5e-4, 2.5e-4):
        F = ufl.as_matrix((np.eye(3) + d * G).tolist())
        diff = ff.first_piola_kirchhoff(ff.Corotated(MU, LMBDA), F) - \
            ff.first_piola_kirchhoff(ff.LinearElastic(MU, LMBDA), F)
        scale = np.abs(value(unit_cube, ff.first_piola_kirchhoff(ff.LinearElastic(MU, LMBDA), F))).max()
        gaps.append(np.abs(value(unit_cube, diff)).max() / scale)
    assert gaps[0] < 5e-3                              # relative gap of the order of the strain
    rates = np.log2(np.array(gaps[:-1]) / np.array(gaps[1:]))
    assert np.all(rates > 0.9), rates                  # gap / |P| = O(strain)


def test_scene_model_parameters_as_constants_and_mixed_split():
    """`model = "corotated"` is a scene choice; bind_constants turns mu, lambda into Constants and
    set_parameters changes them; the mixed energy is stationary in p at p = lambda theta, where it is psi."""
    scene = ff.Scene.from_dict({"mesh": {"generator": "box", "size": [1, 1, 1], "cells": [1, 1, 1]},
                                "material": {"model": "corotated", "E": 2.0e6, "nu": 0.3}})
    mat = scene.material.material
    assert mat == ff.Corotated(MU, LMBDA)
    domain = mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    bound = bind_constants(mat, domain)
    assert isinstance(bound.mu, fem.Constant) and isinstance(bound.lmbda, fem.Constant)
    set_parameters(bound, ff.make_material("corotated", E=4.0e6, nu=0.3))
    assert parameter_value(bound.mu) == pytest.approx(2 * MU)
    F0 = CASES["general"]
    F = ufl.as_matrix(F0.tolist())
    theta = np.trace(polar(F0)[1]) - 3
    lam = 2 * LMBDA                                   # lambda after set_parameters
    psi = value(domain, bound.psi(F))
    for delta in (0.0, 0.1 * MU):                      # mixed = psi - (p - lambda theta)^2 / (2 lambda)
        p = fem.Constant(domain, lam * theta + delta)
        got = value(domain, mixed_energy(bound, F, p))
        assert got == pytest.approx(psi - delta**2 / (2 * lam), rel=1e-12)

def test_unknown_model_message_lists_corotated():
    with pytest.raises(ff.InputError, match="corotated"):
        ff.make_material("hookean", E=1e6, nu=0.3)


def test_chain_rule_stress_gives_the_energys_own_residual_and_tangent():
    """The model's residual (P by the chain rule through the invariants, the term's residual by hand) equals
    ufl.derivative of int psi dX at a large non-uniform deformation, and its tangent equals the central
    difference of that residual (the energy's second ufl.derivative would cost 18 s of JIT)."""
    from dolfinx.fem.petsc import assemble_matrix, assemble_vector
    from fem_forms.physics.assemble import energy_variation
    from fem_forms.physics.elastic import ElasticEnergy
    from fem_forms.physics.terms import Context

    domain = mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 0.3, 0.3]], [2, 1, 1], mesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(domain, ("Lagrange", 1))
    u, v, du = fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    u.interpolate(lambda x: np.array([0.3 * x[0] ** 2 + 0.2 * x[1], 0.4 * x[0] * x[2] - 0.1 * x[1],
                                      0.5 * x[0] ** 2 + 0.6 * x[1] * x[2]]))
    term = ElasticEnergy(ff.Corotated(MU, LMBDA), "corotated")
    ctx = Context(mesh=domain, u=u, dx=ufl.dx, ds=ufl.ds, regions={}, parameters=None, load=None)
    term.prepare(ctx)
    assert term.residual_by_hand
    by_hand = energy_variation([term], ctx, u, v, v)
    residual = fem.form(by_hand)
    b = [assemble_vector(f).array for f in (residual, fem.form(ufl.derivative(term.energy(ctx), u, v)))]
    np.testing.assert_allclose(b[0], b[1], rtol=0, atol=1e-13 * np.abs(b[1]).max())
    K = assemble_matrix(fem.form(ufl.derivative(by_hand, u, du)))
    K.assemble()
    w = np.random.default_rng(1).standard_normal(len(u.x.array))
    Kw = K.convert("dense").getDenseArray() @ w
    u0, h, side = u.x.array.copy(), 1e-6, []
    for sign in (1, -1):
        u.x.array[:] = u0 + sign * h * w
        side.append(assemble_vector(residual).array.copy())
    np.testing.assert_allclose(Kw, (side[0] - side[1]) / (2 * h), rtol=0, atol=1e-8 * np.abs(Kw).max())
    # with a thermal strain (set after prepare(), as build_model does) the by-hand residual takes it in too
    u.x.array[:] = u0
    ctx.thermal_strain = fem.Constant(domain, 0.02)
    b = [assemble_vector(fem.form(f)).array for f in (energy_variation([term], ctx, u, v, v),
                                                       ufl.derivative(term.energy(ctx), u, v))]
    np.testing.assert_allclose(b[0], b[1], rtol=0, atol=1e-13 * np.abs(b[1]).max())
