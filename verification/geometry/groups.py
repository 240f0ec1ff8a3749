"""What the verification meshes share: named surface groups from a classification, then mesh and write."""
from __future__ import annotations

from pathlib import Path

import gmsh


def name_surfaces_and_write(names: dict[int, str], out: Path) -> None:
    """One physical surface group per distinct name (surface tag -> name), then a 3-D mesh written to `out`."""
    for i, name in enumerate(sorted(set(names.values()))):
        tag = gmsh.model.addPhysicalGroup(2, [s for s, n in names.items() if n == name], 10 + i)
        gmsh.model.setPhysicalName(2, tag, name)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(out))
