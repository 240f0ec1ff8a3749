"""gmsh solids for the balance tests (written as .msh files into a folder): shapes with closed-form mass
properties and a leaning figure."""
from pathlib import Path

from fem_forms.meshes.occ_parts import write_part


def _mesh(path: Path, build, h: float) -> Path:
    """Mesh the volumes build(occ) returns (their tags) into path."""
    return write_part(path, lambda occ: [(3, t) for t in build(occ)], h)


def cone(path, R, H, h):
    return _mesh(path, lambda occ: [occ.addCone(0, 0, 0, 0, 0, H, R, 0)], h)


def hemisphere(path, R, h, inner=0.0):
    """Solid hemisphere (flat face on z = 0, dome up), optionally with a concentric hemispherical cavity."""
    def build(occ):
        s = occ.addSphere(0, 0, 0, R)
        box = occ.addBox(-2 * R, -2 * R, -2 * R, 4 * R, 4 * R, 2 * R)
        out, _ = occ.cut([(3, s)], [(3, box)])
        if inner > 0:
            si = occ.addSphere(0, 0, 0, inner)
            box2 = occ.addBox(-2 * R, -2 * R, -2 * R, 4 * R, 4 * R, 2 * R)
            cav, _ = occ.cut([(3, si)], [(3, box2)])
            out, _ = occ.cut(out, cav)
        return [t for d, t in out if d == 3]
    return _mesh(path, build, h)


def leaning_figure(path, h=0.006, lean=0.085):
    """A foot 0.09 x 0.04 x 0.03 under a column 0.04 x 0.04 x 0.14 whose axis leans `lean` m out over the
    foot's +x edge: it topples when solid."""
    def build(occ):
        foot = occ.addBox(-0.03, 0, 0, 0.09, 0.04, 0.03)
        col = occ.addBox(0.02, 0, 0.03, 0.04, 0.04, 0.14)
        occ.affineTransform([(3, col)], [1, 0, lean / 0.14, -lean / 0.14 * 0.03, 0, 1, 0, 0, 0, 0, 1, 0])
        out, _ = occ.fuse([(3, foot)], [(3, col)])
        return [t for d, t in out if d == 3]
    return _mesh(path, build, h)


def lopsided_top(path, h=0.005):
    """A cone standing on its tip at the origin (radius 0.04, height 0.03), a disc on it (0.03 thick) and an
    off-axis lump 0.02 x 0.02 x 0.01 on the disc: its CoM is off the z axis."""
    def build(occ):
        cone = occ.addCone(0, 0, 0.03, 0, 0, -0.03, 0.04, 0)
        disc = occ.addCylinder(0, 0, 0.03, 0, 0, 0.03, 0.04)
        lump = occ.addBox(0.005, -0.01, 0.06, 0.02, 0.02, 0.01)
        out, _ = occ.fuse([(3, cone)], [(3, disc), (3, lump)])
        return [t for d, t in out if d == 3]
    return _mesh(path, build, h)


def roly_poly(path, R=0.05, H=0.0, r=None, h=0.006):
    """A hemisphere of radius R resting on its dome (centre at the origin, dome below z = 0) under a
    cylinder of radius r (default R) and height H on its flat face (H = 0: the hemisphere alone)."""
    def build(occ):
        s = occ.addSphere(0, 0, 0, R)
        box = occ.addBox(-2 * R, -2 * R, 0, 4 * R, 4 * R, 2 * R)
        out, _ = occ.cut([(3, s)], [(3, box)])
        if H > 0:
            out, _ = occ.fuse(out, [(3, occ.addCylinder(0, 0, 0, 0, 0, H, r or R))])
        return [t for d, t in out if d == 3]
    return _mesh(path, build, h)
