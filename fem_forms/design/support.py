"""Standing on the ground: contact points, the support polygon, the stability margin and toppling angle,
and the sphere fit of a rocking surface. Plain numpy/scipy on points already gathered (few: the contact
region only)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from fem_forms.frames import ground_frame


@dataclass
class SupportPolygon:
    """The convex hull of the contact points projected on the ground (2-D, in the frame e1, e2)."""
    up: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    ground: float                    # height of the ground (up . x of the lowest point)
    vertices: np.ndarray             # (k, 2) polygon corners, counter-clockwise (k < 3: degenerate)
    normals: np.ndarray              # (k, 2) outward unit normals of the edges
    offsets: np.ndarray              # (k,) with n . p + offset <= 0 inside

    @classmethod
    def from_points(cls, contact: np.ndarray, gravity: np.ndarray) -> "SupportPolygon":
        up, e1, e2 = ground_frame(gravity)
        ground = float((contact @ up).min())
        p2 = np.column_stack([contact @ e1, contact @ e2])
        try:
            hull = ConvexHull(p2)
            verts = p2[hull.vertices]
            eq = hull.equations
            normals, offsets = eq[:, :2], eq[:, 2]
        except (QhullError, ValueError):              # a point or a segment: no area to stand on
            verts = np.unique(np.round(p2, 12), axis=0)
            normals, offsets = np.empty((0, 2)), np.empty(0)
        return cls(up, e1, e2, ground, verts, normals, offsets)

    @property
    def has_area(self) -> bool:
        return len(self.normals) >= 3

    def project(self, x: np.ndarray) -> np.ndarray:
        return np.array([x @ self.e1, x @ self.e2])

    def margin(self, com: np.ndarray) -> float:
        """Signed distance of the projected CoM to the polygon's boundary: positive inside."""
        p = self.project(com)
        if self.has_area:
            inside = -(self.normals @ p + self.offsets)
            if inside.min() >= 0:
                return float(inside.min())
        return -_distance_to_polygon(p, self.vertices)

    def height(self, com: np.ndarray) -> float:
        """Height of the CoM above the ground."""
        return float(com @ self.up - self.ground)

    def toppling_angle_deg(self, com: np.ndarray) -> float:
        """The tilt about the nearest edge at which the CoM passes over it (negative: it already has)."""
        return float(np.degrees(np.arctan2(self.margin(com), self.height(com))))

    def corners_3d(self) -> np.ndarray:
        """The polygon's corners as 3-D points on the ground."""
        return np.array([self.ground * self.up + a * self.e1 + b * self.e2 for a, b in self.vertices])


def _distance_to_polygon(p: np.ndarray, verts: np.ndarray) -> float:
    """Distance from p to the closed polyline through verts (a point or segment when fewer than 3)."""
    if len(verts) == 1:
        return float(np.linalg.norm(p - verts[0]))
    best = np.inf
    segs = [(verts[i], verts[(i + 1) % len(verts)]) for i in range(len(verts))]
    for a, b in segs:
        ab = b - a
        t = np.clip(np.dot(p - a, ab) / max(np.dot(ab, ab), 1e-300), 0.0, 1.0)
        best = min(best, float(np.linalg.norm(p - (a + t * ab))))
    return best


def fit_sphere(points: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Least-squares sphere |x - c|^2 = R^2 through the points (algebraic fit), or None when the points
    are too few or (nearly) coplanar: no rocking surface."""
    if len(points) < 4:
        return None
    A = np.column_stack([2 * points, np.ones(len(points))])
    b = (points ** 2).sum(axis=1)
    sol, _, rank, sv = np.linalg.lstsq(A, b, rcond=None)
    if rank < 4 or sv[-1] < 1e-9 * sv[0]:
        return None
    c = sol[:3]
    R = float(np.sqrt(sol[3] + c @ c))
    span = np.ptp(points, axis=0).max()
    if not np.isfinite(R) or R > 1e3 * max(span, 1e-12):
        return None
    return c, R
