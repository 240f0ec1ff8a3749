"""The PETSc and SLEPc options a scene may set, each with the kind of value it takes: the solver, line-search,
Krylov, preconditioner, factorisation and eigensolver options users tune, nothing else (scene/petsc_options.py
checks against this list). Kinds: "real" (a finite number), ("int", lo, hi), "bool", or a tuple of words.

Not listed, so refused in a scene (the user's own command line may give them): every option that takes a viewer
or a file (*_view*, *_monitor*, *_converged_reason, *_converged_rate, ksp_compute_eigenvalues, *_print_*, log_*,
options_file, ...), Python and shell types, MUMPS's output streams and out-of-core files (ICNTL 1-4, 22), and
SLEPc's eps_nev/ncv/mpd (the number of modes is [modal] count's, under its cap)."""
from __future__ import annotations

import re

REAL, BOOL = "real", "bool"


def _int(lo: int, hi: int) -> tuple:
    return ("int", lo, hi)


ITS = _int(0, 100_000)            # iteration limits
LAG = _int(-2, 1_000)             # PETSc's lag: -2 rebuild next time, -1 never, n every n
SNES_TYPES = ("newtonls", "newtontr", "nrichardson", "ksponly", "vinewtonrsls", "vinewtonssls", "ngmres", "qn",
              "ngs", "ncg", "anderson")
KSP_TYPES = ("preonly", "cg", "gmres", "fgmres", "lgmres", "dgmres", "pgmres", "bicg", "bcgs", "ibcgs", "fbcgs",
             "fbcgsr", "bcgsl", "pipebcgs", "minres", "symmlq", "richardson", "chebyshev", "tfqmr", "tcqmr", "cr",
             "pipecr", "gcr", "pipegcr", "pipecg", "groppcg", "cgs", "fcg", "pipefcg")
PC_TYPES = ("none", "jacobi", "pbjacobi", "vpbjacobi", "bjacobi", "sor", "lu", "cholesky", "ilu", "icc", "asm",
            "gasm", "gamg", "hypre", "mg", "fieldsplit", "ksp", "redundant", "svd", "eisenstat", "kaczmarz",
            "telescope", "bddc", "hmg", "qr", "lsc")
SOLVER_PACKAGES = ("mumps", "superlu", "superlu_dist", "umfpack", "klu", "cholmod", "petsc", "spqr",
                   "mkl_pardiso", "mkl_cpardiso", "pastix", "strumpack")

