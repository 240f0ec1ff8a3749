"""# A notched silicone strip torn apart (finite-strain phase-field fracture)

Rivlin & Thomas's pure-shear tear test (1953) on a soft silicone strip (demos/scenes/torn_silicone_strip.toml):
64 x 16 x 1 mm, clamped along its long edges, an edge notch of 16 mm along the middle, pulled apart to twice
its height in steps of 5 %. Compressible neo-Hookean (E = 1 MPa, nu = 0.45), AT1 phase field with Gc = 1 kJ/m^2,
l = 2 mm on 1 mm cells, all of psi degraded (split = "none": nothing is compressed). Far ahead of the notch the strip is in pure shear; as
the notch grows by da, a band of the strip's height h0 is unloaded, so the crack runs when W(lambda) h0 = Gc
(with the mesh correction: Gc (1 + 3 h / (8 l))), W the strain energy per volume of plane-stress pure shear,
which this script computes with scipy, independently of the finite elements. Then the crack runs through the
strip at once and the force falls to nothing.

What it prints: the stretch at the peak force against Rivlin-Thomas's, the peak force, the force at the end,
where the crack runs (its centre's distance from the notch's line) and its area against the strip's section
(notch included: the phase field's surface energy / Gc, with the mesh correction). Run:
`.venv/bin/python demos/torn_silicone_strip.py [OUT_DIR]`; writes crack.png, force_displacement.csv and .png,
fields.xdmf (displacement, von Mises and the damage at every step), results.json.
"""
import math
import sys
from pathlib import Path

from mpi4py import MPI
import numpy as np
from scipy.optimize import brentq, minimize_scalar

import fem_forms as ff
from fem_forms.analyses.static import solve_and_write

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/torn_silicone_strip")
ff.quiet_jit()
scene = ff.Scene.from_file(here / "scenes" / "torn_silicone_strip.toml")
s = solve_and_write(scene, out)

m, fr = scene.materials[0], scene.fracture
mu, lmbda = m.E / (2 * (1 + m.nu)), m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu))
width, h0, thick = scene.mesh.size
h = width / scene.mesh.cells[0]


def pure_shear_energy(stretch: float) -> float:
    """W of the compressible neo-Hookean at F = diag(1, stretch, t), t free (plane stress): min over t."""
    def psi(t):
        J = stretch * t
        return mu / 2 * (1 + stretch**2 + t**2 - 3) - mu * math.log(J) + lmbda / 2 * math.log(J) ** 2
    return minimize_scalar(psi, bounds=(0.2, 1.5), method="bounded").fun


toughness = fr.toughness * (1 + 3 * h / (8 * fr.length))
rivlin_thomas = brentq(lambda lam: pure_shear_energy(lam) * h0 - toughness, 1.0 + 1e-9, 3.0)
rows = np.genfromtxt(out / "force_displacement.csv", delimiter=",", names=True)
force, pull = rows["top_Fy"], rows["top_uy"]
k = int(np.argmax(force))
if MPI.COMM_WORLD.rank == 0:
    section = width * thick * (1 + 3 * h / (8 * fr.length))
    print(f"{scene.title}: {s['dofs']} dofs, {s['load_steps']} load steps, {s['staggered_sweeps']} staggered sweeps, "
          f"{s['wall_time_s']:.1f} s -> {out}/crack.png")
    print(f"  the crack runs at a stretch of {1 + pull[k] / h0:.4g} (the last step before it; the next is "
          f"{1 + pull[k + 1] / h0:.4g}); Rivlin-Thomas: {rivlin_thomas:.4g} (W h0 = Gc (1 + 3 h / (8 l)))")
    print(f"  peak force {force[k]:.4g} N; at the end {force[-1]:.3g} N")
    centre = s["crack_center"] or [float("nan")] * 3
    off = abs(centre[1] - h0 / 2) * 1e3
    print(f"  the crack's centre {off:.4g} mm off the notch's line (y = {h0 / 2 * 1e3:.4g} mm; the strip is symmetric "
          "about it: which side is round-off)")
    print(f"  crack area {s['crack_area'] * 1e6:.4g} mm^2 against the strip's section {width * thick * 1e6:.4g} mm^2 "
          f"({section * 1e6:.4g} mm^2 with the mesh correction); damage_max {s['damage_max']:.3g}")
