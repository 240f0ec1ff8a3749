"""PETSc's performance log for the command line's `-log_view` (a global option: given under a solver's prefix
it would do nothing): begun before the run, shown on stdout or written to the file it names when the run ends.
Only the command line may ask for it: a scene may not name a file (scene/petsc_options.py)."""
from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc


class PetscLog:
    """The log begun now; `view()` shows it (stdout) or writes it to `target` ("ascii:PATH" or "PATH")."""

    def __init__(self, target: str):
        self.target = target.split(":", 1)[1] if target.startswith("ascii:") else target
        PETSc.Log.begin()

    def view(self) -> None:
        if self.target:
            viewer = PETSc.Viewer().createASCII(self.target, comm=MPI.COMM_WORLD)
        else:
            viewer = PETSc.Viewer.STDOUT(MPI.COMM_WORLD)
        PETSc.Log.view(viewer)
        if self.target:
            viewer.destroy()


def petsc_log(options: dict) -> PetscLog | None:
    """The log `-log_view` asks for, taken out of `options` (the command line's), or None."""
    return PetscLog(str(options.pop("log_view"))) if "log_view" in options else None
