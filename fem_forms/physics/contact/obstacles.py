"""Rigid analytic obstacles (plane, sphere, box, infinite cylinder) as signed distance functions: the distance
of each surface point to the obstacle (negative inside it), its gradient and Hessian for the barrier, a
conservative step filter (no step may take a point into the obstacle), and the obstacle's rigid motion.
Plain numpy on the gathered surface points."""
from __future__ import annotations

import numpy as np

from fem_forms.physics.histories import piecewise_linear

KEEP = 0.1          # a step filtered by `safe_fraction` leaves every point at least this share of its gap


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def translation(motion: list | None, t: float) -> np.ndarray:
    """A rigid obstacle's translation at time t from its `motion` rows [t, dx, dy, dz], piecewise linear, held
    after the last row (zero without a motion)."""
    if not motion:
        return np.zeros(3)
    return np.array([piecewise_linear([[r[0], r[1 + k]] for r in motion], t) for k in range(3)])


class Obstacle:
    """One rigid obstacle: `distance_terms(p)` gives the signed distance d, grad d and the Hessian of d at the
    points p (n, 3) with the obstacle at its current offset (`move_to(t)`). With `only` (a mask of the surface's
    points: [contact] where) the other points are infinitely far from it, wherever the whole surface is asked."""
    only: np.ndarray | None = None

    def __init__(self, spec):
        self.name, self.shape, self.friction = spec.name, spec.shape, float(spec.friction)
        self.motion = [list(r) for r in spec.motion] if spec.motion else None
        self.offset = np.zeros(3)

    def offset_at(self, t: float) -> np.ndarray:
        """The obstacle's translation at time t (zero without a motion; held after the last row)."""
        return translation(self.motion, t)

    def move_to(self, t: float) -> None:
        self.offset = self.offset_at(t)

    def _seen(self, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        """d with the points `only` leaves out at infinity, when p is the whole surface (a caller passes either the
        whole surface or a subset it chose by these distances, which holds no left-out point)."""
        return d if self.only is None or len(p) != len(self.only) else np.where(self.only, d, np.inf)

    def distance(self, p: np.ndarray) -> np.ndarray:
        return self._seen(p, self.distance_terms(p - self.offset, order=0)[0])

    def derivatives(self, p: np.ndarray, order: int = 2):
        """d, grad d (n, 3) and (order 2) Hessian of d (n, 3, 3) at the points p."""
        d, *rest = self.distance_terms(p - self.offset, order=order)
        return (self._seen(p, d), *rest)

    def distance_terms(self, p: np.ndarray, order: int):
        raise NotImplementedError

    def safe_fraction(self, p0: np.ndarray, dp: np.ndarray) -> float:
        """The largest s in (0, 1] such that every point p0 + s' dp (s' <= s) keeps at least KEEP of its gap:
        conservative advancement (a signed distance changes no faster than the point moves)."""
        d0 = self.distance(p0)
        speed = np.linalg.norm(dp, axis=1)
        risky = speed * 1.0 > (1.0 - KEEP) * d0
        if not risky.any():
            return 1.0
        p0, dp, d0, speed = p0[risky], dp[risky], d0[risky], speed[risky]
        s = np.zeros(len(p0))
        floor = KEEP * d0
        for _ in range(200):
            d = self.distance(p0 + s[:, None] * dp)
            step = (d - floor) / speed
            s = np.minimum(s + np.maximum(step, 0.0), 1.0)
            if np.all((s >= 1.0) | (step <= 1e-6 * np.maximum(s, 1e-3))):
                break
        return float(max(s.min(), 0.0))


class Plane(Obstacle):
    """A half space: the part stays on the side the normal points to."""

    def __init__(self, spec):
        super().__init__(spec)
        self.point, self.normal = np.asarray(spec.point, float), _unit(spec.normal)

    def distance_terms(self, p, order):
        d = (p - self.point) @ self.normal
        if order == 0:
            return (d,)
        g = np.broadcast_to(self.normal, p.shape).copy()
        return (d, g) if order == 1 else (d, g, np.zeros((len(p), 3, 3)))

    def safe_fraction(self, p0, dp):
        d0, rate = self.distance(p0), dp @ self.normal        # exact: d is linear along the step
        closing = rate < 0.0
        if not closing.any():
            return 1.0
        return float(min(1.0, max(0.0, np.min((1.0 - KEEP) * d0[closing] / -rate[closing]))))   # 0: already in


def _radial(r: np.ndarray, order: int, radius: float, project=None):
    """d = |r| - radius with its derivatives, r the point's offset from the centre (or axis); `project` removes
    the axis direction from the Hessian of a cylinder."""
    rn = np.maximum(np.linalg.norm(r, axis=1), 1e-300)
    d = rn - radius
    if order == 0:
        return (d,)
    n = r / rn[:, None]
    if order == 1:
        return d, n
    P = np.eye(3) if project is None else project
    H = (P[None] - n[:, :, None] * n[:, None, :]) / rn[:, None, None]
    return d, n, H


class Sphere(Obstacle):
    def __init__(self, spec):
        super().__init__(spec)
        self.center, self.radius = np.asarray(spec.center, float), float(spec.radius)

    def distance_terms(self, p, order):
        return _radial(p - self.center, order, self.radius)


class Cylinder(Obstacle):
    """An infinite circular cylinder about the line through `point` along `axis`."""

    def __init__(self, spec):
        super().__init__(spec)
        self.point, self.axis, self.radius = np.asarray(spec.point, float), _unit(spec.axis), float(spec.radius)

    def distance_terms(self, p, order):
        r = p - self.point
        r = r - np.outer(r @ self.axis, self.axis)
        return _radial(r, order, self.radius, project=np.eye(3) - np.outer(self.axis, self.axis))


class Box(Obstacle):
    """An axis-aligned solid box [min, max]."""

    def __init__(self, spec):
        super().__init__(spec)
        lo, hi = np.asarray(spec.min, float), np.asarray(spec.max, float)
        self.center, self.half = (lo + hi) / 2, (hi - lo) / 2

    def distance_terms(self, p, order):
        r = p - self.center
        q = np.abs(r) - self.half                      # > 0 on the axes where the point is beyond a face
        outside = np.maximum(q, 0.0)
        dout = np.linalg.norm(outside, axis=1)
        inside = np.minimum(q.max(axis=1), 0.0)
        d = dout + inside
        if order == 0:
            return (d,)
        sign = np.where(r >= 0, 1.0, -1.0)
        g = np.zeros_like(p)
        out = dout > 0
        g[out] = sign[out] * outside[out] / dout[out, None]
        k = np.argmax(q[~out], axis=1)                 # inside: the nearest face's normal
        g[np.flatnonzero(~out), k] = sign[~out][np.arange(len(k)), k]
        if order == 1:
            return d, g
        H = np.zeros((len(p), 3, 3))
        active = (q > 0).astype(float)
        H[out] = ((active[out][:, :, None] * np.eye(3)[None]) - g[out][:, :, None] * g[out][:, None, :]) \
            / dout[out, None, None]
        return d, g, H


SHAPES = {"plane": Plane, "sphere": Sphere, "box": Box, "cylinder": Cylinder}


def make_obstacle(spec) -> Obstacle:
    """The analytic obstacle of a [[contact.obstacle]] table."""
    return SHAPES[spec.shape](spec)
