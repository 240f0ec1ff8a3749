"""Surface meshes in (STL, OBJ, PLY, OFF): a closed triangulated surface tetrahedralised with gmsh.

The surface is read with meshio (its warnings kept off the user's terminal), duplicate points
merged, checked to be closed (every edge shared by exactly two triangles; an open one is refused with
the hint to set `repair = true`, see repair.py), then handed to gmsh as a
discrete surface: classifySurfaces, createGeometry, a surface loop and a volume, generate(3). Cell
quality (radius ratio, 1 for a regular tetrahedron) is reported with the cell count.
"""
from __future__ import annotations

import contextlib
import io
import logging
import math
from pathlib import Path
import warnings

import numpy as np

from fem_forms.errors import InputError

REPAIR_HINT = "set [mesh] repair = true to fill holes and remove bad faces"
FEATURE_ANGLE = 40.0        # degrees: sharper creases between facets become edges of the geometry


@contextlib.contextmanager
def quiet_meshio():
    """meshio prints its warnings (e.g. "Appending zeros to replace the missing physical tag data")
    to sys.stderr through rich, some readers print to stdout, others use `logging` or `warnings`: none
    of it reaches the terminal while meshio runs."""
    previous = logging.root.manager.disable
    logging.disable(logging.WARNING)
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()):
            warnings.simplefilter("ignore")
            yield
    finally:
        logging.disable(previous)


def read_meshio(path: Path, key: str = "mesh.file"):
    """meshio.read, silenced, with a read failure as a one-line InputError naming the scene's `key`."""
    import meshio
    try:
        with quiet_meshio():
            return meshio.read(path)
    except (Exception, SystemExit) as e:    # noqa: BLE001 - any reader failure is bad input (meshio's VTU
        # reader calls sys.exit(1) on malformed XML: that must not end one rank and hang the others)
        why = " ".join(str(e).split())[:200] or "malformed file"
        raise InputError(f"{key} = {str(path)!r}: cannot read it ({type(e).__name__}: {why})") from None


def read_triangles(path: Path, key: str = "mesh.file") -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) and triangles (m, 3) of a surface file as written, quads split in two."""
    m = read_meshio(path, key)
    tris = [np.asarray(b.data)[:, :3] for b in m.cells if b.type == "triangle"]
    for b in m.cells:
        if b.type == "quad":
            q = np.asarray(b.data)
            tris += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    if not tris:
        found = ", ".join(sorted({b.type for b in m.cells})) or "nothing"
        raise InputError(f"{key} = {str(path)!r}: needs a triangulated surface (found: {found})")
    pts = np.asarray(m.points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InputError(f"{key} = {str(path)!r}: points must have 3 coordinates")
    return pts, np.vstack(tris).astype(np.int64)


def merge_points(pts: np.ndarray, tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points closer than 1e-9 of the surface's size merged (STL repeats every vertex per facet), and
    the triangles this collapses to an edge or a point dropped."""
    scale = max(float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))), 1e-300)
    _, first, inverse = np.unique(np.round(pts / (1e-9 * scale)), axis=0, return_index=True,
                                  return_inverse=True)
    tris = inverse.ravel()[tris]
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    return pts[first], tris[keep]


