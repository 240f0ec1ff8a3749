"""The adjoint of a bordered equilibrium for the layout design: a volume-controlled cavity's pressure is an unknown
beside the displacement, so the adjoint has the bordered system's transpose."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.physics.scalars import coupling_forms


class Border:
    """The adjoint of the bordered equilibrium (a volume-controlled cavity: its pressure p an unknown beside u,
    R(u, p) = 0 and c(u, p) = 0). With the Jacobian [K R_p; c_u c_p], the adjoint [lambda; mu] solves
    K^T lambda + sum_i c_u_i mu_i = dJ/du and R_p_j . lambda + sum_i c_p_ij mu_i = 0 (J and c do not depend on
    the layout's fields, so dJ/dw is -d/dw (R . lambda) as before): lambda = a - sum_i b_i mu_i from
    a = K^-T dJ/du, b_i = K^-T c_u_i, and the m x m system for mu."""

    def __init__(self, model):
        forms = coupling_forms(model.global_scalars(), model.residual, model.u)
        self.R_p = [fem.form(f) for f in forms["R_p"]]
        self.c_u = [fem.form(f) for f in forms["c_u"]]
        self.c_p = [[fem.form(f) if isinstance(f, ufl.Form) else f for f in row] for row in forms["c_p"]]
        self.comm = model.mesh.comm

    def _number(self, c) -> float:
        """c_p_ij's value: 0 (None), a number, or a form's integral over all ranks."""
        return 0.0 if c is None else float(c) if isinstance(c, (int, float)) else \
            self.comm.allreduce(fem.assemble_scalar(c), op=MPI.SUM)

    @staticmethod
    def _vector(form: fem.Form) -> PETSc.Vec:
        vec = fpetsc.assemble_vector(form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return vec

    def adjoint(self, a: PETSc.Vec, solve_transposed) -> PETSc.Vec:
        """lambda from a = K^-T dJ/du, solving K^T b_i = c_u_i with `solve_transposed`."""
        b = [solve_transposed(self._vector(f)) for f in self.c_u]
        R_p = [self._vector(f) for f in self.R_p]
        M = np.array([[R_p[j].dot(b[i]) - self._number(self.c_p[i][j]) for i in range(len(b))]
                      for j in range(len(R_p))])
        mu = np.linalg.solve(M, np.array([v.dot(a) for v in R_p]))
        for b_i, mu_i in zip(b, mu):
            a.axpy(-mu_i, b_i)
        return a
