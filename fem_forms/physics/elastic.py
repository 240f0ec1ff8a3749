"""The elastic energy of a material: int psi(F) dX (or the mixed u-p energy when a pressure field exists)."""
from __future__ import annotations

import ufl

from fem_forms.materials import LinearElastic, Material, mixed_energy
from fem_forms.materials.constants import set_parameters
from fem_forms.physics.terms import Context, Solid
from fem_forms.physics.thermoelastic import thermoelastic_density


class ElasticEnergy(Solid):
    """Stored energy of the solid; the material's parameters are Constants (see bind_constants)."""

    def __init__(self, material: Material, model_name: str = "user"):
        self.material = material
        self.name = f"elastic ({model_name})"

    def set_values(self, scene) -> None:
        set_parameters(self.material, scene.material.material)

    def pk1(self, ctx: Context):
        """P = d psi / d F (pressure field and thermal strain included) by ufl.diff."""
        F = ufl.variable(ctx.F)
        return ufl.diff(self.density_at(ctx, F), F)

    def density(self, ctx: Context):
        """psi per rest volume at the context's F (mixed energy with the context's pressure)."""
        return self.density_at(ctx, ctx.F)

    def density_at(self, ctx: Context, F):
        """psi per rest volume at F, with the context's pressure field and thermal strain where they exist
        (stresses for output differentiate this with respect to F)."""
        if ctx.pressure is not None:
            def psi(G):
                return mixed_energy(self.material, G, ctx.pressure)
        else:
            psi = self.material.psi
        return thermoelastic_density(psi, F, ctx, isinstance(self.material, LinearElastic))

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
