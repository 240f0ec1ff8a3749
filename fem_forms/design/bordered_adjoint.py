"""The linear solves of a bordered equilibrium for the designs' adjoints: a volume-controlled cavity's pressure is an
unknown beside the displacement, so the adjoint has the bordered system's transpose (and the inverse design's
Gauss-Newton products and the layout design's start from a nearby layout its forward solve)."""
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

    def linearise(self, solve_transposed, solve=None) -> None:
        """At the current equilibrium (K factored): the border vectors, c_p, b_i = K^-T c_u_i and the adjoint's m x m
        matrix; with `solve` (K x = .) the forward solves' z_j = K^-1 R_p_j and S follow at the first forward solve.
        Once per linearisation, not per solve: a Gauss-Newton step applies both in every CG iteration."""
        self.Rp = [self.vector(f) for f in self.R_p]
        self.cu = [self.vector(f) for f in self.c_u]
        self.Cp = np.array([[self._number(c) for c in row] for row in self.c_p])
        self.b = [solve_transposed(cu.copy()) for cu in self.cu]
        self.M = np.array([[rp.dot(b_i) for b_i in self.b] for rp in self.Rp]) - self.Cp.T
        self._solve, self.z = solve, None

    def adjoint(self, a: PETSc.Vec) -> tuple[PETSc.Vec, np.ndarray]:
        """(lambda, mu) from a = K^-T g (a becomes lambda), at the last linearisation."""
        mu = np.linalg.solve(self.M, np.array([rp.dot(a) for rp in self.Rp]))
        for b_i, mu_i in zip(self.b, mu):
            a.axpy(-mu_i, b_i)
        return a, mu

    def forward(self, x: PETSc.Vec, q: np.ndarray) -> tuple[PETSc.Vec, np.ndarray]:
        """(du, dp) of [K R_p; c_u c_p] [du; dp] = [r; q] from x = K^-1 r (x becomes du), at the last
        linearisation (taken with `solve`)."""
        if self.z is None:
            self.z = [self._solve(rp.copy()) for rp in self.Rp]
            self.S = self.Cp - np.array([[cu.dot(z_j) for z_j in self.z] for cu in self.cu])
        dp = np.linalg.solve(self.S, np.asarray(q, dtype=float) - np.array([cu.dot(x) for cu in self.cu]))
        for z_j, dp_j in zip(self.z, dp):
            x.axpy(-dp_j, z_j)
        return x, dp
