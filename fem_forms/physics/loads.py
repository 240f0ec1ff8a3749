"""External loads as terms, one class per [[load]] type, each registered under its type name.

All values are Constants scaled by the load factor (all loads together, static continuation) and by
each load's own `factor` Constant (its time history in dynamics; 1 otherwise): a new g, traction,
pressure or time compiles nothing.
Dead loads (gravity per rest volume, traction per rest area) have an energy, minus their work; follower
pressure acts on the deformed surface and has none: it adds its virtual work to the residual.
"""
from __future__ import annotations

import ufl

from fem_forms.physics.terms import Context, Load as LoadTerm, register_load


@register_load("gravity")
class Gravity(LoadTerm):
    """Weight: -lambda int rho g . u dX (rho the density field), over the body or a gmsh volume group."""
    name = "gravity"
    value_key = "g"

    def energy(self, ctx: Context) -> ufl.Form:
        weight = ctx.parameters.density * ufl.dot(self.value, ctx.u)
        if self.index in ctx.body_regions:                 # restricted to a gmsh volume group
            work = sum(ctx.volume(weight, k) for k in ctx.body_regions[self.index])
        else:
            work = ctx.volume(weight)
        return -ctx.load.constant * self.factor * work


@register_load("traction")
class Traction(LoadTerm):
    """Dead traction per rest area on the selected facets: -lambda int T . u dA."""
    name = "traction"
    value_key = "value"

    def energy(self, ctx: Context) -> ufl.Form:
        return -ctx.load.constant * self.factor * sum(ctx.area(ufl.dot(self.value, ctx.u), k)
                                                      for k in ctx.regions[self.index])


@register_load("pressure")
class Pressure(LoadTerm):
    """Follower pressure p on the deformed surface, pushing against its outward normal:
    virtual work lambda int p J F^-T N . v dA."""
    name = "pressure"
    value_key = "pressure"

    def virtual_work(self, ctx: Context, v) -> ufl.Form:
        F = ctx.F
        traction = self.value * ufl.det(F) * ufl.inv(F).T * ctx.rest_area_vector()
        return ctx.load.constant * self.factor * sum(ufl.dot(traction, v) * ctx.ds(k) for k in ctx.regions[self.index])
