"""The designed rest shape as a fabricable object: volume mesh and STL files, and the checks that a
mathematically valid rest shape is also a usable one (no crossing of a support plane, no
self-intersection of its surface)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

GMSH_TYPES = {"tetrahedron": (4, 2), "hexahedron": (5, 3)}      # cell -> (gmsh type of the cell, of a face)


def write_volume_mesh(path: Path, points: np.ndarray, cells: np.ndarray, cell_type: str,
                      facet_groups: dict | None = None, cell_groups: dict | None = None) -> None:
    """A gmsh .msh (format 2.2, binary) with named boundary groups (and named volume groups: rows of
    `cells`, e.g. one per material), that `generator = "file"` reads back. Written with numpy: the same
    bytes meshio wrote (checked on the Chen arm), without meshio's import (0.1-0.25 s of every inverse
    run); binary rather than ASCII: 0.2 s -> 0.002 s for 9,225 points."""
    cell_kind, face_kind = GMSH_TYPES[cell_type]
    cells = np.asarray(cells)
    names = []
    if cell_groups:
        blocks = []
        for k, (name, rows) in enumerate(cell_groups.items()):
            blocks.append((cell_kind, 100 + k, cells[rows]))
            names.append(f'3 {100 + k} "{name}"\n')
    else:
        blocks = [(cell_kind, 1, cells)]
    for k, (name, faces) in enumerate((facet_groups or {}).items()):
        blocks.append((face_kind, 10 + k, np.asarray(faces)))
        names.append(f'2 {10 + k} "{name}"\n')
    nodes = np.empty(len(points), dtype=[("id", "<i4"), ("x", "<f8", 3)])
    nodes["id"] = np.arange(1, len(points) + 1)
    nodes["x"] = points
    parts = [b"$MeshFormat\n2.2 1 8\n", np.int32(1).tobytes(), b"\n$EndMeshFormat\n"]
    if names:
        parts.append(f"$PhysicalNames\n{len(names)}\n{''.join(names)}$EndPhysicalNames\n".encode())
    parts += [f"$Nodes\n{len(points)}\n".encode(), nodes.tobytes(), b"\n$EndNodes\n",
              f"$Elements\n{sum(len(c) for _, _, c in blocks)}\n".encode()]
    first = 1
    for kind, tag, conn in blocks:
        if not len(conn):
            continue
        rows = np.empty((len(conn), 3 + conn.shape[1]), dtype="<i4")
        rows[:, 0] = np.arange(first, first + len(conn))          # element number, then its two tags
        rows[:, 1:3] = tag                                         # (physical = geometrical)
        rows[:, 3:] = conn + 1
        parts += [np.array([kind, len(conn), 2], dtype="<i4").tobytes(), rows.tobytes()]
        first += len(conn)
    parts.append(b"\n$EndElements\n")
    Path(path).write_bytes(b"".join(parts))


def crosses_support_plane(rest: np.ndarray, target: np.ndarray, axis: int, at: float, tol: float) -> float:
    """How far (>= 0) rest vertices reach through a support plane to the side the target body is not on."""
    side = np.sign(np.mean(target[:, axis]) - at) or 1.0
    depth = -side * (rest[:, axis] - at)
    return float(max(depth.max() - tol, 0.0))


def _tri_segment_hits(t0, t1, t2, s0, s1, eps=1e-12) -> np.ndarray:
    """Vectorised: does segment s0-s1 cross triangle (t0, t1, t2) at an interior point?"""
    e1, e2, d = t1 - t0, t2 - t0, s1 - s0
    h = np.cross(d, e2)
    a = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(a) > eps * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(d, axis=1)
    f = np.where(ok, 1.0 / np.where(ok, a, 1.0), 0.0)
    s = s0 - t0
    u = f * np.einsum("ij,ij->i", s, h)
    q = np.cross(s, e1)
    v = f * np.einsum("ij,ij->i", d, q)
    t = f * np.einsum("ij,ij->i", e2, q)
    m = 1e-9
    return ok & (u > m) & (v > m) & (u + v < 1 - m) & (t > m) & (t < 1 - m)


def self_intersections(points: np.ndarray, tris: np.ndarray, max_pairs: int = 20_000_000) -> int:
    """Number of pairs of surface triangles sharing no vertex that cross each other (an edge of one
    passes through the other). Candidate pairs come from a uniform grid of triangle bounding boxes."""
    if not len(tris):
        return 0
    p = points[tris]
    lo, hi = p.min(axis=1), p.max(axis=1)
    size = np.median(hi - lo, axis=0).max() * 2 + 1e-300
    cell_lo = np.floor(lo / size).astype(np.int64)
    cell_hi = np.floor(hi / size).astype(np.int64)
    # every (triangle, grid cell) its bounding box touches, as arrays
    span = cell_hi - cell_lo + 1
    count = span.prod(axis=1)
    tri = np.repeat(np.arange(len(tris)), count)
    local = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    sp = span[tri]
    cell = cell_lo[tri] + np.stack([local % sp[:, 0], (local // sp[:, 0]) % sp[:, 1],
                                    local // (sp[:, 0] * sp[:, 1])], axis=1)
    cell -= cell.min(axis=0)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")          # triangles ascending inside each grid cell
    key, tri = key[order], tri[order]
    # all pairs inside each grid cell: entry p pairs with the later entries of its cell
    start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    end = np.r_[start[1:], len(key)]
    later = np.repeat(end, end - start) - np.arange(len(key)) - 1
    later = later[: np.searchsorted(np.cumsum(later), max_pairs, side="right") + 1]
    first = np.repeat(np.arange(len(later)), later)
    second = first + 1 + np.arange(len(first)) - np.repeat(np.cumsum(later) - later, later)
    if not len(first):
        return 0
    a, b = tri[first], tri[second]
    pair = np.unique(np.minimum(a, b) * len(tris) + np.maximum(a, b))
    pa = np.stack([pair // len(tris), pair % len(tris)], axis=1)
    A, B = pa[:, 0], pa[:, 1]
    overlap = np.all((lo[A] <= hi[B]) & (lo[B] <= hi[A]), axis=1)
    share = (tris[A][:, :, None] == tris[B][:, None, :]).any(axis=(1, 2))
    A, B = A[overlap & ~share], B[overlap & ~share]
    hit = np.zeros(len(A), dtype=bool)
    for X, Y in ((A, B), (B, A)):
        for e in ((0, 1), (1, 2), (2, 0)):
            hit |= _tri_segment_hits(p[Y, 0], p[Y, 1], p[Y, 2], p[X, e[0]], p[X, e[1]])
    return int(hit.sum())
