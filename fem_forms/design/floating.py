"""Floating upright at a waterline: the displaced volume, its centre (centre of buoyancy) and the
waterplane's second moment, exact for straight-edged tetrahedra (hexahedra with planar faces are split
into six). Each rank clips its own cells against the water plane; the sums are reduced over ranks.

Metacentric height GM = KB + BM - KG, with K the keel (the lowest point), BM = I_waterplane / V_displaced
and I_waterplane the smaller principal second moment of the waterplane area about its centroid (the
least stable heeling direction)."""
from __future__ import annotations

from dataclasses import dataclass

from mpi4py import MPI
import numpy as np

# a hexahedron (dolfinx tensor order 0..7) split into six tetrahedra around the diagonal 0-7
HEX_TETS = np.array([[0, 1, 3, 7], [0, 1, 7, 5], [0, 5, 7, 4], [0, 3, 2, 7], [0, 6, 4, 7], [0, 2, 6, 7]])


def tetrahedra(corners: np.ndarray) -> np.ndarray:
    """(n, 4, 3) tetrahedra from cells' corner points (n, 4 or 8, 3)."""
    if corners.shape[1] == 4:
        return corners
    return corners[:, HEX_TETS].reshape(-1, 4, 3)


def _volumes(t: np.ndarray) -> np.ndarray:
    a, b, c = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0], t[:, 3] - t[:, 0]
    return np.abs(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0


def _cut(p: np.ndarray, q: np.ndarray, hp: np.ndarray, hq: np.ndarray) -> np.ndarray:
    """Points on segments p-q where the height crosses 0."""
    t = hp / (hp - hq)
    return p + t[:, None] * (q - p)


def submerged(tets: np.ndarray, up: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray, list]:
    """Pieces of the tetrahedra below the plane up . x = level: (tets (k, 4, 3) whose union is the
    submerged part, and for the cut ones the section polygons as a list of (m, n_corners, 3))."""
    h = tets @ up - level
    below = h < 0
    nb = below.sum(axis=1)
    pieces = [tets[nb == 4]]
    polys = []
    order = np.argsort(~below, axis=1, kind="stable")          # below-vertices first
    for k in (1, 2, 3):
        sel = nb == k
        if not sel.any():
            continue
        t = np.take_along_axis(tets[sel], order[sel][:, :, None], axis=1)
        hh = np.take_along_axis(h[sel], order[sel], axis=1)
        P = lambda i, j: _cut(t[:, i], t[:, j], hh[:, i], hh[:, j])
        if k == 1:
            a, b, c = P(0, 1), P(0, 2), P(0, 3)
            pieces.append(np.stack([t[:, 0], a, b, c], axis=1))
            polys.append(np.stack([a, b, c], axis=1))
        elif k == 3:
            a, b, c = P(3, 0), P(3, 1), P(3, 2)
            # the tet minus the small tet at vertex 3: a prism (0, 1, 2 | a, b, c) in three tets
            pieces += [np.stack([t[:, 0], t[:, 1], t[:, 2], a], axis=1),
                       np.stack([t[:, 1], t[:, 2], a, b], axis=1),
                       np.stack([t[:, 2], a, b, c], axis=1)]
            polys.append(np.stack([a, b, c], axis=1))
        else:
            ac, ad, bc, bd = P(0, 2), P(0, 3), P(1, 2), P(1, 3)
            # a prism with triangles (A, AC, AD) and (B, BC, BD)
            pieces += [np.stack([t[:, 0], ac, ad, t[:, 1]], axis=1),
                       np.stack([ac, ad, t[:, 1], bc], axis=1),
                       np.stack([ad, t[:, 1], bc, bd], axis=1)]
            polys.append(np.stack([ac, ad, bd, bc], axis=1))
    return np.concatenate(pieces), polys


def _polygon_moments(polys: list, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """[A, int a, int b, int aa, int bb, int ab] of convex polygons in the plane coordinates (a, b)."""
    out = np.zeros(6)
    for P in polys:
        q = np.stack([P @ e1, P @ e2], axis=2)                  # (m, n, 2)
        for i in range(1, q.shape[1] - 1):                      # fan triangles
            tri = np.stack([q[:, 0], q[:, i], q[:, i + 1]], axis=1)
            d1, d2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
            A = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
            s = tri.sum(axis=1)
            sq = np.einsum("mki,mkj->mij", tri, tri) + np.einsum("mi,mj->mij", s, s)
            out += [A.sum(), (A * s[:, 0]).sum() / 3, (A * s[:, 1]).sum() / 3,
                    (A * sq[:, 0, 0]).sum() / 12, (A * sq[:, 1, 1]).sum() / 12, (A * sq[:, 0, 1]).sum() / 12]
    return out


@dataclass
class Flotation:
    """What floats at a waterline: displaced volume, centre of buoyancy, waterplane area and moment."""
    waterline: float                 # height of the water surface above the keel
    keel: float                      # up . x of the lowest point
    volume: float
    center_of_buoyancy: np.ndarray
    waterplane_area: float
    waterplane_center: np.ndarray    # in the ground-plane coordinates (e1, e2)
    waterplane_inertia: float        # smaller principal second moment of the waterplane area
    up: np.ndarray                   # unit vector against gravity

    @property
    def KB(self) -> float:
        return float(self.center_of_buoyancy @ self.up - self.keel)

    @property
    def BM(self) -> float:
        return self.waterplane_inertia / self.volume

    def metacentric_height(self, com: np.ndarray) -> float:
        """GM = KB + BM - KG."""
        return self.KB + self.BM - float(com @ self.up - self.keel)


def flotation(tets: np.ndarray, up: np.ndarray, e1: np.ndarray, e2: np.ndarray, keel: float,
              waterline: float, comm: MPI.Comm) -> Flotation:
    """Displaced volume, centre of buoyancy and waterplane moments at `waterline` above the keel (this
    rank's tetrahedra, reduced over ranks)."""
    pieces, polys = submerged(tets, up, keel + waterline)
    V = _volumes(pieces)
    local = np.concatenate([[V.sum()], V @ pieces.mean(axis=1), _polygon_moments(polys, e1, e2)])
    tot = comm.allreduce(local, op=MPI.SUM)
    vol, first, wp = tot[0], tot[1:4], tot[4:]
    A = wp[0]
    if vol <= 0 or A <= 0:
        f = Flotation(waterline, keel, float(vol), np.full(3, np.nan), float(A), np.full(2, np.nan), np.nan, up)
    else:
        ca = wp[1:3] / A
        Iaa = wp[3] - A * ca[0] ** 2
        Ibb = wp[4] - A * ca[1] ** 2
        Iab = wp[5] - A * ca[0] * ca[1]
        imin = float(np.linalg.eigvalsh(np.array([[Ibb, -Iab], [-Iab, Iaa]]))[0])
        f = Flotation(waterline, keel, float(vol), first / vol, float(A), ca, imin, up)
    return f
