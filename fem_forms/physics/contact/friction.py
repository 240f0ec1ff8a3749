"""Smoothed Coulomb friction as a lagged dissipative potential (IPC, Li et al. 2020, section 5): per contact
node, D = mu lambda f0(|u_t|) with the normal force lambda and the tangent plane T taken from the step's start
(lagged), u_t = T^T (slip of the node relative to the obstacle over the step). f0 smooths the kink of |u_t|
below the slip eps: sticking is a creep slower than eps per step, sliding a force mu lambda against the slip."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def f0(y: np.ndarray, eps: float) -> np.ndarray:
    """The mollified |u_t|: -y^3/(3 eps^2) + y^2/eps + eps/3 below eps, y above."""
    return np.where(y < eps, -y ** 3 / (3 * eps ** 2) + y ** 2 / eps + eps / 3, y)


def f1_over_y(y: np.ndarray, eps: float) -> np.ndarray:
    """f0'(y) / y: 2/eps - y/eps^2 below eps, 1/y above (finite at y = 0)."""
    return np.where(y < eps, 2 / eps - y / eps ** 2, 1 / np.maximum(y, eps))


def f1_prime(y: np.ndarray, eps: float) -> np.ndarray:
    """f0''(y): 2/eps - 2y/eps^2 below eps, 0 above."""
    return np.where(y < eps, 2 / eps - 2 * y / eps ** 2, 0.0)


def tangent_basis(normal: np.ndarray) -> np.ndarray:
    """(n, 3, 2): two unit vectors orthogonal to each unit normal and to each other."""
    helper = np.where(np.abs(normal[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(normal, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normal, t1)
    return np.stack([t1, t2], axis=2)


@dataclass
class LaggedFriction:
    """One obstacle's friction over one step: the contact nodes at its start, their normal forces, tangent
    planes and start positions, the obstacle's move over the step, mu and the slip eps."""
    nodes: np.ndarray               # indices into the surface's nodes
    normal_force: np.ndarray        # (k,) lambda, N
    basis: np.ndarray               # (k, 3, 2)
    start: np.ndarray               # (k, 3) positions at the step's start
    mu: float
    eps: float
    obstacle_move: np.ndarray       # (3,) the obstacle's translation over the step

    def slip(self, p: np.ndarray) -> np.ndarray:
        """(k, 2) tangential slip of each node relative to the obstacle, p the current surface positions."""
        rel = p[self.nodes] - self.start - self.obstacle_move
        return np.einsum("kij,ki->kj", self.basis, rel)

    def energy(self, p: np.ndarray) -> float:
        y = np.linalg.norm(self.slip(p), axis=1)
        return float(np.sum(self.mu * self.normal_force * f0(y, self.eps)))

    def gradient(self, p: np.ndarray) -> np.ndarray:
        """(k, 3): dD/dx of each node (minus the friction force on it)."""
        s = self.slip(p)
        y = np.linalg.norm(s, axis=1)
        w = (self.mu * self.normal_force * f1_over_y(y, self.eps))[:, None] * s
        return np.einsum("kij,kj->ki", self.basis, w)

    def hessian(self, p: np.ndarray) -> np.ndarray:
        """(k, 3, 3): T [f1/y (I - s s^T / y^2) + f1' s s^T / y^2] T^T mu lambda (positive semidefinite)."""
        s = self.slip(p)
        y = np.linalg.norm(s, axis=1)
        unit = s / np.maximum(y, 1e-300)[:, None]
        uu = unit[:, :, None] * unit[:, None, :]
        a, b = f1_over_y(y, self.eps), f1_prime(y, self.eps)
        small = y < 1e-12 * self.eps                  # no direction yet: isotropic 2/eps
        inner = a[:, None, None] * (np.eye(2) - uu) + b[:, None, None] * uu
        inner[small] = (2 / self.eps) * np.eye(2)
        inner *= (self.mu * self.normal_force)[:, None, None]
        return np.einsum("kia,kab,kjb->kij", self.basis, inner, self.basis)
