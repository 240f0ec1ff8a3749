"""A rigid obstacle given as a closed triangle surface file (shape = "file"): read once, checked to be closed,
moved by the obstacle's rigid motion. Its triangles meet the part's through the IPC Toolkit (ipc_surfaces.py),
so its corners and edges push on the part's faces as much as the part's nodes push on its faces."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fem_forms.errors import InputError
from fem_forms.meshes.surfaces import check_closed, merge_points, read_surface
from fem_forms.physics.contact.obstacles import Obstacle

SAMPLES = 64          # points tested for lying inside the other surface (enough once no triangles cross)


class FileObstacle(Obstacle):
    """The obstacle's rest points (n, 3) and triangles (m, 3); `points_at(t)` moves them rigidly."""

    def __init__(self, spec, key: str, max_triangles: int | None):
        super().__init__(spec)
        path = Path(spec.file)
        self.max_triangles = max_triangles      # the scene's cap (scene/limits.py; None: none), also once refined
        self.points, self.triangles = read_surface(path, f"{key}.file")
        if not len(self.triangles):
            raise InputError(f"{key}.file = {str(path)!r}: holds no triangles")
        if max_triangles is not None and len(self.triangles) > max_triangles:
            raise InputError(f"{key}.file = {str(path)!r}: {len(self.triangles):,} triangles, more than a scene "
                             f"may ask for ({max_triangles:,}); --no-limits lifts it")
        check_closed(self.points, self.triangles, f"{key}.file = {str(path)!r}",
                     hint="an obstacle must enclose a solid (repair it, e.g. with pymeshfix, or use a shape)")

    def refine(self, h: float, key: str) -> None:
        """Split every triangle into k x k (k = its longest edge / h, rounded up): the barrier weights each pair by
        the area of its pieces, so an obstacle's big triangles against the part's small ones push unevenly and
        jump as the part slides over their edges (a block on a two-triangle table needed 35 Newton iterations
        a step; refined, as few as on a plane)."""
        tri = self.points[self.triangles]
        longest = np.linalg.norm(tri - tri[:, [1, 2, 0]], axis=2).max(axis=1)
        ks = np.maximum(np.ceil(longest / h).astype(int), 1)
        if self.max_triangles is not None and int(np.sum(ks ** 2)) > self.max_triangles:
            raise InputError(f"{key}.file: refined to the part's surface edge ({h:.3g} m) it would have "
                             f"{int(np.sum(ks ** 2)):,} triangles, more than a scene may ask for "
                             f"({self.max_triangles:,}); use a shape, a smaller obstacle or a coarser part surface "
                             "(--no-limits lifts it)")
        points, triangles = [], []
        count = 0
        for (a, b, c), k in zip(tri, ks):
            ij = [(i, j) for j in range(k + 1) for i in range(k + 1 - j)]
            index = {q: count + n for n, q in enumerate(ij)}
            points.append(np.array([a + (b - a) * i / k + (c - a) * j / k for i, j in ij]))
            for i, j in ij:
                if i + j < k:
                    triangles.append([index[i, j], index[i + 1, j], index[i, j + 1]])
                if i + j < k - 1:
                    triangles.append([index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]])
            count += len(ij)
        self.points, self.triangles = merge_points(np.vstack(points), np.array(triangles))

    def points_at(self, t: float) -> np.ndarray:
        return self.points + self.offset_at(t)

    def current_points(self) -> np.ndarray:
        return self.points + self.offset


def winding_numbers(q: np.ndarray, points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The generalized winding number of the closed surface (points, triangles) at each point q (k, 3): 1 inside
    an outward-turned surface, -1 inside an inward-turned one, 0 outside (solid angles, Van Oosterom and
    Strackee 1983)."""
    tri = points[triangles]
    out = np.empty(len(q))
    for i, x in enumerate(q):
        a, b, c = tri[:, 0] - x, tri[:, 1] - x, tri[:, 2] - x
        la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        div = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la \
            + np.einsum("ij,ij->i", c, a) * lb
        out[i] = np.sum(2.0 * np.arctan2(det, div)) / (4.0 * np.pi)
    return out


def sample(points: np.ndarray) -> np.ndarray:
    """At most SAMPLES of the points, spread over the list."""
    return points[np.unique(np.linspace(0, len(points) - 1, min(SAMPLES, len(points))).astype(int))]


def inside(q: np.ndarray, points: np.ndarray, triangles: np.ndarray) -> bool:
    """Whether any of (a sample of) the points q lies inside the closed surface (either orientation)."""
    return bool(np.any(np.abs(winding_numbers(sample(q), points, triangles)) > 0.5))
