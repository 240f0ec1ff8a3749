"""Sums of powers of the isochoric principal stretches, sum_k l_k^alpha, as UFL functions of the two invariants
I1_bar, I2_bar of C_bar = J^(-2/3) C (its third is 1): Ogden's energy without the tensor's eigenvalues.

The squared stretches s_k are the roots of s^3 - I1 s^2 + I2 s - 1. Away from isotropy, Cardano's
trigonometric form: q = I1/3, p^2 = (I1^2 - 3 I2)/9, r = det(C_bar - q I)/(2 p^3) with det(C_bar - q I) =
2 I1^3/27 - I1 I2/3 + 1, s_k = q + 2 p cos(acos(r)/3 + 2 pi k/3); r is kept inside (-1, 1): at a double root
(uniaxial tension, r = +-1) r is at its extreme, so its gradient vanishes and the stress stays exact. Near
isotropy (p^2 below TAYLOR), where 1/p amplifies round-off (the stress's relative error ~ eps / p^2), the
fourth-order Taylor series of sum_k g(s_k) about q, whose terms are polynomials in the invariants: with
m_n = sum_k (s_k - q)^n = 3, 0, 6 p^2, 3 det, 18 p^4 (n = 0..4; m_5 = 15 p^2 det), the sum is
sum_n g^(n)(q) m_n / n!: exact for l^2 and l^4, else off by g^(5) p^2 det / 8. At the switch (p = 1e-3)
both branches hold the stress to about 1e-10 of itself for exponents up to 5 (to c (c-1) ... (c-4) 1e-10/2
for l^(2c)); a sixth-order series, good to a larger p, made the tangent 40 % slower.
Written on two scalars instead of the 3 x 3 tensor, the P2 tangent of an Ogden beam assembles about twice as
fast (benchmarks/rubber_cost.md)."""
from __future__ import annotations

import math

import ufl

TAYLOR = 1e-6        # p^2 below it: the Taylor series
EDGE = 1e-15         # r kept within (-1 + EDGE, 1 - EDGE)


def power_sums(I1, I2, exponents, weights=None):
    """sum_i w_i sum_k l_k^a_i over the exponents a_i (l_k = sqrt(s_k) the isochoric principal stretches; w_i = 1
    by default) as one UFL expression of I1_bar and I2_bar: the roots and the moments are shared by every
    exponent, one conditional picks the series or Cardano for all of them."""
    q = I1 / 3
    p2 = (I1 ** 2 - 3 * I2) / 9
    det = 2 * I1 ** 3 / 27 - I1 * I2 / 3 + 1
    p = ufl.sqrt(ufl.max_value(p2, TAYLOR))
    r = ufl.max_value(ufl.min_value(det / (2 * p ** 3), 1 - EDGE), -1 + EDGE)
    phi = ufl.acos(r) / 3
    largest = q + 2 * p * ufl.cos(phi)
    smallest = q + 2 * p * ufl.cos(phi + 2 * math.pi / 3)
    roots = (largest, 3 * q - largest - smallest, smallest)
    moments = (3, 0, 6 * p2, 3 * det, 18 * p2 ** 2)
    series_total, cardano_total = 0, 0
    for a, w in zip(exponents, weights if weights is not None else [1.0] * len(exponents)):
        c = a / 2                                   # l^a = s^c; g^(n)(q) = c (c - 1) ... (c - n + 1) q^(c - n)
        factor, series = 1.0, 0
        for n, m in enumerate(moments):
            if n:
                factor = factor * (c - n + 1) / n   # c (c - 1) ... (c - n + 1) / n!
            if not (isinstance(m, int) and m == 0):
                series = series + factor * m / q ** n
        series_total = series_total + w * q ** c * series
        cardano_total = cardano_total + w * sum(s ** c for s in roots)
    return ufl.conditional(ufl.lt(p2, TAYLOR), series_total, cardano_total)
