"""# Modes of a sagging beam, loaded and unloaded

The soft silicone beam of `sagging_beam.py` (E = 1 MPa, clamped at x = 0) sags under gravity and a
tip traction by most of its length. Its vibration modes about that loaded equilibrium differ from
the modes at rest: the tangent stiffness there includes the stresses from the load (geometric
stiffness) and the bent shape. Both modal analyses use the same scene; `[modal] prestress = true`
first solves the static equilibrium (the same SNES driver as the static analysis) and takes the
tangent there. The picture shows the loaded modes drawn on the sagged shape.

Run: `.venv/bin/python demos/loaded_vs_unloaded_modes.py [OUT_DIR]` (about 20 s).
"""
import sys
from pathlib import Path

from mpi4py import MPI

import fem_forms as ff

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/loaded_vs_unloaded_modes")

ff.quiet_jit()
summaries = {}
for name, prestress in (("unloaded", False), ("loaded", True)):      # the sagging beam's scene, as modal runs
    scene = ff.Scene.from_file(here / "scenes" / "sagging_beam.toml",
                               {"analysis": "modal", "modal.count": 6, "modal.prestress": prestress})
    summaries[name] = ff.write_modal_outputs(ff.solve_modal(scene), out / name)

if MPI.COMM_WORLD.rank == 0:
    un, lo = summaries["unloaded"], summaries["loaded"]
    print(f"{scene.title}: {un['dofs']} dofs ({un['element']}); loaded state: max |u| = "
          f"{lo['static']['max_displacement']:.3f} m after {lo['static']['newton_iterations']} "
          "Newton iterations")
    print("  mode   unloaded [Hz]   loaded [Hz]   change")
    for k, (a, b) in enumerate(zip(un["frequencies_hz"], lo["frequencies_hz"])):
        print(f"  {k + 1:4d}   {a:13.4f}   {b:11.4f}   {100 * (b / a - 1):+6.1f} %")
    print(f"  wrote {out}/unloaded and {out}/loaded (results.json, modes.xdmf, modes.png)")
