"""A dynamic run: the initial state (rest or static equilibrium, initial velocity, consistent initial
acceleration), the march with the scene's scheme, per-step probes and energies, frames and checkpoints."""
from __future__ import annotations

from contextlib import nullcontext
from dataclasses import dataclass, field
import time
from pathlib import Path

from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc

from fem_forms.analyses.dynamic import checkpoint
from fem_forms.analyses.dynamic.energy import EnergyAccount
from fem_forms.analyses.dynamic.explicit import ExplicitStepper, check_stable
from fem_forms.analyses.dynamic.thermal import StaggeredStepper
from fem_forms.analyses.dynamic.implicit import ImplicitStepper
from fem_forms.analyses.dynamic.output import append_rows, write_csvs
from fem_forms.analyses.dynamic.reactions import DynamicReactions
from fem_forms.analyses.dynamic.system import DynamicSystem, build_system
from fem_forms.errors import InputError, SolveError
from fem_forms.output import probes
from fem_forms.output.load_path import records
from fem_forms.output.quantities import tensor_expressions
from fem_forms.output.summary import header
from fem_forms.output.strength import StrengthWatch, has_strength
from fem_forms.scene import Scene
from fem_forms.solvers import continuation
from fem_forms.solvers.linear import make_ksp
from fem_forms.solvers.time_stepping import MarchReport, history_corners, march


@dataclass
class DynamicResult:
    system: DynamicSystem
    report: MarchReport
    energy: EnergyAccount
    probe_rows: list = field(default_factory=list)     # [t, (ux, uy, uz, vx, vy, vz) per probe..., T per probe...]
    dt_stable: float | None = None
    wall_time_s: float = 0.0
    solver: dict = field(default_factory=dict)        # the implicit step's linear solver and its totals
    failure: str | None = None                        # why the march gave up (results.json converged false)
    strength: dict | None = None                      # the lowest safety factor over the accepted steps
    last_accepted: tuple | None = None                # (t, step, next dt) at the last accepted, committed step
    counts_accepted: tuple | None = None              # (rejected, refined, Newton iterations) at that step
    probe_columns: list | None = None                 # probes.csv's header, found once
    keepers: tuple = ()                               # step hooks whose history a checkpoint carries (saved/restore)
    started: float = field(default_factory=time.perf_counter)   # this process's start of the run
    wall_before: float = 0.0                          # wall time of the run before a --restart (its checkpoint's)

    def elapsed(self) -> float:
        """The run's wall time so far, from t = 0 across restarts."""
        return self.wall_before + time.perf_counter() - self.started

    def summary(self) -> dict:
        s, r = self.system, self.report
        names = list(s.scene.output.probes)
        last = self.probe_rows[-1] if self.probe_rows else None
        return {
            **header("dynamic", s.scene, s.model.mesh.comm, s.model.dofs, self.wall_time_s),
            "converged": self.failure is None, "message": self.failure or "reached the end time",
            "scheme": s.scene.dynamic.scheme, "mass": s.scene.dynamic.mass,
            "materials": s.model.materials_report(),
            "steps": r.steps, "time_reached": r.time_reached,
            "dt_min": r.dt_min if r.steps else None, "dt_max": r.dt_max if r.steps else None,
            "rejected_steps": r.rejected, "refined_steps": r.refined, "newton_iterations": r.newton_iterations,
            "energy_balance_error": self.energy.balance_error(self.energy.round_off_floor()),
            "energy_imbalance": self.energy.imbalance(),
            "energy_final": {c: self.energy.now.value(c) for c in self.energy.columns()},
            "dt_stable": self.dt_stable, **self.solver,
            "physics": s.model.physics + ["inertia"] + _damping_names(s.scene) + _heat_names(s.scene),
            "probes": {n: {"point": s.scene.output.probes[n], "displacement": list(last[1 + 6 * i: 4 + 6 * i]),
                           "velocity": list(last[4 + 6 * i: 7 + 6 * i])} for i, n in enumerate(names)}
            if last else {},
            **({"strength": self.strength} if self.strength else {}),
        }


