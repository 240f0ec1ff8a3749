"""The rest shape of a rubber balloon animal's segment that a given pressure inflates into its target (inverse
design under pressure).

    python demos/balloon_segment.py OUT_DIR

The target is a segment of a balloon animal (demos/scenes/balloon.msh, one eighth by symmetry, written by
demos/geometry/balloon.py): a natural-rubber capsule (E 1 MPa, nu 0.45) of outer radius 15 mm, wall 3 mm and a
straight part 60 mm long around one closed cavity, at 30 kPa. The direct method designs the rest shape to mould in
one solve (the pressure acts on the target's known walls) and the forward check inflates the written rest shape
again. Prints the rest shape's waist and tip against the target's, the cavity's volume at rest and inflated, and
where the check lands; writes rest_shape.stl to mould and inverse.png.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "balloon_segment.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = run_analysis(ff.Scene.from_file(SCENE), out / "run")
    rest = {n: p["rest_position"] for n, p in r["probes"].items()}
    air = r["cavities"]["air"]
    print(f"rest shape by the {r['method']} method in {r['iterations']} Newton iterations; forward check "
          f"({r['forward_check']['kind']}) lands within {r['target_mismatch_max']:.3e} m of the target, usable "
          f"{r['usable']}")
    print(f"waist: outer radius {1000 * rest['waist'][1]:.4f} mm, inner {1000 * rest['inner_waist'][1]:.4f} mm at rest "
          f"(inflated 15, 12 mm); half length {1000 * rest['tip'][0]:.4f} mm (inflated 45 mm)")
    print(f"cavity (one eighth): {1e6 * air['rest_volume']:.5f} ml at rest, {1e6 * air['volume']:.5f} ml at "
          f"{air['pressure'] / 1000:.1f} kPa")
    print(f"to mould: {out / 'run' / 'rest_shape.stl'}; picture: {out / 'run' / 'inverse.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "balloon_segment_out"))
