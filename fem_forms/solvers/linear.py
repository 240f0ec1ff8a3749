"""Linear solver choice for Newton steps: MUMPS LU by default, CG + GAMG with the rigid-body
near-nullspace for large, mildly nonlinear problems (measured crossover: about 10k dofs on a cube, 100k
on a slender beam); and the one factory (make_ksp, make_tao) for every KSP and TAO built outside SNES."""
from __future__ import annotations

import re

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

# Above this many dofs "auto" picks the iterative path (sparse direct cost grows ~N^2 in 3D;
# measured crossover ~10k dofs on a cube, ~100k on a slender beam).
ITERATIVE_ABOVE_DOFS = 150_000

DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
ITERATIVE = {"ksp_type": "cg", "ksp_rtol": 1e-8, "ksp_max_it": 1000, "pc_type": "gamg",
             "pc_gamg_type": "agg", "pc_gamg_square_graph": 2, "pc_gamg_threshold": 0.02,
             "mg_levels_ksp_type": "chebyshev", "mg_levels_pc_type": "jacobi",
             "mg_levels_esteig_ksp_type": "cg"}
# P2 and higher: two-level p-multigrid (solvers/pmultigrid.py): Chebyshev/Jacobi on the P_k tangent, one GAMG
# cycle on its Galerkin restriction to P1 below. Measured on the P2 beam at 265,923 dofs (static_beam problem,
# serial, CPU s of the solve, 2 runs each on a shared machine): GAMG on P2 14.6-15.9 s (multigrid set-up 5.8 s,
# 80 CG its in 3 Newton steps); p-multigrid 9.7-10.6 s (set-up 0.4 s, 81 its); with the P1 graph squared on
# one level instead of two (coarse GAMG less aggressive) 7.5-10.4 s, 55 its; squared on none 9.3-9.6 s, 37 its
# but 2.5 s set-up; a threshold of 0.05, point-block Jacobi or Chebyshev degree 3 changed nothing measurable.
# ITERATIVE's own GAMG options stay in (unused by PCMG): a scene's `pc_type = "gamg"` gets GAMG on P_k as before.
P_MULTIGRID = {**ITERATIVE, "pc_type": "mg", "pc_mg_levels": 2, "mg_coarse_ksp_type": "preonly",
               **{"mg_coarse_" + k: v for k, v in ITERATIVE.items() if k.startswith(("pc_", "mg_"))},
               "mg_coarse_pc_gamg_square_graph": 1}
# Direct LU factored once per load step and reused by GMRES for the later Newton iterations: the
# assembled tangent stays the operator (still Newton), the stale factor only preconditions. On the
# Chen-size inverse design (27,675 dofs, 4 Newton its) this cut 4.0 s to 2.5 s (benchmarks/inverse_methods.md).
# GMRES to 1e-6: the same Newton iterations as with 1e-10 on the Chen arm and the soft (E 1e6, 1e7)
# beams, rest shapes within 2e-12 relative, 19 MatSolves instead of 26 (design 1.64 -> 1.47 s CPU).
REUSED_FACTOR = {"ksp_type": "gmres", "ksp_gmres_restart": 100, "ksp_rtol": 1e-6, "ksp_max_it": 100,
                 "snes_lag_preconditioner": 100}
# The chord method: the tangent of the load step's first Newton iteration, factored once, is the operator
# for the whole step (no tangent assembly after the first; each iteration one residual and one MatSolve).
# Convergence is linear, not quadratic: on the Chen-size inverse design 11 iterations instead of 4, the
# design 1.12 s instead of 1.40 s, rest shapes the same to 1e-13. A step it cannot finish within
# snes_max_it falls back to REUSED_FACTOR (continuation.solve).
CHORD = {"ksp_type": "preonly", "snes_lag_jacobian": 100, "snes_lag_preconditioner": 100, "snes_max_it": 15,
         "snes_stol": 0.0}     # a small chord step is no sign of a small error: converge on the residual


