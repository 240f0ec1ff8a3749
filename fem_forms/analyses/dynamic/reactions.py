"""The supports' forces at every accepted time step (probes.csv FIX_Fx, FIX_Fy, FIX_Fz): at a held dof the
residual of the motion, M a + f_int(u) + C v - f_ext(t), with the step's acceleration and velocity, is the force
the support exerts on the body (the inertia of what it holds included); at a free dof it vanishes to the scheme's
balance (exactly for Newmark and backward Euler; generalized-alpha balances at its midpoints, so its loads are
set to their values at the step's end for this residual, and its free dofs keep the scheme's imbalance). With the
lumped mass, inertia and Rayleigh's alpha damping act through the HRZ diagonal D, as in the step: D (a + alpha v)."""
from __future__ import annotations

from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc

from fem_forms.output.reactions import support_forces


class DynamicReactions:
    """Called after a step (before its commit or after: it reads u, v, a): (fixes, 3) support forces."""

    def __init__(self, system, released: set):
        self.s, self.released = system, released
        self.midpoint = float(system.td.alpha_f.value) != 0.0     # generalized-alpha: loads not at t_n+1
        self.rest = system.reaction_form()                # f_int - f_ext + C v_h (alpha M v_h: the step's)
        self.alpha = system.lumped_alpha()
        if system.lumped is not None:
            self.M = None
        else:
            self.M = fpetsc.assemble_matrix(system.mass)      # no Dirichlet rows zeroed: their inertia counts
            self.M.assemble()

    def __call__(self, t: float) -> np.ndarray:
        s = self.s
        s.v_h.x.array[:] = s.v.x.array
        kept = [term.factor.value.copy() for term in s.loads]
        if self.midpoint:
            for term in s.loads:
                term.factor.value = 0.0 if term.index in self.released else term.factor_at(t)
        b = fpetsc.assemble_vector(self.rest)
        for term, value in zip(s.loads, kept):
            term.factor.value = value
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self.M is not None:
            self.M.multAdd(s.a.vector, b, b)
        else:
            n = len(b.array)
            b.array[:] += s.lumped.array * (s.a.x.array[:n] + self.alpha * s.v.x.array[:n])
        for term in s.model.terms.arrays:                  # contact at a held node is part of its reaction
            term.add_gradient(s.u.vector, b)
        b.assemble()
        forces = support_forces(s.model, b)
        b.destroy()
        return forces

    def destroy(self) -> None:
        if self.M is not None:
            self.M.destroy()
