"""Strain and stress measures (fem_forms/output/measures.py) against closed forms: uniaxial stretch,
simple shear (polar decomposition in closed form, e.g. Holzapfel, Nonlinear Solid Mechanics, ex. 2.7),
rigid rotations (every Lagrangian strain vanishes; the infinitesimal strain does not), stresses."""
import math

import numpy as np
import pytest

from fem_forms.output import measures


def rotation(axis, angle):
    """Rodrigues' rotation matrix."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


@pytest.mark.parametrize("stretch", [0.5, 1.0, 1.3, 3.0])
def test_uniaxial_stretch(stretch):
    F = np.diag([stretch, 1.0, 1.0])
    e = np.zeros((3, 3))
    e[0, 0] = 1.0
    np.testing.assert_allclose(measures.green_strain(F), 0.5 * (stretch**2 - 1) * e, atol=1e-14)
    np.testing.assert_allclose(measures.biot_strain(F), (stretch - 1) * e, atol=1e-14)
    np.testing.assert_allclose(measures.hencky_strain(F), math.log(stretch) * e, atol=1e-14)
    np.testing.assert_allclose(measures.infinitesimal_strain(F), (stretch - 1) * e, atol=1e-14)


@pytest.mark.parametrize("gamma", [0.1, 1.0, 2.5])
def test_simple_shear(gamma):
    F = np.eye(3)
    F[0, 1] = gamma
    s = math.sqrt(4 + gamma**2)
    U = np.eye(3)
    U[:2, :2] = np.array([[2, gamma], [gamma, 2 + gamma**2]]) / s
    R = np.eye(3)
    R[:2, :2] = np.array([[2, gamma], [-gamma, 2]]) / s
    lnU = np.zeros((3, 3))
    lnU[:2, :2] = math.asinh(gamma / 2) / s * np.array([[-gamma, 2], [2, gamma]])
    R_num, U_num = measures.polar_decomposition(F)
    np.testing.assert_allclose(U_num, U, atol=1e-13)
    np.testing.assert_allclose(R_num, R, atol=1e-13)
    np.testing.assert_allclose(measures.biot_strain(F), U - np.eye(3), atol=1e-13)
    np.testing.assert_allclose(measures.hencky_strain(F), lnU, atol=1e-13)
    E = np.zeros((3, 3))
    E[0, 1] = E[1, 0] = gamma / 2
    E[1, 1] = gamma**2 / 2
    np.testing.assert_allclose(measures.green_strain(F), E, atol=1e-14)
    eps = np.zeros((3, 3))
    eps[0, 1] = eps[1, 0] = gamma / 2
    np.testing.assert_allclose(measures.infinitesimal_strain(F), eps, atol=1e-14)


@pytest.mark.parametrize("axis, angle", [([0, 0, 1], 0.3), ([1, 2, 3], 2.0), ([1, 0, 0], math.pi / 2)])
def test_rigid_rotation_has_no_lagrangian_strain(axis, angle):
    Q = rotation(axis, angle)
    for name in ("green_strain", "biot_strain", "hencky_strain"):
        np.testing.assert_allclose(measures.STRAINS_OF_F[name](Q), 0.0, atol=1e-13, err_msg=name)
    R, U = measures.polar_decomposition(Q)
    np.testing.assert_allclose(R, Q, atol=1e-13)
    np.testing.assert_allclose(U, np.eye(3), atol=1e-13)
    # the small-strain measure is not rotation invariant: sym(Q) - I = -(1 - cos) (I - k k^T)
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    np.testing.assert_allclose(measures.infinitesimal_strain(Q), -(1 - math.cos(angle)) * (np.eye(3) - np.outer(k, k)),
                               atol=1e-14)


def test_rotated_stretch_is_decomposed_and_batched():
    Q = rotation([1, -1, 2], 0.7)
    stretches = np.diag([1.5, 0.8, 1.1])
    F = np.stack([Q @ stretches, np.eye(3), Q])          # a batch of three
    R, U = measures.polar_decomposition(F)
    np.testing.assert_allclose(R[0], Q, atol=1e-13)
    np.testing.assert_allclose(U[0], stretches, atol=1e-13)
    np.testing.assert_allclose(measures.hencky_strain(F)[0], np.diag(np.log([1.5, 0.8, 1.1])), atol=1e-13)
    np.testing.assert_allclose(measures.biot_strain(F)[1:], 0.0, atol=1e-13)
    np.testing.assert_allclose(R @ U, F, atol=1e-13)


def test_von_mises_and_principal_stresses():
    assert measures.von_mises(np.diag([5.0, 0.0, 0.0])) == pytest.approx(5.0)
    assert measures.von_mises(7.0 * np.eye(3)) == pytest.approx(0.0, abs=1e-12)   # hydrostatic
    tau = np.zeros((3, 3))
    tau[0, 1] = tau[1, 0] = 2.0
    assert measures.von_mises(tau) == pytest.approx(2.0 * math.sqrt(3.0))
    np.testing.assert_allclose(measures.principal_values(tau), [2.0, 0.0, -2.0], atol=1e-14)
    Q = rotation([1, 1, 0], 0.4)
    sigma = Q @ np.diag([-3.0, 10.0, 1.0]) @ Q.T
    np.testing.assert_allclose(measures.principal_values(sigma), [10.0, 1.0, -3.0], atol=1e-12)
