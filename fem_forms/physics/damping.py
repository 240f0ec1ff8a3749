"""Damping as virtual work of a velocity field (the seed's sigma = K eps + D eps_dot): no energy, a
dissipation. Each term is written on the Context and a `velocity` given as UFL (the scheme's v(u) in
an implicit step, a Function in an explicit one or in the energy accounting); its power is
virtual_work(ctx, velocity) >= 0.

- Rayleigh: C = alpha M + beta K0, K0 the elastic tangent at rest (second variation of the material's
  energy at u = 0, by ufl.derivative): exactly beta K for the linear material. beta K0 is not objective:
  it sees a rotation's velocity as strain rate (measured: a free neo-Hookean cube spun a quarter turn
  lost 98 % of its kinetic energy; a sagged silicone beam stopped swinging within one period).
- Viscous (Kelvin-Voigt): S_v = 2 eta_s dev(E_dot) + eta_b tr(E_dot) I with E_dot = sym(F^T grad v)
  the rate of Green strain, power S_v : E_dot; the linear material takes the small-strain limit
  E_dot = sym(grad v). With eta_s = beta mu and eta_b = beta kappa it is beta K for the linear material.
"""
from __future__ import annotations

from dataclasses import replace

from dolfinx import fem
from petsc4py import PETSc
import ufl
from ufl.algorithms import expand_derivatives

from fem_forms.physics.terms import Context, Solid, Term


class RayleighDamping(Term):
    """alpha int rho v . w dX + beta K0(v, w) (the mass part left out when a lumped mass carries it)."""
    name = "damping (Rayleigh)"
    role = "damping"
    keys = ("damping",)

    def __init__(self, mesh, alpha: float, beta: float, elastic: Solid, V: fem.FunctionSpace,
                 velocity, with_mass: bool = True):
        self.alpha = fem.Constant(mesh, PETSc.ScalarType(alpha))
        self.beta = fem.Constant(mesh, PETSc.ScalarType(beta))
        self.elastic, self.V, self.velocity, self.with_mass = elastic, V, velocity, with_mass
        self._rest = fem.Function(V, name="rest")                # u = 0: where K0 is taken

    def stiffness(self, ctx: Context, v, w) -> ufl.Form:
        """K0(v, w): the second variation of the elastic energy at rest, in directions v and w."""
        rest = self._rest
        trial = ufl.TrialFunction(self.V)
        energy = self.elastic.elastic_law_energy(replace(ctx, u=rest))   # a plastic solid: its elastic law
        k0 = ufl.derivative(ufl.derivative(energy, rest, w), rest, trial)
        return ufl.replace(expand_derivatives(k0), {trial: v})

    def virtual_work(self, ctx: Context, w) -> ufl.Form:
        form = self.beta * self.stiffness(ctx, self.velocity, w)
        if self.with_mass:
            form = form + self.alpha * ctx.volume(ctx.parameters.density * ufl.inner(self.velocity, w))
        return form


class ViscousDamping(Term):
    """Kelvin-Voigt stress from the strain rate with shear and bulk viscosities (Pa s)."""
    name = "damping (viscous)"
    role = "damping"
    keys = ("damping",)

    def __init__(self, mesh, shear: float, bulk: float, velocity, small_strain: bool):
        self.shear = fem.Constant(mesh, PETSc.ScalarType(shear))
        self.bulk = fem.Constant(mesh, PETSc.ScalarType(bulk))
        self.velocity, self.small_strain = velocity, small_strain

    def _rate(self, ctx: Context, v):
        if self.small_strain:
            return ufl.sym(ufl.grad(v))
        return ufl.sym(ctx.F.T * ufl.grad(v))

    def _stress(self, rate):
        return 2 * self.shear * ufl.dev(rate) + self.bulk * ufl.tr(rate) * ufl.Identity(len(self.velocity))

    def virtual_work(self, ctx: Context, w) -> ufl.Form:
        rate, virtual = self._rate(ctx, self.velocity), self._rate(ctx, w)
        return ctx.volume(ufl.inner(self._stress(rate), virtual))

    def power_density(self, ctx: Context):
        """Dissipated power per rest volume, S_v : E_dot >= 0 (the heat source of damping heat)."""
        rate = self._rate(ctx, self.velocity)
        return ufl.inner(self._stress(rate), rate)
