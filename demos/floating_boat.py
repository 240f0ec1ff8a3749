"""A boat carved inside so that it floats upright at its design waterline (buoyancy design).

    python demos/floating_boat.py OUT_DIR

The boat (a box hull 0.24 x 0.10 x 0.06 m with a cabin 0.08 x 0.06 x 0.05 m set towards the bow) is meshed by
gmsh from its CAD file demos/scenes/boat.brep, in wood (600 kg/m^3). Solid, it is too heavy for the 3 cm
waterline asked and its centre of mass is off the buoyancy vertical, so it would trim by the bow. `goal =
"swim"` carves the interior (an 8 mm wall kept) so that its mass equals the water displaced at the waterline,
its CoM lies on the vertical through the centre of buoyancy, and the metacentric height GM = KB + BM - KG is
positive (at least 1 % of its size). Prints the mass against the displaced water, the CoM and GM.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "floating_boat.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    d = run_analysis(ff.Scene.from_file(SCENE), out / "swim")
    b = d["before"]
    fmt = lambda v: "(" + ", ".join(f"{x:.6f}" for x in v) + ")"
    print(f"solid: mass {b['mass']:.6f} kg, CoM {fmt(b['center_of_mass'])} m")
    print(f"carved: mass {d['mass']:.6f} kg, displaced water {d['displaced_mass']:.6f} kg, "
          f"carved fraction {d['carved_fraction']:.4f}")
    print(f"CoM {fmt(d['center_of_mass'])} m, centre of buoyancy {fmt(d['center_of_buoyancy'])} m")
    print(f"metacentric height GM {d['metacentric_height']:.6f} m")
    print(f"picture: {out / 'swim' / 'balance.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "floating_boat_out"))
