"""Kinematics of a displacement field: F, C, Green strain, invariants (UFL expressions)."""
from __future__ import annotations

import math

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


def biot_invariants(F, fixed_point_steps: int = 2, newton_steps: int = 3) -> tuple:
    """(tr(U - I), |U - I|^2) of the Biot strain U - I (U of the polar decomposition F = R U, 3x3,
    det F > 0), as smooth UFL expressions of the invariants of C: no eigenvalues, no division by their
    differences, so they are differentiable at repeated stretches (F = I, uniaxial, isotropic states).

    i = tr U is the one root i >= sqrt(I1) of q(i) = ((i^2 - I1)/2)^2 - 2 J i - I2 (from tr U^2 = I1,
    ii_U = (i^2 - I1)/2 and ii_U^2 = I2 + 2 J i). Start at the upper bound sqrt(3 I1), take
    `fixed_point_steps` of the monotone map i <- sqrt(I1 + 2 sqrt(I2 + 2 J i)) (each stays an upper
    bound), then `newton_steps` Newton steps on q, which is convex and increasing there
    (q'(i) = 2 (i ii - J) = 2 (l1+l2)(l2+l3)(l3+l1) > 0), so Newton decreases monotonically onto the
    simple root, and i is a smooth function of C (implicit function theorem).

    Everything is written in small quantities (d = i - 3, the invariants of the Green strain, J - 1,
    square roots as sqrt(9 + s) - 3 = s / (sqrt(9 + s) + 3)), and |U - I|^2 = tr C - 2 tr U + 3 as
    2 tr E - 2 d: written plainly as I1 - 2 i + 3, the energy of a strain of 1e-5 had a round-off noise
    of 1e-16 mu per point, larger than a Newton step's energy decrease on a stiff beam, and the energy
    line search failed on it. Accuracy of |U - I|^2 (worst relative error, 100 random stretches per
    range, no rotation, default 2 + 3 steps): 2e-9 at log-strains 1e-6, 2e-12 at 1e-3, 2e-14 from 0.1
    to 1, 3e-14 at 2 (stretches 0.14 to 7.4); tr U to about 1e-14 absolute over that range."""
    if F.ufl_shape != (3, 3):
        raise ValueError(f"biot_invariants: needs a 3x3 F (got {F.ufl_shape})")
    return biot_from_invariants(*small_invariants(F), fixed_point_steps, newton_steps)


def small_invariants(F) -> tuple:
    """(e1, e2, j): tr E, the second invariant of the Green strain E and J - 1, written in H = F - I
    so that small strains keep their digits (I1 = 3 + 2 e1, I2 = 3 + 4 e1 + 4 e2)."""
    H = F - ufl.Identity(3)
    E = ufl.sym(H) + 0.5 * H.T * H                       # Green strain, from small H
    e1 = ufl.tr(E)
    e2 = 0.5 * (e1**2 - ufl.tr(E * E))
    j = ufl.tr(H) + 0.5 * (ufl.tr(H)**2 - ufl.tr(H * H)) + ufl.det(H)
    return e1, e2, j


def biot_from_invariants(e1, e2, j, fixed_point_steps: int = 2, newton_steps: int = 3) -> tuple:
    """biot_invariants from the small invariants (e1, e2, j) of small_invariants."""
    def sqrt9_minus_3(s):                                # sqrt(9 + s) - 3, exact for small s
        return s / (ufl.sqrt(9 + s) + 3)

    d = sqrt9_minus_3(6 * e1)                            # start: i = sqrt(3 I1)
    for _ in range(fixed_point_steps):                   # i <- sqrt(I1 + 2 sqrt(I2 + 2 J i))
        t = sqrt9_minus_3(4 * e1 + 4 * e2 + 6 * j + 2 * d + 2 * j * d)
        d = sqrt9_minus_3(2 * e1 + 2 * t)
    for _ in range(newton_steps):                        # on q, with g = ii - 3
        g = 3 * d + 0.5 * d**2 - e1
        q = 6 * g + g**2 - 2 * d - 6 * j - 2 * j * d - 4 * e1 - 4 * e2
        d = d - q / (2 * (8 + 3 * d + 3 * g + d * g - j))
    return d, 2 * e1 - 2 * d


