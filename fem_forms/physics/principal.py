"""Energies written on principal values (the spectral split of phase-field fracture, Miehe, Welschinger &
Hofacker 2010).

The closed form itself is kinematics.principal_values (the rubber models use it too)."""
from __future__ import annotations

import ufl

from fem_forms.kinematics import principal_values


def positive(x):
    """<x>+ = max(x, 0) as a UFL expression."""
    return ufl.conditional(ufl.gt(x, 0), x, 0)


def tensile_energy(eps, mu, lmbda):
    """Miehe's psi+ of isotropic linear elasticity: lambda/2 <tr eps>+^2 + mu sum_i <eps_i>+^2 (the part of
    psi = lambda/2 (tr eps)^2 + mu eps:eps that tension stores; the rest, compression's, damage leaves)."""
    return lmbda / 2 * positive(ufl.tr(eps)) ** 2 + mu * sum(positive(e) ** 2 for e in principal_values(eps))
