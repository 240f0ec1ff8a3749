"""Inertia: the kinetic energy 1/2 int rho |u_dot|^2 dX, whose second variation is the mass form.
Modal analysis assembles its mass matrix from it; transient dynamics adds its time-discrete form, an
energy in the unknown u_{n+1} (so the implicit step keeps an energy line search).
Both integrate on the mass's own exact rule (2 x element degree, positive weights: physics/quadrature.py),
whatever rule the energy uses, so the mass matrix is positive definite even at a low energy rule."""
from __future__ import annotations

import ufl

from fem_forms.physics.quadrature import mass_metadata
from fem_forms.physics.terms import Context, Term
from fem_forms.physics.time_discrete import TimeDiscrete


def mass_measure(ctx: Context, v) -> ufl.Measure:
    """ctx.dx on the mass rule of v's element degree."""
    cell = ctx.mesh.topology.cell_name()
    return ctx.dx.reconstruct(metadata=mass_metadata(cell, v.ufl_element().degree()))


class Inertia(Term):
    """Mass of the solid with the context's density field (cellwise, so carving changes it)."""
    name = "inertia"
    role = "inertia"
    keys = ("material", "rho")

    def mass(self, ctx: Context, a, v) -> ufl.Form:
        """int rho a . v dX: the mass form with trial `a` and test `v` (or a load form for a fixed a)."""
        return ctx.volume(ctx.parameters.density * ufl.inner(a, v), dx=mass_measure(ctx, v))


class DiscreteInertia(Inertia):
    """The generalized-alpha inertia force (1 - alpha_m) M a(u) + alpha_m M a_n as the gradient in u of
    (1 - alpha_m) / (2 beta dt^2) int rho |u - u~|^2 dX + alpha_m int rho a_n . u dX
    (consistent mass; a lumped mass is added to the assembled system by the time stepper)."""
    name = "inertia"

    def __init__(self, td: TimeDiscrete, unknown):
        self.td, self.unknown = td, unknown

    def energy(self, ctx: Context) -> ufl.Form:
        td, u = self.td, self.unknown
        d = u - td.predictor()
        rho = ctx.parameters.density
        return ctx.volume(rho * ((1 - td.alpha_m) / (2 * td.beta * td.dt * td.dt) * ufl.inner(d, d)
                                 + td.alpha_m * ufl.inner(td.a_old, u)), dx=mass_measure(ctx, u))
