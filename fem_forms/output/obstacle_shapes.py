"""The contact obstacles as triangles where they are now, for pictures: a plane as a square under the part, a
sphere, a box, a length of cylinder along the part, an obstacle file as its own triangles; sized by the part's
bounding box, so the picture shows what the part touches without drawing to infinity."""
from __future__ import annotations

import numpy as np

from fem_forms.physics.contact.friction import tangent_basis

ROUND = 24              # segments around a sphere or a cylinder


def _plane(point, normal, centre, size) -> tuple:
    foot = centre - ((centre - point) @ normal) * normal
    t = tangent_basis(normal[None])[0].T * 0.7 * size          # two in-plane half sides
    points = np.array([foot - t[0] - t[1], foot + t[0] - t[1], foot + t[0] + t[1], foot - t[0] + t[1]])
    return points, np.array([[0, 1, 2], [0, 2, 3]])


def _sphere(center, radius) -> tuple:
    theta = np.linspace(0.0, np.pi, ROUND // 2 + 1)
    phi = np.linspace(0.0, 2 * np.pi, ROUND, endpoint=False)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    unit = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3)
    points = center + radius * unit
    return points, _grid(len(theta), len(phi))


def _cylinder(point, axis, radius, centre, size) -> tuple:
    mid = point + ((centre - point) @ axis) * axis
    t = tangent_basis(axis[None])[0].T
    phi = np.linspace(0.0, 2 * np.pi, ROUND, endpoint=False)
    ring = radius * (np.cos(phi)[:, None] * t[0] + np.sin(phi)[:, None] * t[1])
    ends = [mid - 0.7 * size * axis, mid + 0.7 * size * axis]
    points = np.vstack([e + ring for e in ends])
    return points, _grid(2, ROUND)


def _grid(rows: int, cols: int) -> np.ndarray:
    """Triangles of a rows x cols grid of points closed around its columns (a sphere's or a tube's)."""
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(cols), indexing="ij")
    a, b = i * cols + j, i * cols + (j + 1) % cols
    c, d = a + cols, b + cols
    return np.vstack([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])


def _box(center, half) -> tuple:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return center + corners * half, np.array([t for q in faces for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])])


def obstacle_surfaces(model, points: np.ndarray) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, points, triangles) of each of the model's contact obstacles at their current positions, sized by
    the part's `points` (its surface, deformed or not); [] without contact."""
    term = next((t for t in model.terms if t.role == "contact"), None)
    if term is None:
        return []
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    out = []
    for ob in term.obstacles:
        off = ob.offset
        if ob.shape == "plane":
            out.append((ob.name, *_plane(ob.point + off, ob.normal, centre, size)))
        elif ob.shape == "sphere":
            out.append((ob.name, *_sphere(ob.center + off, ob.radius)))
        elif ob.shape == "box":
            out.append((ob.name, *_box(ob.center + off, ob.half)))
        else:
            out.append((ob.name, *_cylinder(ob.point + off, ob.axis, ob.radius, centre, size)))
    for ob in term.files:
        out.append((ob.name, ob.current_points(), ob.triangles))
    return out
