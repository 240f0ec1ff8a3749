"""PETSc started without its rc files: PETSc reads .petscrc and petscrc from the current folder at start-up, and a
folder shared with a scene could hold one naming files to write (-log_view ascii:PATH) or code to import
(-pc_python_type). Options are the scene's (checked) and the command line's; PETSC_OPTIONS, the user's own
environment, still applies. Called before anything imports petsc4py.PETSc; once PETSc runs it changes nothing."""
from __future__ import annotations

import sys


def skip_petscrc() -> None:
    """Start PETSc (at its first import) with -skip_petscrc, unless it started already."""
    if "petsc4py.PETSc" in sys.modules:
        return
    import petsc4py
    petsc4py.init(["fem-forms", "-skip_petscrc"])
