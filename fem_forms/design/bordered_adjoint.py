"""The linear solves of a bordered equilibrium for the designs' adjoints: a volume-controlled cavity's pressure is an
unknown beside the displacement, so the adjoint has the bordered system's transpose (and the inverse design's
Gauss-Newton products its forward solve)."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.physics.scalars import coupling_forms


class Border:
    """The bordered equilibrium's linear solves (volume-controlled cavities: their pressures p unknowns beside u,
    R(u, p) = 0 and c(u, p) = 0, the Jacobian [K R_p; c_u c_p]) from solves with K alone. The adjoint [lambda; mu]
    solves K^T lambda + sum_i c_u_i mu_i = g and R_p_j . lambda + sum_i c_p_ij mu_i = 0: lambda = a - sum_i b_i mu_i
    from a = K^-T g, b_i = K^-T c_u_i, and the m x m system for mu. The forward [du; dp] of a right-hand side
    [r; q]: du = x - sum_j z_j dp_j from x = K^-1 r, z_j = K^-1 R_p_j, and S dp = q - c_u . x, S = c_p - c_u . z."""

    def __init__(self, scalars: list, residual, u: fem.Function):
        forms = coupling_forms(scalars, residual, u)
        self.R_p = [fem.form(f) for f in forms["R_p"]]
        self.c_u = [fem.form(f) for f in forms["c_u"]]
        self.c_p = [[fem.form(f) if isinstance(f, ufl.Form) else f for f in row] for row in forms["c_p"]]
        self.comm = u.function_space.mesh.comm

    def _number(self, c) -> float:
        """c_p_ij's value: 0 (None), a number, or a form's integral over all ranks."""
        return 0.0 if c is None else float(c) if isinstance(c, (int, float)) else \
            self.comm.allreduce(fem.assemble_scalar(c), op=MPI.SUM)

    @staticmethod
    def vector(form: fem.Form) -> PETSc.Vec:
        """An assembled vector form, its ghosts' contributions added to their owners."""
        vec = fpetsc.assemble_vector(form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return vec

    def _c_p(self) -> np.ndarray:
        return np.array([[self._number(c) for c in row] for row in self.c_p])

    def adjoint(self, a: PETSc.Vec, solve_transposed) -> tuple[PETSc.Vec, np.ndarray]:
        """(lambda, mu) from a = K^-T g, solving K^T b_i = c_u_i with `solve_transposed` (a becomes lambda)."""
        b = [solve_transposed(self.vector(f)) for f in self.c_u]
        R_p = [self.vector(f) for f in self.R_p]
        M = np.array([[R_p[j].dot(b[i]) for i in range(len(b))] for j in range(len(R_p))]) - self._c_p().T
        mu = np.linalg.solve(M, np.array([v.dot(a) for v in R_p]))
        for b_i, mu_i in zip(b, mu):
            a.axpy(-mu_i, b_i)
        return a, mu

    def forward(self, r: PETSc.Vec, q: np.ndarray, solve) -> tuple[PETSc.Vec, np.ndarray]:
        """(du, dp) of [K R_p; c_u c_p] [du; dp] = [r; q], solving K x = . with `solve`."""
        x = solve(r)
        z = [solve(self.vector(f)) for f in self.R_p]
        c_u = [self.vector(f) for f in self.c_u]
        S = self._c_p() - np.array([[cu.dot(zj) for zj in z] for cu in c_u])
        dp = np.linalg.solve(S, np.asarray(q, dtype=float) - np.array([cu.dot(x) for cu in c_u]))
        for z_j, dp_j in zip(z, dp):
            x.axpy(-dp_j, z_j)
        return x, dp