def _heat_names(scene: Scene) -> list:
    th = scene.thermal
    return [] if th is None else ["heat (backward Euler)"] + (["damping heat"] if th.damping_heat else [])


def _damping_names(scene: Scene) -> list:
    d = scene.damping
    return (["damping (Rayleigh)"] if d.alpha or d.beta else []) + (["damping (viscous)"] if d.shear or d.bulk else [])


def initial_velocity(system: DynamicSystem) -> None:
    spec = system.scene.dynamic.velocity
    if isinstance(spec, dict):
        w, x0 = np.array(spec["angular"]), np.array(spec["about"])
        system.v.interpolate(lambda x: np.cross(w, (x - x0[:, None]).T).T)
    else:
        system.v.interpolate(lambda x: np.tile(np.array(spec)[:, None], (1, x.shape[1])))
    system.v.x.array[system.constrained] = 0.0           # supports hold
    system.v.x.scatter_forward()


def initial_static(system: DynamicSystem) -> None:
    """Equilibrium under the loads listed in [dynamic] initial_loads (released at t = 0) together with the
    other loads at their t = 0 values (gravity kept on: the body starts sagged, pushed, then let go)."""
    held = set(system.scene.dynamic.initial_loads)
    for term in system.loads:
        term.factor.value = 1.0 if term.index in held else term.factor_at(0.0)
    m = system.model
    m.terms.lag(0.0)                               # lagged terms at t = 0, lagged from the start state
    problem = m.problem(m.load.set, state=system.state)
    # friction lagged once here, as the time steps that follow lag it (once a step, never re-lagged). Re-lagged at
    # this equilibrium, the rocking toy demo rocked with a period of 0.744 s against 0.836 s lagged once (0.839 s for
    # rolling without slip) and 28 % more Newton iterations: measured, the cause not yet understood (a friction
    # prestress in the contact patch that the time steps' lag does not keep is one candidate)
    problem.relag = False
    rep = continuation.solve(problem, system.scene.solver.petsc, steps=system.scene.solver.steps,
                             max_cutbacks=system.scene.solver.max_cutbacks, linear_kind="direct")
    if not rep.converged:
        raise SolveError(f"initial static state: {rep.message}")
    m.load.set(1.0)


def initial_acceleration(system: DynamicSystem, released: set, settle: bool = False) -> bool:
    """M a0 = F(0) - f_int(u0) - C v0 (lumped: a division; consistent: CG on M). `settle`: the run starts where
    the scene put the part (no static start), so a barrier already pushing is first settled (Term.settle).
    Returns whether it was: the part starts in contact, undeformed."""
    system.set_load_time(0.0, 0.0, released)
    system.v_h.x.array[:] = system.v.x.array
    L = system.explicit_form()
    b = fpetsc.assemble_vector(L)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    b.scale(-1.0)
    settled = False
    system.model.terms.lag(0.0)
    fpetsc.set_bc(b, system.model.bcs, scale=0.0)      # what the supports carry is no load on a barrier
    for term in system.model.terms.arrays:             # an array term's force at the start (a barrier pushing)
        push = b.duplicate()
        push.set(0.0)
        term.add_gradient(system.u.vector, push)
        push.assemble()
        fpetsc.set_bc(push, system.model.bcs, scale=0.0)
        if settle and (share := settling_share(b, push)) is not None:
            push.scale(term.settle(share))
            settled = True
        b.axpy(-1.0, push)
        push.destroy()
    a = system.a
    if system.lumped is not None:
        inv = system.lumped.copy()
        inv.reciprocal()
        inv.array[system.constrained] = 0.0
        a.vector.array[:] = b.array * inv.array
        inv.destroy()
    else:
        M = fpetsc.assemble_matrix(system.mass, bcs=system.model.bcs)
        M.assemble()
        ksp = make_ksp(M, "mass", "fem_forms_initial_acceleration_",
                       {"ksp_rtol": 1e-12, "ksp_atol": 1e-300, "ksp_max_it": 2000})
        ksp.solve(b, a.vector)
        ksp.destroy()
        M.destroy()
    a.x.scatter_forward()
    b.destroy()
    return settled


