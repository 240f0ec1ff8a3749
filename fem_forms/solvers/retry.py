"""What changes before a failed Newton solve is tried again: one ladder for load continuation and implicit time
steps, each rung tried once per step size before the step is cut. First, where the caller extrapolates its start (a
time step's predictor) and that start already left the domain (a NaN before the first iteration): the last accepted
state as the start. After SNES failed: a fresh preconditioner or factor (where one kept across time steps failed),
LU instead of an indefinite iterative solve, Newton instead of a stalled chord, a factor per iteration instead of a
load step's stale one. After a converged state that acceptance rejected as a saddle of a volume-controlled problem: a
start pushed off it along its unstable mode. Last, after any failed attempt, the other line search where the caller
gave two. For the retries of a volume-controlled (bordered multiplier) solve: the descent of a merit, off again once
a step is accepted."""
from __future__ import annotations

from typing import Callable

from fem_forms.solvers import acceptance, linear
from fem_forms.solvers.reports import UNSTABLE


class RetryPolicy:
    """The retry ladder of one driver, whose scene asked for the linear solver `linear_kind`. `line_searches`:
    (first, other), the line search of every attempt and the one a failed attempt is retried with (implicit time
    steps: the energy line search and full Newton steps); `on_direct()`: what else the caller changes once LU
    replaces CG (the time step keeps its tangent and factor from then on); `plain_start()`: the next attempt starts
    from the last accepted state instead of the caller's extrapolation. All in effect at the caller's rebuild."""

    def __init__(self, drv, linear_kind: str, line_searches: tuple[str, str] | None = None,
                 on_direct: Callable[[], None] | None = None, plain_start: Callable[[], None] | None = None):
        self.drv, self.linear_kind = drv, linear_kind
        self.line_searches, self.on_direct, self.plain_start = line_searches, on_direct, plain_start
        self.tried: set[str] = set()                 # the rungs tried at this step size
        self.factor_per_iteration = False            # a time step's factor renewed at every iteration until accepted

    def same_size(self, rec, why: str | None, at: float, report=None) -> bool:
        """After an attempt at load factor or time `at` failed (SNES: `rec.accepted` False) or was rejected (`why`):
        climb the ladder (see the module) and return whether the step is retried at its size (False: cut it).
        `report.linear_solver` records a switch to LU. The caller rebuilds the driver before the next attempt (as
        after any failure), which puts the changes made here into effect."""
        self._line_search(0)                         # the other line search served one attempt
        if (self.plain_start is not None and rec.iterations == 0 and acceptance.left_the_domain(rec, why)
                and self._once("plain start")):
            self.plain_start()
            return True
        if rec.accepted and self._escape(why, at):
            return True
        if not rec.accepted and self._solver_change(rec, report):
            return True
        if self.line_searches is not None and self._once("line search"):
            self._line_search(1)
            return True
        self.tried.clear()                           # cut: the smaller step may try every rung again
        return False

    def accepted(self) -> None:
        """A step was accepted: the first line search, full Newton steps again (no merit), one factor per step again,
        every rung available."""
        rebuild = self._line_search(0)
        if self.factor_per_iteration:
            self.drv.reuse_factor, self.factor_per_iteration, rebuild = True, False, True
        if rebuild:
            self.drv.rebuild()
        self.descend(False)
        self.tried.clear()

    def _once(self, rung: str) -> bool:
        """Whether `rung` is still untried at this step size (and mark it tried)."""
        if rung in self.tried:
            return False
        self.tried.add(rung)
        return True

    def _solver_change(self, rec, report) -> bool:
        """After SNES failed: a fresh preconditioner (kept across time steps), LU, Newton, a fresh factor (kept
        across time steps) or a factor per iteration (a load step's), the first that applies; whether one did."""
        drv = self.drv
        linear_failed = rec.reason == "DIVERGED_LINEAR_SOLVE"
        stale = linear_failed and drv.stale_preconditioner_failed()
        if stale:                                    # kept across solves (a time step's): the rebuild renews it;
            return drv.keep_preconditioner and self._once("fresh preconditioner")   # else a solve's own: cut
        if self._to_direct(rec, stale):
            if report is not None:
                report.linear_solver = "iterative->direct"
            if self.on_direct is not None:
                self.on_direct()
            return True
        if drv.reuse_factor == "chord":
            drv.reuse_factor = True                  # the chord stalled: Newton (the stale LU preconditions)
            return True
        if linear_failed and drv.reuse_factor:
            if not drv.keep_preconditioner:
                drv.reuse_factor = False             # a load step's LU too far off: factor every iteration
                return True
            if drv.options.get("snes_lag_preconditioner_persists"):
                return self._once("fresh factor")    # a factor kept across time steps: the rebuild factors afresh
            if self._once("factor per iteration"):   # a time step's own factor (contact): this step factors at
                drv.reuse_factor = False             # every iteration; measured on the rocking hemisphere: the
                self.factor_per_iteration = True     # step's retries were the same failure twice, then 4 cuts
                return True
        return False

    def _line_search(self, which: int) -> bool:
        """Attempts from now on with the first (0) or the other (1) line search, once the driver is rebuilt;
        whether that changed it."""
        if self.line_searches is None or self.drv.user_options.get("snes_linesearch_type") == self.line_searches[which]:
            return False
        self.drv.user_options["snes_linesearch_type"] = self.line_searches[which]
        return True

    def _to_direct(self, rec, stale: bool) -> bool:
        """CG failed on a fresh preconditioner (an indefinite tangent) where the scene's choice allows LU: LU from
        now on. `stale`: the failed solve ran with a kept preconditioner (the retry builds a fresh one instead).
        Whether it switched."""
        drv = self.drv
        if (rec.reason == "DIVERGED_LINEAR_SOLVE" and not stale and drv.linear_kind == "iterative"
                and self.linear_kind in linear.FALLBACK_TO_DIRECT):
            drv.linear_kind = "direct"
            return True
        return False

    def _escape(self, why: str | None, at: float) -> bool:
        """After SNES converged but acceptance rejected: when it was a saddle of a volume-controlled problem, retry
        the same load from a start pushed off it along its unstable mode (constrained_stability.py); a symmetric
        state (two joined balloons inflated alike) never leaves its saddle otherwise. Once per load."""
        stability = acceptance.stability_check(self.drv)
        return (why or "").startswith(UNSTABLE) and stability is not None and stability.escape(at)

    def descend(self, on: bool) -> None:
        """Turn the merit line search of a volume-controlled (bordered multiplier) solve on for the retries after a
        failed attempt, off after an accepted step (solvers/multiplier_merit.py). Measured on the PneuNet actuator
        to 26.5 ml (2 ranks): full Newton steps alone stopped at the fold near 16.9 ml for h = 5, 4.5 and 4 mm and
        passed it by luck at 6 and 3.5 mm; the retries pass it at every h. Turned off, the driver is rebuilt (a
        retry's caller rebuilds it anyway)."""
        merit = self.merit
        if merit is not None and merit.active != on:
            merit.active = on
            if not on:
                self.drv.rebuild()

    @property
    def merit(self):
        """The bordered solve's merit (None without global scalars)."""
        return self.drv.bordered.merit if self.drv.bordered is not None else None
