"""NAFEMS LE1 (elliptic membrane): gmsh geometry and mesh, written as le1.msh beside this script.

The plate lies between the ellipses (x/2)^2 + (y/1)^2 = 1 and (x/3.25)^2 + (y/2.75)^2 = 1 in the first
quadrant. It is meshed as a slab of half the plate's thickness (0 <= z <= 0.05 m of the 0.1 m plate):
the scene holds w = 0 on z = 0, the plate's mid-plane, so the slab is the upper half of the symmetric
plate (plane stress: the top face z = 0.05 is free). Structured hexahedra: `n_arc` cells along the
ellipses (graded towards y = 0, where point D = (2, 0) carries the stress peak), `n_radial` across,
`n_z` through the half thickness.

Named surfaces: "inner", "outer" (the loaded edge), "x0" (x = 0), "y0" (y = 0), "bottom" (z = 0), "top".

    python verification/geometry/le1.py [--n-arc 24] [--n-radial 8] [--n-z 1] [--out le1.msh]
"""
import argparse
import math
from pathlib import Path

import gmsh

from groups import extrude_slab, name_surfaces_and_write, slab_faces

HALF_THICKNESS = 0.05


def build(out: Path, n_arc: int = 24, n_radial: int = 8, n_z: int = 1, grading: float = 1.08) -> Path:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("nafems_le1")
        occ = gmsh.model.occ
        inner = occ.addEllipse(0, 0, 0, 2.0, 1.0, angle1=0.0, angle2=math.pi / 2)
        outer = occ.addEllipse(0, 0, 0, 3.25, 2.75, angle1=0.0, angle2=math.pi / 2)
        occ.synchronize()
        # end points of the arcs: inner (2,0)->(0,1), outer (3.25,0)->(0,2.75)
        pi0, pi1 = [t for _, t in gmsh.model.getBoundary([(1, inner)], oriented=True)]
        po0, po1 = [t for _, t in gmsh.model.getBoundary([(1, outer)], oriented=True)]
        y0 = occ.addLine(pi0, po0)
        x0 = occ.addLine(po1, pi1)
        loop = occ.addCurveLoop([inner, x0, outer, y0])
        surf = occ.addPlaneSurface([loop])
        occ.synchronize()
        mesh = gmsh.model.mesh
        # arcs: both run from y = 0 to x = 0; cells smallest at y = 0 (point D)
        for c in (inner, outer):
            mesh.setTransfiniteCurve(c, n_arc + 1, "Progression", grading)
        for c in (y0, x0):
            mesh.setTransfiniteCurve(c, n_radial + 1)
        mesh.setTransfiniteSurface(surf)
        mesh.setRecombine(2, surf)
        vol = extrude_slab(surf, HALF_THICKNESS, n_z)
        names = slab_faces(vol, HALF_THICKNESS, lambda b: "x0" if b[3] < 1e-6 else "y0" if b[4] < 1e-6 else
                           "outer" if b[3] > 3.0 else "inner")
        name_surfaces_and_write(names, out)
    finally:
        gmsh.finalize()
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-arc", type=int, default=24)
    ap.add_argument("--n-radial", type=int, default=8)
    ap.add_argument("--n-z", type=int, default=1)
    ap.add_argument("--out", default=str(Path(__file__).with_name("le1.msh")))
    a = ap.parse_args()
    print(build(Path(a.out), a.n_arc, a.n_radial, a.n_z))
