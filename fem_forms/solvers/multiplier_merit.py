"""A merit function for the bordered Newton of a problem whose global scalars are Lagrange multipliers of its
energy (a cavity's pressure under volume control): the saddle point has no energy to descend, but

    M(u) = E(u, p^) + sum_i rho_i / 2 c_i(u)^2,

with the multipliers p^ = p + dp the Newton direction leads to held fixed, falls along the field step du
whenever du.(K + sum_i rho_i c_u_i c_u_i^T) du > 0: the bordered system gives K du = -dE/du(u, p^) and
c_u.du = -c (c_p = 0), so M'(u).du = -du.(K + sum_i rho_i c_u_i c_u_i^T) du. Where that curvature is negative
(past a fold of the volume-controlled path the constraint no longer holds the state) -du falls instead, down the
unstable direction: the line search follows it to the branch beyond the fold. Used on a retry after a failed
attempt (continuation.py): full Newton steps converge faster where nothing snaps."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem.forms import FormMetaClass
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

# rho_i |q_i| with q_i = c_u_i.K^-1 c_u_i: above 1, K + rho_i c_u_i c_u_i^T is positive definite for a tangent with
# one negative eigenvalue that the constraint holds (q_i < 0)
PENALTY = 2.0


class MultiplierMerit:
    """The merit M, its line-search pre-check and the options that turn it on, for one Bordered system."""

    def __init__(self, bordered, energy):
        self.b = bordered
        self.E = energy if isinstance(energy, FormMetaClass) else fem.form(energy)
        self.rho = np.zeros(bordered.m)          # the penalty weights, set with each tangent
        self.p_hat = np.zeros(bordered.m)        # the multipliers the last Newton direction leads to
        self.active = False                      # set by the continuation for a retry
        self.flips = 0                           # field steps turned down a negative curvature

    def tangent(self, q: np.ndarray) -> None:
        """New tangent: rho_i = PENALTY / |q_ii|, q = C K^-1 C^T (constrained_stability.py)."""
        q = np.abs(np.diag(q))
        ok = np.isfinite(q) & (q > 0)
        self.rho = np.where(ok, PENALTY / np.where(ok, q, 1.0), 0.0)

    def direction(self, dp: np.ndarray) -> None:
        """The Newton direction's multiplier part: SNES steps to X - lambda z, so p^ = p - dp."""
        self.p_hat = self.b.values() - dp

    def objective(self, snes, X: PETSc.Vec) -> float:
        """M at X's field part (X's multipliers are ignored: p^ is held); 1e300 where it is not finite (an
        inverted element: the line search shortens the step)."""
        b = self.b
        saved = b.values()
        b.set_values(self.p_hat)
        try:
            xf = b.set_field_state(X)
            value = b.comm.allreduce(fem.assemble_scalar(self.E), op=MPI.SUM) + b.drv.arrays.energy(xf)
            value += 0.5 * float(np.sum(self.rho * b.equations() ** 2))
        finally:
            b.set_values(saved)
        return value if np.isfinite(value) else 1e300

    def curvature(self, Y: PETSc.Vec) -> float:
        """Y_u.(K + sum_i rho_i c_u_i c_u_i^T) Y_u of the field part of Y (K the last assembled tangent)."""
        value, along = self.b.field_curvature(Y)
        return value + float(np.sum(self.rho * along ** 2))

    def precheck(self, X: PETSc.Vec, Y: PETSc.Vec) -> bool:
        """PETSc's line-search pre-check: where the curvature along the field step is negative, flip it (the
        multiplier part is kept). Returns whether Y changed."""
        if self.curvature(Y) >= 0.0:
            return False
        self.flips += 1
        Y.array[: self.b.n] *= -1.0
        return True

    def options(self, merged: dict) -> None:
        """When active: PETSc's backtracking on M. Its bt takes F.Y as the slope of an objective, which the
        multiplier rows make meaningless: alpha ~ 0 asks only for a decrease."""
        if self.active:
            merged.update({"snes_linesearch_type": "bt", "snes_linesearch_alpha": 1e-12})

    def install(self, snes: PETSc.SNES) -> None:
        if self.active:
            snes.setObjective(self.objective)
            snes.setLineSearchPreCheck(self.precheck)
