"""The one equilibrium solve: static, the modal prestress, the inverse design's forward check and the balance
sag use it."""
from __future__ import annotations

from dataclasses import dataclass, field
import time
from typing import Callable

from dolfinx import fem
from mpi4py import MPI
import numpy as np

from fem_forms.analyses.static.heat import solve_temperature
from fem_forms.model import Model, build_model
from fem_forms.solvers.thermal_step import max_value
from fem_forms.output.histories import step_histories
from fem_forms.output.quantities import Quantities
from fem_forms.output.guard import attempt
from fem_forms.output.reactions import reaction_report
from fem_forms.output.summary import header
from fem_forms.physics import rigid_motion
from fem_forms.physics.histories import piecewise_linear
from fem_forms.scene import Scene
from fem_forms.analyses.static.stable_path import stable_path
from fem_forms.analyses.static.path import LIMIT, PathEnds, arc_length_fits, follow_path, then_arc_length
from fem_forms.solvers import continuation, snes
from fem_forms.solvers.linear import rigid_body_modes


@dataclass
class StaticResult:
    """What a static solve found: the model (mesh, u) and the numbers results.json reports."""
    model: Model
    report: snes.SolveReport
    energy: float = float("nan")
    max_displacement: float = float("nan")
    probes: dict = field(default_factory=dict)
    probe_stresses: dict = field(default_factory=dict)   # probe -> stress, von_mises, strain (recovered)
    reactions: dict = field(default_factory=dict)        # reactions, applied_load, equilibrium_error
    quantities: Quantities | None = None                 # recovered stresses and strains
    term_reports: dict = field(default_factory=dict)     # each term's report (contact, min_distance, crack ...)
    strength: dict | None = None                         # safety factor against [material.strength]
    histories: list = field(default_factory=list)        # per accepted step (a crack's force-displacement curve)
    sweeps: list | None = None                           # staggered sweeps per solved step (terms' sub-problems)
    wall_time_s: float = 0.0

    @property
    def u(self) -> fem.Function:
        return self.model.u

    def summary(self) -> dict:
        r = self.report
        heat = {} if self.model.temperature is None else {"max_temperature": max_value(self.model.temperature)}
        inside = self.model.probe_materials() if self.probes else {}
        return {**header("static", self.model.scene, self.model.mesh.comm, self.model.dofs, self.wall_time_s),
            **heat,
            "mesh": self.model.loaded.info,
            "converged": r.converged,
            "newton_iterations": r.newton_iterations,
            "load_steps": r.load_steps,
            "load_reached": r.load_reached,
            **({"peak_load_factor": r.peak_load_factor} if r.peak_load_factor is not None else {}),
            **({"arc_length_from": r.arc_length_from} if r.arc_length_from is not None else {}),
            "residual_norm": r.residual_norm,
            "energy": self.energy,
            "max_displacement": self.max_displacement,
            "assembly_time_s": r.assembly_time,
            "linear_solver": r.linear_solver,
            "krylov_iterations": r.krylov_iterations,
            "preconditioner_builds": r.preconditioner_builds,
            "element": ("P2-P1 (Taylor-Hood) " if self.model.scene.discretization.formulation == "mixed" else
                        f"P{self.model.scene.discretization.degree} ") + self.model.mesh.topology.cell_name(),
            "quadrature_degree": self.model.scene.discretization.quadrature,
            "formulation": self.model.scene.discretization.formulation,
            "physics": self.model.physics,
            **({"friction_unsettled": r.friction_unsettled} if r.friction_unsettled else {}),
            "warnings": self.model.warnings + ([UNSETTLED.format(n=len(r.friction_unsettled))]
                                               if r.friction_unsettled else []),
            "materials": self.model.materials_report(),
            "probes": {n: {"point": self.model.scene.output.probes[n], "displacement": v,
                           "material": inside.get(n), **self.probe_stresses.get(n, {})}
                       for n, v in self.probes.items()},
            **self.reactions,
            **({"unstable_rejected": r.unstable_rejected} if r.unstable_rejected else {}),
            **stability_checked(self.model, r),
            **self.term_reports,
            **({"strength": self.strength} if self.strength else {}),
            **{k: v for h in self.histories for k, v in h.summary().items()},
            **({"staggered_sweeps": int(sum(self.sweeps))} if self.sweeps else {}),
            "message": r.message,
        }


def max_norm(f: fem.Function) -> float:
    """Largest nodal vector length of f over all ranks."""
    bs = f.function_space.dofmap.index_map_bs
    n = f.function_space.dofmap.index_map.size_local
    vals = f.x.array[: n * bs].reshape(-1, bs)
    local = float(np.linalg.norm(vals, axis=1).max()) if len(vals) else 0.0
    return f.function_space.mesh.comm.allreduce(local, op=MPI.MAX)


