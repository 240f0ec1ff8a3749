"""Arc-length continuation on the one SNES driver: the load factor is solved with the displacement (a global
scalar, bordered Newton) under the constraint of physics/path_constraint.py, so the path is followed through
limit points, where the load factor turns back, and on. The first step is load-controlled (it sets the
displacement scale); each later step goes a distance ds along the last step's direction, grown 1.5x after a
success and halved after a failure. A step that would pass lambda = 1 is replaced by a load-controlled step
onto 1 (the run's answer); a path whose load has dropped past its peak by the scene's fraction (as a test machine
stops at a load drop), or that runs out of steps or of step size, ends without it: a limit point whose largest
load factor the report gives. A path may also start where load control stopped near a limit point (`Handoff`:
control = "auto"), along that continuation's last step."""
from __future__ import annotations

import math
import time

import numpy as np
from typing import Callable, NamedTuple

from fem_forms import progress
from fem_forms.solvers import acceptance
from fem_forms.solvers.limit import RETRY_FACTOR
from fem_forms.solvers.reports import SolveReport
from fem_forms.solvers.snes import NonlinearProblem, SNESDriver

MAX_STEPS = 100          # steps (beyond solver.steps) before the run ends without reaching full load (as
                         # Abaqus's Riks: a balloon's falling branch goes on for ever)
RECENT = 5               # a step may take RETRY_FACTOR times the Newton iterations of the slowest of the last RECENT
                         # accepted ones: past a limit point failing steps took 50 (the PneuNet's path, 11 s each)
ARC_MIN_CAP = 10         # ... and at least this many (8 held every step of the PneuNet's falling branch short)
TURN = 1e-6              # a step whose loads' work is below -TURN x the first step's (per arc length) turns back
ALONG = 1e-3             # ... above ALONG x it, the path goes along the loads: a success there resets the cut-backs
                         # (at a fold it goes across them; tiny steps creeping on there are no progress)
TURNS = "the path turns back (a snap-back: the loaded points move against their loads)"
MAX_GROWTH = 2.0         # the arc length of a step at most this many times the first step's: a limit point
                         # is sampled, not jumped (StVK's peak: 2 points on the rising branch with unbounded growth)


class Handoff(NamedTuple):
    """Where load control left the path: its last accepted load factor, the (displacement increment, load
    increment) of its first and of its last accepted step (the scale U and the direction to go on along), and
    the unknown's increment over the first (the scale of the loads' work)."""
    lam: float
    first: tuple
    last: tuple
    first_unknown: np.ndarray


class _Path:
    """The accepted points: (u, lambda) now and the increment that led there."""

    def __init__(self, u0, lam0: float = 0.0):
        self.u, self.lam = u0.copy(), lam0
        self.du, self.dlam = None, 0.0
        self.points = [(0.0, lam0)]              # (arc length so far, lambda) of every accepted point

    def advance(self, u, lam: float, ds: float) -> None:
        self.du, self.dlam = u - self.u, lam - self.lam
        self.u, self.lam = u.copy(), lam
        self.points.append((self.points[-1][0] + ds, lam))

    @property
    def peak(self) -> float:
        """The largest load factor on the path: the vertex of the parabola through the highest accepted point
        and its neighbours when it lies between them (the steps sample the curve; the vertex is nearer the
        true maximum), else the highest point."""
        s, lam = np.array(self.points).T
        i = int(np.argmax(lam))
        if 0 < i < len(lam) - 1:
            a, b, c = np.polyfit(s[i - 1: i + 2], lam[i - 1: i + 2], 2)
            if a < 0 and s[i - 1] <= -b / (2 * a) <= s[i + 1]:
                return float(c - b * b / (4 * a))
        return float(lam[i])


