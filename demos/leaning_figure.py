"""A leaning figure that topples as a solid part and stands once its interior is carved (Make It Stand).

    python demos/leaning_figure.py OUT_DIR

The figure (a foot and a column leaning out over the foot's edge, demos/scenes/figure_lean85.brep) is meshed by
gmsh from its CAD file (demos/scenes/leaning_figure.toml); `goal = "check"` reports it toppling, `goal = "stand"`
carves the interior (a 3 mm wall kept) so that the centre of mass lies inside the support polygon shrunk by
h tan(2 deg). Prints both toppling angles and the carved share.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "leaning_figure.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    before = run_analysis(ff.Scene.from_file(SCENE, {"balance.goal": "check"}), out / "check")
    after = run_analysis(ff.Scene.from_file(SCENE), out / "stand")
    print(f"solid: toppling angle {before['toppling_angle_deg']:.6f} deg, stands {before['stands']}")
    print(f"carved: toppling angle {after['toppling_angle_deg']:.4f} deg, stands {after['stands']}, "
          f"carved fraction {after['carved_fraction']:.4f}, mass {after['mass']:.6f} kg")
    print(f"picture: {out / 'stand' / 'balance.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "leaning_figure_out"))
