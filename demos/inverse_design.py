"""# Designing the rest shape: what to cast so that gravity bends it into the shape you want

Two scenes, each solved by inverse elastostatics (equilibrium written on the known target shape
with the rest positions as unknowns) and then checked independently: the rest shape is written as a
mesh file, those arrays are loaded as a mesh and solved forward under the same loads with the forward
forms; it must land on the target.

1. A soft silicone beam that must hang straight: its rest shape curls up by most of a metre.
2. A soft goblet (revolved gmsh profile) standing on its base that must keep its designed form.

Run: `.venv/bin/python demos/inverse_design.py [OUT_DIR]`; pictures are `inverse.png` in each folder.
"""
import sys
from pathlib import Path

from mpi4py import MPI

import fem_forms as ff
from fem_forms.analyses import run_analysis

ff.quiet_jit()
here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/inverse_design")
for name in ("straight_beam_inverse", "goblet_inverse"):
    scene = ff.Scene.from_file(here / "scenes" / f"{name}.toml")
    s = run_analysis(scene, out / name)
    if MPI.COMM_WORLD.rank == 0:
        probe = next(iter(s["probes"].values()))
        print(f"{scene.title}: {s['dofs']} dofs, {s['iterations']} Newton iterations, {s['design_time_s']:.1f} s")
        print(f"  largest rest offset {s['max_rest_offset'] * 1000:.1f} mm; target point {probe['point']} "
              f"is cast at {[round(c, 4) for c in probe['rest_position']]}")
        print(f"  forward check from the written rest mesh lands within {s['target_mismatch_max']:.2e} m "
              f"of the target -> {out / name}/inverse.png, rest_shape.msh, rest_shape.stl")
