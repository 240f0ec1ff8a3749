"""Is an equilibrium stable? The inertia of its tangent stiffness, counted by a symmetric LDL^T
factorisation (MUMPS): no negative and no null pivot means positive definite, a stable equilibrium;
a negative pivot means an unstable one (a buckled branch), which a design must not be handed out on.
By Sylvester's law of inertia the pivots' signs are the eigenvalues' signs; the supports' rows carry
a 1 on the diagonal, so they add positive pivots only."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from petsc4py import PETSc
import ufl

from fem_forms.solvers.snes import as_compiled


@dataclass
class Inertia:
    """Pivot signs of a symmetric LDL^T factorisation: how many negative and null ones, among how many."""
    negative: int               # negative pivots = negative eigenvalues of the constrained tangent
    null: int                   # pivots MUMPS found to be zero (a singular tangent)
    dofs: int
    error: str = ""             # why the tangent could not be factored ("" if it was)
    norm_inf: float = 0.0       # |K|_inf of the tangent factored (its round-off scale)

    @property
    def stable(self) -> bool:
        return not self.error and self.negative == 0 and self.null == 0

    def summary(self) -> dict:
        return {"negative_pivots": self.negative, "null_pivots": self.null, "stable": self.stable,
                **({"error": self.error} if self.error else {})}


def tangent_inertia(jacobian: ufl.Form | fem.Form, bcs: list) -> Inertia:
    """Assemble the tangent at the current state (supported rows: 1 on the diagonal), factor it as
    L D L^T with MUMPS and count the negative and null pivots (the same on every rank)."""
    a = as_compiled(jacobian)
    A = fpetsc.assemble_matrix(a, bcs=bcs)      # AIJ: MUMPS's Cholesky/LDL^T takes AIJ, not BAIJ
    A.assemble()
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    comm = A.getComm()
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    pc.setFactorSetUpSolverType()
    F = pc.getFactorMatrix()
    F.setMumpsIcntl(13, 1)      # no ScaLAPACK at the root node: every pivot's sign is counted (INFOG(12))
    F.setMumpsIcntl(24, 1)      # detect null pivots (INFOG(28)) instead of failing on them
    dofs = A.getSize()[0]
    norm = A.norm(PETSc.NormType.INFINITY)
    try:
        pc.setUp()
        inertia = Inertia(int(F.getMumpsInfog(12)), int(F.getMumpsInfog(28)), dofs, norm_inf=norm)
    except PETSc.Error as e:
        inertia = Inertia(-1, -1, dofs, f"MUMPS could not factor the tangent (PETSc error {e.ierr})", norm)
    finally:
        ksp.destroy()
        A.destroy()
    return inertia
