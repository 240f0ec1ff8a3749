"""A soft silicone figure designed to sag into its shape AND stand, in one run (inverse design + [balance]).

    python demos/sag_and_stand.py OUT_DIR

The target is the leaning figure (demos/scenes/figure_lean85.brep: a foot and a column leaning 8.5 cm out over the
foot's edge) in a soft silicone (E 0.15 MPa, nu 0.4, 1100 kg/m^3), its sole clamped to the ground, under
its own weight. `analysis = "inverse"` designs the rest shape to cast so that it sags into the target; as a
solid part that target topples (`[balance] goal = "check"` reports it: the sagged shape is the target, so
the designed part sags into a figure that falls over). With `goal = "stand"` the interior is carved on the
target (a 3 mm wall kept, the centre of mass inside the sole shrunk by h tan 2 deg), the rest shape is
designed for the carved part (voids: no weight, 1e-6 of the stiffness), the carving is redone once with each
cell's mass from its rest volume (and the rest shape again if a cell changed), and the forward check loads the
written, carved rest shape, lets it sag, and measures both the mismatch to the target and the stance.
Prints both designs' mismatch and toppling angles, the carved share and the files to print or cast.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "sag_and_stand.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    solid = run_analysis(ff.Scene.from_file(SCENE, {"balance.goal": "check"}), out / "solid")
    carved = run_analysis(ff.Scene.from_file(SCENE), out / "carved")
    fmt = lambda v: "(" + ", ".join(f"{x:.6f}" for x in v) + ")"
    for label, r in (("solid", solid), ("carved", carved)):
        b = r["balance"]
        t, s = b["on_target"], b["sagged"]
        print(f"{label}: largest rest offset {1000 * r['max_rest_offset']:.2f} mm, forward check lands within "
              f"{r['target_mismatch_max']:.2e} m of the target")
        print(f"{label}: on the target toppling angle {t['toppling_angle_deg']:.4f} deg; sagged (forward check) "
              f"toppling angle {s['toppling_angle_deg']:.4f} deg, stands {s['stands']}")
        print(f"{label}: sagged CoM {fmt(s['center_of_mass'])} m, mass {b['mass']:.6f} kg")
    b = carved["balance"]
    print(f"carved fraction {b['carved_fraction']:.4f} ({b['carved_cells']} of {b['cells']} cells)")
    print(f"to cast: {out / 'carved' / 'rest_shape.stl'} with the core {out / 'carved' / 'void.stl'}")
    print(f"pictures: {out / 'carved' / 'inverse.png'}, {out / 'carved' / 'balance.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "sag_and_stand_out"))
