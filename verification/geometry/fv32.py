"""NAFEMS FV32 (cantilevered tapered membrane): gmsh geometry and mesh, written as fv32.msh here.

The membrane is the trapezoid (0, -2.5), (10, -0.5), (10, 0.5), (0, 2.5) (10 m long, 5 m deep at the
clamped end x = 0, 1 m at the free end, symmetric about y = 0), 0.05 m thick. It is meshed as a slab of
half the thickness (0 <= z <= 0.025 m): the scene holds w = 0 on z = 0, the mid-plane, so only modes
symmetric about the mid-plane remain: the in-plane (membrane, plane stress) modes, and thickness modes
far above the range asked for. The out-of-plane bending modes of the thin plate, antisymmetric about the
mid-plane, are excluded without constraining the Poisson thinning (w = 0 through the whole thickness
would give plane strain, not plane stress). Structured hexahedra: `nx` along, `ny` across, `nz` through.

Named surfaces: "clamped" (x = 0), "free_end" (x = 10), "bottom" (z = 0), "top", "sides".

    python verification/geometry/fv32.py [--nx 16] [--ny 8] [--nz 1] [--out fv32.msh]
"""
import argparse
from pathlib import Path

import gmsh

from groups import extrude_slab, name_surfaces_and_write, slab_faces

HALF_THICKNESS = 0.025


def build(out: Path, nx: int = 16, ny: int = 8, nz: int = 1) -> Path:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("nafems_fv32")
        occ = gmsh.model.occ
        p = [occ.addPoint(0, -2.5, 0), occ.addPoint(10, -0.5, 0), occ.addPoint(10, 0.5, 0),
             occ.addPoint(0, 2.5, 0)]
        lines = [occ.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
        surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
        occ.synchronize()
        mesh = gmsh.model.mesh
        for i, c in enumerate(lines):
            mesh.setTransfiniteCurve(c, (nx if i % 2 == 0 else ny) + 1)
        mesh.setTransfiniteSurface(surf)
        mesh.setRecombine(2, surf)
        vol = extrude_slab(surf, HALF_THICKNESS, nz)
        names = slab_faces(vol, HALF_THICKNESS, lambda b: "clamped" if b[3] < 1e-6 else
                           "free_end" if b[0] > 10 - 1e-6 else "sides")
        name_surfaces_and_write(names, out)
    finally:
        gmsh.finalize()
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nx", type=int, default=16)
    ap.add_argument("--ny", type=int, default=8)
    ap.add_argument("--nz", type=int, default=1)
    ap.add_argument("--out", default=str(Path(__file__).with_name("fv32.msh")))
    a = ap.parse_args()
    print(build(Path(a.out), a.nx, a.ny, a.nz))
