"""Load continuation on the one SNES driver: increments grown after success and halved on failure,
every step accepted only after independent checks, state restored on a cut-back."""
from __future__ import annotations

import math
import re
import time
from typing import Callable

import numpy as np
from petsc4py import PETSc

from fem_forms import progress
from fem_forms.solvers import acceptance
from fem_forms.solvers.limit import NEAR_LIMIT, PathStiffness
from fem_forms.solvers.reports import SolveReport, StepRecord
from fem_forms.solvers.retry import RetryPolicy
from fem_forms.solvers.snes import NonlinearProblem, SNESDriver
from fem_forms.state import State


def solve(problem: NonlinearProblem, options: dict | None = None, steps: int = 1,
          max_cutbacks: int = 12, linear_kind: str = "auto",
          near_nullspace: Callable[[], PETSc.NullSpace] | None = None,
          prefix: str = "fem_forms_", predictor: bool = True, reuse_factor: bool | str = False,
          driver: SNESDriver | None = None, stops: tuple = (), min_step: float = 0.0,
          limit_step: float = 0.0, on_step: Callable[[float], None] = lambda lam: None,
          max_step: float = 1.0) -> SolveReport:
    """Continuation lambda: 0 -> 1 in `steps` increments, the increment grown after a success (next_increment)
    and halved after a failure (at most `max_cutbacks` halvings in a row). A step is accepted only when SNES
    converged AND an independent re-assembly of the residual is small AND the state is finite and admissible (no
    inverted elements). With `predictor`, each step starts from predicted_move's extrapolation (fewer Newton steps).
    `reuse_factor` factors the direct solver's LU once per load step (linear.REUSED_FACTOR). A `driver` built
    once for `problem` and passed to repeated solves keeps its forms, matrix and SNES (the caller owns it).
    `stops`: load factors every step sequence must land on (a static load history's corners: a path-dependent
    material sees the peak load). `max_step`: the largest increment. `min_step`: give up once a halved
    increment is smaller (a limit load such as plastic collapse is otherwise approached for ever, each failure
    resetting the count of cut-backs in a row: 25,000 steps in 2 minutes on a perfectly plastic bar).
    `limit_step`: the same, once the path has flattened (near a limit point: a neo-Hookean sphere past its
    pressure maximum ran 10 minutes); elsewhere tiny steps of a hyperelastic solid do make progress (a
    rope-like beam at E = 100 Pa takes 1,000+ of them). `on_step(lam)` runs after each accepted, committed step."""
    t0 = time.perf_counter()
    drv = driver or SNESDriver(problem, options, linear_kind, prefix, near_nullspace, reuse_factor)
    retry = RetryPolicy(drv, linear_kind)
    assembly0 = drv.assembly_time
    u = problem.u
    set_load = problem.set_load or (lambda lam: None)
    state, old = _starting_state(problem, drv, retry)
    set_load(1.0)                                    # reference scale: the rest state's residual at full load
    r_full = drv.load_scale(refresh=True)            # a reused driver's loads or rest shape may have changed
    report = SolveReport(False, 0.0, 0, math.nan, linear_solver=drv.linear_kind, load_scale=r_full)
    lam, dlam, cuts = 0.0, min(1.0 / steps, max_step), 0
    if problem.set_load is None:                     # nothing to continue in: one attempt
        lam, dlam, max_cutbacks = 0.0, 1.0, 0
    recent, hold = [], False         # (u_k - u_{k-1}, its dlam) of the last accepted steps; a cut-back left the domain
    path = PathStiffness(u)
    while lam < 1.0 - 1e-12:
        trial = min([1.0, lam + dlam] + [s for s in stops if s > lam + 1e-12])
        if trial <= lam:                             # accepted steps shrank below the load factor's round-off
            report.message = f"limit point: load factor {lam:.6g} reached, the accepted steps shrank to round-off"
            break
        set_load(trial)
        corner = any(abs(lam - s) < 1e-12 for s in stops)     # the load path turns: no extrapolation across
        escaped = _start(drv, retry, old, recent if predictor and not corner else [], trial - lam)
        drv.load_factor = trial
        progress.report("load_step", load=trial, step=len(report.steps) + 1)
        rec = _settle_friction(drv, drv.solve_step())
        rec.load = trial
        why = acceptance.why_rejected(drv, rec, load_scale=r_full, stable_only=True)   # SNES, finite, admissible, ...
        same_step = why is not None and retry.same_size(rec, why, trial, report)
        if rec.accepted and why is None:
            report.residual_norm = rec.checked_residual     # the independently re-assembled residual
        report.add_step(rec, why)
        if rec.accepted:
            moved = (u.x.array - old.x.array, trial - lam)
            recent = ([] if corner or drv.arrays.caps else recent[-1:]) + [moved]     # contact: the secant
            path.accepted(moved[1], moved[0], rec.iterations, snapped=escaped)
            recent = [] if path.jumped else recent   # a snap: its move says nothing about the path beyond it
            drv.newton_cap = path.newton_cap()   # near a limit point no step is worth the full Newton limit
            state.commit()
            lam, cuts = trial, 0
            dlam, hold = next_increment(lam, dlam, hold, max_step), False
            report.load_reached = lam
            on_step(lam)
            retry.accepted()
        else:
            state.rollback()                         # back to the last accepted state, history included
            cuts, dlam = (cuts, dlam) if same_step else (cuts + 1, 0.5 * dlam)
            hold = hold or acceptance.left_the_domain(rec, why)
            retry.descend(True)
            drv.rebuild()                        # fresh solver state after a failure
            drv.newton_cap = path.newton_cap()
            if cuts > max_cutbacks or dlam < min_step or (dlam < limit_step and path.near_limit()):
                report.message = _gave_up(report, lam, trial, cuts, cuts > max_cutbacks, path.stiffness)
                break
            report.message = why
    else:
        report.converged, report.message = True, "converged"
    return _finish(report, drv, assembly0, t0, own_driver=driver is None)


