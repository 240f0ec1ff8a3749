"""The solid parts of the demos as OpenCASCADE BREP files (metres), the CAD files their scene files mesh
(`[mesh] file = "figure_lean85.brep"`, `h`, `h_min`): a leaning figure (three leans), a toy boat, two roly-poly
toys, a rocking toy, a spinning top and a silicone finger (and the rocking toy's mesh, see MESHED). Written once
and committed beside the scenes:

    python demos/geometry/parts.py [OUT_DIR]          # default demos/scenes
"""
import sys
from pathlib import Path

import gmsh


def figure(occ, lean: float) -> list:
    """A foot and a column sheared to lean `lean` m out over the foot's edge."""
    foot = occ.addBox(-0.03, 0, 0, 0.09, 0.04, 0.03)
    col = occ.addBox(0.02, 0, 0.03, 0.04, 0.04, 0.14)
    occ.affineTransform([(3, col)], [1, 0, lean / 0.14, -lean / 0.14 * 0.03, 0, 1, 0, 0, 0, 0, 1, 0])
    return occ.fuse([(3, foot)], [(3, col)])[0]


def boat(occ) -> list:
    """The hull, and the cabin towards the bow fused on its deck."""
    hull = occ.addBox(0, 0, 0, 0.24, 0.10, 0.06)
    cabin = occ.addBox(0.13, 0.02, 0.06, 0.08, 0.06, 0.05)
    return occ.fuse([(3, hull)], [(3, cabin)])[0]


def dome_toy(occ, R: float, r: float, H: float) -> list:
    """The lower half of a sphere of radius R about the origin with a cylinder (radius r, height H) on it."""
    dome, _ = occ.cut([(3, occ.addSphere(0, 0, 0, R))], [(3, occ.addBox(-2 * R, -2 * R, 0, 4 * R, 4 * R, 2 * R))])
    return occ.fuse(dome, [(3, occ.addCylinder(0, 0, 0, 0, 0, H, r))])[0]


def top(occ) -> list:
    """A cone on its tip at the origin, a disc on it and an off-axis lump on the disc."""
    cone = occ.addCone(0, 0, 0.03, 0, 0, -0.03, 0.04, 0)
    disc = occ.addCylinder(0, 0, 0.03, 0, 0, 0.03, 0.04)
    lump = occ.addBox(0.005, -0.01, 0.06, 0.02, 0.02, 0.01)
    return occ.fuse([(3, cone)], [(3, disc), (3, lump)])[0]


def finger(occ, radius: float = 0.008, length: float = 0.03) -> list:
    """A cylinder along z from the tip's centre up, on a sphere of the same radius (its lower half)."""
    return occ.fuse([(3, occ.addCylinder(0, 0, radius, 0, 0, length, radius))],
                    [(3, occ.addSphere(0, 0, radius, radius))])[0]


PARTS = {"figure_lean85": lambda occ: figure(occ, 0.085), "figure_lean60": lambda occ: figure(occ, 0.06),
         "figure_lean20": lambda occ: figure(occ, 0.02), "boat": boat,
         "rocking_toy": lambda occ: dome_toy(occ, 0.05, 0.02, 0.04),
         "roly_poly": lambda occ: dome_toy(occ, 0.05, 0.05, 0.04),
         "roly_poly_tall": lambda occ: dome_toy(occ, 0.05, 0.05, 0.05), "spinning_top": top, "finger": finger}


def write(name: str, folder: Path) -> Path:
    """PARTS[name] written to folder/name.brep."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        PARTS[name](gmsh.model.occ)
        gmsh.model.occ.synchronize()
        path = folder / f"{name}.brep"
        gmsh.write(str(path))
        return path
    finally:
        gmsh.finalize()


# parts whose scene reads a mesh written here instead (name: cell size): the rocking toy's motion (stick and slip on
# the floor) changes with the mesh itself - measured on a remeshing of its BREP (2,538 dofs instead of 2,532): the
# rocking period 0.652 s instead of 0.854 s, the largest tilt 7.8 instead of 13.6 degrees - so its demo keeps the
# mesh its test was measured on
MESHED = {"rocking_toy": 0.008}


if __name__ == "__main__":
    from fem_forms.meshes.occ_parts import write_part
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "scenes"
    for part in PARTS.keys() - MESHED.keys():
        print(write(part, out))
    for part, h in MESHED.items():
        print(write_part(out / f"{part}.msh", PARTS[part], h))
