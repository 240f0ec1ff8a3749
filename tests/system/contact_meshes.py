"""Meshes of the contact tests, made with gmsh: the Hertz quarter hemisphere (the verification manual's) and a
thick-walled tube."""
import importlib.util
from pathlib import Path

import gmsh

ROOT = Path(__file__).resolve().parents[2]


_spec = importlib.util.spec_from_file_location("hertz_hemisphere", ROOT / "verification" / "geometry" /
                                               "hertz_hemisphere.py")
_hertz = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_hertz)


def quarter_hemisphere(path, R: float, fine: float, coarse: float, zone: float) -> str:
    """The verification manual's Hertz mesh (verification/geometry/hertz_hemisphere.py)."""
    return str(_hertz.build(path, R, fine, coarse, zone))


def ring(path, outer: float, inner: float, length: float, h: float) -> str:
    """A thick-walled tube (radii outer > inner) of the given length along y, its axis through the origin."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        occ = gmsh.model.occ
        tube = occ.addCylinder(0, 0, 0, 0, length, 0, outer)
        occ.cut([(3, tube)], [(3, occ.addCylinder(0, 0, 0, 0, length, 0, inner))])
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [v[1] for v in gmsh.model.getEntities(3)], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return str(path)
