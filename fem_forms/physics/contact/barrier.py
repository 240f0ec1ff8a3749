"""The IPC barrier of Li et al. 2020, b(d) = -(d - dhat)^2 ln(d / dhat) for 0 < d < dhat (0 beyond), with
its first two derivatives, vectorised over many distances (the IPC Toolkit evaluates one at a time; a unit
test holds these to ipctk.barrier and its derivatives)."""
from __future__ import annotations

import numpy as np


def barrier(d: np.ndarray, dhat: float) -> np.ndarray:
    """b(d); +inf where d <= 0 (an intersection), 0 where d >= dhat."""
    d = np.asarray(d, dtype=float)
    out = np.zeros_like(d)
    act = d < dhat
    with np.errstate(divide="ignore", invalid="ignore"):
        out[act] = -(d[act] - dhat) ** 2 * np.log(d[act] / dhat)
    out[d <= 0] = np.inf
    return out


def barrier_first(d: np.ndarray, dhat: float) -> np.ndarray:
    """b'(d) = (dhat - d)(2 ln(d / dhat) - dhat / d + 1) (<= 0: the barrier pushes apart)."""
    d = np.asarray(d, dtype=float)
    out = np.zeros_like(d)
    act = (d < dhat) & (d > 0)
    r = d[act] / dhat
    out[act] = (dhat - d[act]) * (2 * np.log(r) - 1 / r + 1)
    out[d <= 0] = -np.inf
    return out


def barrier_second(d: np.ndarray, dhat: float) -> np.ndarray:
    """b''(d) = (dhat / d + 2) dhat / d - 2 ln(d / dhat) - 3 (>= 0)."""
    d = np.asarray(d, dtype=float)
    out = np.zeros_like(d)
    act = (d < dhat) & (d > 0)
    q = dhat / d[act]
    out[act] = (q + 2) * q + 2 * np.log(q) - 3
    out[d <= 0] = np.inf
    return out


def pressure_at_half(dhat: float) -> float:
    """-b'(dhat / 2) / dhat: the barrier's push per unit stiffness and distance where the gap is dhat / 2."""
    return float(-barrier_first(np.array([dhat / 2]), dhat)[0] / dhat)


def psd_blocks(H: np.ndarray) -> np.ndarray:
    """Each 3x3 block of H (n, 3, 3) with its negative eigenvalues set to zero (Newton needs a descent
    direction; IPC projects every contact Hessian this way)."""
    w, V = np.linalg.eigh(0.5 * (H + H.transpose(0, 2, 1)))
    return np.einsum("nij,nj,nkj->nik", V, np.maximum(w, 0.0), V)
