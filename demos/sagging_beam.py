"""# A soft silicone beam sagging under its own weight

A 1 m x 0.1 m x 0.1 m silicone beam (neo-Hookean, E = 1 MPa, nu = 0.45, rho = 1100 kg/m^3) is
clamped at x = 0, pulled down by gravity and a small traction on its free end. Linear beam theory
would predict a tip sag of about 1.6 m, more than the beam is long: only a large-deformation
(hyperelastic) solve gives a meaningful answer. The scene file holds the whole setup.

Run: `.venv/bin/python demos/sagging_beam.py [OUT_DIR]` (also under `mpirun -n 2`).
"""
import sys
from pathlib import Path

from mpi4py import MPI

import fem_forms as ff

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/sagging_beam")

ff.quiet_jit()
scene = ff.Scene.from_file(here / "scenes" / "sagging_beam.toml")
result = ff.solve_static(scene)
summary = ff.write_static_outputs(result, out)

if MPI.COMM_WORLD.rank == 0:
    tip = summary["probes"]["tip"]["displacement"]
    print(f"{scene.title}: {summary['dofs']} dofs ({summary['element']}), converged={summary['converged']} "
          f"in {summary['newton_iterations']} Newton iterations, {summary['wall_time_s']:.1f} s")
    print(f"  tip displacement u = ({tip[0]:.4f}, {tip[1]:.4f}, {tip[2]:.4f}) m; "
          f"max |u| = {summary['max_displacement']:.4f} m; max von Mises = {summary['max_von_mises']:.4g} Pa")
    print(f"  wrote {out}/results.json, fields.xdmf (ParaView), deformed.png, newton_history.csv")
sys.exit(0 if summary["converged"] else 3)
