"""How a temperature field enters the elastic energy: thermal strain and a temperature-dependent modulus.

With th = alpha (T - T_ref) (ramped by the load factor in a static solve) the stored energy per rest volume
is, for the small-strain model, psi(eps - th I) (written as psi(F - th I): small_strain(F - th I) = eps - th I),
and for the hyperelastic models the multiplicative split F = F_e F_th, F_th = (1 + th) I:
J_th psi(F / (1 + th)) with J_th = (1 + th)^3. E(T) = E + dE/dT (T - T_ref) scales mu and lambda together
(nu fixed), so it multiplies psi by E(T) / E. Every value is a fem.Constant; T is a Function.
"""
from __future__ import annotations

from dolfinx import fem
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.materials.constants import parameter_value
from fem_forms.physics.thermal import temperature_space
from fem_forms.physics.terms import Context


def young_modulus(material) -> float:
    """E of a built-in model from its Lame parameters (Mooney-Rivlin: mu = 2 (C10 + C01))."""
    if hasattr(material, "C10"):
        mu = 2.0 * (parameter_value(material.C10) + parameter_value(material.C01))
    elif hasattr(material, "mu"):
        mu = parameter_value(material.mu)
    else:
        raise InputError("thermal.modulus_slope: needs a built-in material model (a user psi(F) has no E)")
    lmbda = parameter_value(material.lmbda)
    return mu * (3 * lmbda + 2 * mu) / (lmbda + mu)


def couple_temperature(scene, ctx: Context, material, degree: int) -> fem.Function:
    """The temperature Function of a coupled scene; sets ctx.thermal_strain = lambda alpha (T - T_ref)
    (lambda the load factor) and, when dE/dT != 0, ctx.extra["modulus_factor"] = E(T) / E."""
    th = scene.thermal
    mesh = ctx.mesh
    T = fem.Function(temperature_space(mesh, degree), name="temperature")
    T.x.array[:] = th.initial_temperature

    def const(v: float) -> fem.Constant:
        return fem.Constant(mesh, PETSc.ScalarType(v))

    dT = T - const(th.reference_temperature)
    ctx.thermal_strain = ctx.load.constant * const(th.expansion) * dT
    if th.modulus_slope != 0.0:
        ctx.extra["modulus_factor"] = 1.0 + const(th.modulus_slope / young_modulus(material)) * dT
    ctx.extra["temperature"] = T
    return T


def thermoelastic_density(psi, F, ctx: Context, small_strain: bool):
    """The stored energy per rest volume at F of a material psi(F) with the context's thermal strain and
    modulus factor (psi(F) itself when the temperature is not coupled)."""
    th = ctx.thermal_strain
    if th is None:
        value = psi(F)
    elif small_strain:
        value = psi(F - th * ufl.Identity(len(ctx.u)))
    else:
        value = (1 + th) ** 3 * psi(F / (1 + th))
    factor = ctx.extra.get("modulus_factor")
    return value if factor is None else factor * value
