"""A quarter of a hemisphere for Hertz contact: the part x >= 0, y >= 0 of the ball of radius R centred at
(0, 0, R), below its equator; flat face (group "top") at z = R, lowest point at the origin, tetrahedra of size
`fine` within `zone` of that point growing to `coarse` at 10 x zone. Written as hertz_hemisphere.msh.

    python verification/geometry/hertz_hemisphere.py [--radius 0.01] [--fine 1e-4] [--coarse 2.5e-3]
        [--zone 5e-4] [--out hertz_hemisphere.msh]
"""
import argparse
from pathlib import Path

import gmsh


def build(out: Path, radius: float = 0.01, fine: float = 1e-4, coarse: float = 2.5e-3, zone: float = 5e-4,
          whole_ball: bool = False, spread: float = 10.0) -> Path:
    """The quarter hemisphere (or with `whole_ball`, the quarter of the whole ball: a ball thrown onto a floor),
    graded from `fine` within `zone` of the lowest point to `coarse` at `spread` x zone."""
    R = radius
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        ball = occ.addSphere(0, 0, R, R)
        if not whole_ball:
            occ.cut([(3, ball)], [(3, occ.addBox(-2 * R, -2 * R, R, 4 * R, 4 * R, 2 * R))])
        occ.cut([(3, ball)], [(3, occ.addBox(-2 * R, -2 * R, -R, 2 * R, 4 * R, 4 * R))])
        occ.cut([(3, ball)], [(3, occ.addBox(-2 * R, -2 * R, -R, 4 * R, 2 * R, 4 * R))])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [v[1] for v in gmsh.model.getEntities(3)], 1)
        if not whole_ball:                              # the flat face pressed down
            top = [s[1] for s in gmsh.model.getEntities(2) if abs(occ.getCenterOfMass(2, s[1])[2] - R) < 1e-9 * R]
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, top, 2), "top")
        lowest = occ.addPoint(0, 0, 0)
        occ.synchronize()
        f = gmsh.model.mesh.field
        f.add("Distance", 1)
        f.setNumbers(1, "PointsList", [lowest])
        f.add("Threshold", 2)
        f.setNumber(2, "InField", 1)
        for key, value in (("SizeMin", fine), ("SizeMax", coarse), ("DistMin", zone), ("DistMax", spread * zone)):
            f.setNumber(2, key, value)
        f.setAsBackgroundMesh(2)
        for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(key, 0)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return Path(out)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for name, default in (("radius", 0.01), ("fine", 1e-4), ("coarse", 2.5e-3), ("zone", 5e-4)):
        ap.add_argument(f"--{name}", type=float, default=default)
    ap.add_argument("--out", default="hertz_hemisphere.msh")
    a = ap.parse_args()
    print(build(Path(a.out), a.radius, a.fine, a.coarse, a.zone))
