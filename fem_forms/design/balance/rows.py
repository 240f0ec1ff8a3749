"""Linear functionals of the moment vector M = [m, Sx, Sy, Sz, Sxx, Syy, Szz, Sxy, Sxz, Syz]: the rows the
balance constraints are written with (each constraint is w . M <= b for fixed geometry)."""
from __future__ import annotations

import numpy as np


def mass() -> np.ndarray:
    w = np.zeros(10)
    w[0] = 1.0
    return w


def first(u: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
    """u . (S1 - m p) = m u . (c - p)."""
    w = np.zeros(10)
    w[1:4] = u
    if p is not None:
        w[0] = -float(u @ p)
    return w


def second(u: np.ndarray, v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """u^T S_p v with S_p = int rho (x - p)(x - p)^T."""
    w = np.zeros(10)
    w[4:7] = u * v
    w[7] = u[0] * v[1] + u[1] * v[0]
    w[8] = u[0] * v[2] + u[2] * v[0]
    w[9] = u[1] * v[2] + u[2] * v[1]
    w[1:4] = -(u @ p) * v - (v @ p) * u
    w[0] = (u @ p) * (v @ p)
    return w


def inertia(u: np.ndarray, v: np.ndarray, p: np.ndarray) -> np.ndarray:
    """u^T I_p v for unit vectors u, v (I_p = tr(S_p) I - S_p, the inertia about p)."""
    trace = sum(second(e, e, p) for e in np.eye(3))
    return (u @ v) * trace - second(u, v, p)
