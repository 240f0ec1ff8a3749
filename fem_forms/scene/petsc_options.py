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
from fem_forms.scene.petsc_allowed import BOOL, REAL, kind_of

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

# why an option a scene may not set is refused, by a word of its name (the first that matches), for the message
WHY = (("view", "names a viewer (PETSc writes to it)"), ("monitor", "is a monitor (it may name a viewer)"),
       ("reason", "names a viewer (PETSc writes to it)"), ("converged_rate", "names a viewer (PETSc writes to it)"),
       ("compute_", "prints or draws (a viewer)"), ("print", "writes a file"), ("draw", "draws in a window"),
       ("plot", "draws in a window"), ("log", "writes a log"), ("python", "imports a Python type"),
       ("options", "reads another options source"), ("file", "names a file"), ("help", "prints PETSc's help"),
       ("dump", "writes a file"), ("mat_mumps_icntl_", "is a MUMPS output stream, verbosity or out-of-core files "
                                                        "(MUMPS writes files)"),
       ("eps_nev", "sets the number of modes ([modal] count does, under its cap)"),
       ("eps_ncv", "sets the eigensolver's subspace ([modal] count does)"),
       ("eps_mpd", "sets the eigensolver's subspace ([modal] count does)"))
_FIELDS = re.compile(r"^\d+(,\d+)*$")


def scene_may_set(name: str, value: Any, where: str) -> None:
    """Refuse, in one line naming `where`, an option a scene may not set (scene/petsc_allowed.py lists those it
    may, with their kinds) or a value not of its kind: a scene's options are numbers, booleans and listed words."""
    kind = kind_of(name)
    if kind is None:
        why = next((w for word, w in WHY if word in name.lower()),
                   "not an option a scene may set (the solver's, line search's, Krylov's, preconditioner's, MUMPS's "
                   "and SLEPc's tuning options: docs/sharing.md)")
        raise InputError(f"{where}: {why}; a scene is data: give it on the command line (--petsc)")
    if kind == REAL:
        ok, what = _as_number(value, integer=False), "a finite number"
    elif kind == BOOL:
        ok, what = isinstance(value, bool) or str(value).lower() in BOOLEAN_WORDS, "true or false"
    elif kind == "fields":
        ok, what = isinstance(value, str) and bool(_FIELDS.match(value)), "field numbers such as \"0,1\""
    elif kind[0] == "int":
        lo, hi = kind[1], kind[2]
        ok = _as_number(value, integer=True) and lo <= float(value) <= hi
        what = f"a whole number in {lo}..{hi:,}"
    else:
        ok, what = isinstance(value, str) and value in kind, f"one of {', '.join(kind[:8])}{', ...' * (len(kind) > 8)}"
    if not ok:
        raise InputError(f"{where}: must be {what}")


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
    elif name in ENUM_OPTIONS:
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
