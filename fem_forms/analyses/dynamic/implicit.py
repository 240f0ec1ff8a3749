"""The implicit step (Newmark average acceleration or generalized-alpha): one SNES solve of the
time-discrete balance through the one driver, accepted only after the driver's independent checks; a
lumped mass joins the solve as an array term (HRZ is not a UFL form)."""
from __future__ import annotations

import math

from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.analyses.dynamic.system import DynamicSystem
from fem_forms.physics.array_term import ArrayTerm
from fem_forms.solvers import acceptance, linear, snes
from fem_forms.solvers.retry import RetryPolicy
from fem_forms.solvers.time_stepping import StepOutcome


class LumpedInertia(ArrayTerm):
    """D ((1 - alpha_m) a(x) + alpha_m a_n + alpha v_f(x)) added to the residual, its derivative to the
    tangent's diagonal, and the inertia's incremental potential to the energy (alpha = 0 only)."""
    name, role, keys = "lumped inertia", "inertia", ("dynamic", "mass")

    def __init__(self, system: DynamicSystem):
        self.s = system
        self.D = system.lumped
        self.n = self.D.local_size
        self.alpha = system.scene.damping.alpha

    def _parts(self, x):
        td, old, n = self.s.td, self.s.state.old, self.n
        am, af, beta, gamma, wa = td.params
        dt = float(td.dt.value)
        u0, v0, a0 = (old[k].x.array[:n] for k in ("unknown", "velocity", "acceleration"))
        pred = u0 + dt * v0 + dt * dt * (0.5 - beta) * wa * a0
        acc = (x.array - pred) / (beta * dt * dt)
        vel = v0 + dt * ((1 - gamma) * wa * a0 + gamma * acc)
        return am, af, beta, gamma, dt, pred, acc, vel, v0, a0

    def add_gradient(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        am, af, beta, gamma, dt, pred, acc, vel, v0, a0 = self._parts(x)
        force = (1 - am) * acc + am * a0 + self.alpha * ((1 - af) * vel + af * v0)
        b.array[:] += self.D.array * force

    def add_hessian(self, x: PETSc.Vec, A: PETSc.Mat, constrained: np.ndarray) -> None:
        am, af, beta, gamma, _ = self.s.td.params
        dt = float(self.s.td.dt.value)
        d = self.D.copy()
        d.scale((1 - am) / (beta * dt * dt) + self.alpha * (1 - af) * gamma / (beta * dt))
        d.array[self.s.constrained] = 0.0        # the owned ones among `constrained`, as local indices
        A.setDiagonal(d, addv=PETSc.InsertMode.ADD_VALUES)
        d.destroy()

    def energy_value(self, x: PETSc.Vec) -> float:
        am, af, beta, gamma, dt, pred, acc, vel, v0, a0 = self._parts(x)
        local = float(np.sum(self.D.array * ((1 - am) * 0.5 * (x.array - pred) ** 2 / (beta * dt * dt)
                                             + am * a0 * x.array)))
        return self.D.comm.tompi4py().allreduce(local)


class ImplicitStepper:
    """Advance (u, v, a) by one step; the State holds the new values uncommitted until the caller
    commits them (or rolls back)."""

    # refresh the kept tangent and its LU factor when the stale ones cost more Krylov iterations per Newton
    # iteration or more Newton iterations per step than this
    KRYLOV_PER_NEWTON = 15
    NEWTON_PER_STEP = 5

    def __init__(self, system: DynamicSystem, released: set, options: dict | None = None):
        self.s = system
        self.released = released
        m = system.model
        lumped = [LumpedInertia(system)] if system.lumped is not None else []
        self.problem = snes.NonlinearProblem(m.u, system.residual, system.jacobian, m.bcs,
                                             energy=system.energy, inadmissible=m.inadmissible,
                                             state=system.state, array_terms=lumped + m.terms.arrays)
        # Full Newton first: the incremental potential is dominated by its M / (beta dt^2) part, so near
        # the answer its change drowns in round-off, the energy line search stalls and the polish has to
        # finish (measured on the benchmark beam: 2-5 Newton iterations per step, 2 with full Newton and
        # the same answer). The energy line search retries a failed step before dt is cut.
        self.linear_kind = linear_kind = system.scene.solver.linear \
            if system.scene.discretization.formulation != "mixed" else "direct"
        self.iterative = linear.choose(linear_kind, m.dofs) == "iterative"
        self.user_options = dict(options or {})
        # contact: the barrier's and friction's stiffness change with every iteration (a node sticking or
        # slipping, touching or not): a kept tangent lacks them, and full Newton steps cycle between stick and
        # slip (a block sticking on a slope: 49 iterations a step, most in failed 50-iteration attempts; 11
        # with the energy line search first, full Newton as the retry where round-off stalls the line search)
        self.lagged = bool(m.terms.lagged)
        self.searches = ("bt", "basic") if self.lagged and system.energy is not None else ("basic", "bt")
        self.staggered = bool(m.sub_problems())    # each step an alternate minimization with the terms' fields
        kwargs = dict(reuse_factor=not self.iterative, keep_preconditioner=True)
        self.driver = m.staggered_driver(self.problem, self._options(), linear_kind, **kwargs) or \
            snes.SNESDriver(self.problem, self._options(), linear_kind,
                            near_nullspace=lambda: linear.rigid_body_modes(m.V), **kwargs)
        # the continuation's ladder, and the other line search (where the scene chose none) before dt is cut
        other = self.searches if self.driver.E is not None and "snes_linesearch_type" not in self.user_options \
            else None
        self.retry = RetryPolicy(self.driver, linear_kind, line_searches=other, on_direct=self._on_direct,
                                 plain_start=self._plain_start)
        self.predict = True                        # the next attempt starts from the predictor (else from u_n)
        self.may_unlag = "snes_lag_jacobian" not in self.user_options
        self.fresh = True                          # the next step starts from a freshly built tangent
        self.dt_factored = None
        self.last_why = ""
        self.krylov_iterations = self.preconditioner_builds = 0
        self.u_scale = 0.0                         # the largest displacement seen (the error estimate's scale)
        self.watch_events = system.scene.contact is not None and system.scene.dynamic.refine_events > 0
        if self.watch_events:
            m.terms.watch_events()

    @property
    def motion(self) -> "ImplicitStepper":
        """The stepper of the motion itself (a staggered heat step wraps one)."""
        return self

    def _options(self) -> dict:
        """Direct: the tangent is kept with its factor (modified Newton: the residual is fresh, so the
        answer is the same): one more Newton iteration per step but no tangent assembly, 1.4-1.6x less per
        step on the benchmark beam (benchmarks/dynamic_steps.md); refreshed by the rule in _refresh().
        Iterative (CG + GAMG; GMRES where damping leaves no energy): a fresh tangent at every Newton
        iteration, the multigrid hierarchy kept across iterations and steps by the driver's cost rule."""
        opts = {"snes_linesearch_type": self.searches[0]}
        if not self.iterative and not self.lagged and not self.staggered:   # their tangents change
            opts.update({"snes_lag_preconditioner": 100, "snes_lag_preconditioner_persists": True,
                         "snes_lag_jacobian": 100, "snes_lag_jacobian_persists": True})
        opts.update(self.user_options)
        return opts

    def summary(self) -> dict:
        """The linear solver used and its totals over the run (results.json)."""
        return {"linear_solver": self.driver.linear_kind, "krylov_iterations": self.krylov_iterations,
                "preconditioner_builds": self.preconditioner_builds}

    def step(self, t: float, dt: float) -> StepOutcome:
        s, drv = self.s, self.driver
        if self.dt_factored is None or abs(dt - self.dt_factored) > 1e-6 * dt:
            if self.dt_factored is not None:
                drv.rebuild()                  # a new dt: the kept factor is stale (not the last
                self.fresh = True                  # step's round-off difference from dt)
            self.dt_factored = dt
        s.td.dt.value = dt
        s.td.time.value = t + dt
        s.set_load_time(t + dt, t, self.released)
        s.model.terms.lag(t + dt)                  # lagged terms (obstacles) where they are at the step's end
        s.model.solid.update(t + dt)               # a solid with time (viscoelastic): the step's dt
        rec, why = self._solve(dt)
        newton = krylov = 0                        # the attempts' before the last
        while why is not None:
            same_dt = self.retry.same_size(rec, why, t + dt)     # LU, the other line search, ...
            drv.rebuild()                                      # fresh solver state after a failure
            if not same_dt:
                break
            newton, krylov = newton + rec.iterations, krylov + rec.krylov_iterations
            rec, why = self._solve(dt)
        rec.iterations += newton                   # the step's record counts every attempt
        rec.krylov_iterations += krylov
        if why is not None:
            self.last_why = why
            self.fresh = True
            return StepOutcome(False, rec.iterations, why)
        self.retry.accepted()
        self._refresh(rec)
        old = s.state.old
        v, a = s.td.update(s.u.x.array, old["unknown"].x.array, old["velocity"].x.array,
                           old["acceleration"].x.array)
        s.v.x.array[:] = v
        s.a.x.array[:] = a
        # the error estimate (two reductions over ranks) only where the march uses it; contact's events where it
        # refines them
        return StepOutcome(True, rec.iterations,
                           error=self.error_estimate(dt) if s.scene.dynamic.adaptive else math.nan,
                           event=s.model.terms.step_event(s.u.vector) if self.watch_events else "")

    def _plain_start(self) -> None:
        """The predictor itself left the domain (a NaN before the first iteration: a contact's chatter left a
        velocity that inverts cells within dt): the retry starts from the last accepted displacement."""
        self.predict = False

    def _on_direct(self) -> None:
        """CG failed on a fresh hierarchy (an indefinite tangent) and LU replaced it (the retry policy): the tangent
        and its factor kept across steps from now on, as a direct scene's are."""
        self.iterative = False
        drv = self.driver
        drv.reuse_factor = True
        drv.user_options = self._options()

    def _refresh(self, rec) -> None:
        """A fresh tangent and factor for the next step when the kept ones cost too many iterations. If
        even a fresh tangent needs that many (large motion of a soft part: measured 6.8 per step at
        dt 1e-2 on a silicone beam), assemble the tangent at every Newton iteration from then on and keep
        only the factor (60 instead of 136 Newton iterations there, 2 factorisations instead of 20)."""
        drv = self.driver
        if self.iterative:
            return                                 # the driver keeps or rebuilds the hierarchy by cost
        kept_tangent = drv.user_options.get("snes_lag_jacobian") != 1
        slow = kept_tangent and rec.iterations > self.NEWTON_PER_STEP
        if slow or rec.krylov_iterations > self.KRYLOV_PER_NEWTON * max(rec.iterations, 1):
            if slow and self.fresh and self.may_unlag:
                drv.user_options["snes_lag_jacobian"] = 1
            drv.rebuild()
            self.fresh = True
        else:
            self.fresh = False

    def _solve(self, dt: float):
        """One SNES solve from the constant-velocity predictor (or the last state: _plain_start, _lower_start);
        (record, why rejected or None). A rejected solve leaves the State rolled back (the caller rebuilds the
        driver)."""
        s, drv = self.s, self.driver
        old = s.state.old
        u = s.u
        # constant-velocity predictor: a_n carries the undamped high modes Newmark keeps (an impulsive
        # load or release), and the constant-acceleration guess u_n + dt v_n + dt^2/2 a_n then inverted
        # cells (measured: a released silicone beam, Q2, 30 of 43 steps rejected; this way 0 of 20)
        move, self.predict = (dt if self.predict else 0.0) * old["velocity"].x.array, True
        u.x.array[:] = old["unknown"].x.array + move
        if drv.arrays.caps:                        # a contact's step filter: the guess stays intersection-free
            self._filtered_predictor(old["unknown"], move)
        u.x.scatter_forward()
        if drv.arrays.caps and drv.E is not None and s.model.mesh.comm.allreduce(bool(move.any()), op=MPI.LOR):
            self._lower_start(old["unknown"])
        # supports hold still in dynamics (the scene refuses moving ones): no start check needed, and the
        # residual at the predictor is SNES's first residual (no separate assembly)
        rec = drv.solve_step(check_start=False)
        self.krylov_iterations += rec.krylov_iterations
        self.preconditioner_builds += rec.preconditioner_builds
        # u is exactly SNES's last iterate, and SNES's last residual norm was assembled there by the driver's
        # callback: a re-assembly gives the same number (1-2 ms per step at 5k dofs), so the residual test
        # takes SNES's (it still catches a stop on step length with a large residual); its scale is the
        # step's first residual (no load scale in dynamics: loads follow time, and may be none)
        why = acceptance.why_rejected(drv, rec, reassemble=False)
        if why is not None:
            s.state.rollback()
        return rec, why

    def _lower_start(self, last) -> None:
        """In contact, start where the step's energy is lower: at the predictor or at the last accepted state. The
        predictor can carry contact nodes toward the obstacle (a rocking hemisphere's chatter under Newmark), where
        the barrier makes Newton crawl: measured on the hemisphere, 0.1 s with Newmark, 1,100 Newton iterations
        from the predictor, 341 from the last state; a block sliding down a slope needs the predictor (653 against
        1,154). Two energy evaluations a step."""
        u = self.s.u
        at_predictor = self.driver.energy(u.vector)
        kept = u.x.array.copy()
        u.x.array[:] = last.x.array
        u.x.scatter_forward()
        if self.driver.energy(u.vector) >= at_predictor:
            u.x.array[:] = kept
            u.x.scatter_forward()

    def _filtered_predictor(self, start, step) -> None:
        """u = u_n + s dt v_n with s the largest safe fraction of that move (1 without a contact in the way)."""
        self.s.u.x.array[:] = start.x.array + self.driver.arrays.safe_share(start.vector, step) * step

    def error_estimate(self, dt: float) -> float:
        """Zienkiewicz-Xie local error dt^2 |beta - 1/6| |a_{n+1} - a_n|, relative to the largest
        displacement so far (max norm over all ranks)."""
        s = self.s
        beta = s.td.params[2]
        comm = s.model.mesh.comm
        e = comm.allreduce(float(np.abs(s.a.x.array - s.state.old["acceleration"].x.array).max(initial=0)),
                           op=MPI.MAX)
        scale = comm.allreduce(float(np.abs(s.u.x.array).max(initial=0)), op=MPI.MAX)
        self.u_scale = max(self.u_scale, scale)
        return dt * dt * abs(beta - 1 / 6) * e / max(self.u_scale, 1e-300) if self.u_scale > 0 else 0.0

    def undo(self) -> None:
        self.s.state.rollback()