def polar_rotation(F) -> ufl.core.expr.Expr:
    """The rotation R of the polar decomposition F = R U (3x3, det F > 0) as a UFL expression that
    ufl.derivative goes through. With i = tr U from biot_invariants and ii = (i^2 - I1)/2, Cayley-Hamilton
    for U gives (Hoger & Carlson 1984)
        U = (-C^2 + (i^2 - ii) C + i J I) / (i ii - J),   U^-1 = (C - i U + ii I) / J,   R = F U^-1,
    whose denominators (l1+l2)(l2+l3)(l3+l1) and l1 l2 l3 are positive for every det F > 0, repeated
    stretches included. Accuracy against scipy.linalg.polar (worst of 200 random pairs): 5e-15 for
    principal log-strains up to 0.5, 1e-14 up to 1, 1e-12 up to 2. Exactly rotation invariant:
    everything but the leading F depends on C only, so R(Q F) = Q R(F).

    Why not the matrix Newton iteration R <- (R + R^-T)/2 from F: it needs 6 steps for the same range,
    and the tangent then nests the second derivatives of 6 matrix inverses; with 4 steps FFCx wrote
    3.4 MB of C for the P1 tangent kernel, which gcc took about 17 minutes to compile here."""
    C = right_cauchy_green(F)
    I = ufl.Identity(3)
    I1 = ufl.tr(C)
    J = ufl.det(F)
    i = 3 + biot_invariants(F)[0]
    ii = 0.5 * (i**2 - I1)
    U = (-C * C + (i**2 - ii) * C + i * J * I) / (i * ii - J)
    return F * (C - i * U + ii * I) / J


# Principal values in closed form, the trigonometric (Cardano) solution: q = tr A / 3, p = |dev A| / sqrt(6), r =
# det(dev A / p) / 2, lambda_k = q + 2 p cos(acos(r) / 3 + 2 pi k / 3). Two guards keep it and its UFL derivatives
# finite where eigenvalues coincide: p is floored at FLOOR (an isotropic A: dev A / p would be 0/0) and r is kept
# inside (-1, 1) by EDGE (acos has an infinite slope at +-1). A double eigenvalue is then split by about p
# sqrt(EDGE), the accuracy the formula has there anyway (r carries round-off); sums over the eigenvalues are exact
# to round-off; at a double eigenvalue r is stationary in A, so the gradient (the stress) stays exact and only the
# tangent loses a term (Newton converges, linearly there).
FLOOR = 1.0e-12          # in the tensor's units (a strain): the eigenvalues are exact to about this
EDGE = 1.0e-15


def principal_values(A, floor: float = FLOOR) -> tuple:
    """The eigenvalues (largest, middle, smallest) of the symmetric UFL tensor A, p floored at `floor`. The
    floor's second derivative is 1/floor times a difference of g'(eigenvalue) across eigenvalues `floor` apart:
    a tangent at an isotropic A is good to about eps/floor (FLOOR: 1e-4, the modes of an Ogden solid at rest
    4e-5 off); the second and third moments of the eigenvalues (6 p^2 = |D|^2 + 6 floor^2, 6 p^3 r = 3 det D)
    keep their derivatives exact whatever the floor, so a floor of 1e-6 of the values costs nothing."""
    return principal_values_of(*deviator_moments(A), floor=floor)


def deviator_moments(A) -> tuple:
    """(tr A / 3, |D|^2, det D) of A and its deviator D = A - tr A / 3 I: all the closed form reads of A. Each
    is computed from A itself (|D|^2 from I1 and I2 would lose |D|^2 to cancellation near isotropy)."""
    q = ufl.tr(A) / 3
    D = A - q * ufl.Identity(3)
    return q, ufl.inner(D, D), ufl.det(D)


def principal_values_of(q, dd, det_d, floor: float = FLOOR) -> tuple:
    """The eigenvalues (largest, middle, smallest) from the moments of deviator_moments: three scalars, so a
    material can take its stress by the chain rule through them (the Ogden model)."""
    p = ufl.sqrt(dd / 6 + floor ** 2)
    r = ufl.max_value(ufl.min_value(det_d / (2 * p ** 3), 1 - EDGE), -1 + EDGE)
    phi = ufl.acos(r) / 3
    largest = q + 2 * p * ufl.cos(phi)
    smallest = q + 2 * p * ufl.cos(phi + 2 * math.pi / 3)
    return largest, 3 * q - largest - smallest, smallest