# Kinds whose iterative path falls back to LU when a linear solve fails (an indefinite tangent):
# "auto" (when it chose iterative) and "iterative-then-direct", which starts iterative at any size
# (the inverse design's forward check uses it: CG + GAMG there cut 4.0 s to 1.5 s at 27,675 dofs).
FALLBACK_TO_DIRECT = ("auto", "iterative-then-direct")


def choose(kind: str, dofs: int) -> str:
    """'direct' or 'iterative' from the scene's choice ('auto' decides by size)."""
    if kind == "iterative-then-direct":
        return "iterative"
    if kind != "auto":
        return kind
    return "iterative" if dofs > ITERATIVE_ABOVE_DOFS else "direct"


def options(kind: str, symmetric: bool = True, reuse_factor: bool | str = False, degree: int = 1) -> dict:
    """PETSc KSP/PC defaults for a Newton step; GMRES replaces CG for non-symmetric tangents
    (inverse elastostatics, follower pressure). `reuse_factor` keeps one LU per load step: True as
    GMRES's preconditioner (Newton on the fresh tangent), "chord" as the operator itself. `degree`: the
    unknown's polynomial degree; from 2 on the iterative path is the P1 p-multigrid (P_MULTIGRID)."""
    opts = dict(DIRECT if kind == "direct" else P_MULTIGRID if degree >= 2 else ITERATIVE)
    if kind == "direct" and reuse_factor:
        opts.update(CHORD if reuse_factor == "chord" else REUSED_FACTOR)
    if kind != "direct" and not symmetric:
        opts["ksp_type"] = "gmres"
    return opts


def rigid_body_modes(V: fem.FunctionSpace) -> PETSc.NullSpace:
    """The six rigid-body modes (3 translations, 3 rotations) of a vector P_k space, orthonormalised,
    as the near-nullspace GAMG needs to coarsen elasticity well."""
    index_map = V.dofmap.index_map
    bs = V.dofmap.index_map_bs
    n = index_map.size_local
    x = V.tabulate_dof_coordinates()[:n]
    basis = [np.zeros((n, bs)) for _ in range(6)]
    for i in range(3):
        basis[i][:, i] = 1.0
    basis[3][:, 0], basis[3][:, 1] = -x[:, 1], x[:, 0]
    basis[4][:, 1], basis[4][:, 2] = -x[:, 2], x[:, 1]
    basis[5][:, 0], basis[5][:, 2] = x[:, 2], -x[:, 0]
    vecs = []
    for b in basis:
        v = PETSc.Vec().createMPI((n * bs, PETSc.DECIDE), bsize=bs, comm=V.mesh.comm)
        v.array[:] = b.ravel()
        for w in vecs:                      # Gram-Schmidt
            v.axpy(-v.dot(w), w)
        v.normalize()
        vecs.append(v)
    return PETSc.NullSpace().create(vectors=vecs, comm=V.mesh.comm)


# The default options of each kind of KSP made outside SNES (make_ksp); a caller's `options` and then the
# PETSc options database under the KSP's prefix (the command line) override them.
KSP_KINDS = {
    # MUMPS LU: the design's forward and adjoint systems, the linear extension of a bad start
    "lu": DIRECT,
    # MUMPS LDL^T (Cholesky) with the inertia counted (stability of the tangent): ICNTL(13) 1 keeps
    # ScaLAPACK off the root node so that every pivot's sign is counted (INFOG(12)); ICNTL(24) 1 detects null
    # pivots (INFOG(28)) instead of failing on them. The matrix must be AIJ (MUMPS's LDL^T refuses BAIJ).
    "inertia": {"ksp_type": "preonly", "pc_type": "cholesky", "pc_factor_mat_solver_type": "mumps",
                "mat_mumps_icntl_13": 1, "mat_mumps_icntl_24": 1},
    # CG + Jacobi: mass-matrix solves (recovery projections, the initial acceleration): SPD and well
    # conditioned, a few dozen iterations; the caller sets its tolerances
    "mass": {"ksp_type": "cg", "pc_type": "jacobi"},
    # CG on a matrix-free operator preconditioned by the caller's python PC context (`python_pc`)
    "cg-python": {"ksp_type": "cg", "pc_type": "python"},
}
TAO_KINDS = {
    # bounded L-BFGS (the adjoint design's optional optimiser)
    "blmvm": {"tao_type": "blmvm"},
}
# options PETSc reads after setFromOptions (multigrid levels and sub-solvers at set-up): kept in the database
_READ_LATER = ("mg_", "sub_", "fieldsplit_")


