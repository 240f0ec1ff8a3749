"""A quarter of a centre-cracked plate for phase-field fracture: x in [0, W/2], y in [0, H/2], one layer of
cells through the thickness t (z), fine cells (h_fine, about l/3) in the band 0 <= y <= 4 l where the crack
lies and runs, coarse (h_coarse) elsewhere. The crack is on the symmetry plane y = 0; the scene holds
u_x = 0 on x = 0 and u_y = 0 on y = 0 and gives damage 1 on the crack's nodes (y = 0, x <= a).

    python verification/geometry/centre_crack.py [--h-fine 0.0033] [--ell 0.01] [--out centre_crack.msh]
"""
import argparse
from pathlib import Path

import gmsh

from fem_forms.meshes.occ_parts import fine_in_box


def build(out: Path, half_width: float = 0.5, half_height: float = 0.75, thickness: float = 0.01,
          ell: float = 0.01, h_fine: float = 0.0033, h_coarse: float = 0.05) -> Path:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("centre_crack")
        occ = gmsh.model.occ
        s = occ.addRectangle(0, 0, 0, half_width, half_height)
        occ.synchronize()
        fine_in_box(gmsh, {"XMin": 0.0, "XMax": half_width, "YMin": 0.0, "YMax": 4 * ell,
                           "Thickness": 0.1 * half_height}, h_fine, h_coarse)
        occ.extrude([(2, s)], 0, 0, thickness, numElements=[1])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [t for _, t in gmsh.model.getEntities(3)], 1)
        gmsh.model.mesh.generate(3)
        out = Path(out)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--h-fine", type=float, default=0.0033)
    p.add_argument("--ell", type=float, default=0.01)
    p.add_argument("--out", default="centre_crack.msh")
    a = p.parse_args()
    print(build(Path(a.out), ell=a.ell, h_fine=a.h_fine))