OPTIONS: dict = {
    # nonlinear solver and its line search
    "snes_type": SNES_TYPES, "snes_rtol": REAL, "snes_atol": REAL, "snes_stol": REAL, "snes_max_it": ITS,
    "snes_max_funcs": _int(0, 10_000_000), "snes_divergence_tolerance": REAL, "snes_max_fail": ITS,
    "snes_max_linear_solve_fail": ITS, "snes_lag_jacobian": LAG, "snes_lag_preconditioner": LAG,
    "snes_lag_jacobian_persists": BOOL, "snes_lag_preconditioner_persists": BOOL, "snes_ksp_ew": BOOL,
    "snes_ksp_ew_version": _int(1, 3), "snes_ksp_ew_rtol0": REAL, "snes_ksp_ew_rtolmax": REAL,
    "snes_ksp_ew_gamma": REAL, "snes_ksp_ew_alpha": REAL, "snes_ksp_ew_alpha2": REAL, "snes_ksp_ew_threshold": REAL,
    "snes_force_iteration": BOOL, "snes_tr_delta0": REAL, "snes_trtol": REAL, "snes_qn_m": _int(1, 100),
    "snes_ngmres_m": _int(1, 100),
    "snes_linesearch_type": ("basic", "bt", "nleqerr", "l2", "cp", "ncglinear", "none"),
    "snes_linesearch_order": _int(1, 3), "snes_linesearch_damping": REAL, "snes_linesearch_maxstep": REAL,
    "snes_linesearch_minlambda": REAL, "snes_linesearch_max_it": _int(0, 1_000), "snes_linesearch_rtol": REAL,
    "snes_linesearch_atol": REAL, "snes_linesearch_ltol": REAL, "snes_linesearch_alpha": REAL,
    "snes_linesearch_norms": BOOL, "snes_linesearch_keeplambda": BOOL,
    # Krylov
    "ksp_type": KSP_TYPES, "ksp_rtol": REAL, "ksp_atol": REAL, "ksp_divtol": REAL, "ksp_max_it": ITS,
    "ksp_initial_guess_nonzero": BOOL, "ksp_gmres_restart": _int(1, 1_000), "ksp_gmres_modifiedgramschmidt": BOOL,
    "ksp_lgmres_augment": _int(0, 100), "ksp_bcgsl_ell": _int(1, 20), "ksp_reuse_preconditioner": BOOL,
    "ksp_norm_type": ("none", "preconditioned", "unpreconditioned", "natural"),
    "ksp_pc_side": ("left", "right", "symmetric"), "ksp_diagonal_scale": BOOL, "ksp_diagonal_scale_fix": BOOL,
    "ksp_chebyshev_esteig_steps": _int(1, 1_000),
    # preconditioners and factorisations
    "pc_type": PC_TYPES, "pc_factor_mat_solver_type": SOLVER_PACKAGES, "pc_factor_levels": _int(0, 20),
    "pc_factor_fill": REAL, "pc_factor_shift_type": ("none", "nonzero", "positive_definite", "inblocks"),
    "pc_factor_shift_amount": REAL, "pc_factor_nonzeros_along_diagonal": REAL,
    "pc_factor_mat_ordering_type": ("natural", "nd", "1wd", "rcm", "qmd", "rowlength", "amd"),
    "pc_factor_reuse_ordering": BOOL, "pc_factor_reuse_fill": BOOL,
    "pc_gamg_type": ("agg", "geo", "classical"), "pc_gamg_threshold": REAL, "pc_gamg_threshold_scale": REAL,
    "pc_gamg_agg_nsmooths": _int(0, 10), "pc_gamg_square_graph": _int(0, 50), "pc_gamg_coarse_eq_limit":
    _int(1, 10_000_000), "pc_gamg_process_eq_limit": _int(1, 10_000_000), "pc_gamg_reuse_interpolation": BOOL,
    "pc_gamg_sym_graph": BOOL, "pc_gamg_repartition": BOOL, "pc_gamg_esteig_ksp_max_it": _int(1, 1_000),
    "pc_mg_levels": _int(1, 30), "pc_mg_cycle_type": ("v", "w"),
    "pc_mg_type": ("multiplicative", "additive", "full", "kaskade"), "pc_mg_galerkin": ("both", "pmat", "mat", "none"),
    "pc_hypre_type": ("boomeramg", "pilut", "parasails", "euclid"), "pc_hypre_boomeramg_strong_threshold": REAL,
    "pc_hypre_boomeramg_max_iter": _int(1, 1_000), "pc_hypre_boomeramg_max_levels": _int(2, 50),
    "pc_hypre_boomeramg_tol": REAL, "pc_hypre_boomeramg_agg_nl": _int(0, 10),
    "pc_hypre_boomeramg_coarsen_type": ("CLJP", "Ruge-Stueben", "modifiedRuge-Stueben", "Falgout", "PMIS", "HMIS"),
    "pc_hypre_boomeramg_interp_type": ("classical", "direct", "multipass", "multipass-wts", "ext+i", "ext+i-cc",
                                       "standard", "standard-wts", "FF", "FF1"),
    "pc_hypre_boomeramg_nodal_coarsen": _int(0, 6), "pc_hypre_boomeramg_vec_interp_variant": _int(0, 3),
    "pc_jacobi_type": ("diagonal", "rowmax", "rowsum"), "pc_jacobi_abs": BOOL,
    "pc_sor_omega": REAL, "pc_sor_its": _int(1, 1_000), "pc_sor_lits": _int(1, 1_000), "pc_sor_symmetric": BOOL,
    "pc_asm_overlap": _int(0, 10), "pc_asm_type": ("basic", "restrict", "interpolate", "none"),
    "pc_gasm_overlap": _int(0, 10), "pc_bjacobi_blocks": _int(1, 100_000),
    "pc_fieldsplit_type": ("additive", "multiplicative", "symmetric_multiplicative", "special", "schur", "gkb"),
    "pc_fieldsplit_schur_fact_type": ("diag", "lower", "upper", "full"),
    "pc_fieldsplit_schur_precondition": ("self", "selfp", "a11", "full"), "pc_fieldsplit_block_size": _int(1, 10),
    # SLEPc: eigensolver and spectral transformation (the number of modes is the scene's [modal] count)
    "eps_type": ("krylovschur", "arnoldi", "lanczos", "lobpcg", "gd", "jd", "power", "subspace", "rqcg", "lapack"),
    "eps_tol": REAL, "eps_max_it": ITS, "eps_target": REAL, "eps_krylovschur_restart": REAL, "eps_purify": BOOL,
    "eps_which": ("largest_magnitude", "smallest_magnitude", "largest_real", "smallest_real", "target_magnitude",
                  "target_real", "all"),
    "eps_conv_abs": BOOL, "eps_conv_rel": BOOL, "eps_conv_norm": BOOL,
    "st_type": ("shift", "sinvert", "cayley", "precond", "filter"), "st_shift": REAL,
}
# MUMPS's integer controls a scene may set (ICNTL 1-4: output streams and verbosity, 22: out-of-core files: not),
# each with its range; its real controls (CNTL)
MUMPS_ICNTL = {5: (0, 1), 6: (0, 7), 7: (0, 7), 8: (-2, 77), 10: (-100, 100), 11: (0, 2), 12: (0, 3), 13: (-1, 1),
               14: (0, 1_000), 18: (0, 3), 19: (0, 3), 20: (0, 3), 21: (0, 1), 23: (0, 1_000_000), 24: (0, 1),
               25: (-1, 1), 26: (0, 2), 27: (-1_000, 1_000), 28: (0, 2), 29: (0, 2), 30: (0, 1), 31: (0, 2),
               33: (0, 1), 35: (0, 3), 36: (0, 1), 37: (0, 1), 38: (0, 1_000), 58: (0, 2)}
