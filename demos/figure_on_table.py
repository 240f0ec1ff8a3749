"""A soft silicone figure standing on a table under its own weight, with no clamps at all (contact).

    python demos/figure_on_table.py OUT_DIR

The figure (the leaning figure's foot and column, leaning 2 cm: demos/scenes/figure_lean20.brep, meshed by gmsh
from that CAD file) in soft silicone (E 0.15 MPa, nu 0.4, 1100 kg/m^3) rests on a table (a plane 0.1 mm below
its sole, friction 0.6): the table's push and friction hold it, the barrier keeps the sole off the table (IPC),
nothing is glued. Prints the force the table carries
(its weight, m g), how much of the sole touches, the largest pressure and the sag; writes the deformed
picture, deformed.stl and the contact pressure for ParaView.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis

SCENE = Path(__file__).parent / "scenes" / "figure_on_table.toml"


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    r = run_analysis(ff.Scene.from_file(SCENE), out / "run")
    table = r["contact"]["table"]
    print(f"table force ({table['force'][0]:.3e}, {table['force'][1]:.3e}, {table['force'][2]:.6f}) N, "
          f"converged {r['converged']}")
    print(f"touching {table['area'] * 1e4:.3f} cm^2 with {table['active_points']} nodes, largest pressure "
          f"{table['max_pressure']:.1f} Pa, smallest gap {r['min_distance']:.3e} m, sag {r['max_displacement'] * 1e3:.3f} mm")
    print(f"picture: {out / 'run' / 'deformed.png'}; surface: {out / 'run' / 'deformed.stl'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "figure_on_table_out"))
