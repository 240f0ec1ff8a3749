"""What the verification meshes share: a half-thickness slab extruded from a planar surface, its boundary
surfaces named by a rule on their bounding boxes, then meshed and written."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import gmsh


def name_surfaces_and_write(names: dict[int, str], out: Path) -> None:
    """One physical surface group per distinct name (surface tag -> name), then a 3-D mesh written to `out`."""
    for i, name in enumerate(sorted(set(names.values()))):
        tag = gmsh.model.addPhysicalGroup(2, [s for s, n in names.items() if n == name], 10 + i)
        gmsh.model.setPhysicalName(2, tag, name)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(out))


def extrude_slab(surface: int, half_thickness: float, layers: int) -> int:
    """Extrude a recombined planar surface by half_thickness in z (hexahedra); the volume's tag."""
    ext = gmsh.model.occ.extrude([(2, surface)], 0, 0, half_thickness, numElements=[layers], recombine=True)
    gmsh.model.occ.synchronize()
    volume = [t for d, t in ext if d == 3][0]
    gmsh.model.addPhysicalGroup(3, [volume], 1)
    return volume


def slab_faces(volume: int, half_thickness: float, side: Callable[[tuple], str]) -> dict[int, str]:
    """Names of the slab's boundary surfaces: "bottom" (z = 0), "top" (z = half_thickness), and for the
    others whatever `side` says from their bounding box (xmin, ymin, zmin, xmax, ymax, zmax)."""
    names = {}
    for _, s in gmsh.model.getBoundary([(3, volume)], oriented=False):
        box = gmsh.model.getBoundingBox(2, s)
        if box[5] < 1e-6:
            names[s] = "bottom"
        elif box[2] > half_thickness - 1e-6:
            names[s] = "top"
        else:
            names[s] = side(box)
    return names
