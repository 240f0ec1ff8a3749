"""# A bimetal strip curls when heated (two materials)

A thermostat's blade: steel below, brass above, each 0.5 mm, bonded; clamped at one end and heated by
200 K. Brass expands more (19e-6 against 12e-6 per K), so the blade curls towards the steel into a circular
arc. Two `[[material]]` tables in one scene (demos/scenes/bimetal_strip.toml): the steel layer claims its
cells by a box, brass takes the rest; each has its own E, density and expansion coefficient.

Closed form: Timoshenko (1925), Analysis of bi-metal thermostats: the curvature of a bonded strip of
layers h1, h2 (moduli E1, E2, expansions a1, a2) heated by dT; the clamped blade's interface becomes an arc
of that curvature, stretched by e_i = a1 dT + P / (E1 h1) + kappa h1 / 2 (P = 2 kappa (E1 h1^3 + E2 h2^3) /
(12 h), the layers' force per width): its tip drops (1 - cos(kappa L)) / kappa (1 + e_i) and moves back
L - (1 + e_i) sin(kappa L) / kappa.

Run: `.venv/bin/python demos/bimetal_strip.py [OUT_DIR]`; picture `deformed.png`, fields `fields.xdmf`
(displacement, von Mises, and each cell's material).
"""
import math
import sys
from pathlib import Path

from mpi4py import MPI

import fem_forms as ff
from fem_forms.analyses import run_analysis

ff.quiet_jit()
here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/bimetal_strip")
scene = ff.Scene.from_file(here / "scenes" / "bimetal_strip.toml")
s = run_analysis(scene, out)

brass, steel = scene.materials
h1 = h2 = scene.mesh.size[2] / 2
m, n = h1 / h2, steel.E / brass.E
dT = scene.thermal.boundary[0].value - scene.thermal.reference_temperature
kappa = (6 * (brass.expansion - steel.expansion) * dT * (1 + m) ** 2
         / ((h1 + h2) * (3 * (1 + m) ** 2 + (1 + m * n) * (m ** 2 + 1 / (m * n)))))
L = scene.mesh.size[0]
force = 2 * kappa * (steel.E * h1 ** 3 + brass.E * h2 ** 3) / 12 / (h1 + h2)       # per unit width
stretch = 1 + steel.expansion * dT + force / (steel.E * h1) + kappa * h1 / 2   # the interface's
drop, back = stretch * (1 - math.cos(kappa * L)) / kappa, L - stretch * math.sin(kappa * L) / kappa
if MPI.COMM_WORLD.rank == 0:
    tip = s["probes"]["tip"]["displacement"]
    print(f"{scene.title}: {s['dofs']} dofs, {s['newton_iterations']} Newton iterations, "
          f"{s['wall_time_s']:.1f} s -> {out}/deformed.png")
    for mat in s["materials"]:
        print(f"  {mat['name']}: {mat['cells']} cells, {mat['volume'] * 1e6:.4g} cm^3, {mat['mass'] * 1e3:.4g} g")
    print(f"  Timoshenko curvature {kappa:.5g} 1/m (radius {1000 / kappa:.4g} mm), interface stretch {stretch:.6f}")
    print(f"  tip drop {-tip[2] * 1000:.5f} mm, arc {drop * 1000:.5f} mm; "
          f"tip moves back {-tip[0] * 1000:.5f} mm, arc {back * 1000:.5f} mm")
