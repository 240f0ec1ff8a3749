"""What a solve reports: one record per SNES solve (a load or time step) and the report of a whole
continuation (steps, Newton and Krylov counts, timings, the message)."""
from __future__ import annotations

from dataclasses import dataclass, field
import math

from fem_forms import progress


# how a rejected saddle's note begins (solvers/constrained_stability.py)
UNSTABLE = "unstable equilibrium"


@dataclass
class StepRecord:
    load: float
    iterations: int
    residuals: list
    reason: str
    accepted: bool
    note: str = ""            # why an SNES-converged step was still rejected
    krylov_iterations: int = 0
    preconditioner_builds: int = 0   # multigrid hierarchies built (kept across Newton steps when cheaper)
    checked_residual: float = math.nan   # the residual norm acceptance.why_rejected tested
    unsettled: bool = False   # its lagged friction's normal forces still moved after the last re-lag (continuation)


@dataclass
class SolveReport:
    converged: bool
    load_reached: float
    newton_iterations: int
    residual_norm: float
    steps: list = field(default_factory=list)
    linear_solver: str = "direct"
    assembly_time: float = 0.0
    solve_time: float = 0.0
    message: str = ""
    load_scale: float = 0.0         # the residual of the starting state under the full load (tolerances' scale)
    peak_load_factor: float | None = None   # arc length: the largest load factor on the path followed
    stability_checked: bool | None = None   # volume control: the tangent's inertia was counted (None: no check)
    arc_length_from: float | None = None    # control = "auto": the load factor where arc length took over

    def then(self, later: SolveReport) -> SolveReport:
        """This continuation followed by `later`, which went on from its last accepted state: the steps and
        counts of both, the outcome and the peak of the later (at least this one's load reached)."""
        peak = max(self.load_reached, later.peak_load_factor or later.load_reached)
        residual = later.residual_norm if later.load_steps else self.residual_norm     # none accepted: this one's
        return SolveReport(later.converged, later.load_reached, self.newton_iterations + later.newton_iterations,
                           residual, self.steps + later.steps, later.linear_solver,
                           self.assembly_time + later.assembly_time, self.solve_time + later.solve_time,
                           later.message, self.load_scale, peak, later.stability_checked)

    def add_step(self, rec: StepRecord, why: str | None) -> None:
        """Book a finished step: accepted when `why` (the reason to reject it) is None; progress reported."""
        rec.accepted, rec.note = why is None, why or ""
        self.steps.append(rec)
        self.newton_iterations += rec.iterations
        progress.report("step_accepted" if rec.accepted else "step_rejected", load=rec.load,
                        iterations=rec.iterations, why=why or "")

    @property
    def friction_unsettled(self) -> list:
        """The load factors of accepted steps whose friction's normal forces had not settled after the last re-lag."""
        return [s.load for s in self.steps if s.accepted and s.unsettled]

    @property
    def unstable_rejected(self) -> list:
        """The load factors whose converged state was rejected as a saddle (volume control: the path snaps)."""
        return sorted({s.load for s in self.steps if s.note.startswith(UNSTABLE)})

    @property
    def load_steps(self) -> int:
        return sum(1 for s in self.steps if s.accepted)

    @property
    def krylov_iterations(self) -> int:
        return sum(s.krylov_iterations for s in self.steps)

    @property
    def preconditioner_builds(self) -> int:
        return sum(s.preconditioner_builds for s in self.steps)
