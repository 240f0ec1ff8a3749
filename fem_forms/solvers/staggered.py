"""Staggered (alternate minimization) solve of several fields: one SNES sub-problem per field, each for its own
Function with the others frozen (its forms simply reference the other fields' Functions), swept in order
until no field changes any more.

Monolithic or staggered, chosen per analysis: monolithic is one NonlinearProblem on a mixed (or block) space
(the mixed u-p formulation of model.py), solved by the continuation as any other problem: Newton on the
coupled tangent, quadratic convergence, but one indefinite or non-convex system. Staggered is this module:
each sub-problem is small and convex in its own field where the whole is not (phase-field fracture: the
energy is convex in u and in d separately, not jointly), and each may carry its own bounds (d_old <= d <= 1);
it converges linearly, at a rate set by the coupling (~ c^2 / (a b) for two quadratic fields)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

from mpi4py import MPI
import numpy as np

from fem_forms.solvers import acceptance
from fem_forms.solvers.reports import StepRecord
from fem_forms.solvers.snes import NonlinearProblem, SNESDriver

MAX_PUSHES = 3           # pushes off a saddle per load step, each followed by another alternate minimization


@dataclass
class StaggeredReport:
    converged: bool
    iterations: int                  # sweeps over all fields
    changes: list = field(default_factory=list)   # per sweep: each field's |change|_inf / |field|_inf
    reason: str = ""
    records: list = field(default_factory=list)   # per sweep: each field's StepRecord


def solve(problems: Sequence[NonlinearProblem | SNESDriver], rtol: float = 1e-8, max_iterations: int = 100,
          options: dict | None = None, relaxation: Sequence[float] | None = None) -> StaggeredReport:
    """Alternate over `problems` (one per field, in order) until the largest relative change of any field in a
    sweep is below `rtol` or `max_iterations` sweeps are done. Each sub-solve is judged by
    acceptance.why_rejected against the residual of its field at zero (the others frozen); a rejected one ends
    the solve (converged False, the reason says which field and why). Fields are left at the last iterate:
    committing or rolling back a State is the caller's. Drivers built here (from NonlinearProblems, with
    `options`) are destroyed at the end; drivers passed in are reused and kept. `relaxation` (one per field, 1:
    none) over-relaxes each field's step within its bounds (over_relax)."""
    drivers = [p if isinstance(p, SNESDriver) else SNESDriver(p, options) for p in problems]
    kept = [d.polish_stuck for d in drivers]     # a caller's driver gets its own setting back at the end
    for d in drivers:
        d.polish_stuck = True                    # a sub-solve 1e-9 from its answer: the line search sees only noise
    report = StaggeredReport(False, 0)
    try:
        for sweep in range(1, max_iterations + 1):
            changes, records = [], []
            for i, drv in enumerate(drivers):
                before = drv.p.u.x.array.copy()
                scale = drv.load_scale(refresh=True)  # the frozen fields moved: scale of this field's residual
                rec: StepRecord = drv.solve_step()
                records.append(rec)
                if why := acceptance.why_rejected(drv, rec, load_scale=scale):
                    drv.rebuild()                    # a failed SNES must not be reused as it is
                    report.iterations, report.reason = sweep, f"field {i} ({drv.p.u.name}), sweep {sweep}: {why}"
                    report.records.append(records)
                    return report
                changes.append(_relative_change(drv, before))     # the plain step's: the fixed point's residual
                if relaxation is not None and relaxation[i] != 1.0:
                    over_relax(drv, before, relaxation[i])
            report.changes.append(changes)
            report.records.append(records)
            report.iterations = sweep
            if max(changes) <= rtol:
                report.converged, report.reason = True, f"largest change {max(changes):.2e} <= {rtol:.1e}"
                return report
        report.reason = f"{max_iterations} sweeps, largest change still {max(report.changes[-1]):.2e}"
        return report
    finally:
        for p, drv, flag in zip(problems, drivers, kept):
            if drv is p:
                drv.polish_stuck = flag
            else:
                drv.destroy()


def over_relax(drv: SNESDriver, before: np.ndarray, omega: float) -> None:
    """The field x <- before + omega (x - before), projected onto its bounds: over-relaxed alternate minimization
    (Farrell & Maurini 2017), whose fixed points are the plain iteration's. A damage field that moves the same
    way sweep after sweep (a crack growing through a load step) gets there in fewer sweeps."""
    x = drv.p.u.x.array
    x[:] = before + omega * (x - before)
    if drv.bounds is not None:                       # the bound vectors hold the owned dofs
        owned = drv.bounds.lower.array_r.size
        np.clip(x[:owned], drv.bounds.lower.array_r, drv.bounds.upper.array_r, out=x[:owned])
    drv.p.u.x.scatter_forward()


