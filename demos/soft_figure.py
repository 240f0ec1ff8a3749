"""A soft silicone figure that stands as a rigid part, topples once it sags under its own weight, and
stands again when its interior is carved for the sagged shape (`elastic = true`).

    python demos/soft_figure.py OUT_DIR

The figure is the leaning figure's shape (demos/scenes/figure_lean60.brep) leaning less (6 cm), in a soft
silicone (E 0.15 MPa, nu 0.4, 1100 kg/m^3), its sole clamped to the ground. `goal = "check"` with
`elastic = true` reports the rigid numbers and, side by side under "deformed", those of the shape sagged
under gravity (P2 tetrahedra). `goal = "stand"` with `elastic = true` starts from the rigid design, solves
the sag with the carving (carved cells keep 1e-6 of the stiffness), redesigns on the sagged shape and
repeats until the design stays (at most 4 static solves). Prints the toppling angles and the solves.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "soft_figure.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    check = run_analysis(ff.Scene.from_file(SCENE, {"balance.goal": "check"}), out / "check")
    d = run_analysis(ff.Scene.from_file(SCENE), out / "stand")
    fmt = lambda v: "(" + ", ".join(f"{x:.6f}" for x in v) + ")"
    for label, r in (("solid", check), ("carved", d)):
        s = r["deformed"]
        print(f"{label}: rigid toppling angle {r['toppling_angle_deg']:.4f} deg, stands {r['stands']}; sagged "
              f"(max |u| {1000 * s['max_displacement']:.2f} mm) toppling angle {s['toppling_angle_deg']:.4f} deg, "
              f"stands {s['stands']}")
        print(f"{label}: sagged CoM {fmt(s['center_of_mass'])} m, mass {r['mass']:.6f} kg")
    print(f"carved fraction {d['carved_fraction']:.4f}, static solves {d['static_solves']}")
    print(f"picture: {out / 'stand' / 'balance.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "soft_figure_out"))
