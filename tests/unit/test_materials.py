"""Unit tests: energy densities and stresses against closed forms at a homogeneous deformation."""
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

import fem_forms as ff
from fem_forms.materials import lame_from_young_poisson

F0 = np.array([[1.10, 0.05, 0.00], [0.02, 0.95, 0.03], [0.00, -0.04, 1.02]])


@pytest.fixture(scope="module")
def unit_cube():
    return mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)


def value(domain, expr) -> np.ndarray:
    """A constant (cell-independent) UFL expression evaluated once, through one compiled kernel."""
    one = fem.Constant(domain, 1.0)                     # binds the expression to the mesh
    e = fem.Expression(expr * one, np.array([[0.25, 0.25, 0.25]]))
    return e.eval(np.array([0], dtype=np.int32)).reshape(expr.ufl_shape)


def integrate(domain, expr) -> float:
    return float(value(domain, expr))


def closed_form_pk1(name, mu, lmbda, F):
    J = np.linalg.det(F)
    Finv_T = np.linalg.inv(F).T
    C = F.T @ F
    if name == "neo-hookean":
        return mu * (F - Finv_T) + lmbda * np.log(J) * Finv_T
    if name == "stvk":
        E = 0.5 * (C - np.eye(3))
        return F @ (2 * mu * E + lmbda * np.trace(E) * np.eye(3))
    if name == "linear":
        eps = 0.5 * (F + F.T) - np.eye(3)
        return 2 * mu * eps + lmbda * np.trace(eps) * np.eye(3)
    raise ValueError(name)


@pytest.mark.parametrize("name", ["linear", "stvk", "neo-hookean"])
def test_first_piola_kirchhoff_matches_closed_form(unit_cube, name):
    mu, lmbda = lame_from_young_poisson(2.0e6, 0.3)
    mat = ff.make_material(name, E=2.0e6, nu=0.3)
    F = ufl.as_matrix(F0.tolist())
    P = ff.first_piola_kirchhoff(mat, F)
    got = value(unit_cube, P)
    np.testing.assert_allclose(got, closed_form_pk1(name, mu, lmbda, F0), rtol=1e-12, atol=1e-6)


def test_mooney_rivlin_reduces_to_neo_hookean_when_c01_is_zero(unit_cube):
    mu, lmbda = 1.0e6, 2.0e6
    mr = ff.MooneyRivlin(C10=mu / 2, C01=0.0, lmbda=lmbda)
    nh = ff.NeoHookean(mu, lmbda)
    F = ufl.as_matrix(F0.tolist())
    diff = integrate(unit_cube, (mr.psi(F) - nh.psi(F)) ** 2)
    assert diff < 1e-20 * mu**2


@pytest.mark.parametrize("name", ["linear", "stvk", "neo-hookean", "mooney-rivlin"])
def test_rest_state_is_stress_free_with_small_strain_shear_modulus(unit_cube, name):
    """P(I) = 0, and a small shear gamma gives P12 = mu gamma for every model (same E, nu)."""
    E, nu = 1.0e6, 0.3
    mu, _ = lame_from_young_poisson(E, nu)
    mat = ff.make_material(name, E=E, nu=nu)
    P0 = ff.first_piola_kirchhoff(mat, ufl.Identity(3))
    assert np.abs(value(unit_cube, P0)).max() < 1e-6
    g = 1e-6
    P = ff.first_piola_kirchhoff(mat, ufl.as_matrix([[1, g, 0], [0, 1, 0], [0, 0, 1]]))
    assert integrate(unit_cube, P[0, 1]) == pytest.approx(mu * g, rel=1e-4)


def test_cauchy_and_von_mises_of_uniaxial_stress(unit_cube):
    """sigma = P F^T / J; a pure uniaxial Cauchy stress s has von Mises stress |s|."""
    mat = ff.NeoHookean(1.0e6, 1.0e6)
    F = ufl.as_matrix(F0.tolist())
    sigma = ff.cauchy_stress(mat, F)
    P = closed_form_pk1("neo-hookean", 1.0e6, 1.0e6, F0)
    expect = P @ F0.T / np.linalg.det(F0)
    got = value(unit_cube, sigma)
    np.testing.assert_allclose(got, expect, rtol=1e-12, atol=1e-6)
    s = ufl.as_matrix([[5.0, 0, 0], [0, 0, 0], [0, 0, 0]])
    assert integrate(unit_cube, ff.von_mises(s)) == pytest.approx(5.0)


def test_user_energy_function_is_accepted(unit_cube):
    """A plain function psi(F) is a material: here neo-Hookean written by the user."""
    def psi(F):
        J = ufl.det(F)
        return 0.5 * 3.0 * (ufl.tr(F.T * F) - 3) - 3.0 * ufl.ln(J) + 0.5 * 2.0 * ufl.ln(J) ** 2
    from fem_forms.materials import as_material
    user = as_material(psi)
    F = ufl.as_matrix(F0.tolist())
    P = ff.first_piola_kirchhoff(user, F)
    expect = closed_form_pk1("neo-hookean", 3.0, 2.0, F0)
    got = value(unit_cube, P)
    np.testing.assert_allclose(got, expect, rtol=1e-12)


@pytest.mark.parametrize("kw, fragment", [
    (dict(E=-1.0, nu=0.3), "material.E"),
    (dict(E=1e6, nu=0.5), "material.nu"),
    (dict(E=1e6, nu=-1.0), "material.nu"),
    (dict(E=1e6), "give both E and nu"),
])
def test_bad_parameters_are_rejected_by_name(kw, fragment):
    with pytest.raises(ff.InputError, match=fragment):
        ff.make_material("neo-hookean", **kw)