# a static step's lagged friction is re-lagged at its equilibrium until its normal forces change by less than
# this share of their sum, at most RELAGS times (then the step keeps its last re-lag, unsettled, and the run says so:
# measured 3-6 re-lags a step on the soft column and the standing designs)
RELAG_TOLERANCE, RELAGS = 1e-4, 8


def _settle_friction(drv: SNESDriver, rec: StepRecord) -> StepRecord:
    """A converged step whose friction was lagged at the step's start, re-lagged at its equilibrium (normal forces
    and tangent planes; slips still from the start) and solved again from there until the normal forces settle
    (IPC's lagging iterations): a block put down on a table in one load step otherwise slides on the near-zero
    normal forces of its start (measured: a soft column landed 3.7 mm off where 20 steps put it). One record, its
    iterations summed; a re-solve that fails fails the step (its state is the failed solve's: the step is cut)."""
    if not (drv.p.relag and drv.arrays.relags):
        return rec
    for _ in range(RELAGS):
        if not rec.accepted or drv.arrays.relag(drv.p.u.vector, RELAG_TOLERANCE) <= RELAG_TOLERANCE:
            break
        more = drv.solve_step()
        more.iterations += rec.iterations
        more.residuals = rec.residuals + more.residuals
        more.krylov_iterations += rec.krylov_iterations
        more.preconditioner_builds += rec.preconditioner_builds
        rec = more
    else:
        rec.unsettled = rec.accepted          # kept, and said (results.json friction_unsettled, a warning)
    return rec


def _starting_state(problem: NonlinearProblem, drv: SNESDriver, retry: RetryPolicy) -> tuple[State, object]:
    """The state a cut-back returns to (the problem's own, or one holding its unknown; global scalars committed
    and rolled back with it), committed at the start, and the unknown's committed copy. The first tangent is
    the starting state's: a bordered solve's stability check counts negative eigenvalues against it."""
    if (stability := acceptance.stability_check(drv)) is not None:
        stability.new_path()
    retry.descend(False)                             # a reused driver starts with full Newton steps again
    state = problem.state or State({"unknown": problem.u})
    for s in problem.scalars:
        state.add_scalar(s.name, s.value)
    state.commit()
    return state, state.old[next(k for k, f in state.fields.items() if f is problem.u)]


