"""Stresses derived from an energy density with ufl.diff (never written by hand), and the mixed u-p energy."""
from __future__ import annotations

import copy

import ufl

from fem_forms.errors import InputError
from fem_forms.materials.hyperelastic import Material


def first_piola_kirchhoff(material: Material, F) -> ufl.core.expr.Expr:
    """P = d psi / d F: the material's own `pk1(F)` where it has one (the same derivative taken by the chain
    rule through its invariants, which compiles faster), else ufl.diff of psi."""
    if hasattr(material, "pk1"):
        return material.pk1(F)
    F = ufl.variable(F)
    return ufl.diff(material.psi(F), F)


def cauchy_stress(material: Material, F) -> ufl.core.expr.Expr:
    """sigma = P F^T / J."""
    return first_piola_kirchhoff(material, F) * F.T / ufl.det(F)


def von_mises(sigma) -> ufl.core.expr.Expr:
    """sqrt(3/2 s:s) with s the deviator of sigma."""
    s = ufl.dev(sigma)
    return ufl.sqrt(1.5 * ufl.inner(s, s))


def _smallest(value) -> float:
    """A parameter's value: a number, a Constant, or the smallest of a DG0 field over all ranks."""
    field = getattr(value, "x", None)
    if field is None:
        return float(getattr(value, "value", value))
    from mpi4py import MPI
    local = float(field.array.min()) if field.array.size else float("inf")
    return value.function_space.mesh.comm.allreduce(local, op=MPI.MIN)


def mixed_energy(material: Material, F, p):
    """Perturbed-Lagrangian energy of the u-p formulation: psi|_(k=0)(F) + p theta(F) - p^2/(2 k), k the
    modulus of the volumetric part (lambda, or the rubber models' bulk modulus). Stationary in p at
    p = k theta, where it equals psi(F); finite as k grows (nu -> 1/2), so nearly incompressible parts
    neither lock nor fail."""
    name = getattr(material, "VOLUMETRIC_MODULUS", "lmbda")
    if not hasattr(material, "volumetric") or not hasattr(material, name):
        raise InputError("discretization.formulation = 'mixed': needs a built-in material model "
                         "(a user psi(F) has no volumetric part to split off)")
    modulus = getattr(material, name)
    if _smallest(modulus) <= 0:
        raise InputError(f"discretization.formulation = 'mixed': needs {'lambda' if name == 'lmbda' else name} > 0 "
                         "(nu > 0); it is meant for nearly incompressible materials")
    deviatoric = copy.copy(material)                 # k = 0, without re-validating Constants
    object.__setattr__(deviatoric, name, 0.0)
    return deviatoric.psi(F) + p * material.volumetric(F) - p**2 / (2 * modulus)