def make_ksp(A: PETSc.Mat | None, kind: str, prefix: str | None = None, options: dict | None = None,
             comm: MPI.Comm | None = None, python_pc: object | None = None) -> PETSc.KSP:
    """A KSP of `kind` (KSP_KINDS) on operator A (None: the caller sets it later; then give `comm`) under
    options `prefix` (default fem_forms_<kind>_): the kind's defaults, overridden by `options`, overridden
    by what the options database already holds under the prefix. mat_mumps_icntl_* entries are set on the
    factor (this needs A). `python_pc`: the context of a python preconditioner (kind "cg-python")."""
    merged = {**KSP_KINDS[kind], **(options or {})}
    prefix = prefix if prefix is not None else f"fem_forms_{re.sub(r'[^0-9a-zA-Z]', '_', kind)}_"
    ksp = PETSc.KSP().create(comm if A is None else A.getComm())
    ksp.setOptionsPrefix(prefix)
    if python_pc is not None:
        pc = ksp.getPC()
        pc.setType("python")
        pc.setPythonContext(python_pc)
    if A is not None:
        ksp.setOperators(A)
    icntl = {k: v for k, v in merged.items() if k.startswith("mat_mumps_icntl_")}
    _from_options(ksp, prefix, {k: v for k, v in merged.items() if k not in icntl})
    if icntl:
        if A is None:
            raise ValueError(f"make_ksp({kind!r}): MUMPS controls need the operator")
        db = PETSc.Options()
        pc = ksp.getPC()
        pc.setFactorSetUpSolverType()
        F = pc.getFactorMatrix()
        for k, v in icntl.items():
            F.setMumpsIcntl(int(k.rsplit("_", 1)[1]), db.getInt(prefix + k, int(v)))
    return ksp


def make_tao(comm: MPI.Comm, kind: str = "blmvm", prefix: str | None = None,
             options: dict | None = None) -> PETSc.TAO:
    """A TAO of `kind` (TAO_KINDS) under options `prefix` (default fem_forms_tao_), its options merged as
    make_ksp's; the caller sets objective, bounds and convergence test afterwards."""
    prefix = prefix if prefix is not None else "fem_forms_tao_"
    tao = PETSc.TAO().create(comm)
    tao.setOptionsPrefix(prefix)
    _from_options(tao, prefix, {**TAO_KINDS[kind], **(options or {})})
    return tao


def _from_options(obj, prefix: str, defaults: dict) -> None:
    """setFromOptions with `defaults` under `prefix` where the database has no value of its own; the values
    written are removed again once read (except those read later), so no other object inherits them."""
    db = PETSc.Options()
    written = [k for k in defaults if not db.hasName(prefix + k)]
    for k in written:
        db[prefix + k] = defaults[k]
    obj.setFromOptions()
    for k in written:
        if not k.startswith(_READ_LATER):
            db.delValue(prefix + k)


def roundoff_floor(tangent_norm: float, x: PETSc.Vec, safety: float = 1.0) -> float:
    """The residual norm round-off allows at state x for a tangent of infinity norm `tangent_norm`:
    safety x machine epsilon x |K|_inf x |x|_inf x sqrt(n)."""
    return safety * np.finfo(float).eps * tangent_norm * max(x.norm(PETSc.NormType.INFINITY), 1e-300) \
        * np.sqrt(x.getSize())
