"""Every eigenvalue of K x = lambda M x in an interval, and Sylvester's count of those below a shift.

Spectrum slicing (SLEPc Krylov-Schur over [a, b], shift-and-invert, MUMPS LDL^T with inertia): SLEPc
factors K - sigma M at shifts it picks inside the interval and, from the inertia of each factor, knows
how many eigenvalues lie between two shifts, so it returns all of them however many there are. The
count is certified independently afterwards: by Sylvester's law of inertia the number of negative
pivots of an LDL^T factorisation of K - sigma M is the number of eigenvalues below sigma (M positive
semi-definite). Supported dofs (K diagonal 1, M diagonal 0, rows and columns zeroed) only add positive
pivots, so they never count.
"""
from __future__ import annotations

import time

import numpy as np
from petsc4py import PETSc
from slepc4py import SLEPc

from fem_forms.errors import SolveError
from fem_forms.solvers.eigen import EPS_DEFAULTS, EigenResult

# LDL^T by MUMPS; ICNTL(13) = 1 keeps the root front off ScaLAPACK, else MUMPS cannot count
# negative pivots on more than one rank
LDLT = {"ksp_type": "preonly", "pc_type": "cholesky", "pc_factor_mat_solver_type": "mumps",
        "mat_mumps_icntl_13": 1, "mat_mumps_icntl_24": 1}
# eigenvalues SLEPc computes about each shift (its subproblem size): measured on the 72k-dof bar
# (benchmarks/modal_band.md)
PER_SHIFT = 40


def _set_options(prefix: str, options: dict) -> list:
    opts = PETSc.Options()
    for k, v in options.items():
        opts[prefix + k] = v
    return [prefix + k for k in options]


def as_aij(A: PETSc.Mat) -> PETSc.Mat:
    """A itself if AIJ, else an AIJ copy: SLEPc's spectrum slicing factors K - sigma M by Cholesky."""
    return A.convert("aij", PETSc.Mat()) if A.getType().endswith("baij") else A   # out=None: in place


def inertia_below(K: PETSc.Mat, M: PETSc.Mat, sigma: float, prefix: str = "fem_forms_inertia_") -> int:
    """The number of eigenvalues of K x = lambda M x below sigma: negative pivots of K - sigma M."""
    A = K.copy()
    A.axpy(-sigma, M, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    if A.getType().endswith("baij") and not A.getType().endswith("sbaij"):
        A.convert("sbaij")             # in place: MUMPS has no Cholesky of BAIJ, only of AIJ and SBAIJ
    ksp = PETSc.KSP().create(K.getComm())
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A)
    names = _set_options(prefix, LDLT)
    try:
        ksp.setFromOptions()
        ksp.setUp()
        F = ksp.getPC().getFactorMatrix()
        negative, _, _ = F.getInertia()
    finally:
        opts = PETSc.Options()
        for n in names:
            opts.delValue(n)
        ksp.destroy()
        A.destroy()
    return int(negative)


def eigensolve_interval(K: PETSc.Mat, M: PETSc.Mat, lower: float, upper: float,
                        options: dict | None = None, prefix: str = "fem_forms_slice_") -> EigenResult:
    """Every eigenpair of the symmetric pencil (K, M) with lower <= lambda <= upper, ascending,
    vectors M-normalised. Neither bound may be an eigenvalue (lower is usually a little below 0).
    K and M must be AIJ (see as_aij)."""
    t0 = time.perf_counter()
    merged = dict(EPS_DEFAULTS) | {"st_" + k: v for k, v in LDLT.items()}
    merged["eps_krylovschur_nev"] = PER_SHIFT
    merged.update({k: v for k, v in (options or {}).items() if k.startswith(("eps_", "st_"))})
    eps = SLEPc.EPS().create(K.getComm())
    eps.setOptionsPrefix(prefix)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.ALL)
    eps.setInterval(lower, upper)
    eps.getST().setType(SLEPc.ST.Type.SINVERT)
    names = _set_options(prefix, merged)
    try:
        eps.setFromOptions()
        eps.solve()
    finally:
        opts = PETSc.Options()
        for n in names:
            opts.delValue(n)
    nconv = eps.getConverged()
    reason = eps.getConvergedReason()
    if reason < 0:
        eps.destroy()
        raise SolveError(f"spectrum slicing over [{lower:.6g}, {upper:.6g}] failed (SLEPc reason {reason})")
    values, vectors = [], []
    for i in range(nconv):
        vr = K.createVecRight()
        lam = eps.getEigenpair(i, vr).real
        Mv = vr.duplicate()
        M.mult(vr, Mv)
        vr.scale(1.0 / np.sqrt(abs(vr.dot(Mv))))         # mass-normalise: phi^T M phi = 1
        Mv.destroy()
        values.append(lam)
        vectors.append(vr)
    order = np.argsort(values, kind="stable")
    result = EigenResult(np.asarray(values)[order], [vectors[i] for i in order], nconv, nconv,
                         eps.getIterationNumber(), time.perf_counter() - t0)
    eps.destroy()
    return result
