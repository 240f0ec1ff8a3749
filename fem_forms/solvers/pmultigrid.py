"""Two-level p-multigrid for P2 (and higher) vector problems: the fine level is the P_k tangent with a cheap
smoother, the coarse level is the same tangent restricted to P1 on the same mesh (Galerkin, P^T K P) and
solved by one GAMG cycle with the rigid-body near-nullspace of the P1 space.

Why: GAMG's set-up on the P2 tangent itself was the largest single cost of a large iterative solve (its
Galerkin products on the smoothed-aggregation prolongator: 58 of 213 s at 1M dofs). The P1 -> P2
interpolation is exact and very sparse (a vertex node copies its vertex, an edge midpoint averages its two
ends), so P^T K P is cheap, and GAMG then coarsens a matrix with about 1/8 of the unknowns and half the
entries per row. The P1 subspace of a P2 space holds the rigid modes and the smooth part of the error,
which is what the coarse level must catch; Chebyshev/Jacobi on P2 removes the rest.

It is driven through PETSc's own PCMG: the options are the ordinary `pc_type mg`, `mg_levels_*` (fine
smoother) and `mg_coarse_*` (the GAMG below); this module only supplies what the options cannot, the
interpolation matrix and the coarse operator with its near-nullspace.
"""
from __future__ import annotations

from dolfinx import fem
import dolfinx.cpp.fem.petsc as cpp_petsc
from petsc4py import PETSc

from fem_forms.solvers import linear


def degree(V: fem.FunctionSpace) -> int:
    """The polynomial degree of a Lagrange space V, 0 for any other element (no P1 subspace to coarsen to)."""
    element = V.ufl_element()
    return element.degree() if element.family() in ("Lagrange", "P", "Q") else 0


def applies(V: fem.FunctionSpace, options: dict) -> bool:
    """Whether the PCMG in `options` is ours to set up: pc_type mg on a Lagrange space of degree >= 2 with
    2 levels (more levels need interpolations this module does not build)."""
    return (options.get("pc_type") == "mg" and degree(V) >= 2 and int(options.get("pc_mg_levels", 2)) == 2)


def drop_unused(merged: dict, user: dict) -> None:
    """When the scene chose another preconditioner (say pc_type gamg), remove the p-multigrid's default
    pc_mg_levels and mg_coarse_* options: GAMG reads them too (pc_mg_levels as its largest number of levels;
    mg_coarse_* left in had its coarsest level solved by a GAMG cycle instead of LU: 401 CG iterations for
    81 on the P2 beam at 19,683 dofs)."""
    if merged.get("pc_type") != "mg":
        for k in [k for k in merged if (k == "pc_mg_levels" or k.startswith("mg_coarse_")) and k not in user]:
            del merged[k]


def for_driver(existing: PMultigrid | None, V: fem.FunctionSpace, options: dict) -> PMultigrid | None:
    """The p-multigrid a driver (re)built with `options` needs: None if they choose another preconditioner,
    else `existing` (its P1 space and interpolation outlive the rebuild, its coarse operator is made anew
    from the new fine matrix) or a new one."""
    if not applies(V, options):
        if existing is not None:
            existing.destroy()
        return None
    if existing is None:
        return PMultigrid(V)
    if existing.coarse is not None:
        existing.coarse.destroy()
        existing.coarse = None
    return existing


class PMultigrid:
    """The P1 coarse space, the P1 -> P_k interpolation and the Galerkin coarse operator of one driver."""

    def __init__(self, V: fem.FunctionSpace):
        mesh = V.mesh
        shape = V.ufl_element().value_shape()
        self.V1 = (fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=shape[0]) if shape
                   else fem.FunctionSpace(mesh, ("Lagrange", 1)))
        # dolfinx 0.5.2's interpolation matrix: rows in V's (owned, blocked) dof layout, columns in V1's
        self.interpolation = cpp_petsc.interpolation_matrix(self.V1._cpp_object, V._cpp_object)
        self.interpolation.assemble()
        self.vector = bool(shape) and shape[0] == 3
        self.coarse: PETSc.Mat | None = None
        self._installed = None

    def refresh(self, ksp: PETSc.KSP, P: PETSc.Mat) -> None:
        """Recompute the coarse operator from the (AIJ) fine matrix P and hand the interpolation and the
        coarse operator to the PCMG of `ksp` (first call: after SNES set its options, before its set-up)."""
        if self.coarse is None:
            self.coarse = P.ptap(self.interpolation)
            if self.vector:
                self.coarse.setNearNullSpace(linear.rigid_body_modes(self.V1))
        else:
            P.ptap(self.interpolation, result=self.coarse)
        pc = ksp.getPC()
        if self._installed is not pc:          # a rebuilt SNES has a new PC
            if pc.getType() != "mg":
                raise RuntimeError(f"p-multigrid needs pc_type mg, the KSP has {pc.getType()!r}")
            if pc.getMGLevels() != 2:
                pc.setMGLevels(2)
            pc.setMGInterpolation(1, self.interpolation)
            self._installed = pc
        pc.getMGCoarseSolve().setOperators(self.coarse, self.coarse)

    def destroy(self) -> None:
        """Free the PETSc matrices."""
        for m in (self.interpolation, self.coarse):
            if m is not None:
                m.destroy()
