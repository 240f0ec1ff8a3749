"""# A spoon handle bent past yield stays bent

A strip of annealed aluminium (E = 70 GPa, nu = 0.33, von Mises yield stress 35 MPa, perfectly plastic),
200 x 4 x 2 mm, clamped at one end, is pushed down at the other by 0.95 of its plastic collapse load and
then released. Two runs of one scene: the load history cut at its peak (the bent strip under load), and
the whole history (load, then unload: what stays). The released strip keeps a permanent tip deflection
and its plastic strain (fields.xdmf: plastic_strain, equivalent_plastic_strain).

Run: `.venv/bin/python demos/bent_spoon.py [OUT_DIR]` (also under `mpirun -n 2`).
"""
import sys
from pathlib import Path

from mpi4py import MPI

import fem_forms as ff
from fem_forms.output.pictures import picture

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/bent_spoon")

ff.quiet_jit()
tips = {}
for stage, history in (("loaded", [[0.0, 0.0], [1.0, 1.0]]), ("released", None)):
    scene = ff.Scene.from_file(here / "scenes" / "bent_spoon.toml")
    if history is not None:
        scene.load[0].history = history
    scene.title = f"{scene.title}: {stage}"
    result = ff.solve_static(scene)
    summary = ff.write_static_outputs(result, out / stage)
    if not summary["converged"]:
        sys.exit(3)
    tips[stage] = summary["probes"]["tip"]["displacement"][2]
    picture(out / f"{stage}_x5.png", result.u, scene.title, scale=5.0)
    if MPI.COMM_WORLD.rank == 0:
        print(f"{scene.title}: {summary['dofs']} dofs, {summary['newton_iterations']} Newton iterations in "
              f"{summary['load_steps']} load steps, tip u_z = {tips[stage] * 1e3:.3f} mm, max plastic strain "
              f"{summary['max_plastic_strain']:.4g}, yielded fraction {summary['yielded_fraction']:.3f}, "
              f"{summary['wall_time_s']:.1f} s")
if MPI.COMM_WORLD.rank == 0:
    print(f"  permanent set: tip stays {-tips['released'] * 1e3:.3f} mm down after release "
          f"({tips['released'] / tips['loaded'] * 100:.1f} % of the loaded deflection)")
    print(f"  springback {(tips['released'] - tips['loaded']) * 1e3:.3f} mm; wrote {out}/loaded_x5.png, "
          f"{out}/released_x5.png and {out}/loaded, {out}/released (results.json, fields.xdmf, deformed.png)")
