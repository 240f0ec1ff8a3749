"""Solid hemisphere of radius R (flat face on z = 0, centred at the origin, dome up), optionally with a
concentric hemispherical cavity of radius `inner` open at the flat face: gmsh geometry and a tetrahedral
mesh of size h, written as hemisphere.msh (straight-sided tetrahedra inscribed in the curved surfaces).

    python verification/geometry/hemisphere.py [--radius 0.05] [--inner 0] [--h 0.005] [--out hemisphere.msh]
"""
import argparse
from pathlib import Path

from fem_forms.meshes.occ_parts import write_part


def _half_ball(occ, radius: float) -> list:
    """The upper half (z >= 0) of the ball of this radius about the origin, as OCC dim-tags."""
    ball = occ.addSphere(0, 0, 0, radius)
    below = occ.addBox(-2 * radius, -2 * radius, -2 * radius, 4 * radius, 4 * radius, 2 * radius)
    dome, _ = occ.cut([(3, ball)], [(3, below)])
    return dome


def build(out: Path, radius: float = 0.05, h: float = 0.005, inner: float = 0.0) -> Path:
    def solid(occ):
        dome = _half_ball(occ, radius)
        return occ.cut(dome, _half_ball(occ, inner))[0] if inner > 0 else dome
    return write_part(Path(out), solid, h)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radius", type=float, default=0.05)
    ap.add_argument("--inner", type=float, default=0.0, help="cavity radius (0: solid)")
    ap.add_argument("--h", type=float, default=0.005)
    ap.add_argument("--out", type=Path, default=Path(__file__).with_name("hemisphere.msh"))
    a = ap.parse_args()
    print(build(a.out, a.radius, a.h, a.inner))
