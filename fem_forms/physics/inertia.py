"""Inertia: the kinetic energy 1/2 int rho |u_dot|^2 dX, whose second variation is the mass form.
Modal analysis assembles its mass matrix from it; transient dynamics will add its time-discrete form."""
from __future__ import annotations

import ufl

from fem_forms.physics.terms import Context, Term


class Inertia(Term):
    """Mass of the solid with the context's density field (cellwise, so carving changes it)."""
    name = "inertia"

    def mass(self, ctx: Context, a, v) -> ufl.Form:
        """int rho a . v dX: the mass form with trial `a` and test `v` (or a load form for a fixed a)."""
        return ctx.volume(ctx.parameters.density * ufl.inner(a, v))

    def kinetic_energy(self, ctx: Context, velocity) -> ufl.Form:
        """1/2 int rho |velocity|^2 dX."""
        return 0.5 * ctx.volume(ctx.parameters.density * ufl.inner(velocity, velocity))