UNCHECKED_MIXED = ("volume control in the mixed formulation: states are accepted without the stability check (its "
                   "inertia test needs the displacement's own energy; the mixed energy is a saddle in (u, p)); "
                   "results.json stability_checked = false")


UNSETTLED = ("friction: in {n} load steps the lagged normal forces still moved after the last re-lag (8 a step; "
             "results.json friction_unsettled lists their load factors): smaller load steps (solver.max_step) settle")


UNCOUNTED = ("volume control: states were accepted without the stability check (the tangent's inertia is counted by "
             "MUMPS's LDL^T only; this solve used LU or an iterative solver)")


def stability_checked(model: Model, report: snes.SolveReport | None = None) -> dict:
    """results.json `stability_checked` of a model with scalar unknowns (volume control): whether only stable
    states were accepted (solvers/constrained_stability.py), and why not; {} without scalars. Before the solve
    (no `report`) the mixed formulation is known to go unchecked: it gets its warning then."""
    if not model.global_scalars():
        return {}
    if model.scene.discretization.formulation == "mixed":
        why = UNCHECKED_MIXED
    elif report is None or report.stability_checked:
        return {} if report is None else {"stability_checked": True}
    else:
        why = UNCOUNTED
    if why not in model.warnings:
        model.warnings.append(why)
    return {"stability_checked": False, "stability_unchecked_why": why}


def load_path(model: Model) -> tuple:
    """(set_load, stops) of the continuation. Without any [[load]] history: lambda scales every load and
    prescribed displacement. With one (load, then unload: plasticity): lambda is pseudo-time over the
    histories' span, each load follows its own history (a load without one is held at 1, as in the
    dynamic analysis), prescribed displacements still scale with lambda, and every history corner is a
    step end."""
    timed = [t for t in model.loads if t.history]
    held = [(i, f) for i, f in enumerate(model.scene.fix) if f.history]   # supports following their own history
    for t in model.loads:                     # every load's own factor at 1, as a new model has it (the rest-
        t.factor.value = 1.0                  # state checks see the full loads): none is left where an earlier
    if not timed and not held:                # run of this model put it; set_load moves them along the histories
        if not model.terms.lagged:
            return model.load.set, ()

        def set_factor(lam: float) -> None:   # lagged terms (contact) move and lag with pseudo-time lambda
            model.load.set(lam)
            model.terms.lag(lam)
        return set_factor, ()
    histories = [t.history for t in timed] + [f.history for _, f in held]
    t_end = max(h[-1][0] for h in histories)

    def set_load(lam: float) -> None:
        model.load.set(lam)
        model.load.constant.value = 1.0
        for i, fix in held:
            factor = piecewise_linear(fix.history, lam * t_end)
            for c in fix.components:
                model.load.set_one((i, c), factor)
        model.terms.update(lam * t_end)
    stops = tuple(sorted({p[0] / t_end for h in histories for p in h if 0 < p[0] < t_end}))
    return set_load, stops


def min_load_step(model: Model) -> float:
    """The smallest load increment: max_cutbacks halvings of the first. Near a limit point (plastic collapse, a
    balloon's pressure maximum) steps of shrinking size keep passing, each success resetting the count of
    cut-backs in a row, so without a floor the limit is approached for ever (measured: 25,000 steps in 2
    minutes on a perfectly plastic bar). A plastic solid has the floor always, an elastic one once its path
    has flattened (continuation's limit_step)."""
    solver = model.scene.solver
    return 1.0 / solver.steps / 2**solver.max_cutbacks


def chain(first: Callable[[float], None], then: Callable[[float], None] | None) -> Callable[[float], None]:
    """One on_step hook calling `first`, then `then` (if any)."""
    def both(lam: float) -> None:
        first(lam)
        if then is not None:
            then(lam)
    return both


def load_span(model: Model) -> float:
    """The pseudo-time at load factor 1: the span of the [[load]] histories (time = lambda x span, as
    `load_path` moves the loads), 1 without any history (time = the load factor)."""
    spans = [t.history[-1][0] for t in model.loads if t.history] + [f.history[-1][0] for f in model.scene.fix
                                                                     if f.history]
    return max(spans) if spans else 1.0


