"""Keep an expensive preconditioner (GAMG) across Newton steps while that is cheaper than rebuilding it.

Between Newton steps of a mildly nonlinear solve the tangent changes little, so the multigrid hierarchy
built for the first step still preconditions the later ones almost as well (measured on the 139,587-dof
P2 beam: 27-28 CG iterations with the kept hierarchy, 26-29 with fresh ones), while building it costs as
much as ~30 CG iterations. The operator is always the freshly assembled tangent, so Newton and its
convergence test are unchanged; only the preconditioner may be older. The rule is the cost balance:
rebuild as soon as the extra iterations of the last solve cost more than a rebuild did.
"""
from __future__ import annotations

import ctypes
import time

from mpi4py import MPI
import numpy as np
from petsc4py import PETSc


def _petsc_library():
    """libpetsc's symbols through petsc4py's own extension module (petsc4py 3.18 has no binding for
    SNESSetLagPreconditioner); None when they cannot be found, and then every step rebuilds."""
    try:
        lib = ctypes.CDLL(PETSc.__file__)
        fn = lib.SNESSetLagPreconditioner
    except (OSError, AttributeError):
        return None
    fn.argtypes = [ctypes.c_void_p, ctypes.c_int64 if PETSc.IntType().itemsize == 8 else ctypes.c_int32]
    fn.restype = ctypes.c_int
    return fn


_SET_LAG = _petsc_library()
REBUILD_ONCE, KEEP = -2, -1          # PETSc's lag values: rebuild at this Jacobian only / never rebuild


def set_lag(snes: PETSc.SNES, lag: int) -> bool:
    """SNESSetLagPreconditioner(snes, lag) (KEEP: never rebuild, REBUILD_ONCE); False where it is unavailable."""
    if _SET_LAG is None:
        return False
    _SET_LAG(ctypes.c_void_p(snes.handle), lag)
    return True


class PreconditionerReuse:
    """Decides at every Jacobian of an SNES solve whether the Krylov solver rebuilds its preconditioner.

    The first Jacobian of each solve rebuilds. After that the last fresh build's set-up time S and the
    time per Krylov iteration c are measured (KSP monitor; the maximum over ranks, so that every rank
    decides alike); the hierarchy is kept until a solve with it takes `extra` iterations more than the
    solve after the build, with extra * c > S."""

    def __init__(self, snes: PETSc.SNES, comm: MPI.Comm):
        self.snes = snes
        self.comm = comm
        self.available = _SET_LAG is not None
        self.rebuilds = 0
        snes.getKSP().setMonitor(self._ksp_monitor)
        self.start_solve()

    def start_solve(self) -> None:
        """A new SNES solve (new load step or problem): its first Jacobian rebuilds."""
        self._last = None          # (setup seconds, seconds per iteration, iterations) of the last solve
        self._fresh = None         # the same for the last solve with a fresh preconditioner
        self._reused_now = False
        self._t_operator = None

    @property
    def last_solve_reused(self) -> bool:
        """Whether the latest linear solve ran with a kept (older) preconditioner."""
        return self._reused_now

    def decide(self) -> bool:
        """Call at the end of the Jacobian callback (PETSc reads the lag right after it); returns
        whether the preconditioner is rebuilt for this Newton step."""
        self._finish_solve()
        rebuild = True
        if self.available and self._fresh is not None and self._last is not None:
            setup, per_it, fresh_its = self._fresh
            extra = self._last[2] - fresh_its
            rebuild = bool(extra * max(per_it, self._last[1]) > setup)
        set_lag(self.snes, REBUILD_ONCE if rebuild else KEEP)
        self.rebuilds += rebuild
        self._reused_now = not rebuild
        self._t_operator = time.perf_counter()
        self._t_first = self._t_last = None
        self._its = 0
        return rebuild

    def _ksp_monitor(self, ksp, it: int, rnorm: float) -> None:
        now = time.perf_counter()
        if it == 0:
            self._t_first = now
        self._t_last, self._its = now, it

    def _finish_solve(self) -> None:
        """Turn the monitor's times of the solve that just ended into (setup, per-iteration) costs."""
        if self._t_operator is None or self._t_first is None:
            return
        setup = self._t_first - self._t_operator
        per_it = (self._t_last - self._t_first) / max(self._its, 1)
        costs = np.array([setup, per_it])
        self.comm.Allreduce(MPI.IN_PLACE, costs, op=MPI.MAX)         # one reduction per Newton step
        setup, per_it = float(costs[0]), float(costs[1])
        self._last = (setup, per_it, self._its)
        if not self._reused_now:
            self._fresh = self._last
        self._t_operator = None