def next_increment(lam: float, dlam: float, hold: bool, max_step: float) -> float:
    """The increment after an accepted step at `lam`: 1.5x the last, or the same when the cut-back before it
    was for a trial that left the domain (an element inverted: grown at once it met the same failure, the
    PneuNet actuator every other step), at most `max_step` (a load path sampled at least that finely) and
    what is left to full load."""
    return min(1.0 - lam, (1.0 if hold else 1.5) * dlam, max_step) if lam < 1.0 else dlam


def _finish(report: SolveReport, drv: SNESDriver, assembly0: float, t0: float, own_driver: bool) -> SolveReport:
    """Timings into the report; a driver built for this solve is destroyed (its options leave PETSc's database,
    which holds 512: a design's hundreds of solves would fill it)."""
    report.assembly_time = drv.assembly_time - assembly0
    report.solve_time = time.perf_counter() - t0 - report.assembly_time
    stability = acceptance.stability_check(drv)
    report.stability_checked = None if stability is None else stability.counted
    if own_driver:
        drv.destroy()
    progress.report("solve_done", converged=report.converged)
    return report


def predicted_move(t: float, recent: list) -> np.ndarray:
    """The move from the last accepted state to t further along the load path: the quadratic through the last
    three accepted states (Newton's divided differences, any spacing), or the secant through the last two (the
    caller keeps one state at the start, after a corner and with contact: with the quadratic, a frictional rocking
    toy's tilt went 13.7 -> 7.9 deg).
    Measured on the PneuNet actuator (32,817 dofs, 2 ranks): 167 -> 131 Newton iterations, 13 -> 11 rejected
    trials, solve 86 -> 56 s; its first residuals fall 5-10x."""
    step1, h1 = recent[-1]
    if len(recent) < 2:
        return (t / h1) * step1       # as the secant always was: a round-off change moved the rocking toy's period 2 %
    step0, h0 = recent[-2]
    d1 = step1 / h1
    return t * d1 + t * (t + h1) * (d1 - step0 / h0) / (h1 + h0)


def _start(drv: SNESDriver, retry: RetryPolicy, old, recent: list, t: float) -> bool:
    """Where the attempt's Newton starts: off the saddle the last attempt converged to, along its unstable mode
    (the saddle-escape rung of RetryPolicy.same_size); for another descent of the merit the last accepted state
    (from an extrapolation a descent can fall into another branch's basin: the PneuNet's tip angle dropped
    88 -> 78 deg); else that state
    moved by predicted_move over the load increment t, when `recent` has accepted steps to extrapolate. Returns
    whether it starts off a saddle (accepted, that step is a snap)."""
    u, merit, stability = drv.p.u, retry.merit, acceptance.stability_check(drv)
    escaped = stability is not None and stability.take_start(u)
    if not escaped:
        if (merit is not None and merit.active) or not recent:
            return False
        step = predicted_move(t, recent)
        u.x.array[:] = old.x.array + drv.arrays.safe_share(old.vector, step) * step   # contact: no crossing
    u.x.scatter_forward()
    return escaped


def _gave_up(report: SolveReport, lam: float, trial: float, cuts: int, too_many: bool,
             stiffness: float | None) -> str:
    """The message of a continuation that stopped: where it got, how stiff the path still was (a limit point
    when it had flattened out), and every kind of failure it saw."""
    flat = stiffness is not None and stiffness < NEAR_LIMIT
    how = (f"limit point: the load-displacement path flattened to {stiffness:.2g} of its initial stiffness; "
           if flat else "no convergence: ")
    return (f"{how}load factor {lam:.6g} reached, the step to {trial:.6g} failed after "
            f"{cuts - 1} cut-backs{'' if too_many else ' (the step fell below its smallest size)'} (failures "
            f"seen: {'; '.join(_distinct(s.note for s in report.steps if s.note))})")


def _distinct(notes) -> list:
    """The first note of each kind (kinds differ in their words, not their numbers)."""
    first = {}
    for n in notes:
        first.setdefault(re.sub(r"[-+]?[0-9][0-9.e+-]*", "#", n), n)
    return list(first.values())