NO_NET_PUSH = 1e-8     # a net push below this share of the pushes' sizes is round-off: none to settle


def settling_share(force: PETSc.Vec, push: PETSc.Vec) -> float | None:
    """s with the net force of s x push (a barrier's gradient) best balancing the net of `force` (the loads less
    the elastic forces) on the body: s = F.P / |P|^2 of the node sums; None when nothing pushes. Collective."""
    comm = force.comm.tompi4py()
    F, P = (comm.allreduce(v.array.reshape(-1, 3).sum(axis=0)) for v in (force, push))
    pushes = comm.allreduce(float(np.linalg.norm(push.array.reshape(-1, 3), axis=1).sum()))
    size = float(P @ P)
    if size <= (NO_NET_PUSH * pushes) ** 2:       # pushes that cancel (self-contact alone): nothing net to settle
        return None
    return float(F @ P) / size


def probe_row(points: probes.ProbeSet, system: DynamicSystem, t: float,
              reactions: DynamicReactions | None = None) -> list:
    """[t, then (ux, uy, uz, vx, vy, vz) at each probe, NAME_T at each with heat, FIX_Fx, FIX_Fy, FIX_Fz per
    support (`reactions`), then the terms' records (an obstacle's force, active points and the smallest gap; a
    cavity's pressure and volume; the crack's numbers)] (points located once, before the march). Collective."""
    row = [t]
    if points.names:
        u, v = points.evaluate(system.u), points.evaluate(system.v)
        for n in points.names:
            row += list(u[n]) + list(v[n])
        if system.model.temperature is not None:       # NAME_T columns after every probe's motion
            T = points.evaluate(system.model.temperature)
            row += [T[n][0] for n in points.names]
    if reactions is not None:
        row += reactions(t).ravel().tolist()
    return row + list(records(system.model).values())


def start_system(scene: Scene) -> tuple:
    """(system, stepper, released loads, stable dt of an explicit scheme or None): the system at its initial
    state (at rest or in static equilibrium, initial velocity, consistent acceleration), committed."""
    dyn = scene.dynamic
    for m in scene.materials:
        if m.rho <= 0:
            raise InputError(f"{m.key}.rho: dynamic analysis needs a positive density")
    system = build_system(scene)
    system.model.terms.start(system.state)   # each term's start: a solid with time at rest, the notches, t = 0
    if system.model.temperature is not None:
        system.model.temperature.x.array[:] = scene.thermal.initial_temperature
    released = set(dyn.initial_loads) if dyn.initial == "static" else set()
    system.model.probes                               # located now: a point outside the mesh is bad input
    if dyn.initial == "static":
        initial_static(system)
    initial_velocity(system)
    if initial_acceleration(system, released, settle=dyn.initial == "rest") and dyn.scheme != "backward-euler":
        system.start_warnings.append(
            f"the part starts in contact, undeformed: {dyn.scheme} keeps the contact's first shock as ringing at the "
            "step's frequency (slow steps, rejected steps); initial = \"static\" rests it on what holds it first, "
            "scheme = \"backward-euler\" damps the ringing")
    system.state.commit()
    dt_stable = None
    if dyn.scheme == "central-difference":
        dt_stable, _ = check_stable(system, dyn.dt)
        stepper = ExplicitStepper(system, released)
    else:
        stepper = ImplicitStepper(system, released, scene.solver.petsc)
    if system.model.temperature is not None:
        stepper = StaggeredStepper(system, stepper)
    return system, stepper, released, dt_stable


