"""Generalized eigenproblems K x = lambda M x with SLEPc (Krylov-Schur, shift-and-invert).

The lowest modes of a structure cluster near zero and are poorly separated, so the operator SLEPc
iterates with is (K - sigma M)^-1 M: its largest eigenvalues are the modes nearest the target sigma.
The inner solves use MUMPS LU (one factorisation, exact) or CG + GAMG with the rigid-body
near-nullspace (less memory for large meshes; the solves must be tight, rtol 1e-10).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import time

import numpy as np
from petsc4py import PETSc
from slepc4py import SLEPc

from fem_forms.errors import SolveError
from fem_forms.solvers import linear

ST_DIRECT = {"st_ksp_type": "preonly", "st_pc_type": "lu", "st_pc_factor_mat_solver_type": "mumps"}
ST_ITERATIVE = {"st_" + k: v for k, v in linear.ITERATIVE.items()} | {"st_ksp_rtol": 1e-10,
                                                                      "st_ksp_max_it": 2000}
EPS_DEFAULTS = {"eps_tol": 1e-10, "eps_max_it": 200}


@dataclass
class EigenResult:
    """The requested eigenpairs sorted by ascending real eigenvalue; vectors M-normalised."""
    values: np.ndarray
    vectors: list = field(default_factory=list)
    converged: int = 0
    requested: int = 0
    iterations: int = 0
    solve_time: float = 0.0
    max_imag: float = 0.0          # largest |Im lambda| seen (non-symmetric problems only)


def st_options(kind: str) -> dict:
    """PETSc options (without prefix) of the spectral transformation's inner solver."""
    return dict(ST_DIRECT if kind == "direct" else ST_ITERATIVE)


def eigensolve(K: PETSc.Mat, M: PETSc.Mat, nev: int, target: float = 0.0, kind: str = "direct",
               symmetric: bool = True, same_pattern: bool = True, options: dict | None = None,
               near_nullspace: PETSc.NullSpace | None = None,
               prefix: str = "fem_forms_modal_") -> EigenResult:
    """The `nev` eigenpairs of K x = lambda M x nearest `target`. Options are defaults for the
    `kind` of inner solver merged with `options` (keys like "eps_tol", "st_ksp_rtol"), set under
    `prefix`. Raises SolveError when fewer than `nev` pairs converge."""
    t0 = time.perf_counter()
    comm = K.getComm()
    merged = dict(EPS_DEFAULTS) | st_options(kind)
    merged.update({k: v for k, v in (options or {}).items() if k.startswith(("eps_", "st_"))})
    opts = PETSc.Options()
    for k, v in merged.items():
        opts[prefix + k] = v
    if near_nullspace is not None:
        K.setNearNullSpace(near_nullspace)           # GAMG coarsens elasticity with the rigid modes

    eps = SLEPc.EPS().create(comm)
    eps.setOptionsPrefix(prefix)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP if symmetric else SLEPc.EPS.ProblemType.GNHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(nev=nev)
    eps.setTarget(target)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(target)
    # K - sigma M is formed in K's storage (and undone afterwards): keeps K's near-nullspace for GAMG
    st.setMatMode(SLEPc.ST.MatMode.INPLACE)
    st.setMatStructure(PETSc.Mat.Structure.SAME_NONZERO_PATTERN if same_pattern
                       else PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    eps.setFromOptions()
    try:
        eps.solve()
    finally:
        for k in merged:
            opts.delValue(prefix + k)
    nconv = eps.getConverged()
    if nconv < nev:
        reason, its = eps.getConvergedReason(), eps.getIterationNumber()
        eps.destroy()
        raise SolveError(f"eigensolver: {nconv} of {nev} requested modes converged "
                         f"(SLEPc reason {reason}, {its} iterations)")
    values, vectors, max_imag = [], [], 0.0
    for i in range(nev):               # SLEPc orders by distance to the target: the nearest nev
        # each vector costs one more solve (SLEPc's purification for a singular M): only nev of them
        vr = K.createVecRight()
        lam = complex(eps.getEigenpair(i, vr))
        max_imag = max(max_imag, abs(lam.imag))
        Mv = vr.duplicate()
        M.mult(vr, Mv)
        vr.scale(1.0 / np.sqrt(abs(vr.dot(Mv))))     # mass-normalise: phi^T M phi = 1
        Mv.destroy()
        values.append(lam.real)
        vectors.append(vr)
    order = np.argsort(values, kind="stable")
    result = EigenResult(np.asarray(values)[order], [vectors[i] for i in order], nconv, nev,
                         eps.getIterationNumber(), time.perf_counter() - t0, max_imag)
    eps.destroy()
    return result
