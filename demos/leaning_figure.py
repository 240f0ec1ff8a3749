"""A leaning figure that topples as a solid part and stands once its interior is carved (Make It Stand).

    python demos/leaning_figure.py OUT_DIR

The figure (a foot and a column leaning out over the foot's edge) is meshed with gmsh; `goal = "check"`
reports it toppling, `goal = "stand"` carves the interior (a 3 mm wall kept) so that the centre of mass
lies inside the support polygon shrunk by h tan(2 deg). Prints both toppling angles and the carved share.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis
from fem_forms.meshes.occ_parts import write_part


def figure(occ, lean: float = 0.085) -> list:
    """A foot and a column sheared to lean `lean` m out over the foot's edge (gmsh dim-tags)."""
    foot = occ.addBox(-0.03, 0, 0, 0.09, 0.04, 0.03)
    col = occ.addBox(0.02, 0, 0.03, 0.04, 0.04, 0.14)
    occ.affineTransform([(3, col)], [1, 0, lean / 0.14, -lean / 0.14 * 0.03, 0, 1, 0, 0, 0, 0, 1, 0])
    return occ.fuse([(3, foot)], [(3, col)])[0]


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    mesh = write_part(out / "figure.msh", figure, 0.006)
    scene = {"title": "leaning figure", "analysis": "balance", "mesh": {"generator": "file", "file": str(mesh)},
             "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0},
             "balance": {"goal": "stand", "margin_angle": 2.0, "shell": 0.003}}
    before = run_analysis(ff.Scene.from_dict(dict(scene, balance={"goal": "check"})), out / "check")
    after = run_analysis(ff.Scene.from_dict(scene), out / "stand")
    print(f"solid: toppling angle {before['toppling_angle_deg']:.6f} deg, stands {before['stands']}")
    print(f"carved: toppling angle {after['toppling_angle_deg']:.4f} deg, stands {after['stands']}, "
          f"carved fraction {after['carved_fraction']:.4f}, mass {after['mass']:.6f} kg")
    print(f"picture: {out / 'stand' / 'balance.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "leaning_figure_out"))
