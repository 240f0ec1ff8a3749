"""Self-contact by the IPC Toolkit (ipctk): the part's surface triangles against each other (vertex-face and
edge-edge pairs closer than dhat, neighbours excluded), the area-weighted barrier potential with its gradient and
PSD-projected Hessian, continuous collision detection for the step filter and an exact intersection test. The
toolkit measures squared distances; its stiffness is calibrated so that two parallel patches a gap dhat / 2
apart push with the same pressure as an obstacle's barrier does (term.py)."""
from __future__ import annotations

import ipctk
import numpy as np
import scipy.sparse as sp

from fem_forms.meshes.boundary_surface import BoundarySurface

SHORTEN = 0.8          # a step that would make surfaces touch is cut to this share of its time of impact
REACH = 2.0            # no step moves a surface node farther than this many mean surface edges
# Tight Inclusion CCD stopped after this many iterations returns a conservative time of impact: its default (1e7)
# took 247 s on two parallel patches passing through each other, 1e4 took 0.2 s for the same impact (0.477 vs 0.480)
CCD = ipctk.TightInclusionCCD(1e-6, 10_000)


def _plates(h: float, gap: float, n: int = 6):
    """Two parallel square patches of n x n cells of size h, `gap` apart (the calibration's probe)."""
    xs = np.arange(n + 1) * h
    P = np.array([[x, y, 0.0] for y in xs for x in xs])
    k = lambda i, j: j * (n + 1) + i                       # noqa: E731
    F = np.array([t for j in range(n) for i in range(n)
                  for t in ([k(i, j), k(i + 1, j), k(i + 1, j + 1)], [k(i, j), k(i + 1, j + 1), k(i, j + 1)])])
    V = np.vstack([P, P + [0.0, 0.0, gap]])
    F = np.vstack([F, F[:, ::-1] + len(P)])
    return V, F, len(P), (n * h) ** 2


class SelfContact:
    """The barrier between the surface's own triangles, with `stiffness` (set by `calibrate`)."""

    def __init__(self, surface: BoundarySurface, dhat: float):
        self.surface, self.dhat = surface, dhat
        self.mesh = ipctk.CollisionMesh(np.asfortranarray(surface.rest), np.asfortranarray(surface.edges(), np.int32),
                                        np.asfortranarray(surface.faces, np.int32))
        self.potential = ipctk.BarrierPotential(dhat, 1.0)
        self.stiffness = 1.0
        self._cache = (None, None)
        e = surface.edges()
        self.edge = float(np.mean(np.linalg.norm(surface.rest[e[:, 0]] - surface.rest[e[:, 1]], axis=1)))

    def calibrate(self, h: float, pressure: float) -> None:
        """Stiffness such that patches of cells h, dhat / 2 apart, push each other with `pressure` (Pa)."""
        V, F, n, area = _plates(h, self.dhat / 2)
        mesh = ipctk.CollisionMesh(V, ipctk.edges(F).astype(np.int32), F.astype(np.int32))
        c = self._build(mesh, V)
        push = self.potential.gradient(c, mesh, V).reshape(-1, 3)[:n, 2].sum()    # dE/dz of the lower patch > 0
        self.stiffness = pressure * area / push

    def _build(self, mesh, p: np.ndarray, dhat: float | None = None) -> ipctk.NormalCollisions:
        c = ipctk.NormalCollisions()
        c.use_area_weighting = True
        c.build(mesh, np.asfortranarray(p), dhat or self.dhat)
        return c

    def collisions(self, p: np.ndarray) -> ipctk.NormalCollisions:
        """The pairs closer than dhat at positions p (kept for the last p: energy, gradient and Hessian share)."""
        last, c = self._cache
        if last is None or last.shape != p.shape or not np.array_equal(last, p):
            c = self._build(self.mesh, p)
            self._cache = (p.copy(), c)
        return c

    def energy(self, p: np.ndarray) -> float:
        return self.stiffness * self.potential(self.collisions(p), self.mesh, np.asfortranarray(p))

    def gradient(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) dE/dx of every surface node."""
        g = self.potential.gradient(self.collisions(p), self.mesh, np.asfortranarray(p))
        return self.stiffness * g.reshape(-1, 3)

    def hessian(self, p: np.ndarray) -> sp.coo_matrix:
        """(3n, 3n) the PSD-projected Hessian, node-major (3 i + c), as triplets."""
        H = self.potential.hessian(self.collisions(p), self.mesh, np.asfortranarray(p),
                                   ipctk.PSDProjectionMethod.CLAMP)
        return (self.stiffness * H).tocoo()

    def safe_fraction(self, p0: np.ndarray, dp: np.ndarray) -> float:
        """The largest safe share of the step p0 -> p0 + dp; first limited to moving no node farther than
        REACH surface edges (a far step's candidate pairs grow quadratically: 3 GB and no end were seen on a
        ring whose first Newton step moved nodes 30 edges), then cut before any time of impact."""
        longest = float(np.linalg.norm(dp, axis=1).max(initial=0.0))
        reach = min(1.0, REACH * self.edge / longest) if longest > 0 else 1.0
        s = ipctk.compute_collision_free_stepsize(self.mesh, np.asfortranarray(p0),
                                                  np.asfortranarray(p0 + reach * dp), narrow_phase_ccd=CCD)
        return reach if s >= 1.0 else SHORTEN * s * reach

    def intersects(self, p: np.ndarray) -> bool:
        return bool(ipctk.has_intersections(self.mesh, np.asfortranarray(p)))

    def min_distance(self, p: np.ndarray) -> float:
        """The smallest gap between non-neighbouring surface pieces within 10 dhat (inf if none that close)."""
        c = self._build(self.mesh, p, 10 * self.dhat)
        return float(np.sqrt(c.compute_minimum_distance(self.mesh, np.asfortranarray(p)))) if len(c) else np.inf
