"""PETSc option values checked before they reach PETSc (whose own complaint is a traceback), and the options a
scene may set at all.

Pure Python, no petsc4py import: reading a scene stays cheap. Options whose meaning we know are checked by kind
(a number, a whole number, a boolean, one of a list of names); any other option must at least be a plain scalar.
A scene is data (it may come with a part someone shared): its options (and --set's) must be ones users tune, of
the solver, line-search, Krylov, preconditioner, factorisation and SLEPc families, and none that names a file, a
viewer, a monitor, a Python type or another options source, since PETSc would write that file, import that
module or read those options. The command line is the user's own: its options (trailing, or --petsc) are
checked by kind only.
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
                 "cgs", "lsqr", "cgne", "fcg", "pipefcg", "qcg", "nash", "stcg", "gltr", "lcd"),
    "pc_type": ("none", "jacobi", "pbjacobi", "vpbjacobi", "bjacobi", "sor", "lu", "cholesky", "ilu", "icc",
                "asm", "gasm", "gamg", "hypre", "ml", "mg", "fieldsplit", "ksp", "composite", "redundant",
                "svd", "lmvm", "shell", "eisenstat", "mat", "kaczmarz", "telescope", "patch", "bddc", "hmg",
                "deflation", "qr", "lsc", "tfs", "spai", "parms", "chowiluviennacl"),
    "pc_factor_mat_solver_type": ("mumps", "superlu", "superlu_dist", "umfpack", "klu", "cholmod", "petsc",
                                  "spqr", "mkl_pardiso", "mkl_cpardiso", "pastix", "strumpack", "cusparse",
                                  "essl", "lusol", "matlab", "elemental", "scalapack", "cusolver"),
    "pc_gamg_type": ("agg", "geo", "classical"),
    "pc_hypre_type": ("boomeramg", "pilut", "parasails", "euclid", "ams", "ads"),
}
_NAME = re.compile(r"^[A-Za-z0-9_]+$")

# the families a scene's option may belong to, after the prefixes of nested solvers (below)
FAMILIES = ("snes_", "ksp_", "pc_", "mat_mumps_icntl_", "mat_mumps_cntl_", "eps_", "st_", "bv_", "ds_", "rg_")
# nested solvers' prefixes: multigrid levels, sub-domains, field splits, SLEPc's spectral transformation, MUMPS
NESTED = re.compile(r"^(?:mg_levels_(?:\d+_)?|mg_coarse_|esteig_|sub_|redundant_|fieldsplit_[A-Za-z0-9]+_|st_|inner_)*")
# words that make an option write, draw, import or read (by name): refused in a scene whatever its family
REFUSED = (("view", "names a viewer (PETSc writes to it)"), ("monitor", "is a monitor (it may name a viewer)"),
           ("reason", "names a viewer (PETSc writes to it)"), ("draw", "draws in a window"),
           ("plot", "draws in a window"), ("log", "writes a log"), ("python", "imports a Python type"),
           ("options", "reads another options source"), ("file", "names a file"), ("help", "prints PETSc's help"),
           ("dump", "writes a file"), ("save", "writes a file"), ("load", "reads a file"), ("dir", "names a folder"),
           ("ooc", "writes out-of-core files"), ("history", "records a history"), ("test", "runs PETSc's checks"),
           ("error", "prints an error viewer"), ("info", "writes information"), ("trace", "traces calls"),
           ("dll", "loads a library"), ("debug", "starts a debugger"), ("malloc", "changes memory checking"))
# MUMPS's output streams (Fortran units: a number writes fort.N) and out-of-core factorisation (files)
REFUSED_MUMPS = {"mat_mumps_icntl_1", "mat_mumps_icntl_2", "mat_mumps_icntl_3", "mat_mumps_icntl_22"}
# option values that are Python or user code, however the option is named
CODE_VALUES = {"python", "shell"}
_WORD = re.compile(r"^[A-Za-z0-9_.,+-]*$")


def scene_may_set(name: str, value: Any, where: str) -> None:
    """Refuse, in one line naming `where`, an option a scene may not set: outside the families users tune, or one
    that names a file, a viewer, a monitor, a Python type or another options source."""
    why = next((w for word, w in REFUSED if word in name.lower()), None)
    if why is None and name in REFUSED_MUMPS:
        why = "names an output stream or out-of-core files (MUMPS writes files)"
    if why is None and isinstance(value, str) and value.strip().lower() in CODE_VALUES:
        why = f"{value!r} is user code (PETSc would import or call it)"
    if why is None and isinstance(value, str) and not _WORD.match(value.strip()):
        why = "a value with a path, a viewer or spaces (a scene's options take numbers and plain words)"
    if why is None and not (name.startswith(FAMILIES) or NESTED.sub("", name).startswith(FAMILIES)):
        why = ("not an option a scene may set (solver, line search, Krylov, preconditioner, MUMPS, SLEPc: snes_*, "
               "ksp_*, pc_*, mat_mumps_*, eps_*, st_*)")
    if why is not None:
        raise InputError(f"{where}: {why}; a scene is data: give it on the command line (--petsc)")


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


def check_option(name: Any, value: Any, key: str, sep: str = ".", scene: bool = True) -> None:
    """Refuse a PETSc option (name without the dash) whose value PETSc would reject, or (`scene`) one a scene may
    not set, in one line naming it as key + sep + name."""
    if not isinstance(name, str) or not _NAME.match(name) or len(name) > 80:
        raise InputError(f"{key}{sep}{_short(name)}: not a PETSc option name (letters, digits, _)")
    where = f"{key}{sep}{name} = {_short(value)}"
    if isinstance(value, (dict, list, tuple)) or value is None:
        raise InputError(f"{where}: must be a single number, word or boolean")
    if scene:
        scene_may_set(name, value, where)
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


def check_options(options: dict, key: str, sep: str = ".", scene: bool = True) -> dict:
    """Every option of a table checked (`scene`: also against what a scene may set); the table returned (a copy)."""
    for name, value in options.items():
        check_option(name, value, key, sep, scene)
    return dict(options)
