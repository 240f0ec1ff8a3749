"""Is an equilibrium stable? The inertia of its tangent stiffness, counted by a symmetric LDL^T
factorisation (MUMPS): no negative and no null pivot means positive definite, a stable equilibrium;
a negative pivot means an unstable one (a buckled branch), which a design must not be handed out on.
By Sylvester's law of inertia the pivots' signs are the eigenvalues' signs; the supports' rows carry
a 1 on the diagonal, so they add positive pivots only. In the mixed u-p formulation the tangent is a
saddle point [[K, B^T], [B, -C]] with -C (the pressure block, -M/kappa) negative definite: by Haynsworth
In(H) = In(-C) + In(K + B^T C^-1 B), so a stable state (the displacement Hessian with p condensed out
positive definite) has exactly as many negative pivots as pressure dofs (`saddle`), and any more is unstable."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from petsc4py import PETSc
import ufl

from fem_forms.solvers.array_terms import ArrayTerms
from fem_forms.solvers.linear import make_ksp
from fem_forms.solvers.snes import as_compiled


@dataclass
class Inertia:
    """Pivot signs of a symmetric LDL^T factorisation: how many negative and null ones, among how many."""
    negative: int               # negative pivots = negative eigenvalues of the constrained tangent
    null: int                   # pivots MUMPS found to be zero (a singular tangent)
    dofs: int
    error: str = ""             # why the tangent could not be factored ("" if it was)
    saddle: int = 0             # the negative pivots a stable state has: the mixed formulation's pressure dofs

    @property
    def stable(self) -> bool:
        return not self.error and self.negative == self.saddle and self.null == 0

    def summary(self) -> dict:
        return {"negative_pivots": self.negative, "null_pivots": self.null, "stable": self.stable,
                **({"pressure_dofs": self.saddle} if self.saddle else {}),
                **({"error": self.error} if self.error else {})}


def assemble_tangent(jacobian: ufl.Form | fem.Form, bcs: list) -> PETSc.Mat:
    """The tangent at the current state as a symmetric AIJ matrix (supported rows: 1 on the diagonal);
    AIJ because MUMPS's Cholesky/LDL^T takes AIJ, not BAIJ. The caller destroys it."""
    A = fpetsc.assemble_matrix(as_compiled(jacobian), bcs=bcs)
    A.assemble()
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return A


def pressure_dofs(unknown: fem.Function) -> int:
    """The mixed formulation's pressure dofs (all ranks; 0 for a displacement unknown): the negative pivots of a
    stable state's tangent."""
    space = unknown.function_space
    if type(space.ufl_element()) is not ufl.MixedElement:     # a VectorElement is a MixedElement of components
        return 0
    pressure = space.sub(1).collapse()[0]
    return pressure.dofmap.index_map.size_global * pressure.dofmap.index_map_bs


def inertia_of(A: PETSc.Mat, saddle: int = 0) -> Inertia:
    """Factor the symmetric A as L D L^T with MUMPS and count its negative and null pivots (the same on
    every rank); `saddle`: the negative pivots a stable state has (pressure_dofs)."""
    ksp = make_ksp(A, "inertia", "fem_forms_inertia_")    # MUMPS LDL^T, every pivot's sign counted
    pc = ksp.getPC()
    F = pc.getFactorMatrix()
    dofs = A.getSize()[0]
    try:
        pc.setUp()
        return Inertia(int(F.getMumpsInfog(12)), int(F.getMumpsInfog(28)), dofs, saddle=saddle)
    except PETSc.Error as e:
        return Inertia(-1, -1, dofs, f"MUMPS could not factor the tangent (PETSc error {e.ierr})", saddle)
    finally:
        ksp.destroy()


def tangent_inertia(jacobian: ufl.Form | fem.Form, bcs: list, saddle: int = 0, arrays=None) -> Inertia:
    """The inertia of the tangent at the current state (`saddle`: as inertia_of's); `arrays`: (the model's array
    terms, the state) whose Hessians join the forms' (a contact's barrier and friction)."""
    A = assemble_tangent(jacobian, bcs)
    if arrays is not None and arrays[0]:
        terms, u = arrays
        ArrayTerms(terms, u.function_space, bcs, as_compiled(jacobian)).add_hessian(u.vector, A)
    try:
        return inertia_of(A, saddle)
    finally:
        A.destroy()
