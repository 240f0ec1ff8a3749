"""Principal values of a symmetric 3 x 3 UFL tensor in closed form, for energies written on them (the spectral
split of phase-field fracture, Miehe, Welschinger & Hofacker 2010).

The trigonometric (Cardano) solution: q = tr A / 3, p = |dev A| / sqrt(6), r = det(dev A / p) / 2,
lambda_k = q + 2 p cos(acos(r) / 3 + 2 pi k / 3). Two guards keep it and its UFL derivatives finite where
eigenvalues coincide: p is floored at FLOOR (an isotropic A: dev A / p would be 0/0) and r is kept inside
(-1, 1) by EDGE (acos has an infinite slope at +-1). A double eigenvalue is then split by about p sqrt(EDGE),
the accuracy the formula has there anyway (r carries round-off); sums over the eigenvalues are exact to
round-off; at a double eigenvalue r is stationary in A, so the gradient (the stress) stays exact and only the
tangent loses a term (Newton converges, linearly there)."""
from __future__ import annotations

import math

import ufl

FLOOR = 1.0e-12          # in the tensor's units (a strain): the eigenvalues are exact to about this
EDGE = 1.0e-15


def principal_values(A, floor: float = FLOOR) -> tuple:
    """The eigenvalues (largest, middle, smallest) of the symmetric UFL tensor A, p floored at `floor`. The
    floor's second derivative is 1/floor times a difference of g'(eigenvalue) across eigenvalues `floor` apart:
    a tangent at an isotropic A is good to about eps/floor (FLOOR: 1e-4, the modes of an Ogden solid at rest
    4e-5 off); the second and third moments of the eigenvalues (6 p^2 = |D|^2 + 6 floor^2, 6 p^3 r = 3 det D)
    keep their derivatives exact whatever the floor, so a floor of 1e-6 of the values costs nothing."""
    I = ufl.Identity(3)
    q = ufl.tr(A) / 3
    D = A - q * I
    p = ufl.sqrt(ufl.inner(D, D) / 6 + floor ** 2)
    r = ufl.max_value(ufl.min_value(ufl.det(D / p) / 2, 1 - EDGE), -1 + EDGE)
    phi = ufl.acos(r) / 3
    largest = q + 2 * p * ufl.cos(phi)
    smallest = q + 2 * p * ufl.cos(phi + 2 * math.pi / 3)
    return largest, 3 * q - largest - smallest, smallest


def positive(x):
    """<x>+ = max(x, 0) as a UFL expression."""
    return ufl.conditional(ufl.gt(x, 0), x, 0)


def tensile_energy(eps, mu, lmbda):
    """Miehe's psi+ of isotropic linear elasticity: lambda/2 <tr eps>+^2 + mu sum_i <eps_i>+^2 (the part of
    psi = lambda/2 (tr eps)^2 + mu eps:eps that tension stores; the rest, compression's, damage leaves)."""
    return lmbda / 2 * positive(ufl.tr(eps)) ** 2 + mu * sum(positive(e) ** 2 for e in principal_values(eps))
