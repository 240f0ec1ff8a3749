"""Heat in a dynamic run, staggered per time step: a backward-Euler heat step from t to t + dt, then the
motion step with the new temperature's thermal strain. Both are committed together when the motion step is
accepted, and both roll back (the State holds T with u, v, a) when either fails.

Damping heat: the source of a heat step is the viscous power of the last accepted motion step at its mean
velocity (u_{n+1} - u_n) / dt, the velocity with which the implicit schemes' energy account measures the
dissipation (the end-of-step velocities of the trapezoidal rule ring in the overdamped high modes: a source
taken from them heated a test bar 2.4 times too much). The heat so lags the motion by one step and their
totals agree (tests/system/test_thermal_dynamic.py)."""
from __future__ import annotations

from dataclasses import replace

from dolfinx import fem

from fem_forms.physics.damping import ViscousDamping
from fem_forms.physics.thermal import HeatForms
from fem_forms.solvers.thermal_step import HeatSolver
from fem_forms.solvers.time_stepping import StepOutcome


def heat_solver(system, mean_velocity: fem.Function) -> HeatSolver:
    """The heat step of a dynamic system whose model carries a temperature (damping heat from the
    `mean_velocity` of the last motion step)."""
    scene, model, state = system.scene, system.model, system.state
    th = scene.thermal
    model.temperature.x.array[:] = th.initial_temperature
    old = state.old
    source = None
    if th.damping_heat:
        d = scene.damping
        viscous = ViscousDamping(model.mesh, d.shear, d.bulk, mean_velocity,
                                 scene.small_strain)
        source = viscous.power_density(replace(model.context, u=old["unknown"]))
    forms = HeatForms(th, scene.materials, model.loaded, model.temperature, old["temperature"], True,
                      scene.discretization.quadrature, source, model.context.materials)
    return HeatSolver(forms, state, commit=False)


class StaggeredStepper:
    """Heat step, then the motion step (the time-stepping protocol: step(t, dt), undo())."""

    def __init__(self, system, motion):
        self.motion, self.state = motion, system.state
        self.u = system.state.fields["unknown"]
        self.mean_velocity = fem.Function(self.u.function_space, name="mean_velocity")
        self._previous = self.mean_velocity.x.array.copy()
        self.heat = heat_solver(system, self.mean_velocity)

    def step(self, t: float, dt: float) -> StepOutcome:
        out = self.heat.step(t, dt)                     # rolls the State back itself when rejected
        if not out.accepted:
            return StepOutcome(False, out.iterations, why=f"heat step: {out.why}")
        moved = self.motion.step(t, dt)                 # rolls back u, v, a and T when rejected
        moved.iterations += out.iterations
        if moved.accepted:
            w = self.mean_velocity.x.array
            self._previous[:] = w
            w[:] = (self.u.x.array - self.state.old["unknown"].x.array) / dt
        return moved

    def undo(self) -> None:
        self.motion.undo()
        self.mean_velocity.x.array[:] = self._previous
