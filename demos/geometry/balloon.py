"""A segment of a rubber balloon animal: a thick-walled capsule (a tube with hemispherical ends) around one closed
cavity, one eighth of it (x, y, z >= 0: the segment's middle at the origin, its axis along x). Gmsh geometry and
tetrahedral mesh (metres). Named surfaces: "inner" (the cavity's wall), "outer", "x0", "y0", "z0" (the symmetry
planes, where rollers hold it and x . n = 0 closes the cavity).

    python demos/geometry/balloon.py [--h 0.003] [--out balloon.msh]
"""
import argparse
from pathlib import Path

from fem_forms.meshes.occ_parts import symmetry_plane, write_part

# the inflated segment, the design's target (m): outer radius 15 mm, wall 3 mm, a straight part 60 mm long
OUTER, WALL, STRAIGHT = 0.015, 0.003, 0.060


def capsule(occ, radius: float, half: float) -> list:
    """A tube of `radius` from x = -half to half with hemispherical ends: its dim-tags."""
    tube = occ.addCylinder(-half, 0, 0, 2 * half, 0, 0, radius)
    whole, _ = occ.fuse([(3, tube)], [(3, occ.addSphere(-half, 0, 0, radius)), (3, occ.addSphere(half, 0, 0, radius))])
    return whole


def build(out: Path, h: float = 0.003) -> Path:
    """Write the eighth segment's mesh (cell size h down to h/2) to `out`."""
    half = STRAIGHT / 2

    def eighth(occ):
        shell, _ = occ.cut(capsule(occ, OUTER, half), capsule(occ, OUTER - WALL, half))
        size = half + OUTER
        return occ.intersect(shell, [(3, occ.addBox(0, 0, 0, size, size, size))])[0]
    return write_part(out, eighth, h, 0.5 * h, lambda box: symmetry_plane(box) or     # else how far from the axis
                      ("outer" if max(box[4], box[5]) > OUTER - WALL / 2 else "inner"))   # the wall reaches


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=0.003)
    ap.add_argument("--out", default="balloon.msh")
    a = ap.parse_args()
    print(build(Path(a.out), a.h))
