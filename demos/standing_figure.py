"""A soft silicone figure designed to stand freely on a table: the rest shape to cast (inverse design, adjoint
method, the table's contact and friction as its only support).

    python demos/standing_figure.py OUT_DIR

The target is the leaning figure (demos/scenes/figure_lean20.brep: a foot and a column leaning 2 cm) in a soft
silicone (E 0.15 MPa, nu 0.4, 1100 kg/m^3) standing on a table (friction 1.0, its sole 0.1 mm above it). Put down
as it is, the figure sags about a centimetre. The design finds the rest shape that, put down on the table and left
to its own weight, sags into the figure; the forward check re-solves the written rest shape on the table with the
static analysis. Prints the design, where the checked part lands (how high it rests is the barrier's gap), what the
table carries against the rest shape's weight, how much of the friction it uses, and its stance; writes
rest_shape.stl to cast and inverse.png.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "standing_figure.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = run_analysis(ff.Scene.from_file(SCENE), out / "run")
    table, stance = r["contact"]["table"], r["stance"]
    print(f"rest shape in {r['iterations']} Gauss-Newton iterations ({r['forward_solves']} forward solves), "
          f"largest rest offset {1000 * r['max_rest_offset']:.3f} mm, usable {r['usable']}")
    print(f"checked on the table: rests {1000 * r['resting_offset_m']:+.4f} mm from the target's height, shape "
          f"within {r['shape_mismatch_max']:.3e} m, the design's prediction within {r['design_gap_max']:.3e} m")
    print(f"table force ({table['force'][0]:.3e}, {table['force'][1]:.3e}, {table['force'][2]:.6f}) N over "
          f"{1e4 * table['area']:.3f} cm^2; friction use {table['friction_use']:.3f}, sliding points "
          f"{table['sliding_points']}")
    com = ", ".join(f"{x:.6f}" for x in stance["centre_of_mass"])
    print(f"stance: centre of mass ({com}) m, {1000 * stance['margin_m']:.3f} mm inside the contact patch, toppling "
          f"angle {stance['toppling_angle_deg']:.3f} deg, stands {stance['stands']}")
    print(f"to cast: {out / 'run' / 'rest_shape.stl'}; picture: {out / 'run' / 'inverse.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "standing_figure_out"))
