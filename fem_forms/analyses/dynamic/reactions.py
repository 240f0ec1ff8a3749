"""The supports' forces at every accepted time step (probes.csv FIX_Fx, FIX_Fy, FIX_Fz): at a held dof the
residual of the motion, M a + f_int(u) + C v - f_ext(t), with the step's acceleration and velocity, is the force
the support exerts on the body (the inertia of what it holds included); at a free dof it vanishes to the scheme's
balance (exactly for Newmark and backward Euler, at the generalized midpoints for generalized-alpha)."""
from __future__ import annotations

from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc

from fem_forms.output.reactions import support_forces


class DynamicReactions:
    """Called after a step (before its commit or after: it reads u, v, a): (fixes, 3) support forces."""

    def __init__(self, system):
        self.s = system
        self.rest = system.explicit_form()                # f_int - f_ext + C v_h (the explicit step's form)
        if system.lumped is not None:
            self.M = None
        else:
            self.M = fpetsc.assemble_matrix(system.mass)      # no Dirichlet rows zeroed: their inertia counts
            self.M.assemble()

    def __call__(self) -> np.ndarray:
        s = self.s
        s.v_h.x.array[:] = s.v.x.array
        b = fpetsc.assemble_vector(self.rest)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self.M is not None:
            self.M.multAdd(s.a.vector, b, b)
        else:
            b.array[:] += s.lumped.array * s.a.x.array[: len(b.array)]
        for term in s.model.terms.arrays:                  # contact at a held node is part of its reaction
            term.add_gradient(s.u.vector, b)
        b.assemble()
        forces = support_forces(s.model, b)
        b.destroy()
        return forces

    def destroy(self) -> None:
        if self.M is not None:
            self.M.destroy()
