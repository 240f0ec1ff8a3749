"""Thick-walled sphere (inner radius a, outer b), one eighth of it: gmsh geometry and tetrahedral mesh.

The eighth x, y, z >= 0 of the shell a <= r <= b; its symmetry planes carry roller supports in the scene.
Named surfaces: "inner" (r = a, the pressure), "outer" (r = b), "x0", "y0", "z0" (symmetry planes).
`build_pair` writes two such shells, the second the first's mirror image through the origin (octant x, y, z <= 0):
both are closed by planes through the origin, so their inner walls can be one cavity, two balloons joined by a
tube of no volume, and the mesh is exactly symmetric.

    python verification/geometry/thick_sphere.py [--a 1] [--b 2] [--h 0.25] [--out thick_sphere.msh]
"""
import argparse
from pathlib import Path

import gmsh
import meshio
import numpy as np

from fem_forms.meshes.occ_parts import name_boundary, symmetry_plane


def build(out: Path, a: float = 1.0, b: float = 2.0, h: float = 0.25, pair: bool = False) -> Path:
    """Write the eighth shell's tetrahedral mesh (cell size h) to `out` (with `pair`, build_pair's)."""
    if pair:
        return build_pair(out, a, b, h)
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("thick_sphere")
        occ = gmsh.model.occ
        shell, _ = occ.cut([(3, occ.addSphere(0, 0, 0, b))], [(3, occ.addSphere(0, 0, 0, a))])
        eighth, _ = occ.intersect(shell, [(3, occ.addBox(0, 0, 0, b, b, b))])
        occ.synchronize()
        volume = eighth[0][1]
        gmsh.model.addPhysicalGroup(3, [volume], 1)
        name_boundary(gmsh, [volume], lambda box: symmetry_plane(box) or
                      ("outer" if max(box[3:]) > 0.5 * (a + b) else "inner"))
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", h)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMin", 0.5 * h)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out


def build_pair(out: Path, a: float = 1.0, b: float = 2.0, h: float = 0.25) -> Path:
    """Write the eighth shell and its mirror image through the origin as one mesh (gmsh 2.2 format, the same
    named groups over both) to `out`."""
    one = meshio.read(build(Path(out).with_suffix(".one.msh"), a, b, h))
    n = len(one.points)
    cells, physical, entity = [], [], []
    for k, block in enumerate(one.cells):
        order = [1, 0] + list(range(2, block.data.shape[1]))       # the inversion turns cells inside out
        cells.append((block.type, np.vstack([block.data, block.data[:, order] + n])))
        physical.append(np.tile(one.cell_data["gmsh:physical"][k], 2))
        tags = one.cell_data["gmsh:geometrical"][k]
        entity.append(np.concatenate([tags, tags + 1000]))
    pair = meshio.Mesh(np.vstack([one.points, -one.points]), cells, field_data=one.field_data,
                       cell_data={"gmsh:physical": physical, "gmsh:geometrical": entity})
    meshio.write(out, pair, file_format="gmsh22", binary=False)
    return Path(out)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--a", type=float, default=1.0)
    ap.add_argument("--b", type=float, default=2.0)
    ap.add_argument("--h", type=float, default=0.25)
    ap.add_argument("--out", type=Path, default=Path(__file__).with_name("thick_sphere.msh"))
    args = ap.parse_args()
    print(build(args.out, args.a, args.b, args.h))
