"""PneuNet-style bending actuator: gmsh geometry and tetrahedral mesh (metres).

A silicone body L x W x H (x along the length, z up) with six chambers in its upper part, joined by a
channel along x at the chambers' floor; chambers and channel are cut out of the body as one closed cavity
(no inlet: the cavity never opens to the outside). Below the chambers a solid layer of thickness `base` is
the stiff side that does not stretch: inflating the chambers lengthens the top, and the actuator curls
down towards its base. With `layer` > 0 the lowest `layer` metres of the base are a volume of their own
(a harder silicone, a fabric: the strain-limiting layer, given its own [[material]]). Named groups: surfaces
"cavity" (every chamber and channel wall), "clamp" (x = 0), "outer" (the rest of the outside), volumes
"body" and (with a layer) "layer".

    python demos/geometry/pneunet.py [--h 0.003] [--layer 0.002] [--half] [--out pneunet.msh]
"""
import argparse
import csv
import math
from pathlib import Path

import gmsh

from fem_forms.meshes.occ_parts import name_boundary

# body (m): 100 x 20 x 15 mm
L, W, H = 0.100, 0.020, 0.015
# chambers: 6 of 10 mm along x, 4 mm walls between them, 3 mm side and 2.5 mm top walls, a 6 mm base layer
# (2 mm side and top walls with a 4 mm base balloon past their pressure maximum at 11.7 kPa and 73 degrees)
CHAMBERS, CHAMBER_X, PITCH, FIRST_X = 6, 0.010, 0.014, 0.010
SIDE, TOP, BASE = 0.003, 0.0025, 0.006
# the strain-limiting layer of the demo: the lowest 2 mm of the base, a harder silicone
LAYER = 0.002

# channel joining the chambers: 4 mm wide, 2 mm high, on the chambers' floor, from the first to the last
CHANNEL_W, CHANNEL_H = 0.004, 0.002


def tip_angle(top, bottom) -> float:
    """Rotation (degrees) about y of the end face, from the displacements of its top and bottom edge probes:
    the segment bottom -> top starts along +z."""
    return math.degrees(math.atan2(top[0] - bottom[0], H + top[2] - bottom[2]))


def curve_from_probes(path: Path, v0: float, cavity: str = "chambers") -> list:
    """(injected volume, pressure, tip angle) per accepted load step from a run's probes.csv (its columns
    `<cavity>_volume`, `<cavity>_pressure`, tip_top_u[xyz], tip_bottom_u[xyz]); v0 the cavity's rest volume."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [(float(r[f"{cavity}_volume"]) - v0, float(r[f"{cavity}_pressure"]),
             tip_angle([float(r[f"tip_top_u{c}"]) for c in "xyz"], [float(r[f"tip_bottom_u{c}"]) for c in "xyz"]))
            for r in rows]


def chamber_boxes(occ, side: float = SIDE, top: float = TOP, base: float = BASE) -> list:
    """The six chambers and the channel as OCC boxes (dim-tags)."""
    SIDE, TOP, BASE = side, top, base      # noqa: N806 (the walls: the module's defaults or the caller's)
    boxes = [(3, occ.addBox(FIRST_X + k * PITCH, SIDE, BASE, CHAMBER_X, W - 2 * SIDE, H - BASE - TOP))
             for k in range(CHAMBERS)]
    x0, x1 = FIRST_X + 0.5 * CHAMBER_X, FIRST_X + (CHAMBERS - 1) * PITCH + 0.5 * CHAMBER_X
    boxes.append((3, occ.addBox(x0, 0.5 * (W - CHANNEL_W), BASE, x1 - x0, CHANNEL_W, CHANNEL_H)))
    return boxes


def build(out: Path, h: float = 0.003, layer: float = 0.0, half: bool = False, **walls: float) -> Path:
    """Write the actuator's tetrahedral mesh (cell size about h, metres) to `out`; `layer`: the thickness of
    a bottom layer meshed as a volume group of its own (0: none); `half`: only the half y <= 0 of the actuator
    moved to -W/2 <= y <= 0, its cut face "symmetry" in the plane y = 0 (through the origin: it closes the cavity's
    half); `walls`: side, top, base thicknesses other than the defaults."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("pneunet")
        occ = gmsh.model.occ
        boxes = chamber_boxes(occ, **walls)
        cavity, _ = occ.fuse(boxes[:1], boxes[1:])          # one cavity: chambers joined by the channel
        body, _ = occ.cut([(3, occ.addBox(0, 0, 0, L, W, H))], cavity)
        assert len(body) == 1, f"expected one solid, got {body}"
        y0, width = (-0.5 * W, 0.5 * W) if half else (0.0, W)
        if half:
            body, _ = occ.intersect(body, [(3, occ.addBox(0, 0, 0, L, width, H))])
            occ.translate(body, 0, y0, 0)
        if layer > 0:                                # split off the bottom layer, bonded (one conforming mesh)
            parts, _ = occ.fragment(body, [(3, occ.addBox(0, y0, 0, L, width, layer))])
            body = [p for p in parts if p[0] == 3]
        occ.synchronize()
        eps = 1e-5                                   # OCC pads bounding boxes by about 1e-7
        lower = [t for _, t in body if gmsh.model.getBoundingBox(3, t)[5] < layer + eps]
        upper = [t for _, t in body if t not in lower]
        for k, (name, tags) in enumerate((("body", upper), ("layer", lower))):
            if tags:
                gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, tags, 1 + k), name)
        def name_of(box):
            xa, ya, za, xb, yb, zb = box
            if xb < eps:
                return "clamp"
            if half and ya > -eps:
                return "symmetry"
            outside = xa > L - eps or yb < y0 + eps or ya > y0 + W - eps or zb < eps or za > H - eps
            return "outer" if outside else "cavity"
        name_boundary(gmsh, [t for _, t in body], name_of)                # of the union: no interface
        gmsh.option.setNumber("Mesh.CharacteristicLengthMax", h)
        gmsh.option.setNumber("Mesh.CharacteristicLengthMin", 0.3 * h)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=0.003)
    ap.add_argument("--layer", type=float, default=0.0)
    ap.add_argument("--half", action="store_true", help="the half y <= 0, its cut face 'symmetry' at y = 0")
    ap.add_argument("--out", type=Path, default=Path("pneunet.msh"))
    args = ap.parse_args()
    print(build(args.out, args.h, args.layer, args.half))
