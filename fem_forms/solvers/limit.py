"""How stiff the load path still is: Bergan's current stiffness parameter, the load increment per displacement
increment of the last accepted step over that of the first (1 at the start of a linear path, 0 at a limit
point, where the load reaches its maximum). Under load control no equilibrium lies beyond a limit point, so
near one a failing step is not worth Newton's full iteration limit: the retries are capped, and the step
floor ends the run sooner. The stiffness goes into the stopping message."""
from __future__ import annotations

from dolfinx import fem
from mpi4py import MPI
import numpy as np

# the path counts as near a limit point below this stiffness (a tenth of the first step's)
NEAR_LIMIT = 0.1
# near a limit point a retry may take this many times the Newton iterations of the slowest accepted step
# (at least MIN_CAP): a neo-Hookean sphere inflated past its maximum spent 50 iterations on each failed step
RETRY_FACTOR = 2
MIN_CAP = 8
# a step that moved this many times further per unit load than the step before has jumped to another branch of the
# path (a snap under volume control): the next step's start is not extrapolated through it
JUMP = 2.0


class PathStiffness:
    """The accepted steps' load-per-displacement ratios, and the Newton iteration cap they suggest."""

    def __init__(self, u: fem.Function):
        self.u = u
        imap = u.function_space.dofmap.index_map
        self.owned = imap.size_local * u.function_space.dofmap.index_map_bs
        self.first: float | None = None
        self.last: float | None = None
        self.slowest = 0
        self.jumped = False

    def _norm(self, step: np.ndarray) -> float:
        local = float(np.dot(step[: self.owned], step[: self.owned]))
        return float(np.sqrt(self.u.function_space.mesh.comm.allreduce(local, op=MPI.SUM)))

    def accepted(self, dlam: float, step: np.ndarray, iterations: int, snapped: bool = False) -> None:
        """Record an accepted step: load increment dlam, displacement increment `step` (the unknown's local
        array, ghosts included; only owned entries count), Newton iterations it took. A step known to have
        `snapped` (it started off a rejected saddle) is a jump and says nothing of the path's stiffness."""
        self.jumped = snapped
        self.slowest = max(self.slowest, iterations)
        if snapped:
            return
        norm = self._norm(step)
        if norm == 0.0 or dlam <= 0.0:
            return
        ratio = dlam / norm
        if self.first is None:
            self.first = ratio
        self.jumped = self.last is not None and ratio < self.last / JUMP
        self.last = ratio

    @property
    def stiffness(self) -> float | None:
        """The last accepted step's load per displacement over the first's (None before two steps)."""
        if self.first is None or self.last is None:
            return None
        return self.last / self.first

    def near_limit(self) -> bool:
        return self.stiffness is not None and self.stiffness < NEAR_LIMIT

    def newton_cap(self) -> int | None:
        """The Newton iteration limit of the next retry (None: the options' own)."""
        return max(MIN_CAP, RETRY_FACTOR * self.slowest) if self.near_limit() else None
