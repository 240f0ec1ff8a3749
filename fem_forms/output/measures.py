"""Strain and stress measures of continuum mechanics, evaluated with numpy on batches of 3x3 tensors
(shape (..., 3, 3)), for output at points or nodes.

UFL has no eigen- or polar decomposition, and output does not need derivatives through them, so the
measures that need U = sqrt(C) (Biot, Hencky) are computed here from values of F rather than in the
forms. The eigen decomposition of the symmetric C = F^T F = Q diag(l^2) Q^T gives U = Q diag(l) Q^T,
ln U = Q diag(ln l) Q^T and R = F U^-1 (the polar decomposition F = R U, R a rotation when det F > 0).
Green and the infinitesimal strain are included so that every measure is available by one name.
"""
from __future__ import annotations

import numpy as np

I3 = np.eye(3)


def _sym(A: np.ndarray) -> np.ndarray:
    return 0.5 * (A + np.swapaxes(A, -1, -2))


def _stretch_basis(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(principal stretches l, principal directions Q) with C = F^T F = Q diag(l^2) Q^T."""
    C = _sym(np.swapaxes(F, -1, -2) @ F)
    lam2, Q = np.linalg.eigh(C)
    return np.sqrt(np.maximum(lam2, 0.0)), Q


def _from_basis(values: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Q diag(values) Q^T for batches."""
    return (Q * values[..., None, :]) @ np.swapaxes(Q, -1, -2)


def right_stretch(F: np.ndarray) -> np.ndarray:
    """U = sqrt(F^T F), the symmetric positive definite right stretch tensor."""
    lam, Q = _stretch_basis(np.asarray(F, dtype=float))
    return _from_basis(lam, Q)


def polar_decomposition(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R, U) with F = R U, U = sqrt(F^T F) symmetric positive definite and R = F U^-1 (a rotation
    for det F > 0). F must be invertible."""
    F = np.asarray(F, dtype=float)
    lam, Q = _stretch_basis(F)
    U = _from_basis(lam, Q)
    R = F @ _from_basis(1.0 / lam, Q)
    return R, U


def green_strain(F: np.ndarray) -> np.ndarray:
    """Green-Lagrange strain E = (F^T F - I) / 2."""
    F = np.asarray(F, dtype=float)
    return 0.5 * (_sym(np.swapaxes(F, -1, -2) @ F) - I3)


def biot_strain(F: np.ndarray) -> np.ndarray:
    """Biot strain U - I (U the right stretch of F = R U)."""
    return right_stretch(F) - I3


def hencky_strain(F: np.ndarray) -> np.ndarray:
    """Hencky (logarithmic) strain ln U = Q diag(ln l) Q^T."""
    lam, Q = _stretch_basis(np.asarray(F, dtype=float))
    return _from_basis(np.log(lam), Q)


def infinitesimal_strain(F: np.ndarray) -> np.ndarray:
    """Small-strain tensor sym(grad u) = sym(F - I)."""
    return _sym(np.asarray(F, dtype=float)) - I3


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """sqrt(3/2 s:s) with s the deviator of sigma (shape (...,))."""
    sigma = np.asarray(sigma, dtype=float)
    s = sigma - np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] / 3.0 * I3
    return np.sqrt(1.5 * np.sum(s * s, axis=(-2, -1)))


def principal_values(S: np.ndarray) -> np.ndarray:
    """Eigenvalues of the symmetric part of S, largest first (shape (..., 3)): principal stresses
    sigma_1 >= sigma_2 >= sigma_3 of a Cauchy stress."""
    return np.linalg.eigvalsh(_sym(np.asarray(S, dtype=float)))[..., ::-1]


# name -> measure of F, for the strain fields computed point by point from the recovered F
STRAINS_OF_F = {
    "green_strain": green_strain,
    "biot_strain": biot_strain,
    "hencky_strain": hencky_strain,
    "infinitesimal_strain": infinitesimal_strain,
}
