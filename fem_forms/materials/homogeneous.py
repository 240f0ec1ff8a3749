"""The rubber models' stresses in the homogeneous tests of a lab, in closed form (incompressible): uniaxial
tension (a dog-bone), equibiaxial tension (a bulge or a biaxial rig) and pure shear (a wide strip), written
from the models' textbook formulas with numpy, apart from the UFL energies; and Drucker's stability of a
parameter set. What a fit is computed on, and what a finite-element cube is checked against."""
from __future__ import annotations

import numpy as np

from fem_forms.materials.isochoric import ARRUDA_BOYCE_SERIES

MODES = ("uniaxial", "biaxial", "shear")
# the tangent's determinant is a difference of products: below this fraction of their size it is round-off
# (one stretch far from the others: Ogden's l^alpha spans 20 digits), and counted as no loss of stability
ROUNDOFF = 1e-9


def mode_stretches(mode: str, lam) -> tuple:
    """The principal stretches (l1, l2, l3) of a mode at the stretch `lam` along 1; l3 is the free direction."""
    lam = np.asarray(lam, dtype=float)
    if mode == "uniaxial":
        return lam, lam ** -0.5, lam ** -0.5
    if mode == "biaxial":
        return lam, lam, lam ** -2.0
    if mode == "shear":
        return lam, np.ones_like(lam), 1.0 / lam
    raise ValueError(f"unknown test mode {mode!r} (one of {', '.join(MODES)})")


def _dW_dI1(model: str, p: dict, I1):
    """dW/dI1 of the models written in I1 alone."""
    x = I1 - 3
    if model == "yeoh":
        return p["C10"] + 2 * p.get("C20", 0.0) * x + 3 * p.get("C30", 0.0) * x ** 2
    if model == "gent":
        return 0.5 * p["mu"] / (1 - x / p["Jm"])
    if model == "arruda-boyce":
        return p["mu"] * sum(i * c * I1 ** (i - 1) / p["lambda_m"] ** (2 * i - 2)
                             for i, c in enumerate(ARRUDA_BOYCE_SERIES, start=1))
    if model == "neo-hookean":
        return 0.5 * p["mu"] + 0 * x
    raise ValueError(f"no closed form for model {model!r}")


def stress_difference(model: str, p: dict, la, lb, I1):
    """sigma_a - sigma_b, the Cauchy stress difference between two principal directions (the pressure of an
    incompressible solid cancels): Ogden sum_i mu_i (la^alpha_i - lb^alpha_i), the I1 models 2 (la^2 - lb^2) W'."""
    if model == "ogden":
        return sum(m * (la ** a - lb ** a) for m, a in zip(p["mu"], p["alpha"]))
    return 2 * (la ** 2 - lb ** 2) * _dW_dI1(model, p, I1)


def nominal_stress(model: str, p: dict, mode: str, lam):
    """The nominal (first Piola-Kirchhoff) stress along 1 of a mode at stretch lam: force per rest area, what a
    tensile tester records; the free direction 3 carries none."""
    l1, l2, l3 = mode_stretches(mode, lam)
    return stress_difference(model, p, l1, l3, l1 ** 2 + l2 ** 2 + l3 ** 2) / l1


def locked(model: str, p: dict, mode: str, lam):
    """Where Gent's chains have locked (I1 - 3 >= Jm): no state exists there."""
    if model != "gent":
        return np.zeros(np.shape(lam), dtype=bool)
    l1, l2, l3 = mode_stretches(mode, lam)
    return l1 ** 2 + l2 ** 2 + l3 ** 2 - 3 >= p["Jm"]


def drucker_stable(model: str, p: dict, e1, e2, h: float = 1e-20):
    """Drucker's condition d sigma : d eps > 0 at the log strains (e1, e2, -e1 - e2): with s_a = sigma_a -
    sigma_3 (the pressure drops out of an isochoric increment), the 2 x 2 tangent d s_a / d e_b must be
    positive definite. Complex-step derivatives of the closed forms: exact to round-off, which the
    determinant needs (with one stretch far from the others it is a small difference of large products, and a
    negative one within ROUNDOFF of their size is taken as zero)."""
    def s(a, b):
        l1, l2, l3 = np.exp(a), np.exp(b), np.exp(-a - b)
        I1 = l1 ** 2 + l2 ** 2 + l3 ** 2
        return stress_difference(model, p, l1, l3, I1), stress_difference(model, p, l2, l3, I1)
    e1, e2 = np.asarray(e1, dtype=complex), np.asarray(e2, dtype=complex)
    s1a, s2a = s(e1 + 1j * h, e2)
    s1b, s2b = s(e1, e2 + 1j * h)
    d11, d21, d12, d22 = s1a.imag / h, s2a.imag / h, s1b.imag / h, s2b.imag / h
    off = 0.5 * (d12 + d21)
    with np.errstate(all="ignore"):
        det, size = d11 * d22 - off ** 2, d11 ** 2 + d22 ** 2 + 2 * off ** 2
        return (d11 + d22 > 0) & (det > -ROUNDOFF * size) & np.isfinite(det)


def stable_range(model: str, p: dict, mode: str, lo: float = 0.1, hi: float = 10.0, n: int = 2001) -> tuple:
    """(smallest, largest) stretch of the mode between lo and hi reached from 1 without leaving Drucker's stable
    set or passing the locking limit (to the scan's resolution, 0.1 % here); lo or hi when all of it is stable."""
    out = []
    for end in (lo, hi):
        lam = np.geomspace(1.0, end, n)[1:]
        l1, l2, _ = mode_stretches(mode, lam)
        bad = ~drucker_stable(model, p, np.log(l1), np.log(l2)) | locked(model, p, mode, lam)
        first = int(np.argmax(bad))
        out.append(float(end if not bad.any() else lam[first - 1] if first else 1.0))
    return out[0], out[1]
