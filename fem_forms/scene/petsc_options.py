"""PETSc option values checked before they reach PETSc (whose own complaint is a traceback).

Pure Python, no petsc4py import: reading a scene stays cheap. Options whose meaning we know are
checked by kind (a number, a whole number, a boolean, one of a list of names); any other option
must at least be a plain scalar. The lists cover what this package and its users set; an option
outside them passes through unchecked, as PETSc itself would take it.
"""
from __future__ import annotations

import re
from typing import Any

from fem_forms.errors import InputError

# suffixes of options that take a real number, or a whole number
REAL_SUFFIXES = ("_rtol", "_atol", "_stol", "_divtol", "_damping", "_maxstep", "_minlambda",
                 "_threshold", "_alpha", "_shift_amount", "_lambda")
INTEGER_SUFFIXES = ("_max_it", "_max_funcs", "_restart", "_levels", "_max_fail", "_lag_jacobian",
                    "_lag_preconditioner", "_smooths")
BOOLEAN_OPTIONS = {"snes_lag_jacobian_persists", "snes_lag_preconditioner_persists",
                   "ksp_initial_guess_nonzero", "snes_ksp_ew", "pc_gamg_square_graph_bool",
                   "ksp_diagonal_scale", "snes_check_jacobian_bool"}
BOOLEAN_WORDS = {"", "1", "0", "true", "false", "yes", "no", "on", "off"}
ENUM_OPTIONS = {
    "snes_type": ("newtonls", "newtontr", "nrichardson", "ksponly", "ksptransposeonly", "vinewtonrsls",
                  "vinewtonssls", "ngmres", "qn", "shell", "ngs", "ncg", "fas", "ms", "nasm", "anderson",
                  "aspin", "composite", "patch"),
    "snes_linesearch_type": ("basic", "bt", "nleqerr", "l2", "cp", "shell", "ncglinear", "none"),
    "ksp_type": ("preonly", "cg", "gmres", "fgmres", "lgmres", "dgmres", "pgmres", "bicg", "bcgs", "ibcgs",
                 "fbcgs", "fbcgsr", "bcgsl", "pipebcgs", "minres", "symmlq", "richardson", "chebyshev",
                 "tfqmr", "tcqmr", "cr", "pipecr", "gcr", "pipegcr", "pipecg", "pipecgrr", "groppcg",
                 "cgs", "lsqr", "cgne", "fcg", "pipefcg", "qcg", "nash", "stcg", "gltr", "lcd", "python"),
    "pc_type": ("none", "jacobi", "pbjacobi", "vpbjacobi", "bjacobi", "sor", "lu", "cholesky", "ilu", "icc",
                "asm", "gasm", "gamg", "hypre", "ml", "mg", "fieldsplit", "ksp", "composite", "redundant",
                "svd", "lmvm", "shell", "eisenstat", "mat", "kaczmarz", "telescope", "patch", "bddc", "hmg",
                "deflation", "qr", "lsc", "python", "tfs", "spai", "parms", "chowiluviennacl"),
    "pc_factor_mat_solver_type": ("mumps", "superlu", "superlu_dist", "umfpack", "klu", "cholmod", "petsc",
                                  "spqr", "mkl_pardiso", "mkl_cpardiso", "pastix", "strumpack", "cusparse",
                                  "essl", "lusol", "matlab", "elemental", "scalapack", "cusolver"),
    "pc_gamg_type": ("agg", "geo", "classical"),
    "pc_hypre_type": ("boomeramg", "pilut", "parasails", "euclid", "ams", "ads"),
}
_NAME = re.compile(r"^[A-Za-z0-9_]+$")


def _short(v: Any, limit: int = 40) -> str:
    text = repr(v)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _as_number(v: Any, integer: bool) -> bool:
    if isinstance(v, bool):
        return False
    if isinstance(v, int):
        return True
    if isinstance(v, float):
        return not integer and v == v and abs(v) != float("inf")
    if isinstance(v, str):
        try:
            x = float(v.strip())
        except ValueError:
            return False
        return x == x and abs(x) != float("inf") and (not integer or x == int(x))
    return False


def check_option(name: Any, value: Any, key: str, sep: str = ".") -> None:
    """Refuse a PETSc option (name without the dash) whose value PETSc would reject, in one line
    naming it as key + sep + name."""
    if not isinstance(name, str) or not _NAME.match(name) or len(name) > 80:
        raise InputError(f"{key}{sep}{_short(name)}: not a PETSc option name (letters, digits, _)")
    where = f"{key}{sep}{name} = {_short(value)}"
    if isinstance(value, (dict, list, tuple)) or value is None:
        raise InputError(f"{where}: must be a single number, word or boolean")
    if name in ENUM_OPTIONS:
        if not isinstance(value, str) or value not in ENUM_OPTIONS[name]:
            raise InputError(f"{where}: must be one of {', '.join(ENUM_OPTIONS[name][:8])}, ...")
    elif name in BOOLEAN_OPTIONS:
        if not isinstance(value, bool) and str(value).lower() not in BOOLEAN_WORDS:
            raise InputError(f"{where}: must be true or false")
    elif name.endswith(INTEGER_SUFFIXES):
        if not _as_number(value, integer=True):
            raise InputError(f"{where}: must be a whole number")
    elif name.endswith(REAL_SUFFIXES):
        if not _as_number(value, integer=False):
            raise InputError(f"{where}: must be a finite number")
    elif isinstance(value, str) and len(value) > 200:
        raise InputError(f"{where}: too long for a PETSc option value")


def check_options(options: dict, key: str, sep: str = ".") -> dict:
    """Every option of a table checked; the table itself returned (a copy)."""
    for name, value in options.items():
        check_option(name, value, key, sep)
    return dict(options)
