"""What changes before a failed Newton solve is tried again: one policy for load continuation and implicit time
steps. After SNES failed: a fresh preconditioner (a kept one failed), LU instead of an indefinite iterative solve,
Newton instead of a stalled chord, a factor per iteration instead of a stale one. After a converged state that
acceptance rejected as a saddle of a volume-controlled problem: a start pushed off it along its unstable mode. For
the retries of a volume-controlled (bordered multiplier) solve: the descent of a merit, off again once a step is
accepted."""
from __future__ import annotations

from fem_forms.solvers import acceptance, linear
from fem_forms.solvers.reports import UNSTABLE


class RetryPolicy:
    """The retry ladder of one driver, whose scene asked for the linear solver `linear_kind`."""

    def __init__(self, drv, linear_kind: str):
        self.drv, self.linear_kind = drv, linear_kind

    def to_direct(self, rec, stale: bool) -> bool:
        """CG failed on a fresh preconditioner (an indefinite tangent) where the scene's choice allows LU: LU from
        now on. `stale`: the failed solve ran with a kept preconditioner (the retry builds a fresh one instead).
        Whether it switched."""
        drv = self.drv
        if (rec.reason == "DIVERGED_LINEAR_SOLVE" and not stale and drv.linear_kind == "iterative"
                and self.linear_kind in linear.FALLBACK_TO_DIRECT):
            drv.linear_kind = "direct"
            return True
        return False

    def after_failure(self, rec, report) -> bool:
        """After SNES failed a load step: what the retry solves with (see the module). Returns whether the step is
        retried at its size (the chord's fallback) rather than halved."""
        drv = self.drv
        stale = rec.reason == "DIVERGED_LINEAR_SOLVE" and drv.stale_preconditioner_failed()
        if stale:
            return False                             # the retry (fresh SNES) rebuilds the preconditioner
        if self.to_direct(rec, stale):
            report.linear_solver = "iterative->direct"
        elif drv.reuse_factor == "chord":
            drv.reuse_factor = True                  # the chord stalled: Newton (the stale LU preconditions)
            return True                              # retries this step at its size
        elif rec.reason == "DIVERGED_LINEAR_SOLVE" and drv.reuse_factor:
            drv.reuse_factor = False                 # stale LU too far off: factor every iteration
        return False

    def after_rejection(self, why: str | None, trial: float) -> bool:
        """After SNES converged but acceptance rejected: when it was a saddle of a volume-controlled problem, retry
        the same load from a start pushed off it along its unstable mode (constrained_stability.py); a symmetric
        state (two joined balloons inflated alike) never leaves its saddle otherwise. Once per load."""
        stability = acceptance.stability_check(self.drv)
        return (why or "").startswith(UNSTABLE) and stability is not None and stability.escape(trial)

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
