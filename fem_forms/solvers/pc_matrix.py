"""The matrix a Newton step's preconditioner is built from, when it is not the assembled tangent itself: an AIJ
copy for multigrid (GAMG, hypre and PCMG take AIJ) and the upper triangle (SBAIJ) for MUMPS's LDL^T.

The tangent of an energy is symmetric, so the direct path factors it as LDL^T (MUMPS Cholesky, symmetric
indefinite with pivoting) instead of LU: half the factor's work and memory. MUMPS takes a Cholesky from AIJ
or SBAIJ, not from the BAIJ the tangent is assembled as (BAIJ assembles 2.5-3x faster than AIJ, and dolfinx
0.5.2 cannot assemble SBAIJ: it stores almost nothing); the BAIJ -> SBAIJ copy costs 0.009 s on a 60k-dof P2
tangent serially, 0.03 s on a 33k-dof one on 2 ranks (PETSc converts row by row in parallel: 5 % of the PneuNet
demo's solve, benchmarks/pneunet.md). Measured on a 31k-dof P2 neo-Hookean tangent (serial, medians of 3):
BAIJ + LU 0.143 s assembly + 1.261 s factor and solve; BAIJ -> SBAIJ + LDL^T 0.160 s + 0.757 s, the same solution
to 3e-13."""
from __future__ import annotations

from typing import Callable

from petsc4py import PETSc


def prefer_ldlt(merged: dict, user_options: dict, symmetric: bool) -> None:
    """MUMPS LU -> MUMPS LDL^T (pc_type "cholesky") in `merged`, in place, when the tangent is symmetric and the
    scene did not choose the factorisation itself; with MUMPS's diagonal scaling (ICNTL(8) = 1) unless the
    scene sets one. The automatic choice (77) took the iterative row/column scaling (7), with which the
    1e11 Pa beam of tests/system/test_extremes.py stalled at 1e-4 of its load's residual: 570 load steps and
    2,751 Newton iterations instead of 1 step and 6 (LU: 7); diagonal scaling and no scaling both gave 6."""
    if (symmetric and merged.get("pc_type") == "lu" and "pc_type" not in user_options
            and merged.get("pc_factor_mat_solver_type") == "mumps"):
        merged["pc_type"] = "cholesky"
        if "mat_mumps_icntl_8" not in user_options:
            merged["mat_mumps_icntl_8"] = 1


def copy_format(merged: dict, tangent_format: str) -> str | None:
    """The format the preconditioner needs a copy in, or None when it takes the tangent as assembled."""
    if merged.get("pc_type") in ("gamg", "hypre", "mg"):
        return "aij"
    if merged.get("pc_type") == "cholesky" and tangent_format == "baij":
        return "sbaij"
    return None


class PreconditioningMatrix:
    """The copy of the tangent a preconditioner is built from (format `fmt`), refreshed in place."""

    def __init__(self, fmt: str, near_nullspace: Callable[[], PETSc.NullSpace] | None = None):
        self.fmt = fmt
        self.near_nullspace = near_nullspace if fmt == "aij" else None    # multigrid's rigid-body modes
        self.P: PETSc.Mat | None = None
        self._placeholder: PETSc.Mat | None = None

    def placeholder(self, A: PETSc.Mat) -> PETSc.Mat:
        """An empty matrix of A's sizes in the copy's format, for a solver set up before A holds values (A cannot
        be copied yet: assembling it empty would drop its preallocated pattern); the first refresh replaces it."""
        if self._placeholder is None:
            self._placeholder = PETSc.Mat().create(A.getComm())
            self._placeholder.setSizes(A.getSizes(), bsize=A.getBlockSize())
            self._placeholder.setType(self.fmt)
            self._placeholder.setUp()
        return self._placeholder

    def refresh(self, A: PETSc.Mat) -> tuple[PETSc.Mat, bool]:
        """The copy, with A's current values; and whether it was made now (a solver must be handed it)."""
        if self.P is not None:
            A.convert(self.fmt, self.P)
            return self.P, False
        self.P = A.convert(self.fmt, PETSc.Mat())
        if self.near_nullspace is not None:
            self.P.setNearNullSpace(self.near_nullspace())
        return self.P, True

    def destroy(self) -> None:
        for m in (self.P, self._placeholder):
            if m is not None:
                m.destroy()
        self.P = self._placeholder = None