def solve(problem: NonlinearProblem, path_constraint, displacement: Callable, set_displacement: Callable | None,
          load_scale: float, options: dict | None = None, steps: int = 1, max_cutbacks: int = 12,
          linear_kind: str = "auto", near_nullspace=None, on_step: Callable | None = None,
          load_drop: float = 1.0, start: Handoff | None = None) -> SolveReport:
    """Follow the path from lambda = 0 (or the `start`'s, from the current state) to 1, or as far as it goes: past
    a limit point, until the load factor has fallen below (1 - load_drop) of its peak. `path_constraint`: an
    ArcLength whose scalar is in problem.scalars; `displacement()` the displacement's local array,
    `set_displacement(a)` sets it (None: the predictor moves only lambda); `load_scale` the full load's residual
    at rest (N). `on_step(lam)` is called after each accepted step."""
    t0 = time.perf_counter()
    drv = SNESDriver(problem, options, linear_kind, "fem_forms_arc_", near_nullspace)
    drv.use_load_scale(load_scale)
    pc, state, lam_const = path_constraint, problem.state, path_constraint.scalar.value
    lam_const.value = 0.0 if start is None else start.lam
    state.commit()
    path = _Path(displacement(), 0.0 if start is None else start.lam)
    report = SolveReport(False, path.lam, 0, math.nan, linear_solver=drv.linear_kind, load_scale=load_scale)
    ds, ds_first, cuts, final, recent = 1.0 / steps, None, 0, False, []
    unknown = problem.u.x.array.copy()           # the unknown at the last accepted point
    rate_first = None                            # the loads' work per arc length of the first step
    if start is not None:
        ds, ds_first, rate_first = _resume(pc, path, start)
    while len(report.steps) < MAX_STEPS + steps:
        u_pred, lam_pred = _predict(pc, path, ds, final)
        lam_const.value = lam_pred
        if set_displacement is not None and path.du is not None and not final:
            if _inverts_cells(problem, set_displacement, u_pred):   # a shorter one, without a Newton solve from there
                cuts, ds = cuts + 1, 0.5 * ds
                if cuts > max_cutbacks:
                    report.message = _ended(report, path, "the step could not be made smaller", ds)
                    break
                continue
        drv.load_factor = lam_pred
        progress.report("load_step", load=lam_pred, step=len(report.steps) + 1)
        rec = drv.solve_step()
        lam = float(lam_const.value)
        rec.load = lam
        why = acceptance.why_rejected(drv, rec, load_scale=load_scale)
        work = pc.load_work(problem.u.x.array - unknown) if why is None else 0.0
        if why is None and not final:
            why = _along_the_path(work, rate_first, ds, lam)
            final = why is not None and why.startswith("passes")
        report.add_step(rec, why)
        if not rec.accepted:
            state.rollback()
            drv.rebuild()
            if not rec.note.startswith("passes"):
                cuts, ds, final = cuts + 1, 0.5 * ds, False    # a failed step onto full load: walk on, shorter
            if cuts > max_cutbacks:
                report.message = _ended(report, path, TURNS + " however short the step" if rec.note.startswith(TURNS)
                                        else "the step could not be made smaller", ds)
                break
            continue
        unknown = problem.u.x.array.copy()
        report.residual_norm = rec.checked_residual
        path.advance(displacement(), lam, ds if path.du is not None else 0.0)
        state.commit()
        report.load_reached = lam
        if on_step is not None:
            on_step(lam)
        if ds_first is None:                     # the first, load-controlled step sets the path's scales
            ds_first = ds = pc.first_step_done(path.du, path.dlam)
            path.points[-1], rate_first = (ds, lam), abs(work) / ds_first
        if work >= ALONG * rate_first * (path.points[-1][0] - path.points[-2][0]):
            cuts = 0                             # cut-backs count on while the path goes across the loads
        ds = min(ds * (1.5 if rec.iterations <= 5 else 1.0), MAX_GROWTH * ds_first)
        recent = recent[-(RECENT - 1):] + [rec.iterations]
        drv.newton_cap = max(ARC_MIN_CAP, RETRY_FACTOR * max(recent))   # no step worth 50 Newton iterations
        if final or abs(lam - 1.0) < 1e-12:
            report.converged, report.message = True, "converged"
            break
        if (end := _path_ends(path, lam, ds, ds_first, max_cutbacks, load_drop)) is not None:
            report.message = _ended(report, path, end, ds)
            break
    else:
        report.message = _ended(report, path, f"{len(report.steps)} steps taken", ds)
    return _finish(report, path, drv, t0)


def _finish(report: SolveReport, path: _Path, drv: SNESDriver, t0: float) -> SolveReport:
    """The peak and the timings into the report; the driver destroyed."""
    report.peak_load_factor = path.peak
    report.assembly_time = drv.assembly_time
    report.solve_time = time.perf_counter() - t0 - report.assembly_time
    drv.destroy()
    progress.report("solve_done", converged=report.converged)
    return report


def _inverts_cells(problem: NonlinearProblem, set_displacement: Callable, u_pred: np.ndarray) -> bool:
    """Set the predicted displacement; True (and the state back at the last accepted one) where it inverts cells."""
    set_displacement(u_pred)
    if problem.inadmissible is not None and problem.inadmissible():
        problem.state.rollback()
        return True
    return False


def _predict(pc, path: _Path, ds: float, final: bool) -> tuple[np.ndarray, float]:
    """The next step's constraint set up and its Newton start (u, lambda): load control for the first step and
    the step onto full load, else ds along the last step."""
    if path.du is None or final:
        pc.load_control(path.lam, (1.0 - path.lam) if final else ds)
    else:
        pc.along(path.u, path.lam, path.du, path.dlam, ds)
    return pc.predictor()


def _resume(pc, path: _Path, start: Handoff) -> tuple[float, float, float]:
    """On along load control's last step, at its length (at most MAX_GROWTH first steps): (ds, the first step's
    arc length, the loads' work per arc length of the first step)."""
    ds_first = pc.first_step_done(*start.first)
    rate_first = abs(pc.load_work(start.first_unknown)) / ds_first
    path.du, path.dlam = start.last
    return min(pc.length(*start.last), MAX_GROWTH * ds_first), ds_first, rate_first


def _along_the_path(work: float, rate_first: float | None, ds: float, lam: float) -> str | None:
    """Why a converged arc-length step is not taken as it is: it turns back (the loads do negative work over it), or
    it passes full load (a load-controlled step onto 1 follows); None: it is."""
    if rate_first is not None and work < -TURN * rate_first * ds:
        return f"{TURNS} (the loads' work over the step {work:.3g} J)"
    if lam > 1.0 + 1e-9:
        return "passes full load: a load-controlled step onto it instead"
    return None


def _path_ends(path: _Path, lam: float, ds: float, ds_first: float, max_cutbacks: int, load_drop: float) -> str | None:
    """Why the path is followed no further after an accepted step at `lam`, or None."""
    if ds < ds_first / 2**max_cutbacks:          # creeping on (a fold, a part crushed flat): no progress
        return "its steps shrank below 2^-max_cutbacks of the first"
    if lam <= (1.0 - load_drop) * path.peak and path.peak > 0.0:
        return f"the load factor fell to {lam / path.peak:.3g} of its peak"
    return None


def _ended(report: SolveReport, path: _Path, why: str, ds: float) -> str:
    """The message of an arc-length run that did not reach full load."""
    return (f"limit point: the load factor peaked at {path.peak:.6g} and full load lies beyond the path "
            f"followed ({why}; load factor {path.lam:.6g} at the last of {len([s for s in report.steps if s.accepted])} "
            f"accepted arc-length steps)")
