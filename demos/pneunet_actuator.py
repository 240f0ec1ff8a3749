"""# A PneuNet bending actuator inflated by volume control

A silicone body 100 x 20 x 15 mm (Mooney-Rivlin from E = 100 kPa, nu = 0.49: C10 = 3/8 mu, C01 = 1/8 mu) with
six chambers joined by a channel (one closed cavity, demos/geometry/pneunet.py) is clamped at x = 0 and inflated
by injecting air: the scene prescribes the injected volume and the solver finds the chamber pressure with the
displacement. The upper part lengthens, the solid base does not (its lowest 2 mm a ten times stiffer silicone,
a second [[material]] on the mesh's volume group "layer"): the actuator curls down. The tip angle is the
rotation about y of the end face, from two probes at its top and bottom edges.

One point per accepted load step: from probes.csv when the static run writes it (`<probe>_ux..`, `chambers_
pressure`, `chambers_volume`), else recorded here after each accepted step. Run:
`.venv/bin/python demos/pneunet_actuator.py [OUT_DIR] [H]` (H the cell size in m, default 0.006). Writes
the mesh, results.json, fields.xdmf (every step), curve.csv, curve.png (tip angle and pressure against
injected volume; tip angle against pressure) and stroke.gif (the deformed actuator at every accepted step, true scale).

Why Mooney-Rivlin: under volume control the solver accepts only stable states (the tangent's inertia,
solvers/multiplier_merit.py). With a neo-Hookean body the chamber roofs balloon past a pressure maximum
(15.6 kPa near 18 ml): beyond it the evenly inflated actuator is a saddle point a real part snaps away from,
and the solver follows the snap, the tip angle falling from 86.6 to 72.5 deg at 18.7 ml, 74 deg at 26 ml
(measured, benchmarks/pneunet.md). A positive C01 stiffens the roofs as they stretch: the pressure rises
all the way, every state is stable, and 26 ml curls the actuator past 90 deg.
"""
import sys
from pathlib import Path

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms import progress
from fem_forms.analyses.dynamic.output import write_gif
from fem_forms.analyses.static import write_static_outputs
from fem_forms.analyses.static.solve import solve_static
from fem_forms.model import build_model
from fem_forms.output.fields import boundary_surface
from fem_forms.physics.cavities import cavity_report

here = Path(__file__).parent
sys.path.insert(0, str(here / "geometry"))
import pneunet  # noqa: E402

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/pneunet_actuator")
h = float(sys.argv[2]) if len(sys.argv) > 2 else 0.006
comm = MPI.COMM_WORLD


def recorder(model, rows: list, frames: list):
    """A progress reporter appending (injected volume, pressure, tip angle) and the deformed boundary (rank 0)
    after each accepted step."""
    def report(event, **info):
        if event == "step_accepted":
            model.sync_displacement()
            cav = cavity_report(model.terms)["chambers"]
            u = model.probes.evaluate(model.u)
            rows.append((cav["volume_change"], cav["pressure"], pneunet.tip_angle(u["tip_top"], u["tip_bottom"])))
            surface = boundary_surface(model.u)             # gathered on rank 0 for the GIF
            if surface is not None:
                frames.append((cav["volume_change"] * 1e6, surface))
    return report


ff.quiet_jit()
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
    pneunet.build(out / "pneunet.msh", h, layer=pneunet.LAYER)
comm.barrier()
scene = ff.Scene.from_file(here / "scenes" / "pneunet.toml", overrides={"mesh.file": str(out / "pneunet.msh")})
model, rows, frames = build_model(scene), [], []
progress.set_reporter(recorder(model, rows, frames))
result = solve_static(scene, model=model)
progress.set_reporter(None)
s = write_static_outputs(result, out)

if comm.rank == 0:
    cav = s.get("cavities", {}).get("chambers")
    try:
        rows = pneunet.curve_from_probes(out / "probes.csv", cav["volume"] - cav["volume_change"])
        source = "probes.csv"
    except (OSError, KeyError, TypeError):
        source = "recorded per step"
    curve = np.array([(0.0, 0.0, 0.0)] + rows)
    np.savetxt(out / "curve.csv", curve, delimiter=",", header="injected_volume_m3,pressure_pa,tip_angle_deg",
               comments="")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, ax3) = plt.subplots(1, 2, figsize=(10, 4))
    ax.plot(curve[:, 0] * 1e6, curve[:, 2], "o-", color="C0")
    ax.set_xlabel("injected volume [ml]")
    ax.set_ylabel("tip angle [deg]", color="C0")
    ax2 = ax.twinx()
    ax2.plot(curve[:, 0] * 1e6, curve[:, 1] / 1e3, "s--", color="C3")
    ax2.set_ylabel("chamber pressure [kPa]", color="C3")
    ax.set_title(scene.title, fontsize=9)
    ax3.plot(curve[:, 1] / 1e3, curve[:, 2], "o-", color="C2")      # what a pressure regulator would set
    ax3.set_xlabel("chamber pressure [kPa]")
    ax3.set_ylabel("tip angle [deg]")
    ax3.set_title("tip angle against pressure", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "curve.png", dpi=120)
    write_gif(out / "stroke.gif", frames, "PneuNet", fps=8, label="{:.1f} ml injected")
    print(f"{scene.title}: {s['dofs']} dofs, {s['load_steps']} load steps, {s['newton_iterations']} Newton "
          f"iterations, {s['wall_time_s']:.1f} s, converged {s['converged']}")
    print(f"  curve ({source}): injected volume [ml], pressure [kPa], tip angle [deg]")
    for v, p, a in curve[1:]:
        print(f"    {v * 1e6:8.4f} {p / 1e3:8.3f} {a:8.2f}")
    if cav:
        print(f"  at {cav['volume_change'] * 1e6:.4f} ml injected: pressure {cav['pressure'] / 1e3:.4f} kPa, "
              f"tip angle {curve[-1, 2]:.2f} deg")
    print(f"  wrote {out}/results.json, fields.xdmf, curve.csv, curve.png, stroke.gif ({len(frames)} frames)")
