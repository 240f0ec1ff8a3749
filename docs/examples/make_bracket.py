"""Writes bracket.step, the L-bracket of the manual's CAD page (docs/cad.md), as a CAD tool would export it: a
solid in millimetres, its product named "bracket". Run it with the venv's python to make the file again."""
import re
from pathlib import Path

import gmsh

HERE = Path(__file__).resolve().parent

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("bracket")
occ = gmsh.model.occ
shelf = occ.addBox(0, 0, 0, 60, 20, 8)               # mm
upright = occ.addBox(0, 0, 0, 8, 20, 40)
hole = occ.addCylinder(40, 10, -1, 0, 0, 10, 4)
body, _ = occ.fuse([(3, shelf)], [(3, upright)])
occ.cut(body, [(3, hole)])
occ.synchronize()
gmsh.write(str(HERE / "bracket.step"))
gmsh.finalize()
step = HERE / "bracket.step"
step.write_text(re.sub(r"PRODUCT\('[^']*',\s*'[^']*'", "PRODUCT('bracket','bracket'", step.read_text()))