def _relative_change(drv: SNESDriver, before: np.ndarray) -> float:
    """|u - before|_inf / |u|_inf over the owned dofs of all ranks (0 for a field that is and stays 0)."""
    owned = drv.p.u.function_space.dofmap.index_map.size_local * drv.p.u.function_space.dofmap.index_map_bs
    now = drv.p.u.x.array[:owned]
    diff = drv.comm.allreduce(float(np.abs(now - before[:owned]).max(initial=0.0)), op=MPI.MAX)
    size = drv.comm.allreduce(float(np.abs(now).max(initial=0.0)), op=MPI.MAX)
    return diff / size if size > 0 else diff


class AlternateMinimization(SNESDriver):
    """The driver of a field whose every step is an alternate minimization with other fields (phase-field
    fracture: the displacement, then sweeps of [damage, displacement] until `solve` above converges): to the
    continuation it is the displacement's driver (its forms, acceptance and cut-backs), its steps staggered."""

    def __init__(self, problem: NonlinearProblem, others: Sequence[NonlinearProblem], rtol: float,
                 max_iterations: int, options: dict | None = None, stability=None,
                 relaxation: Sequence[float] | None = None, **kwargs):
        super().__init__(problem, options, **kwargs)
        self.relaxation = [*(relaxation or [1.0] * len(others)), 1.0]     # the others' over-relaxation; u's none
        # `stability.push(load_factor)`: pushes a converged saddle along its unstable mode (True) or finds the state
        # stable (False); each push is followed by another alternate minimization (the stable path)
        self.stability = stability
        # the other fields' energies are quadratic in their own field with this one frozen (the phase field's
        # for a frozen u): full Newton steps are exact, and an energy line search only met round-off near the
        # answer (DIVERGED_LINE_SEARCH on a tearing silicone strip's damage, every few steps)
        self.others = [SNESDriver(p, {"snes_linesearch_type": "basic"}, "direct" if _small(p) else "auto",
                                  prefix="fem_forms_other_") for p in others]
        self.rtol, self.max_iterations = rtol, max_iterations
        self.sweeps: list[int] = []        # per solved step: the sweeps it took
        self._inner = False

    def solve_step(self, check_start: bool = True) -> StepRecord:
        first = super().solve_step(check_start)
        if self._inner or not first.accepted:
            return first
        scale = self.known_load_scale
        self._inner = True
        records = [first]
        try:
            report = self._sweeps()
            for _ in range(MAX_PUSHES if self.stability is not None else 0):
                kept = [drv.p.u.x.array.copy() for drv in (*self.others, self)]
                if not report.converged or not self.stability.push(self.load_factor):
                    break
                moved = self.solve_step()          # the displacement first (inner: one SNES step), then sweeps
                trial = self._sweeps() if moved.accepted else \
                    StaggeredReport(False, 0, reason=f"displacement after the push: {moved.reason}")
                if not trial.converged:            # no equilibrium found off the saddle: keep the one converged to
                    for drv, x in zip((*self.others, self), kept):
                        drv.p.u.x.array[:] = x
                        drv.p.u.x.scatter_forward()
                    self.stability.gave_up(self.load_factor, trial.reason)
                    break
                records += [r for sweep in report.records for r in sweep] + [moved]
                report = trial
                self.stability.kept()
        finally:
            self._inner = False
            self._load_scale = scale               # staggered sub-solves refreshed it at this step's load
        self.sweeps.append(report.iterations)
        records += [r for sweep in report.records for r in sweep]
        last = report.records[-1][-1] if report.records else first
        iterations = sum(r.iterations for r in records)
        if not report.converged:
            return StepRecord(0.0, iterations, last.residuals, f"STAGGERED ({report.reason})", False)
        return StepRecord(0.0, iterations, last.residuals, last.reason, True,
                          krylov_iterations=sum(r.krylov_iterations for r in records))

    def _sweeps(self) -> StaggeredReport:
        """Alternate minimization of the others' fields and this one from the current state."""
        return solve([*self.others, self], self.rtol, self.max_iterations, relaxation=self.relaxation)

    def rebuild(self) -> None:
        super().rebuild()
        for other in getattr(self, "others", []):
            other.rebuild()

    def destroy(self) -> None:
        for other in getattr(self, "others", []):
            other.destroy()
        super().destroy()


def _small(problem: NonlinearProblem) -> bool:
    """A field small enough for a direct solve whatever `auto` would choose for it (a scalar P1 field: one
    third of a P1 displacement's dofs)."""
    V = problem.u.function_space
    return V.dofmap.index_map.size_global * V.dofmap.index_map_bs <= 200_000

