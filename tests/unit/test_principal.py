"""The closed-form principal values in UFL (kinematics.principal_values) and Miehe's tensile energy written on them,
against numpy's symmetric eigensolver: values, and the tensile stress lambda <tr eps>+ I + 2 mu eps+ (the
energy's derivative), also where eigenvalues coincide (uniaxial strain, isotropic, zero)."""
from dolfinx import fem, mesh
from mpi4py import MPI
import numpy as np
import pytest
import ufl

from fem_forms.kinematics import FLOOR, principal_values
from fem_forms.physics.principal import tensile_energy

MU, LMBDA = 0.7, 1.3
CASES = {
    "general": [[2e-3, 5e-4, -3e-4], [5e-4, -1e-3, 2e-4], [-3e-4, 2e-4, 4e-4]],
    "uniaxial tension": [[1e-3, 0, 0], [0, -3e-4, 0], [0, 0, -3e-4]],
    "uniaxial compression": [[-1e-3, 0, 0], [0, 3e-4, 0], [0, 0, 3e-4]],
    "double largest": [[1e-3, 0, 0], [0, 1e-3, 0], [0, 0, -2e-3]],
    "isotropic": [[1e-3, 0, 0], [0, 1e-3, 0], [0, 0, 1e-3]],
    "zero": [[0, 0, 0], [0, 0, 0], [0, 0, 0]],
    "rotated": None,
    "rotated double positive": None,
}


def case(name: str) -> np.ndarray:
    if CASES[name] is not None:
        return np.array(CASES[name], dtype=float)
    Q = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    pair = [1e-3, 1e-3, -2e-3] if "positive" in name else [4e-3, -1e-3, -1e-3]
    return Q @ np.diag(pair) @ Q.T                                 # a double eigenvalue in a rotated frame


def reference(eps: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    values, vectors = np.linalg.eigh(eps)
    tr = max(np.trace(eps), 0.0)
    plus = np.maximum(values, 0.0)
    psi = LMBDA / 2 * tr ** 2 + MU * np.sum(plus ** 2)
    sigma = LMBDA * tr * np.eye(3) + 2 * MU * (vectors * plus) @ vectors.T
    return values[::-1], psi, sigma


@pytest.fixture(scope="module")
def evaluate():
    cube = mesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1)
    eps = fem.Constant(cube, np.zeros((3, 3)))
    direction = fem.Constant(cube, np.zeros((3, 3)))
    e = ufl.variable(eps)
    psi = tensile_energy(e, MU, LMBDA)
    forms = [fem.form(v * ufl.dx) for v in principal_values(e)]
    psi_form = fem.form(psi * ufl.dx)
    stress_form = fem.form(ufl.inner(ufl.diff(psi, e), direction) * ufl.dx)

    def run(A: np.ndarray):
        eps.value[:] = A
        values = np.array([fem.assemble_scalar(f) for f in forms])
        sigma = np.zeros((3, 3))
        for i in range(3):
            for j in range(3):
                direction.value[:] = 0.0
                direction.value[i, j] = 1.0
                sigma[i, j] = fem.assemble_scalar(stress_form)
        return values, fem.assemble_scalar(psi_form), sigma
    return run


@pytest.mark.parametrize("name", list(CASES))
def test_principal_values_energy_and_stress_match_numpy(evaluate, name):
    A = case(name)
    values, psi, sigma = evaluate(A)
    ref_values, ref_psi, ref_sigma = reference(A)
    scale = max(np.abs(A).max(), 1e-3)
    assert values == pytest.approx(ref_values, abs=1e-7 * scale)     # a double one: to p sqrt(EDGE)
    assert psi == pytest.approx(ref_psi, rel=1e-9, abs=1e-18)
    assert sigma == pytest.approx(ref_sigma, abs=1e-9 * MU * scale + 8 * MU * FLOOR)   # eigenvalues >= FLOOR off
