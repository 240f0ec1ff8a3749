"""# A 3D-printed hook pulled until it cracks (phase-field fracture)

A flat PLA wall hook (demos/geometry/hook.py: shank 6 mm wide, 5 mm thick, a half-ring bend of radii 9 and 15 mm)
is held at the top of its shank and pulled down by the lower inner arc of its bend (as a pin would), the pull
prescribed in 16 steps to 0.8 mm (demos/scenes/printed_hook.toml). PLA: E = 3.5 GPa, nu = 0.35; AT1 phase field
with Gc = 2 kJ/m^2 and l = 1 mm, whose strength sqrt(3 Gc E / (8 l)) is 51 MPa. The bending moment is largest
where the shank meets the bend: the crack starts on the inner side there and runs through the shank; the force
carried rises elastically, peaks and falls to nothing.

What it prints: the peak force and the pull at the peak, where the crack is (results.json crack_center), the
crack's area against the shank's section (the phase field's surface energy / Gc, with Bourdin's mesh
correction 1 + 3 h / (8 l)), and the strength check of the elastic hook at the first step (the safety factor's
critical point). Run: `.venv/bin/python demos/printed_hook.py [OUT_DIR]`; writes crack.png, force_displacement.csv
and .png, fields.xdmf (displacement, von Mises and the damage at every step), results.json.
"""
import sys
from pathlib import Path

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms.analyses.static import solve_and_write

here = Path(__file__).parent
sys.path.insert(0, str(here / "geometry"))
import hook  # noqa: E402

ff.quiet_jit()
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/printed_hook")
comm = MPI.COMM_WORLD
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
    hook.build(out / "printed_hook.msh", h_fine=0.5e-3)
comm.barrier()
scene = ff.Scene.from_file(here / "scenes" / "printed_hook.toml",
                           overrides={"mesh.file": str(out / "printed_hook.msh")})
s = solve_and_write(scene, out)

rows = np.genfromtxt(out / "force_displacement.csv", delimiter=",", names=True)
force, pull = -rows["load_Fy"], -rows["load_uy"]
first = 0                                                    # the elastic hook at the first step
k = int(np.argmax(force))
if comm.rank == 0:
    fr = scene.fracture
    section = hook.WIDTH * hook.THICK
    corrected = section * (1 + 3 * 0.5e-3 / (8 * fr.length))
    print(f"{scene.title}: {s['dofs']} dofs, {s['load_steps']} load steps, {s['staggered_sweeps']} staggered sweeps, "
          f"{s['wall_time_s']:.1f} s -> {out}/crack.png")
    print(f"  elastic stiffness {force[first] / pull[first] / 1e3:.4g} N/mm; peak force {force[k]:.4g} N at a pull "
          f"of {pull[k] * 1e3:.4g} mm; at the end {force[-1]:.3g} N")
    centre = s["crack_center"] or [float("nan")] * 3
    print(f"  the crack's centre at [{centre[0] * 1e3:.4g}, {centre[1] * 1e3:.4g}] mm (x, y)")
    print(f"  crack area {s['crack_area'] * 1e6:.4g} mm^2 against the shank's section {section * 1e6:.4g} mm^2 "
          f"({corrected * 1e6:.4g} mm^2 with the mesh correction); damage_max {s['damage_max']:.3g}")
