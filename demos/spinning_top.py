"""A lopsided top carved inside so that it spins true (Spin-It).

    python demos/spinning_top.py OUT_DIR

The top (a cone standing on its tip, a disc on it and an off-axis lump on the disc) is meshed by gmsh from its
CAD file (demos/scenes/spinning_top.brep);
solid, its centre of mass lies off the spin axis (the z axis through the tip), so it wobbles. `goal =
"spin"` carves the interior (a 3 mm wall kept) so that the CoM lies on the axis, the axis is a principal
axis of inertia, and the ratio of the spin moment to the other principal moments is as large as it gets.
Prints the CoM's distance from the axis before and after, the spin ratio and the axis' tilt.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "spinning_top.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    d = run_analysis(ff.Scene.from_file(SCENE), out / "spin")
    b = d["before"]
    off = lambda c: (c[0] ** 2 + c[1] ** 2) ** 0.5
    print(f"solid: CoM {off(b['center_of_mass']):.4e} m off the axis, mass {b['mass']:.6f} kg")
    print(f"carved: CoM {d['com_distance_from_axis']:.4e} m off the axis, mass {d['mass']:.6f} kg, "
          f"carved fraction {d['carved_fraction']:.4f}")
    print(f"spin ratio {d['spin_ratio']:.4f} (solid {b['spin_ratio']:.4f}), axis {d['principal_axis_angle_deg']:.4f} "
          f"deg from a principal axis (solid {b['principal_axis_angle_deg']:.4f} deg)")
    print(f"picture: {out / 'spin' / 'balance.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "spinning_top_out"))
