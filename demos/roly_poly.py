"""A roly-poly toy carved inside so that it rocks back upright (Make it swing).

    python demos/roly_poly.py OUT_DIR

The toy (a hemisphere of radius 5 cm resting on its dome, under a cylinder 4 cm tall) is meshed by gmsh from
its CAD file, demos/scenes/roly_poly.brep.
Tilted, it rolls on its dome about the dome's centre: it comes back only if its centre of mass lies below
that centre. Solid, the CoM is above it (the toy falls over); `goal = "swing"` fits a sphere to the
contact region (the rocking surface), then carves the interior (a 3 mm wall kept) so that the CoM lies on
the vertical through the sphere's centre and at least R sin(5 deg) below it, with the largest righting
moment m g d sin(tilt). Prints the rocking centre and radius and the CoM's depth below the centre.

A toy 5 cm tall cannot be saved by hollowing (the wall alone holds the CoM too high); with
`fill_density = 7850` the carved cavity is filled with steel (its surface: ballast/void.stl), a ballast
that brings the CoM below the centre again.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "roly_poly.toml"
STEEL = 7850.0            # kg/m^3: the ballast filling the carved cavity of the taller toy


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    d = run_analysis(ff.Scene.from_file(SCENE), out / "swing")
    b = d["before"]
    c = d["curvature_center"]
    print(f"rocking surface: centre ({c[0]:.3e}, {c[1]:.3e}, {c[2]:.3e}) m, radius {d['curvature_radius']:.6f} m")
    print(f"solid: CoM height above the centre {-b['com_depth_below_center']:.6f} m, mass {b['mass']:.6f} kg")
    print(f"carved: CoM depth below the centre {d['com_depth_below_center']:.6f} m, off its vertical "
          f"{d['com_offset_from_center_vertical']:.3e} m, mass {d['mass']:.6f} kg, carved fraction "
          f"{d['carved_fraction']:.4f}")
    print(f"picture: {out / 'swing' / 'balance.png'}")
    # a taller toy (H = 5 cm): no hollowing brings its CoM low enough; a steel ballast in a carved cavity does
    tall = {"title": "tall roly-poly, steel ballast", "mesh.file": "roly_poly_tall.brep",
            "balance.fill_density": STEEL}
    d = run_analysis(ff.Scene.from_file(SCENE, tall), out / "ballast")
    print(f"ballasted (H = 5 cm, steel {STEEL:.0f} kg/m^3 in the cavity): CoM depth below the centre "
          f"{d['com_depth_below_center']:.6f} m, off its vertical {d['com_offset_from_center_vertical']:.3e} m, "
          f"mass {d['mass']:.6f} kg, ballast fraction {d['carved_fraction']:.4f} -> {out / 'ballast' / 'void.stl'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "roly_poly_out"))
