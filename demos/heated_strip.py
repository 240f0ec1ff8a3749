"""# A silicone strip heated from below curls up

The strip lies on a heater at 80 C; its top loses heat to 20 C air. One `fem-forms run` solves the steady
temperature first (conduction with a held face and a convecting face), then the large-deformation
equilibrium of the neo-Hookean strip with the thermal strain alpha (T - T_ref) (multiplicative split,
ramped by the load continuation). No load is applied: the temperature change alone bends it.

Closed form (the bimetal / thermal-gradient beam): a linear temperature through the thickness h with
difference dT bends a free strip to the curvature alpha dT / h per unit rest length; its mid-line,
stretched by s = 1 + alpha (T_mid - T_ref), becomes a circular arc of curvature alpha dT / (h s^2). The temperatures on both faces
follow from the heat balance (wall then film in series), so the reference shares no number with the solve.

Run: `.venv/bin/python demos/heated_strip.py [OUT_DIR]`; picture `deformed.png`, fields `fields.xdmf`.
"""
import math
import sys
from pathlib import Path

from mpi4py import MPI

import fem_forms as ff
from fem_forms.analyses import run_analysis

ff.quiet_jit()
here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/heated_strip")
scene = ff.Scene.from_file(here / "scenes" / "heated_strip.toml")
s = run_analysis(scene, out)

# closed form: steady heat through wall (h/k) and film (1/h_c) in series, then the gradient beam's arc
th = scene.thermal
L, h = scene.mesh.size[0], scene.mesh.size[2]
T_hot, conv = th.boundary[0].value, th.boundary[1]
flux = (T_hot - conv.ambient) / (h / th.conductivity + 1 / conv.h)
dT = flux * h / th.conductivity                                  # hot face minus cool face
stretch = 1 + th.expansion * (T_hot - dT / 2 - th.reference_temperature)
# fibres at z stretch by 1 + alpha (T(z) - T_ref): the mid-line (stretch s) turns through the angle
# alpha dT L / (h s) along its deformed length L s, a circular arc of curvature alpha dT / (h s^2)
arc = L * stretch
kappa = th.expansion * dT / h / stretch**2
rise = (1 - math.cos(kappa * arc)) / kappa
if MPI.COMM_WORLD.rank == 0:
    tip = s["probes"]["tip"]["displacement"][2] - s["probes"]["root"]["displacement"][2]
    T_h, T_c = s["probes"]["hot"]["temperature"], s["probes"]["cool"]["temperature"]
    print(f"{scene.title}: {s['dofs']} dofs, {s['newton_iterations']} Newton iterations, "
          f"{s['wall_time_s']:.1f} s -> {out}/deformed.png")
    print(f"  faces at {T_h:.3f} C and {T_c:.3f} C (closed form {T_hot:.3f} C and {T_hot - dT:.3f} C)")
    print(f"  tip rise {tip * 1000:.4f} mm; gradient-beam closed form {rise * 1000:.4f} mm "
          f"(linear theory alpha dT L^2 / 2h: {th.expansion * dT * L * L / (2 * h) * 1000:.4f} mm)")
