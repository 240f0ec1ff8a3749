"""How a temperature field enters the elastic energy: thermal strain and a temperature-dependent modulus.

With th = alpha (T - T_ref) (ramped by the load factor in a static solve) the stored energy per rest volume
is, for the small-strain model, psi(eps - th I) (written as psi(F - th I): small_strain(F - th I) = eps - th I),
and for the hyperelastic models the multiplicative split F = F_e F_th, F_th = (1 + th) I:
J_th psi(F / (1 + th)) with J_th = (1 + th)^3. E(T) = E + dE/dT (T - T_ref) scales mu and lambda together
(nu fixed), so it multiplies psi by E(T) / E. Every value is a fem.Constant; T is a Function.
"""
from __future__ import annotations

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.materials.constants import parameter_values
from fem_forms.physics.thermal import temperature_space, thermal_constant
from fem_forms.physics.terms import Context


def young_modulus(material) -> float:
    """E of a built-in model as the material states it (Mooney-Rivlin: mu = 2 (C10 + C01); anisotropic: its
    stiffest direction); with parameter fields (several materials) the largest over the cells of all ranks: a
    scale for barrier stiffness. InputError for a model that states none (a user's psi(F))."""
    comms = []

    def value(p):
        if isinstance(p, fem.Function):                 # a field over a distributed mesh: every rank's cells
            comms.append(p.function_space.mesh.comm)
        return parameter_values(p)
    stated = getattr(material, "young_modulus", None)   # a user's own material object may not state it
    E = stated(value) if stated is not None else None
    if E is None:
        raise InputError("thermal.modulus_slope: needs a built-in material model (a user psi(F) has no E)")
    local = float(np.max(E)) if np.size(E) else -np.inf
    return comms[0].allreduce(local, op=MPI.MAX) if comms else local


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
    alpha = [thermal_constant(m, th, "expansion") for m in scene.materials]
    expansion = const(alpha[0]) if len(alpha) == 1 else ctx.materials.field(alpha, "expansion")
    ctx.thermal_strain = ctx.load.constant * expansion * dT
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
