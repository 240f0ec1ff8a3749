"""The elastic energy of a material: int psi(F) dX (or the mixed u-p energy when a pressure field exists)."""
from __future__ import annotations

import ufl

from fem_forms.materials import Material, mixed_energy
from fem_forms.physics.terms import Context, Term


class ElasticEnergy(Term):
    """Stored energy of the solid; the material's parameters are Constants (see bind_constants)."""

    def __init__(self, material: Material, model_name: str = "user"):
        self.material = material
        self.name = f"elastic ({model_name})"

    def density(self, ctx: Context):
        """psi per rest volume at the context's F (mixed energy with the context's pressure)."""
        if ctx.pressure is not None:
            return mixed_energy(self.material, ctx.F, ctx.pressure)
        return self.material.psi(ctx.F)

    def energy(self, ctx: Context) -> ufl.Form:
        return ctx.volume(self.density(ctx))

    def first_variation(self, ctx: Context, v) -> ufl.Form:
        """d/du of the energy in the direction v, written as P : Grad v dX with P = d psi / d F by ufl.diff
        (no pressure field). The same derivative as ufl.derivative of `energy`, in a form whose tangent
        FFCx evaluates faster when F is not I + grad u (the inverse problem: measured 13 %)."""
        F = ufl.variable(ctx.F)
        P = ufl.diff(self.material.psi(F), F)
        grad_v = ufl.grad(v) if ctx.rest_map is None else ufl.grad(v) * ufl.inv(ctx.rest_map)
        return ctx.volume(ufl.inner(P, grad_v))
