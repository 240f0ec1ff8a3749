"""A soft finger pressed onto a rigid ball (contact with friction, a support moved).

    python demos/finger_on_ball.py OUT_DIR

A silicone finger (a cylinder of radius 8 mm and length 30 mm ending in a hemispherical tip, E 0.1 MPa,
nu 0.45) is held at its base and pushed 3 mm down onto a rigid ball of radius 20 mm (friction 0.5) that
its tip starts 0.1 mm above, in 6 load steps. Prints the force the ball takes against the support's
reaction (equal and opposite), the touching area against the tip's flattening, and the largest pressure;
writes the deformed picture, deformed.stl, contact_pressure in fields.xdmf and the force path in probes.csv.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis
from fem_forms.meshes.occ_parts import write_part

R_TIP, LENGTH, R_BALL, PRESS, GAP = 0.008, 0.03, 0.02, 0.003, 1e-4


def finger(occ) -> list:
    """A cylinder along z from the tip's centre up, on a sphere of the same radius (its lower half)."""
    return occ.fuse([(3, occ.addCylinder(0, 0, R_TIP, 0, 0, LENGTH, R_TIP))], [(3, occ.addSphere(0, 0, R_TIP, R_TIP))])[0]


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    mesh = write_part(out / "finger.msh", finger, 0.0025)
    scene = {"title": "finger on a ball", "mesh": {"generator": "file", "file": str(mesh)},
             "material": {"model": "neo-hookean", "E": 1e5, "nu": 0.45, "rho": 1100.0},
             "fix": [{"name": "base", "where": {"axis": "z", "at": R_TIP + LENGTH}, "value": [0.0, 0.0, -PRESS]}],
             "solver": {"steps": 6},
             "contact": {"distance": 5e-5, "obstacle": [{"name": "ball", "shape": "sphere",
                                                         "center": [0.0, 0.0, -GAP - R_BALL], "radius": R_BALL,
                                                         "friction": 0.5}]},
             "output": {"fields": ["displacement", "von_mises", "contact_pressure"]}}
    r = run_analysis(ff.Scene.from_dict(scene), out / "run")
    ball, base = r["contact"]["ball"], r["reactions"]["base"]
    print(f"ball force ({ball['force'][0]:.3e}, {ball['force'][1]:.3e}, {ball['force'][2]:.6f}) N; base reaction "
          f"({base[0]:.3e}, {base[1]:.3e}, {base[2]:.6f}) N; converged {r['converged']}")
    print(f"touching {ball['area'] * 1e6:.3f} mm^2 with {ball['active_points']} nodes, largest pressure "
          f"{ball['max_pressure']:.1f} Pa, smallest gap {r['min_distance']:.3e} m, intersection free "
          f"{r['intersection_free']}")
    print(f"picture: {out / 'run' / 'deformed.png'}; force path: {out / 'run' / 'probes.csv'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "finger_on_ball_out"))
