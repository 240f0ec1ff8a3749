"""Time marching, whatever the scheme: a stepper advances the State from t to t + dt (one SNES solve for
an implicit scheme, one residual assembly for an explicit one) and says whether the step is accepted;
this loop cuts the step on failure (the stepper has rolled the State back), grows and shrinks it by a
local error estimate when asked, reports progress and hands each accepted step to the caller.

Also here: piecewise-linear load histories and the power-iteration estimate of the largest
eigenvalue of M^-1 K (the explicit scheme's stable step)."""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, Protocol

from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms import progress
from fem_forms.errors import SolveError


@dataclass
class StepOutcome:
    """What one attempted step did."""
    accepted: bool
    iterations: int = 0            # Newton iterations (0 for an explicit step)
    why: str = ""                  # why it was rejected
    error: float = math.nan        # local error estimate relative to the tolerance's scale (adaptive)
    event: str = ""                # what happened over the step that shorter steps resolve ("impact", "stick-slip")


class Stepper(Protocol):
    def step(self, t: float, dt: float) -> StepOutcome: ...   # advance the State (rolled back if rejected)

    def undo(self) -> None: ...                                # roll back the last accepted step


@dataclass
class MarchReport:
    steps: int = 0
    time_reached: float = 0.0
    dt_min: float = math.inf
    dt_max: float = 0.0
    newton_iterations: int = 0
    rejected: int = 0
    refined: int = 0               # accepted steps redone shorter for an event (refine_events)
    next_dt: float = 0.0           # the step the march takes next (a checkpoint's, so a restart goes on alike)


def march(stepper: Stepper, t0: float, t_end: float, dt: float, on_accept: Callable[[float, float, int], None],
          *, adaptive: bool = False, tolerance: float = 1e-3, max_cutbacks: int = 10, step0: int = 0,
          report: MarchReport | None = None, dt_max: float | None = None, stops: tuple = (),
          refine_events: int = 0, first_dt: float | None = None) -> MarchReport:
    """Advance from t0 to t_end. After a rejected step dt is halved (at most `max_cutbacks` times in a
    row, and never below the floor dt / 2^max_cutbacks, `dt` the asked-for step: then SolveError, so a
    step that keeps being cut gives up in bounded time instead of creeping on); with `adaptive`, a step whose error estimate exceeds 2 x tolerance is redone
    smaller and dt follows 0.9 (tolerance / error)^(1/3) (third-order local error), within [dt/2, 2 dt]
    and below dt_max. Every time in `stops` (the corners of load and temperature histories) is a step end,
    so that no step, cut back or not, steps over a peak. With `refine_events` N, a step whose outcome tells an
    event (an impact, a stick-slip transition) is undone and redone at a quarter of its length, down to
    dt / 2^N, so that the event falls in a short step; the steps then double back. `first_dt`: the first step's
    size (a restart's next_dt; floors stay dt's). on_accept(t, dt, step) runs after each accepted step, with
    report.next_dt already the next step's size."""
    rep = report or MarchReport()
    t, cuts, step = t0, 0, step0
    dt_max = dt_max or dt
    dt_floor = dt / 2.0 ** max_cutbacks
    event_floor = dt / 2.0 ** refine_events
    dt = min(first_dt or dt, dt_max)
    eps = 1e-12 * max(t_end, 1.0)
    while t < t_end - eps:
        end = min([t_end] + [s for s in stops if s > t + 1e-9 * dt])
        h = min(dt, end - t)
        if end - (t + h) < 1e-3 * h:            # no sliver step before a stop or the end
            h = end - t
        out = stepper.step(t, h)
        if out.accepted and adaptive and out.error > 2 * tolerance:
            stepper.undo()
            out = StepOutcome(False, out.iterations, f"local error {out.error:.3g} > 2 x tolerance")
        rep.newton_iterations += out.iterations
        if out.accepted and out.event and refine_events and h > event_floor * (1 + 1e-9):
            stepper.undo()
            rep.refined += 1
            dt = max(0.25 * h, event_floor)
            progress.report("step_refined", time=t, dt=dt, why=out.event)
            continue
        if not out.accepted:
            rep.rejected += 1
            cuts += 1
            if cuts > max_cutbacks or (0.5 * h < dt_floor and h < end - t):     # gives up: the log says so
                progress.report("step_rejected", load=t, why=out.why)
                progress.report("march_done", time=t, steps=rep.steps, rejected=rep.rejected, failed=True)
            if cuts > max_cutbacks:
                raise SolveError(f"time step cut {cuts - 1} times in a row at t = {t:.6g} "
                                 f"(dt = {h:.3g}; solver.max_cutbacks = {max_cutbacks}): {out.why}")
            if 0.5 * h < dt_floor and h < end - t:        # a last sliver before a stop may be shorter
                raise SolveError(f"time step at t = {t:.6g}: dt below its floor ({0.5 * h:.3g} < {dt_floor:.3g} = "
                                 f"dt / 2^solver.max_cutbacks) after {rep.rejected} rejected steps: {out.why}")
            dt = 0.5 * h
            progress.report("step_rejected", load=t, why=out.why)
            continue
        cuts = 0
        t += h
        step += 1
        rep.steps, rep.time_reached = rep.steps + 1, t
        rep.dt_min, rep.dt_max = min(rep.dt_min, h), max(rep.dt_max, h)
        if adaptive and math.isfinite(out.error):
            factor = 0.9 * (tolerance / max(out.error, 1e-300)) ** (1 / 3)
            dt = min(dt_max, h * min(2.0, max(0.5, factor)))
        else:
            dt = min(dt_max, max(dt, 2 * h))        # back towards the asked-for step after a cut
        rep.next_dt = dt
        on_accept(t, h, step)                   # booked (and written) before it is said to be accepted
        progress.report("time_step", time=t, dt=h, step=step, total_time=t_end, iterations=out.iterations)
    progress.report("march_done", time=t, steps=rep.steps, rejected=rep.rejected)
    return rep


def history_corners(*histories: list | None) -> tuple:
    """The inner corner times of [[t, f], ...] histories, sorted (the steps must end there)."""
    return tuple(sorted({p[0] for h in histories if h for p in h[1:-1]} | {h[-1][0] for h in histories if h}))


def largest_eigenvalue(apply_K: Callable[[PETSc.Vec, PETSc.Vec], None], inv_mass: PETSc.Vec,
                       iterations: int = 40, seed: int = 1) -> float:
    """lambda_max of M^-1 K (M diagonal, given as its inverse, zero at constrained dofs) by power
    iteration on the M-symmetric operator: the Rayleigh quotient x.Kx / x.Mx approaches it from below."""
    comm = inv_mass.comm.tompi4py()
    x, y = inv_mass.duplicate(), inv_mass.duplicate()
    free = inv_mass.array != 0
    mass = np.where(free, 1.0 / np.where(free, inv_mass.array, 1.0), 0.0)
    rng = np.random.default_rng(seed + inv_mass.getOwnershipRange()[0])
    x.array[:] = rng.standard_normal(x.local_size) * free
    lam = 0.0
    for _ in range(iterations):
        x.scale(1.0 / max(x.norm(), 1e-300))
        apply_K(x, y)                       # y = K x
        xkx = comm.allreduce(float(x.array @ y.array), op=MPI.SUM)
        xmx = comm.allreduce(float((x.array ** 2 * mass).sum()), op=MPI.SUM)
        lam = xkx / max(xmx, 1e-300)
        y.pointwiseMult(y, inv_mass)        # x <- M^-1 K x
        y.copy(x)
    x.destroy()
    y.destroy()
    return lam
