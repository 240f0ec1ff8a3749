"""The explicit central-difference step (velocity Verlet form) with the HRZ-lumped mass: one residual
assembly, no linear solve. Its stable step is estimated before the run and a larger dt refused."""
from __future__ import annotations

import math

from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc

from fem_forms.analyses.dynamic.system import DynamicSystem
from fem_forms.errors import InputError
from fem_forms.physics.time_discrete import NEWMARK_AVERAGE
from fem_forms.solvers.time_stepping import StepOutcome, largest_eigenvalue

# the power iteration approaches omega_max from below and the tangent stiffens as the body deforms
STABLE_SAFETY = 0.9


def inverse_mass(system: DynamicSystem) -> PETSc.Vec:
    inv = system.lumped.copy()
    inv.reciprocal()
    inv.array[system.constrained] = 0.0
    return inv


def stable_step(system: DynamicSystem) -> tuple[float, float]:
    """(dt_stable, omega_max): 0.9 x 2 / omega_max (sqrt(1 + zeta^2) - zeta), omega_max^2 the largest
    eigenvalue of M^-1 K at the current state by power iteration, zeta the Rayleigh damping ratio there."""
    m = system.model
    a = m.compiled("jacobian")
    K = fpetsc.assemble_matrix(a, bcs=m.bcs)
    K.assemble()
    inv = inverse_mass(system)
    lam = largest_eigenvalue(lambda x, y: K.mult(x, y), inv)
    K.destroy()
    inv.destroy()
    omega = math.sqrt(max(lam, 1e-300))
    d = system.scene.damping
    zeta = d.alpha / (2 * omega) + d.beta * omega / 2
    return STABLE_SAFETY * 2.0 / omega * (math.sqrt(1 + zeta * zeta) - zeta), omega


def check_stable(system: DynamicSystem, dt: float) -> tuple[float, float]:
    """Refuse a dt above the stable step estimate (InputError naming it)."""
    dt_stable, omega = stable_step(system)
    if dt > dt_stable:
        raise InputError(f"dynamic.dt = {dt:g}: above the central-difference stable step estimate "
                         f"{dt_stable:.4g} s (0.9 x 2 / omega_max, omega_max = {omega:.4g} rad/s by power "
                         f"iteration); use dt <= {dt_stable:.3g} or an implicit scheme")
    return dt_stable, omega


class ExplicitStepper:
    """v_h = v_n + dt/2 a_n, u_{n+1} = u_n + dt v_h, a_{n+1} = M^-1 (f_ext - f_int(u_{n+1}) - C v_h),
    v_{n+1} = v_h + dt/2 a_{n+1} (damping lags half a step)."""

    def __init__(self, system: DynamicSystem, released: set):
        self.s, self.released = system, released
        system.model.only_ufl_terms("explicit dynamics")
        system.td.set_params(NEWMARK_AVERAGE)          # loads at t_{n+1} (alpha_f = 0)
        self.L = system.explicit_form()
        self.b = fpetsc.create_vector(self.L)
        self.inv = inverse_mass(system)
        self.n = self.inv.local_size

    @property
    def motion(self) -> "ExplicitStepper":
        """The stepper of the motion itself (a staggered heat step wraps one)."""
        return self

    def acceleration(self) -> None:
        """a = -M^-1 R(u) with R = f_int - f_ext + C v_h (zero at supported dofs)."""
        b = self.b
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, self.L)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        a = self.s.a
        a.x.array[: self.n] = -b.array * self.inv.array
        a.x.scatter_forward()

    def step(self, t: float, dt: float) -> StepOutcome:
        s = self.s
        old = s.state.old
        s.set_load_time(t + dt, t, self.released)
        vh = old["velocity"].x.array + 0.5 * dt * old["acceleration"].x.array
        s.v_h.x.array[:] = vh
        s.u.x.array[:] = old["unknown"].x.array + dt * vh
        self.acceleration()
        s.v.x.array[:] = vh + 0.5 * dt * s.a.x.array
        if not np.all(np.isfinite(s.u.x.array)):
            s.state.rollback()
            return StepOutcome(False, 0, "NaN or Inf (unstable explicit step)")
        return StepOutcome(True, 0)

    def undo(self) -> None:
        self.s.state.rollback()