MUMPS_CNTL = (1, 2, 3, 4, 5, 7)
# prefixes of nested solvers: multigrid levels, sub-domains, field splits, SLEPc's spectral transformation, the
# Chebyshev smoother's eigenvalue estimate, our bordered solve's inner one
NESTED = re.compile(r"^(?:mg_levels_(?:\d+_)?|mg_coarse_|esteig_|sub_|redundant_|fieldsplit_[A-Za-z0-9]+_|st_|inner_|"
                    r"pc_gamg_esteig_|telescope_)")


def kind_of(name: str):
    """The kind of value option `name` (no dash) takes in a scene, or None when a scene may not set it."""
    while True:
        if name in OPTIONS:
            return OPTIONS[name]
        m = re.fullmatch(r"mat_mumps_icntl_(\d+)", name)
        if m and int(m.group(1)) in MUMPS_ICNTL:
            return _int(*MUMPS_ICNTL[int(m.group(1))])
        m = re.fullmatch(r"mat_mumps_cntl_(\d+)", name)
        if m and int(m.group(1)) in MUMPS_CNTL:
            return REAL
        if re.fullmatch(r"pc_fieldsplit_[A-Za-z0-9]+_fields", name):
            return "fields"
        stripped = NESTED.sub("", name, count=1)
        if stripped == name:
            return None
        name = stripped
