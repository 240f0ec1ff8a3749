"""Kinematics of a displacement field: F, C, Green strain, invariants (UFL expressions)."""
from __future__ import annotations

import ufl


def deformation_gradient(u) -> ufl.core.expr.Expr:
    """F = I + grad u, the gradient of the deformation x = X + u(X)."""
    return ufl.Identity(len(u)) + ufl.grad(u)


def right_cauchy_green(F) -> ufl.core.expr.Expr:
    """C = F^T F."""
    return F.T * F


def green_strain(F) -> ufl.core.expr.Expr:
    """Green-Lagrange strain E = (C - I) / 2."""
    return 0.5 * (right_cauchy_green(F) - ufl.Identity(F.ufl_shape[0]))


def small_strain(F) -> ufl.core.expr.Expr:
    """Infinitesimal strain eps = sym(F - I) = sym(grad u)."""
    return ufl.sym(F - ufl.Identity(F.ufl_shape[0]))


def invariants(F) -> tuple:
    """(I1, I2, J): I1 = tr C, I2 = ((tr C)^2 - tr C^2) / 2, J = det F."""
    C = right_cauchy_green(F)
    I1 = ufl.tr(C)
    I2 = 0.5 * (I1**2 - ufl.tr(C * C))
    return I1, I2, ufl.det(F)
