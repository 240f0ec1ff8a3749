"""A soft silicone figure standing on a table under its own weight, with no clamps at all (contact).

    python demos/figure_on_table.py OUT_DIR

The figure (the leaning figure's foot and column, leaning 2 cm) in soft silicone (E 0.15 MPa, nu 0.4,
1100 kg/m^3) rests on a table (a plane 0.1 mm below its sole, friction 0.6): the table's push and friction
hold it, the barrier keeps the sole off the table (IPC), nothing is glued. Prints the force the table carries
(its weight, m g), how much of the sole touches, the largest pressure and the sag; writes the deformed
picture, deformed.stl and the contact pressure for ParaView.
"""
from pathlib import Path
import sys

import fem_forms as ff
from fem_forms.analyses import run_analysis
from fem_forms.meshes.occ_parts import write_part
from leaning_figure import figure


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    mesh = write_part(out / "figure.msh", lambda occ: figure(occ, lean=0.02), 0.008)
    scene = {"title": "figure on a table", "mesh": {"generator": "file", "file": str(mesh)},
             "material": {"model": "neo-hookean", "E": 1.5e5, "nu": 0.4, "rho": 1100.0},
             "load": [{"type": "gravity"}],
             "contact": {"distance": 2e-4, "obstacle": [{"name": "table", "shape": "plane", "point": [0, 0, -1e-4],
                                                         "normal": [0, 0, 1], "friction": 0.6}]},
             "output": {"fields": ["displacement", "von_mises", "contact_pressure"]}}
    r = run_analysis(ff.Scene.from_dict(scene), out / "run")
    table = r["contact"]["table"]
    print(f"table force ({table['force'][0]:.3e}, {table['force'][1]:.3e}, {table['force'][2]:.6f}) N, "
          f"converged {r['converged']}")
    print(f"touching {table['area'] * 1e4:.3f} cm^2 with {table['active_points']} nodes, largest pressure "
          f"{table['max_pressure']:.1f} Pa, smallest gap {r['min_distance']:.3e} m, sag {r['max_displacement'] * 1e3:.3f} mm")
    print(f"picture: {out / 'run' / 'deformed.png'}; surface: {out / 'run' / 'deformed.stl'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "figure_on_table_out"))
