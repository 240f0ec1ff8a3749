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


def box_surface(path, lo, hi, open_face: bool = False) -> str:
    """A closed triangle surface of the box [lo, hi] (12 triangles, outward) as STL; `open_face` leaves its
    top's two triangles out (a surface with a hole)."""
    import meshio
    import numpy as np
    P = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    F = np.array([[0, 2, 1], [1, 2, 3], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6],
                  [1, 3, 5], [3, 7, 5], [4, 5, 6], [5, 7, 6]])
    meshio.write(str(path), meshio.Mesh(P.astype(float), [("triangle", F[:-2] if open_face else F)]),
                 file_format="stl")
    return str(path)


def two_blocks(path, gap: float, h: float) -> str:
    """A slab [-0.1, 0.2] x [-0.05, 0.15] x [-0.05, 0] and a 0.1 m cube [0, 0.1]^2 x [gap, 0.1 + gap] above it:
    two solids in one mesh (the cube rests on the slab through self-contact)."""
    from fem_forms.meshes.occ_parts import write_part
    return str(write_part(path, lambda occ: [(3, occ.addBox(-0.1, -0.05, -0.05, 0.3, 0.2, 0.05)),
                                             (3, occ.addBox(0.0, 0.0, gap, 0.1, 0.1, 0.1))], h))