def solve_static(scene: Scene, material=None, model: Model | None = None,
                 on_step: Callable[[float], None] | None = None, answers: bool = True) -> StaticResult:
    """Solve the scene's equilibrium. `material` may be a Material or a user's psi(F) function.
    `on_step(lam)` is called after each accepted load step (the state committed): the static analysis
    writes its load path there. Raises InputError for bad input; a failed solve is returned with
    report.converged False: at a limit point with the answer numbers of the last accepted state, else none.
    `answers=False` leaves the answer numbers (stresses, reactions, probes) out: a design loop needs the state
    only (half of a small model's solve)."""
    t0 = time.perf_counter()
    histories, sweeps = [], None
    model = model or build_model(scene, material)
    model.probes                                           # located now: a probe outside the mesh is bad input
    stability_checked(model)                               # said before the solve, where it is not checked
    model.terms.start(model.state)     # a new solve: each term's start (a solid with time at rest, the notches)
    if model.temperature is not None:
        solve_temperature(model)
    set_load, stops = load_path(model)
    problem = model.problem(set_load)
    linear_kind = "direct" if scene.discretization.formulation == "mixed" else scene.solver.linear
    r0 = rigid_motion.rest_residual(model)
    if rigid_motion.nothing_to_solve(model, r0):
        model.unknown.x.array[:] = 0.0
        report = snes.SolveReport(True, 1.0, 0, r0.norm(), linear_solver="none",
                                  message="converged: nothing to solve (no loads, no prescribed displacement): u = 0")
    else:
        rigid_motion.check_supports_hold_loads(model, r0)
        if scene.solver.control == "arc-length":
            report = follow_path(model, r0.norm(), linear_kind, on_step or (lambda lam: None))
        else:
            auto = scene.solver.control == "auto" and arc_length_fits(model) is None
            ends = PathEnds(model) if auto else None
            driver = model.staggered_driver(problem, scene.solver.petsc, linear_kind, stability=stable_path(model))
            histories = step_histories(model, load_span(model))
            for h in histories:
                on_step = chain(h, on_step)
            later = on_step or (lambda lam: None)
            on_step = chain(ends, on_step) if auto else on_step
            try:
                report = continuation.solve(problem, scene.solver.petsc, steps=scene.solver.steps,
                                            max_cutbacks=scene.solver.max_cutbacks, linear_kind=linear_kind,
                                            near_nullspace=lambda: rigid_body_modes(model.V), stops=stops,
                                            min_step=min_load_step(model) if model.solid.is_plastic else 0.0,
                                            limit_step=1.0 if auto else min_load_step(model),
                                            on_step=on_step or (lambda lam: None),
                                            max_step=scene.solver.max_step, driver=driver)
            finally:
                if driver is not None:
                    sweeps = driver.sweeps
                    driver.destroy()
            if auto:
                report = then_arc_length(model, report, ends, r0.norm(), linear_kind, later)
    r0.destroy()
    if not report.converged and (why := model.solid.near_limit(model.context, report.message)):
        report.message = f"{report.message}; {why}"
    result = StaticResult(model, report, histories=histories, sweeps=sweeps)
    if answers and report.converged:
        post_process(result)
    elif answers and limit_point(result):     # the loads back at the last accepted factor (the state was rolled back there)
        set_load(report.load_reached)
        post_process(result)
    result.wall_time_s = time.perf_counter() - t0
    return result


GAVE_UP = "no convergence: "        # how continuation._gave_up starts the message of a continuation that stopped


def limit_point(result: StaticResult) -> bool:
    """The continuation stopped past an accepted step because its cut-backs reached their floor (or an arc-
    length path ended short of full load)."""
    r = result.report
    went = r.load_reached > 0 or (r.peak_load_factor or 0.0) > 0    # arc length may end at load factor <= 0
    return not r.converged and went and r.message.startswith((GAVE_UP, LIMIT))


def post_process(result: StaticResult) -> None:
    """The answer numbers of the model's current state (energy, largest displacement, probes, recovered
    stresses, reactions) into `result`. solve_static calls it at full load, or for a continuation stopped
    at a limit point with its loads set back to the last accepted factor (so writing the outputs never solves)."""
    model, report = result.model, result.report
    model.sync_displacement()
    if caveat := model.solid.energy_caveat:           # its step energy is no stored energy: not reported
        if caveat not in model.warnings:
            model.warnings.append(caveat)
    elif model.energy is not None and model.solid.energy(model.context) is not None:   # von Mises: none
        result.energy = model.mesh.comm.allreduce(fem.assemble_scalar(model.compiled("energy")), op=MPI.SUM) \
            + sum(t.energy_value(model.unknown.vector) for t in model.terms.arrays)
    result.max_displacement = max_norm(model.u)
    result.term_reports = model.terms.report(model.unknown.vector)
    result.probes = model.probes.evaluate(model.u)
    result.quantities = Quantities(model)
    result.probe_stresses = attempt(model.warnings, "stress recovery at the probes",
                                    lambda: result.quantities.at_probes(model.probes), {})
    result.strength = attempt(model.warnings, "strength", lambda: result.quantities.strength(), None)
    result.reactions = attempt(model.warnings, "reactions", lambda: reaction_report(model, noise=report.residual_norm), {})
    if model.temperature is not None:
        for name, value in model.probes.evaluate(model.temperature).items():
            result.probe_stresses.setdefault(name, {})["temperature"] = value[0]
