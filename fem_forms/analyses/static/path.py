"""Which continuation follows a static run's load path (solver.control): the load factor stepped (load), the
arc length along the load-displacement path (arc-length), or load control that hands over to arc length where
it stops near a limit point (auto), so the falling branch past a limit load is followed instead of approached
for minutes with ever smaller failing steps."""
from __future__ import annotations

from typing import Callable

import numpy as np

from fem_forms.errors import InputError
from fem_forms.model import Model
from fem_forms.physics import rigid_motion
from fem_forms.physics.path_constraint import ArcLength
from fem_forms.solvers import arc_length, snes
from fem_forms.solvers.linear import rigid_body_modes

LIMIT = "limit point: "             # how a continuation that stopped at a limit point begins its message


def arc_length_fits(model: Model) -> str | None:
    """Why the model's loads cannot be followed by arc length (None: they can). Its constraint steps one load
    factor scaling every load; path-dependent and lagged terms, staggered sub-problems and other scalar unknowns
    keep load control."""
    scene = model.scene
    if any(t.history for t in model.loads) or rigid_motion.prescribes_motion(scene):
        return "the loads must scale with one load factor (no [[load]] history, no prescribed displacement in " \
               "[[fix]] value)"
    if model.solid.is_plastic or model.terms.lagged or model.sub_problems() or model.global_scalars():
        return "plasticity, contact, a phase field and volume control keep load control"
    return None


def synced_displacement(model: Model) -> np.ndarray:
    """A copy of the displacement's local array, synced from the unknown (the mixed formulation's u part)."""
    model.sync_displacement()
    return model.u.x.array.copy()


def follow_path(model: Model, load_scale: float, linear_kind: str, on_step: Callable[[float], None],
                start: arc_length.Handoff | None = None) -> snes.SolveReport:
    """Arc-length continuation of the model's loads, the load factor solved with the displacement, limit points
    passed: from the rest state, or on from where load control left the path (`start`). InputError where the
    loads do not scale with one factor (arc_length_fits)."""
    scene = model.scene
    if (why := arc_length_fits(model)) is not None:
        raise InputError(f"solver.control = 'arc-length': {why}; use control = 'load'")
    constraint = ArcLength(model)
    problem = model.problem()
    problem.scalars = problem.scalars + [constraint.scalar]
    problem.set_load = None

    def displacement():
        return synced_displacement(model)
    moves = model.unknown is model.u                     # the predictor moves u in the displacement formulation

    def set_displacement(a):
        model.u.x.array[:] = a
    return arc_length.solve(problem, constraint, displacement, set_displacement if moves else None, load_scale,
                            scene.solver.petsc, scene.solver.steps, scene.solver.max_cutbacks, linear_kind,
                            near_nullspace=lambda: rigid_body_modes(model.V), on_step=on_step,
                            load_drop=scene.solver.load_drop, start=start)


class PathEnds:
    """The displacement (and the unknown, in the mixed formulation) at the start of a load-controlled path and
    after its first, last-but-one and last accepted steps: what arc length needs to go on from there (an on_step
    hook; four states kept, not the path)."""

    def __init__(self, model: Model):
        self.model = model
        self.start = self._now(0.0)
        self.first = self.before = self.last = None

    def _now(self, lam: float) -> tuple[np.ndarray, float, np.ndarray]:
        u = synced_displacement(self.model)
        return u, lam, (u if self.model.unknown is self.model.u else self.model.unknown.x.array.copy())

    def __call__(self, lam: float) -> None:
        self.before, self.last = self.last, self._now(lam)
        self.first = self.first or self.last

    def handoff(self) -> arc_length.Handoff | None:
        """Load control's last load factor and its first and last increments (None before an accepted step)."""
        if self.last is None:
            return None
        before = self.before or self.start
        step = lambda a, b: (b[0] - a[0], b[1] - a[1])      # noqa: E731
        return arc_length.Handoff(self.last[1], step(self.start, self.first), step(before, self.last),
                                  self.first[2] - self.start[2])


def then_arc_length(model: Model, report: snes.SolveReport, ends: PathEnds, load_scale: float, linear_kind: str,
                    on_step: Callable[[float], None]) -> snes.SolveReport:
    """control = "auto": where load control stopped at a limit point, arc length goes on from its last accepted
    state along its last step; the two reports joined. Any other ending is load control's."""
    start = ends.handoff()
    if report.converged or start is None or not report.message.startswith(LIMIT):
        return report
    model.load.set(start.lam)                            # a failed trial left the loads beyond the state
    joined = report.then(follow_path(model, load_scale, linear_kind, on_step, start))
    joined.arc_length_from = start.lam
    return joined
