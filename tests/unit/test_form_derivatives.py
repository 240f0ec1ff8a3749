"""Unit tests of the assembled forms: the residual is the gradient of the energy and the Jacobian its
derivative (Taylor tests), for every built-in material model."""
import numpy as np
import pytest
from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI

import fem_forms as ff
from fem_forms.model import build_model
from helpers import beam_scene


def _vector(form):
    b = fpetsc.assemble_vector(fem.form(form))
    b.ghostUpdate(addv=1, mode=1)   # ADD, REVERSE
    return b


@pytest.mark.parametrize("model_name", ["neo-hookean", "mooney-rivlin", "stvk", "corotated"])
def test_taylor_residual_is_gradient_of_energy_and_jacobian_its_derivative(model_name):
    """|Pi(u + h du) - Pi(u) - h R(u).du| = O(h^2) and |R(u + h du) - R(u) - h K(u) du| = O(h^2)."""
    scene = ff.Scene.from_dict(beam_scene(material={"model": model_name, "E": 1e6, "nu": 0.3, "rho": 1000}))
    m = build_model(scene)
    rng = np.random.default_rng(1)
    m.u.interpolate(lambda X: np.vstack([0.05 * X[0] ** 2, 0.02 * X[1], -0.1 * X[0] ** 2]))
    u0 = m.u.x.array.copy()
    du = fem.Function(m.V)
    du.x.array[:] = rng.uniform(-0.01, 0.01, du.x.array.shape)
    du.x.scatter_forward()
    comm = MPI.COMM_WORLD
    energy = fem.form(m.energy)

    def Pi():
        return comm.allreduce(fem.assemble_scalar(energy), op=MPI.SUM)

    R0 = _vector(m.residual)
    K = fpetsc.assemble_matrix(fem.form(m.jacobian))
    K.assemble()
    Kdu = R0.duplicate()
    K.mult(du.vector, Kdu)
    dPi = R0.dot(du.vector)
    Pi0 = Pi()
    e_energy, e_res = [], []
    for h in [1e-1, 5e-2, 2.5e-2, 1.25e-2]:
        m.u.x.array[:] = u0 + h * du.x.array
        e_energy.append(abs(Pi() - Pi0 - h * dPi))
        R = _vector(m.residual)
        R.axpy(-1.0, R0)
        R.axpy(-h, Kdu)
        e_res.append(R.norm())
    rates_e = np.log2(np.array(e_energy[:-1]) / np.array(e_energy[1:]))
    rates_r = np.log2(np.array(e_res[:-1]) / np.array(e_res[1:]))
    assert np.all(rates_e > 1.9), rates_e
    assert np.all(rates_r > 1.9), rates_r
