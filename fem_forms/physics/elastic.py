"""The elastic energy of a material: int psi(F) dX (or the mixed u-p energy when a pressure field exists)."""
from __future__ import annotations

import ufl

from fem_forms.materials import Material, mixed_energy
from fem_forms.materials.hyperelastic import is_small_strain
from fem_forms.materials.constants import set_parameters
from fem_forms.materials.stresses import first_piola_kirchhoff
from fem_forms.physics.admissibility import SmallestValue
from fem_forms.physics.terms import Context, Solid, register_solid

LOCKING_NEAR = 0.9          # a locking measure above this, when a solve stops short, is why
LOCKED = ("the chains lock: (I1_bar - 3) / Jm reached {:.4g} (Gent's energy is infinite at 1, no state exists "
          "beyond; raise Jm or lower the load)")
from fem_forms.physics.thermoelastic import thermoelastic_density


class ElasticEnergy(Solid):
    """Stored energy of the solid; the material's parameters are Constants (see bind_constants)."""

    def __init__(self, material: Material, model_name: str = "user", binding=None):
        self.material = material
        self.binding = binding                 # several materials: their DG0 parameter fields
        self.name = f"elastic ({model_name})"
        self._locking = None

    def _locking_measure(self, F):
        """The materials' `locking(F)` measure (Gent: (I1_bar - 3) / Jm, 1 where the chains lock) as one UFL
        expression: a part's on its own cells where models of several kinds share the body (fibres aside), or
        None when no material has one."""
        parts = getattr(self.material, "parts", None)
        if parts is None:
            base = getattr(self.material, "base", self.material)
            return base.locking(F) if hasattr(base, "locking") else None
        own = [p.indicator * getattr(p.material, "base", p.material).locking(F) for p in parts
               if hasattr(getattr(p.material, "base", p.material), "locking")]
        return sum(own[1:], own[0]) if own else None

    def _locking_reached(self, ctx: Context) -> float | None:
        """The largest value of the locking measure over the quadrature points (all ranks), or None."""
        if self._locking is None:                              # compiled once, on first use (False: none)
            measure = self._locking_measure(ctx.F)
            self._locking = False if measure is None else SmallestValue(1 - measure, ctx.mesh,
                                                                        ctx.dx.metadata()["quadrature_degree"])
        return None if self._locking is False else 1 - self._locking()

    def outside_theory(self, ctx: Context) -> str | None:
        """A state at or past the locking limit has no finite energy: rejected."""
        reached = self._locking_reached(ctx)
        return None if reached is None or reached < 1 else LOCKED.format(reached)

    def near_limit(self, ctx: Context, said: str = "") -> str | None:
        """Near the locking limit (LOCKING_NEAR of it) when a solve stops short: why (unless `said` says it)."""
        reached = self._locking_reached(ctx)
        if reached is None or not reached > LOCKING_NEAR or LOCKED.split(":")[0] in said:
            return None
        return LOCKED.format(reached)

    def set_values(self, scene) -> None:
        base = getattr(self.material, "base", self.material)       # without its fibres
        if self.binding is not None:
            self.binding.update(scene.materials)
        else:
            set_parameters(base, scene.material.material)
        if base is not self.material:
            self.material.update(scene.materials)

    def prepare(self, ctx: Context) -> None:
        """A material with its own pk1 (the chain rule through its invariants) gives the residual by hand,
        so that the tangent differentiates that P once instead of psi twice; not in the mixed formulation,
        whose residual has the pressure equation too."""
        self.residual_by_hand = hasattr(self.material, "pk1") and ctx.pressure is None

    def pk1(self, ctx: Context):
        """P = d psi / d F (pressure field and thermal strain included) by ufl.diff, or by the material's
        own pk1 where it has one and neither a pressure field nor a temperature enters psi."""
        if self._plain(ctx):
            return first_piola_kirchhoff(self.material, ctx.F)
        F = ufl.variable(ctx.F)
        return ufl.diff(self.density_at(ctx, F), F)

    @staticmethod
    def _plain(ctx: Context) -> bool:
        """psi(F) is the material's own: no pressure field, no thermal strain or modulus factor."""
        return (ctx.pressure is None and ctx.thermal_strain is None
                and not {"modulus_factor", "stiffness_factor", "damage"} & set(ctx.extra))

    def density(self, ctx: Context):
        """psi per rest volume at the context's F (mixed energy with the context's pressure)."""
        return self.density_at(ctx, ctx.F)

    def density_at(self, ctx: Context, F):
        """psi per rest volume at F, with the context's pressure field and thermal strain where they exist
        (stresses for output differentiate this with respect to F; models of several kinds: their sum
        weighted by each one's cell indicator)."""
        parts = getattr(self.material, "parts", None)
        if parts is None:
            return self._density_of(self.material, ctx, F)
        terms = [p.indicator * self._density_of(p.material, ctx, F) for p in parts]
        return sum(terms[1:], terms[0])

    @staticmethod
    def _density_of(material: Material, ctx: Context, F):
        if ctx.pressure is not None:
            base = getattr(material, "base", material)            # fibres add to the mixed energy

            def psi(G):
                value = mixed_energy(base, G, ctx.pressure)
                return value if base is material else value + material.fiber_psi(G)
        else:
            psi = material.psi
        if "damage" in ctx.extra:                      # phase-field fracture: g(d) psi+ + psi-
            psi = ctx.extra["damage"].degraded(psi, is_small_strain(material), material)
        density = thermoelastic_density(psi, F, ctx, is_small_strain(material))
        factor = ctx.extra.get("stiffness_factor")      # a DG0 field scaling psi per cell (a carved fill)
        return density if factor is None else factor * density

    def energy(self, ctx: Context) -> ufl.Form:
        """int psi dX. Models of several kinds: each over its own cells (a kernel per model: 1.05x one
        material's assembly, against 1.22-1.30x for every psi weighted by indicators everywhere), unless a
        body load has cell tags of its own (one form takes one subdomain_data): then weighted by indicators."""
        parts = getattr(self.material, "parts", None)
        if parts is None or ctx.dx_regions is not None:
            return ctx.volume(self.density(ctx))
        dx = ufl.Measure("dx", domain=ctx.mesh, subdomain_data=ctx.materials.tags(), metadata=ctx.dx.metadata())
        forms = [ctx.volume(self._density_of(p.material, ctx, ctx.F), dx=dx(tuple(i + 1 for i in p.members)))
                 for p in parts]
        return sum(forms[1:], forms[0])

    def first_variation(self, ctx: Context, v) -> ufl.Form:
        """d/du of the energy in the direction v (the displacement part of the test function), written as
        P : Grad v dX with P = pk1 (thermal strain included; no pressure field). The same derivative as
        ufl.derivative of `energy`, in a form whose tangent FFCx evaluates faster when F is not I + grad u
        (the inverse problem: measured 13 %) and compiles faster for a material with its own pk1."""
        P = self.pk1(ctx)
        grad_v = ufl.grad(v) if ctx.rest_map is None else ufl.grad(v) * ufl.inv(ctx.rest_map)
        return ctx.volume(ufl.inner(P, grad_v))


@register_solid(priority=0)
def elastic_solid(scene, material, mesh, model_name: str, binding, regions) -> ElasticEnergy:
    """The elastic solid: what no other kind of solid claims."""
    return ElasticEnergy(material, model_name, binding)
