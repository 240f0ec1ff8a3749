"""One heat solve, steady or a backward-Euler step, through the one SNES driver: linear conduction and
convection take one linear solve (`ksponly`, the factor kept while dt stays the same); radiation takes
Newton. A step is accepted only if SNES converged, the temperature is finite and a linear step's residual
after the solve fell by acceptance.LINEAR_DROP (acceptance.why_rejected); otherwise the State rolls back."""
from __future__ import annotations

import math

from mpi4py import MPI

from fem_forms.physics.thermal import HeatForms
from fem_forms.solvers import acceptance, snes
from fem_forms.solvers.time_stepping import StepOutcome
from fem_forms.state import State

# "auto" takes GMRES + GAMG above this many temperature dofs. Measured at 97,336 P1 dofs (a cube, load 3,
# benchmarks/thermal_step.md): the first step 6.8 s with MUMPS (factor) against 1.3 s (multigrid set-up),
# later steps 0.215 s against 0.210 s: LU does not pay back at this size (2 ranks: 14.3 s against 2.1 s, then
# 0.55 s against 0.52 s); the scalar problem's fill makes LU dear sooner than elasticity's
ITERATIVE_ABOVE_DOFS = 20_000
# linear heat: one Krylov/LU solve per step, tangent and factor kept across steps of equal dt
LINEAR = {"snes_type": "ksponly", "snes_lag_jacobian": -2, "snes_lag_jacobian_persists": True,
          "snes_lag_preconditioner": -2, "snes_lag_preconditioner_persists": True}


class HeatSolver:
    """Solves HeatForms for its temperature; `state` holds the temperature and its last committed value."""

    def __init__(self, forms: HeatForms, state: State, options: dict | None = None, linear_kind: str = "auto",
                 commit: bool = True):
        self.forms, self.state, self.commit = forms, state, commit
        opts = dict(LINEAR) if forms.linear else {}
        opts.update(options or {})
        problem = snes.NonlinearProblem(forms.T, forms.residual, forms.jacobian, forms.bcs, state=state)
        if linear_kind == "auto":
            space = forms.T.function_space
            linear_kind = "iterative" if space.dofmap.index_map.size_global > ITERATIVE_ABOVE_DOFS else "direct"
        self.driver = snes.SNESDriver(problem, opts, linear_kind=linear_kind, prefix="fem_forms_heat_")
        self.iterations = 0
        self._dt = None

    def solve(self, t: float = 0.0, dt: float | None = None) -> StepOutcome:
        """The temperature at time t (after a step dt from the committed one, or steady with dt None);
        committed when accepted (unless the caller commits: a staggered step), rolled back otherwise."""
        self.forms.set_time(t, dt)
        if self.forms.linear and dt != self._dt and self._dt is not None:
            self.driver.rebuild()            # a new dt changes the operator: assemble and factor anew
        self._dt = dt
        record = self.driver.solve_step(check_start=False)   # T^4 and k grad T stay finite at any start
        self.iterations += max(record.iterations, 1)
        # a linear step: its residual after the one solve (the monitor's, at the state) fell by LINEAR_DROP;
        # Newton (radiation) steps: SNES's own tests and a finite temperature
        linear_check = self.forms.linear and len(record.residuals) >= 2
        why = acceptance.why_rejected(self.driver, record, rtol=acceptance.LINEAR_DROP if linear_check else None,
                                      reassemble=False)
        if why is None:
            if self.commit:
                self.state.commit()
            return StepOutcome(True, record.iterations)
        self.state.rollback()
        self.driver.rebuild()
        return StepOutcome(False, record.iterations, why=why)

    def step(self, t: float, dt: float) -> StepOutcome:
        """The time-stepping protocol: advance the committed temperature from t to t + dt."""
        return self.solve(t + dt, dt)

    def undo(self) -> None:                       # heat steps are not adaptive: nothing to undo
        pass


def max_value(f) -> float:
    """Largest owned nodal value of a scalar Function over all ranks."""
    n = f.function_space.dofmap.index_map.size_local
    local = float(f.x.array[:n].max()) if n else -math.inf
    return f.function_space.mesh.comm.allreduce(local, op=MPI.MAX)


def min_value(f) -> float:
    n = f.function_space.dofmap.index_map.size_local
    local = float(f.x.array[:n].min()) if n else math.inf
    return f.function_space.mesh.comm.allreduce(local, op=MPI.MIN)