def solve_dynamic(scene: Scene, out: Path | None = None, restart: Path | None = None,
                  on_frame=None, on_step=None, interrupts=None, on_result=None, keepers: tuple = ()) -> DynamicResult:
    """March the scene's [dynamic] span; `on_frame(system, t, step)` every output_every steps (and at
    t = 0); `on_step(system, t)` at t = 0 and after every accepted step (the state then committed);
    checkpoints into out/checkpoint every checkpoint_every steps; `restart` continues from one. With
    `interrupts` (output/interrupts.py) each accepted step is booked whole before a signal stops the run;
    `on_result(result)` receives the result as soon as it exists (what an interrupted run writes from). `keepers`:
    step hooks with a history of their own (the impact recorder: `saved()` arrays, `restore(arrays)`), carried by
    the checkpoint so that a restarted run's account covers it from t = 0."""
    t0 = time.perf_counter()
    dyn = scene.dynamic
    system, stepper, released, dt_stable = start_system(scene)
    points = system.model.probes
    reactions = DynamicReactions(system, released) if scene.fix else None     # probes.csv's support forces every step
    account = EnergyAccount(system, released)
    result = DynamicResult(system, MarchReport(), account, dt_stable=dt_stable, keepers=tuple(keepers), started=t0)
    if on_result is not None:
        on_result(result)
    critical = interrupts.critical if interrupts is not None else nullcontext
    watch = StrengthWatch(system.model, tensor_expressions(system.model)["cauchy_stress"]) \
        if has_strength(scene) else None
    t_start, step0, dt = 0.0, 0, dyn.dt
    if restart is not None:
        t_start, step0, dt = checkpoint.load(restart, result)
        result.last_accepted = (t_start, step0, dt)
        system.model.terms.resume(t_start)         # the next step starts at the checkpoint's time
    else:
        result.last_accepted = (0.0, 0, dt)
        account.start(0.0)
        result.probe_rows.append(probe_row(points, system, 0.0, reactions))
        if watch is not None:
            watch.step(0.0)
        if on_frame:
            on_frame(system, 0.0, 0)
        if on_step:
            on_step(system, 0.0)
    if out is not None:                        # the tables begin now and grow by a row per accepted step
        write_csvs(out, result, system.model.mesh.comm)

    state = {"t": t_start}

    def on_accept(t: float, h: float, step: int) -> None:
        with critical():                       # a step is booked whole, or not at all
            account.advance(state["t"], t)
            system.state.commit()
            state["t"] = t
            result.probe_rows.append(probe_row(points, system, t, reactions))
            result.last_accepted = (t, step, result.report.next_dt)     # where a restart goes on from
            r = result.report                  # the counts at this step (an interrupt undoes a later attempt's)
            result.counts_accepted = (r.rejected, r.refined, r.newton_iterations)
            if watch is not None:
                watch.step(t)
            if on_frame and step % dyn.output_every == 0:
                on_frame(system, t, step)
            if on_step:
                on_step(system, t)
            if out is not None:
                append_rows(out, result, system.model.mesh.comm)
            if out is not None and dyn.checkpoint_every and step % dyn.checkpoint_every == 0:
                checkpoint.save(out / "checkpoint", result, t, step, result.report.next_dt)
        if interrupts is not None:
            interrupts.check()                 # several ranks: all stop here together

    try:
        march(stepper, t_start, dyn.duration, dyn.dt, on_accept, first_dt=dt,
              adaptive=dyn.adaptive and dyn.scheme != "central-difference", tolerance=dyn.tolerance,
              max_cutbacks=scene.solver.max_cutbacks, step0=step0, report=result.report,
              dt_max=10 * dyn.dt if dyn.adaptive else dyn.dt, stops=history_corners(*_histories(scene)),
              refine_events=dyn.refine_events if scene.contact is not None else 0)
    except SolveError as e:                  # gave up: the steps so far are still written (exit 3 after)
        result.failure = str(e)
    if isinstance(stepper.motion, ImplicitStepper):           # the staggered heat step wraps the motion
        result.solver = stepper.motion.summary()
    result.wall_time_s = result.elapsed()
    result.strength = watch.lowest if watch is not None else None
    return result


def _histories(scene: Scene) -> list:
    """Every time history of the scene: loads' and prescribed temperatures'."""
    thermal = scene.thermal
    return [ld.history for ld in scene.load] + ([b.history for b in thermal.boundary] if thermal else [])
