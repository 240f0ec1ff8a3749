"""# A silicone finger, pushed down and let go

A soft silicone finger 150 x 15 x 15 mm (neo-Hookean, E = 3 MPa, nu = 0.45, rho = 1100 kg/m^3) is
clamped at one end and sags under its own weight. A finger presses its tip down (a 500 Pa traction on
the end face) and lets go at t = 0: the beam swings about its sagged shape and settles. Gravity stays on
the whole time (`[dynamic] initial = "static"` starts from the equilibrium under gravity and the push;
`initial_loads = [1]` releases only the push). Losses: air drag as mass-proportional Rayleigh damping
(alpha = 1/s) and the silicone's own viscosity as a Kelvin-Voigt stress (shear 1034.5 Pa s = beta mu,
bulk 1e4 Pa s = beta kappa, beta = 1e-3 s). Kelvin-Voigt acts on the rate of Green strain, which a
rotation leaves at zero; stiffness-proportional Rayleigh damping (beta K at rest) would also damp the
rotation of the sagged beam and stopped this swing within one period.

The swing is read from the tip's vertical motion in probes.csv: the period from successive maxima and
the decay per cycle from successive peak-to-peak ranges (independent of the sagged centre). Both are
compared with small-amplitude theory: the Euler-Bernoulli first bending frequency of the straight beam,
(1.8751)^2 / (2 pi L^2) sqrt(E I / (rho A)), and the Rayleigh decay per cycle
exp(-2 pi zeta / sqrt(1 - zeta^2)), zeta = alpha / (2 omega) + beta omega / 2.

Run: `.venv/bin/python demos/silicone_swing.py [OUT_DIR]` (also under `mpirun -n 2`). Writes
results.json, probes.csv, energy.csv, motion.gif (the swing) and history.png (tip motion and energies).
"""
import math
import sys
from pathlib import Path

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms.analyses.dynamic import run as run_dynamic

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/silicone_swing")


def extrema(t: np.ndarray, x: np.ndarray, sign: float) -> np.ndarray:
    """[(time, value)] of the local maxima of sign * x, refined by a parabola through three samples."""
    y, found = sign * x, []
    for k in range(1, len(y) - 1):
        if y[k] > y[k - 1] and y[k] >= y[k + 1]:
            a, b, c = y[k - 1], y[k], y[k + 1]
            s = 0.5 * (a - c) / (a - 2 * b + c)
            found.append((t[k] + s * (t[k + 1] - t[k]), sign * (b - 0.25 * (a - c) * s)))
    return np.array(found)


ff.quiet_jit()
scene = ff.Scene.from_file(here / "scenes" / "silicone_swing.toml")
summary = run_dynamic(scene, out)

if MPI.COMM_WORLD.rank == 0:
    data = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    t, w = data["time"], data["tip_uz"]
    highs, lows = extrema(t, w, 1.0), extrema(t, w, -1.0)
    period = float(np.mean(np.diff(highs[:, 0])))
    ranges = np.array([hv - lows[lows[:, 0] > ht][0, 1] for ht, hv in highs if np.any(lows[:, 0] > ht)])
    decay = float(np.exp(np.mean(np.log(ranges[1:] / ranges[:-1]))))

    L, h, m, d = scene.mesh.size[0], scene.mesh.size[2], scene.material, scene.damping
    f_eb = 1.8751**2 / (2 * math.pi * L**2) * math.sqrt(m.E * h * h / (12 * m.rho))
    omega = 2 * math.pi * f_eb
    beta = d.shear / (m.E / (2 * (1 + m.nu)))                 # Kelvin-Voigt = beta K for small strains
    zeta = d.alpha / (2 * omega) + beta * omega / 2
    decay_ref = math.exp(-2 * math.pi * zeta / math.sqrt(1 - zeta * zeta))
    e = summary["energy_final"]
    print(f"{scene.title}: {summary['dofs']} dofs, {summary['steps']} steps to t = {summary['time_reached']:.2f} s, "
          f"{summary['newton_iterations']} Newton iterations, {summary['wall_time_s']:.1f} s")
    centre = 0.5 * (highs[-1, 1] + lows[-1, 1])
    print(f"  tip starts at w = {1000 * w[0]:.2f} mm and swings about w = {1000 * centre:.2f} mm (its sag under gravity)")
    print(f"  swing frequency {1 / period:.3f} Hz (Euler-Bernoulli {f_eb:.3f} Hz, {100 * (1 / period / f_eb - 1):+.2f} %)")
    print(f"  decay per cycle {decay:.4f} (Rayleigh zeta = {zeta:.4f}: {decay_ref:.4f}, "
          f"{100 * (decay / decay_ref - 1):+.2f} %)")
    print(f"  energy: {1000 * e['dissipated']:.3f} mJ dissipated, balance error {summary['energy_balance_error']:.1e}")
    print(f"  wrote {out}/results.json, probes.csv, energy.csv, motion.gif, history.png")
