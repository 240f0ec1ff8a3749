"""A flat 3D-printed wall hook (PLA), drawn in the x-y plane and printed 5 mm thick (z, one layer of cells): a
shank 6 mm wide from y = 30 to 80 mm (x in [-3, 3] mm), a half-ring bend below it (centre (12, 30) mm, inner
radius 9, outer 15) and a short tip rising to y = 40 mm on the right. Cells of size h_fine in the bend (where it
cracks), h_coarse elsewhere. Named volumes: "hook". Lengths in m.

    python demos/geometry/hook.py OUT.msh [h_fine]
"""
import sys
from pathlib import Path

import gmsh

from fem_forms.meshes.occ_parts import fine_in_box

MM = 1e-3
WIDTH, THICK = 6 * MM, 5 * MM
CENTRE, R_IN, R_OUT = (12 * MM, 30 * MM), 9 * MM, 15 * MM
SHANK_TOP, TIP_TOP = 80 * MM, 40 * MM


def build(out: Path, h_fine: float = 0.4 * MM, h_coarse: float = 1.5 * MM) -> Path:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("hook")
        occ = gmsh.model.occ
        cx, cy = CENTRE
        ring = occ.addDisk(cx, cy, 0, R_OUT, R_OUT)
        hole = occ.addDisk(cx, cy, 0, R_IN, R_IN)
        annulus, _ = occ.cut([(2, ring)], [(2, hole)])
        upper = occ.addRectangle(cx - 2 * R_OUT, cy, 0, 4 * R_OUT, 2 * R_OUT)
        bend, _ = occ.cut(annulus, [(2, upper)])                 # the lower half ring
        shank = occ.addRectangle(-WIDTH / 2, cy, 0, WIDTH, SHANK_TOP - cy)
        tip = occ.addRectangle(cx + R_IN, cy, 0, WIDTH, TIP_TOP - cy)
        pieces, _ = occ.fuse(bend, [(2, shank), (2, tip)])
        occ.synchronize()
        whole = max(pieces, key=lambda dt: occ.getMass(*dt))     # gmsh 4.11 also hands back the pieces
        occ.remove([dt for dt in pieces if dt != whole])
        occ.synchronize()
        fine_in_box(gmsh, {"XMin": cx - R_OUT, "XMax": cx + R_OUT, "YMin": cy - R_OUT, "YMax": cy + 4 * MM,
                           "Thickness": 4 * MM}, h_fine, h_coarse)
        volume = [t for d, t in occ.extrude([whole], 0, 0, THICK, numElements=[1]) if d == 3]
        occ.synchronize()
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, volume), "hook")
        gmsh.model.mesh.generate(3)
        out = Path(out)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out


if __name__ == "__main__":
    print(build(Path(sys.argv[1]), *(float(a) for a in sys.argv[2:3])))
