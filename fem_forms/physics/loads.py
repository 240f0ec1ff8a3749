"""External loads as terms, one class per [[load]] type, each registered under its type name.

All values are Constants scaled by the load factor (all loads together, static continuation) and by
each load's own `factor` Constant (its time history in dynamics; 1 otherwise): a new g, traction,
pressure or time compiles nothing.
Dead loads (gravity per rest volume, traction per rest area) have an energy, minus their work; follower
pressure acts on the deformed surface and has none: it adds its virtual work to the residual.
"""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from petsc4py import PETSc
import ufl

from fem_forms.physics.terms import Context, Load as LoadTerm, register_load
from fem_forms.scene import Load


@register_load("gravity")
class Gravity(LoadTerm):
    """Weight: -lambda int rho g . u dX (rho the density field), over the body or a gmsh volume group."""
    name = "gravity"

    def declare(self, spec: Load, mesh: dmesh.Mesh) -> None:
        self.g = fem.Constant(mesh, PETSc.ScalarType(tuple(spec.g)))

    def set_spec(self, spec: Load) -> None:
        self.g.value = spec.g

    def energy(self, ctx: Context) -> ufl.Form:
        weight = ctx.parameters.density * ufl.dot(self.g, ctx.u)
        if self.index in ctx.body_regions:                 # restricted to a gmsh volume group
            work = sum(ctx.volume(weight, k) for k in ctx.body_regions[self.index])
        else:
            work = ctx.volume(weight)
        return -ctx.load.constant * self.factor * work


@register_load("traction")
class Traction(LoadTerm):
    """Dead traction per rest area on the selected facets: -lambda int T . u dA."""
    name = "traction"

    def declare(self, spec: Load, mesh: dmesh.Mesh) -> None:
        self.value = fem.Constant(mesh, PETSc.ScalarType(tuple(spec.value)))

    def set_spec(self, spec: Load) -> None:
        self.value.value = spec.value

    def energy(self, ctx: Context) -> ufl.Form:
        return -ctx.load.constant * self.factor * sum(ctx.area(ufl.dot(self.value, ctx.u), k)
                                                      for k in ctx.regions[self.index])


@register_load("pressure")
class Pressure(LoadTerm):
    """Follower pressure p on the deformed surface, pushing against its outward normal:
    virtual work lambda int p J F^-T N . v dA."""
    name = "pressure"

    def declare(self, spec: Load, mesh: dmesh.Mesh) -> None:
        self.value = fem.Constant(mesh, PETSc.ScalarType(spec.pressure))

    def set_spec(self, spec: Load) -> None:
        self.value.value = spec.pressure

    def virtual_work(self, ctx: Context, v) -> ufl.Form:
        F = ctx.F
        traction = self.value * ufl.det(F) * ufl.inv(F).T * ctx.rest_area_vector()
        return ctx.load.constant * self.factor * sum(ufl.dot(traction, v) * ctx.ds(k) for k in ctx.regions[self.index])
