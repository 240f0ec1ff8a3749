"""A two-material layout as files to make it from: the placed material's volume and the body's as STL surfaces
(ready for a mould or a slicer), the mesh with both as named volume groups (layout.msh: a plain static scene reads
it with [[material]] where = { group = NAME }) and a picture. Rank 0 writes from the gathered mesh, with the
surface and .msh writers the inverse design's rest shape uses."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fem_forms.design.rest_shape import write_volume_mesh
from fem_forms.meshes.cell_faces import boundary_faces, triangles
from fem_forms.output.fields import gather_mesh
from fem_forms.output.stl import write_stl

VERTICES = {"tetrahedron": 4, "hexahedron": 8}


def positively_oriented(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """The cells (VTK/gmsh vertex order) reordered where their volume is negative, so that rest_shape's
    boundary_faces come out outward (a box mesh's tetrahedra have either orientation)."""
    p = points[cells]
    if cells.shape[1] == 4:
        volume = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
        swap = [0, 2, 1, 3]
    else:
        volume = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 3] - p[:, 0]), p[:, 4] - p[:, 0])
        swap = [4, 5, 6, 7, 0, 1, 2, 3]
    out = cells.copy()
    out[volume < 0] = cells[volume < 0][:, swap]
    return out


def write_layout_files(out: Path, mesh, order: np.ndarray, placed: np.ndarray, names: tuple[str, str],
                       picture: bool = True, facet_groups: dict | None = None) -> dict:
    """placed.stl, body.stl, layout.msh and (with `picture`) layout.png for the cells `placed` (design order) of
    the placed material names[1] in the body names[0]; {what: file name}. layout.msh keeps `facet_groups` (rank 0:
    the scene mesh's named boundaries, as fields.gather_facet_groups gives them) for the scene's supports and loads."""
    gathered = gather_mesh(mesh)
    files = {"placed_stl": "placed.stl", "body_stl": "body.stl", "layout_mesh": "layout.msh"}
    if picture:
        files["layout_picture"] = "layout.png"
    if mesh.comm.rank == 0:
        points, cells, cell_name = gathered
        cells = positively_oriented(points, cells[:, :VERTICES[cell_name]])
        member = np.empty(len(cells), dtype=bool)
        member[order] = np.asarray(placed, dtype=bool)        # the design's order -> gather_mesh's (rank order)
        surfaces = {}
        for key, chosen, name in (("placed_stl", member, names[1]), ("body_stl", ~member, names[0])):
            tris = triangles(boundary_faces(cells[chosen], cell_name)) if chosen.any() else np.empty((0, 3), int)
            write_stl(out / files[key], points, tris, name)
            surfaces[name] = tris
        write_volume_mesh(out / files["layout_mesh"], points, cells, cell_name,
                          facet_groups=facet_groups, cell_groups={names[0]: ~member, names[1]: member})
        if picture:
            _picture(out / files["layout_picture"], points, surfaces, names)
    mesh.comm.barrier()
    return files


def _picture(path: Path, points: np.ndarray, surfaces: dict, names) -> None:
    """The placed material's surface in colour inside the body's, seen from two sides."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    fig = plt.figure(figsize=(10, 4.5))
    lo, hi = points.min(axis=0), points.max(axis=0)
    for k, (elev, azim) in enumerate(((25, -60), (-25, 120))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(points[surfaces[names[0]]], facecolor=(0.7, 0.7, 0.7, 0.12),
                                             edgecolor=(0.5, 0.5, 0.5, 0.15), linewidths=0.2))
        ax.add_collection3d(Poly3DCollection(points[surfaces[names[1]]], facecolor=(0.85, 0.33, 0.1, 0.9),
                                             edgecolor=(0.4, 0.15, 0.05, 0.5), linewidths=0.2))
        ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(np.maximum(hi - lo, 1e-3 * np.max(hi - lo)))
        ax.view_init(elev, azim)
        ax.locator_params(nbins=3)
        ax.set_xlabel("x (m)"), ax.set_ylabel("y (m)"), ax.set_zlabel("z (m)")
    fig.suptitle(f"{names[1]} (orange) placed in {names[0]} (grey)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

