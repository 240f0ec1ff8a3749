"""A two-material layout as files to make it from: the placed material's volume and the body's as STL surfaces
(ready for a mould or a slicer), the mesh with both as named volume groups (layout.msh: a plain static scene reads
it with [[material]] where = { group = NAME }) and a picture. Rank 0 writes from the gathered cells."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fem_forms.output.stl import write_stl

# each cell's faces as vertex positions in DOLFINx's reference ordering (hexahedra: tensor-product order)
FACES = {"tetrahedron": [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)],
         "hexahedron": [(0, 1, 3, 2), (0, 1, 5, 4), (0, 2, 6, 4), (1, 3, 7, 5), (2, 3, 7, 6), (4, 5, 7, 6)]}
VERTICES = {"tetrahedron": 4, "hexahedron": 8}
GMSH_TYPE = {"tetrahedron": "tetra", "hexahedron": "hexahedron"}
TO_GMSH = {"tetrahedron": [0, 1, 2, 3], "hexahedron": [0, 1, 3, 2, 4, 5, 7, 6]}     # DOLFINx -> gmsh/VTK order


def gathered_cells(mesh, order: np.ndarray) -> np.ndarray | None:
    """Every cell's vertex positions (cells x vertices x 3) in the design's cell order, on rank 0 (None elsewhere)."""
    tdim = mesh.topology.dim
    nown = mesh.topology.index_map(tdim).size_local
    nv = VERTICES[mesh.topology.cell_name()]
    nodes = mesh.geometry.dofmap.array.reshape(-1, mesh.geometry.dofmap.links(0).size)[:nown, :nv]
    mine = mesh.geometry.x[nodes]
    every = mesh.comm.gather(mine, root=0)
    return None if mesh.comm.rank else np.concatenate(every)[order]


def _numbered(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distinct points, cells as point indices): vertices shared by cells merged by position."""
    flat = cells.reshape(-1, 3)
    scale = max(float(np.ptp(flat)), 1e-300)
    _, first, index = np.unique(np.round(flat / (1e-9 * scale)), axis=0, return_index=True, return_inverse=True)
    return flat[first], index.reshape(cells.shape[:2])


def boundary_triangles(points: np.ndarray, ids: np.ndarray, member: np.ndarray, cell_name: str) -> np.ndarray:
    """The triangles bounding the member cells (faces only one member cell has), oriented outward."""
    faces, owner = [], []
    for f in FACES[cell_name]:
        faces.append(ids[:, f])
        owner.append(np.arange(len(ids)))
    faces, owner = np.concatenate(faces), np.concatenate(owner)
    keep = member[owner]
    faces, owner = faces[keep], owner[keep]
    _, inverse, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
    single = counts[inverse] == 1
    faces, owner = faces[single], owner[single]
    tris = faces[:, :3] if faces.shape[1] == 3 else np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    cell = owner if faces.shape[1] == 3 else np.concatenate([owner, owner])
    p = points[tris]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    outward = np.einsum("ij,ij->i", normal, p.mean(axis=1) - points[ids[cell]].mean(axis=1)) > 0
    tris[~outward] = tris[~outward][:, ::-1]
    return tris


def write_layout_files(out: Path, mesh, order: np.ndarray, placed: np.ndarray, names: tuple[str, str],
                       picture: bool = True) -> dict:
    """placed.stl, body.stl, layout.msh and (with `picture`) layout.png for the cells `placed` (design order) of
    the placed material names[1] in the body names[0]; {what: file name}."""
    cells = gathered_cells(mesh, order)
    files = {"placed_stl": "placed.stl", "body_stl": "body.stl", "layout_mesh": "layout.msh"}
    if picture:
        files["layout_picture"] = "layout.png"
    if mesh.comm.rank == 0:
        cell_name = mesh.topology.cell_name()
        points, ids = _numbered(cells)
        placed = np.asarray(placed, dtype=bool)
        surfaces = {}
        for key, member, name in (("placed_stl", placed, names[1]), ("body_stl", ~placed, names[0])):
            tris = boundary_triangles(points, ids, member, cell_name)
            write_stl(out / files[key], points, tris, name)
            surfaces[name] = tris
        _write_msh(out / files["layout_mesh"], points, ids, placed, names, cell_name)
        if picture:
            _picture(out / files["layout_picture"], points, surfaces, names)
    mesh.comm.barrier()
    return files


def _write_msh(path: Path, points: np.ndarray, ids: np.ndarray, placed: np.ndarray, names, cell_name: str) -> None:
    import meshio
    tags = np.where(placed, 2, 1).astype(int)
    m = meshio.Mesh(points, [(GMSH_TYPE[cell_name], ids[:, TO_GMSH[cell_name]])],
                    cell_data={"gmsh:physical": [tags], "gmsh:geometrical": [tags]},
                    field_data={names[0]: np.array([1, 3]), names[1]: np.array([2, 3])})
    meshio.write(path, m, file_format="gmsh22", binary=False)


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

