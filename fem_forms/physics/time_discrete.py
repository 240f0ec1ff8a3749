"""The Newmark family in one place: generalized-alpha (Chung-Hulbert) with Newmark average acceleration
as its special case alpha_m = alpha_f = 0, beta = 1/4, gamma = 1/2, and backward Euler (first order, the
scheme IPC codes use for its damping of the barrier's stiff vibrations) as beta = gamma = 1 with the old
acceleration weighted w_a = 0.

With the old values u_n, v_n, a_n (the State's committed fields) and the unknown u = u_{n+1}:
    a(u) = (u - u~) / (beta dt^2),  u~ = u_n + dt v_n + dt^2 (1/2 - beta) w_a a_n
    v(u) = v_n + dt ((1 - gamma) w_a a_n + gamma a(u))
(backward Euler: v = (u - u_n) / dt, a = (v - v_n) / dt.)
and the balance is written at the generalized midpoints
    x_m = (1 - alpha_m) x_{n+1} + alpha_m x_n  (accelerations),  x_f = (1 - alpha_f) x_{n+1} + alpha_f x_n.
Every coefficient is a fem.Constant: a new dt or rho_inf compiles nothing. The same formulas are given
for UFL (the forms) and for arrays (the update after a converged step)."""
from __future__ import annotations

from dolfinx import fem
import numpy as np
from petsc4py import PETSc


def chung_hulbert(rho_inf: float) -> tuple[float, float, float, float, float]:
    """(alpha_m, alpha_f, beta, gamma, w_a) of generalized-alpha with spectral radius rho_inf at infinity:
    second order, unconditionally stable, high frequencies damped to rho_inf."""
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    gamma = 0.5 - am + af
    return am, af, 0.25 * (1 - am + af) ** 2, gamma, 1.0


NEWMARK_AVERAGE = (0.0, 0.0, 0.25, 0.5, 1.0)
BACKWARD_EULER = (0.0, 0.0, 1.0, 1.0, 0.0)


class TimeDiscrete:
    """Constants dt, beta, gamma, alpha_m, alpha_f, w_a and time t_{n+1}, with the old fields they act on."""

    def __init__(self, mesh, u_old: fem.Function, v_old: fem.Function, a_old: fem.Function,
                 params: tuple = NEWMARK_AVERAGE, dt: float = 1.0):
        c = lambda x: fem.Constant(mesh, PETSc.ScalarType(x))      # noqa: E731
        self.dt, self.time = c(dt), c(0.0)
        self.alpha_m, self.alpha_f, self.beta, self.gamma, self.a_weight = (c(p) for p in params)
        self.u_old, self.v_old, self.a_old = u_old, v_old, a_old

    def _constants(self) -> tuple:
        return self.alpha_m, self.alpha_f, self.beta, self.gamma, self.a_weight

    def set_params(self, params: tuple) -> None:
        for k, p in zip(self._constants(), params):
            k.value = p

    @property
    def params(self) -> tuple[float, float, float, float, float]:
        """(alpha_m, alpha_f, beta, gamma, w_a)."""
        return tuple(float(k.value) for k in self._constants())

    # -- UFL ---------------------------------------------------------------------------------------
    def predictor(self):
        """u~ = u_n + dt v_n + dt^2 (1/2 - beta) w_a a_n."""
        dt = self.dt
        return self.u_old + dt * self.v_old + dt * dt * (0.5 - self.beta) * self.a_weight * self.a_old

    def acceleration(self, u):
        return (u - self.predictor()) / (self.beta * self.dt * self.dt)

    def velocity(self, u):
        return self.v_old + self.dt * ((1 - self.gamma) * self.a_weight * self.a_old
                                       + self.gamma * self.acceleration(u))

    def mid_f(self, new, old):
        return (1 - self.alpha_f) * new + self.alpha_f * old

    # -- arrays ------------------------------------------------------------------------------------
    def update(self, u: np.ndarray, u0: np.ndarray, v0: np.ndarray, a0: np.ndarray) -> tuple:
        """(v_{n+1}, a_{n+1}) from the converged u_{n+1} and the old values (same formulas as above)."""
        am, af, beta, gamma, wa = self.params
        dt = float(self.dt.value)
        a = (u - u0 - dt * v0 - dt * dt * (0.5 - beta) * wa * a0) / (beta * dt * dt)
        v = v0 + dt * ((1 - gamma) * wa * a0 + gamma * a)
        return v, a
