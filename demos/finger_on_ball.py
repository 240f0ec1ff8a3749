"""A soft finger pressed onto a rigid ball (contact with friction, a support moved).

    python demos/finger_on_ball.py OUT_DIR

A silicone finger (a cylinder of radius 8 mm and length 30 mm ending in a hemispherical tip, E 0.1 MPa, nu 0.45;
demos/scenes/finger.brep) is held at its base and pushed 3 mm down onto a rigid ball of radius 20 mm (friction
0.5) that its tip starts 0.1 mm above, in 6 load steps. Prints the force the ball takes against the support's
reaction (equal and opposite), the touching area against the tip's flattening, and the largest pressure; writes
the deformed picture, deformed.stl, contact_pressure in fields.xdmf and the force path in probes.csv.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "finger_on_ball.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = run_analysis(ff.Scene.from_file(SCENE), out / "run")
    ball, base = r["contact"]["ball"], r["reactions"]["base"]
    print(f"ball force ({ball['force'][0]:.3e}, {ball['force'][1]:.3e}, {ball['force'][2]:.6f}) N; base reaction "
          f"({base[0]:.3e}, {base[1]:.3e}, {base[2]:.6f}) N; converged {r['converged']}")
    print(f"touching {ball['area'] * 1e6:.3f} mm^2 with {ball['active_points']} nodes, largest pressure "
          f"{ball['max_pressure']:.1f} Pa, smallest gap {r['min_distance']:.3e} m, intersection free "
          f"{r['intersection_free']}")
    print(f"picture: {out / 'run' / 'deformed.png'}; force path: {out / 'run' / 'probes.csv'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "finger_on_ball_out"))