def read_surface(path: Path, key: str = "mesh.file") -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) and triangles (m, 3) of a surface file, quads split, duplicate points merged."""
    return merge_points(*read_triangles(path, key))


def check_closed(points: np.ndarray, tris: np.ndarray, key: str, hint: str = REPAIR_HINT) -> None:
    """Every edge must belong to exactly two triangles: open edges (a hole) and edges shared by more
    than two (not a manifold) are refused, counted, with where the first one is."""
    edges = np.sort(np.vstack([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    uniq, counts = np.unique(edges, axis=0, return_counts=True)
    for bad, what in ((counts == 1, "open"), (counts > 2, "non-manifold (shared by 3+ triangles)")):
        if bad.any():
            where = np.round(points[uniq[bad][0]].mean(axis=0), 6).tolist()
            raise InputError(f"{key}: the surface is not closed: {int(bad.sum())} {what} edges, the first "
                             f"near {where}; a solid needs a watertight surface: {hint}")


def enclosed_volume(points: np.ndarray, tris: np.ndarray) -> float:
    """Volume inside a closed triangulated surface (divergence theorem)."""
    p = points[tris]
    return abs(float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum()) / 6.0)


def mean_edge(points: np.ndarray, tris: np.ndarray) -> float:
    p = points[tris]
    return float(np.mean(np.linalg.norm(p - p[:, [1, 2, 0]], axis=2)))


def tetrahedralise(points: np.ndarray, tris: np.ndarray, h: float, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Linear tetrahedra filling a closed surface at target size h: (points, cells)."""
    import gmsh
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("surface")
        surf = gmsh.model.addDiscreteEntity(2)
        gmsh.model.mesh.addNodes(2, surf, list(range(1, len(points) + 1)), points.ravel().tolist())
        gmsh.model.mesh.addElementsByType(surf, 2, [], (tris + 1).ravel().tolist())
        gmsh.model.mesh.classifySurfaces(math.radians(FEATURE_ANGLE), True, True, math.pi)
        gmsh.model.mesh.createGeometry()
        loop = gmsh.model.geo.addSurfaceLoop([t for _, t in gmsh.model.getEntities(2)])
        gmsh.model.geo.addVolume([loop])
        gmsh.model.geo.synchronize()
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", h)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMin", h / 4)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        try:
            gmsh.model.mesh.generate(3)
        except Exception as e:                                   # noqa: BLE001 - gmsh raises plain Exception
            raise InputError(f"{key}: gmsh could not fill the surface with tetrahedra ({e})") from None
        tags, coords, _ = gmsh.model.mesh.getNodes()
        types, _, nodes = gmsh.model.mesh.getElements(3)
        tets = [np.asarray(n, dtype=np.int64).reshape(-1, 4) for t, n in zip(types, nodes) if t == 4]
        if not tets:
            raise InputError(f"{key}: gmsh made no tetrahedra from the surface")
        index = np.full(int(np.max(tags)) + 1, -1, dtype=np.int64)
        index[np.asarray(tags, dtype=np.int64)] = np.arange(len(tags))
        return np.asarray(coords, dtype=float).reshape(-1, 3), index[np.vstack(tets)]
    finally:
        gmsh.finalize()


def radius_ratio(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """3 r_in / r_circ of each tetrahedron: 1 for a regular one, 0 for a flat one."""
    p = points[cells]
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    vol6 = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    faces = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
    area = sum(0.5 * np.linalg.norm(np.cross(p[:, j] - p[:, i], p[:, k] - p[:, i]), axis=1) for i, j, k in faces)
    r_in = vol6 / (2.0 * np.maximum(area, 1e-300))
    # circumradius: |a|^2 (b x c) + |b|^2 (c x a) + |c|^2 (a x b) over 2 * 6V
    num = (np.einsum("ij,ij->i", a, a)[:, None] * np.cross(b, c) + np.einsum("ij,ij->i", b, b)[:, None]
           * np.cross(c, a) + np.einsum("ij,ij->i", c, c)[:, None] * np.cross(a, b))
    r_circ = np.linalg.norm(num, axis=1) / np.maximum(2.0 * vol6, 1e-300)
    return 3.0 * r_in / np.maximum(r_circ, 1e-300)


def quality(points: np.ndarray, cells: np.ndarray) -> dict:
    """Cell count and radius-ratio quality (min, mean) of a tetrahedral mesh."""
    q = radius_ratio(points, cells)
    return {"cells": int(len(cells)), "radius_ratio_min": round(float(q.min()), 4),
            "radius_ratio_mean": round(float(q.mean()), 4)}
