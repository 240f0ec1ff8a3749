"""# The struck aluminium bar, in the time domain

The free aluminium bar of `struck_bar.py` (300 x 30 x 10 mm, E = 70 GPa, nu = 0.33, rho = 2700 kg/m^3)
is struck again, now by a load: a 0.1 ms triangular pressure pulse (1 MPa peak) on a 30 x 15 mm patch of
its top face near one end, then 25 ms of free, undamped vibration by Newmark average acceleration
(dt = 25 us). The spectrum of the struck point's vertical velocity (numpy FFT, through the project's peak
finder `fem_forms.output.sound.spectrum_peaks`) is compared with the modal analysis of the same bar and
mesh: each peak must lie within the frequency resolution 1 / duration of a mode. Newmark average
acceleration is exact in amplitude but lengthens periods: a mode of frequency f rings at
(1 / (pi dt)) atan(pi f dt), a 2 % shift at 3 kHz with this dt, so the modes are compared after that map.

Run: `.venv/bin/python demos/struck_bar_in_time.py [OUT_DIR]` (also under `mpirun -n 2`).
"""
import math
import sys
import tomllib
from pathlib import Path

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms.analyses.dynamic import run as run_dynamic
from fem_forms.output.sound import spectrum_peaks

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/struck_bar_in_time")

ff.quiet_jit()
scene_dict = tomllib.loads((here / "scenes" / "struck_bar_in_time.toml").read_text())
scene = ff.Scene.from_dict(scene_dict)
summary = run_dynamic(scene, out)

# the reference: the modes of the same bar and mesh (modal analysis, SLEPc)
modal = {k: v for k, v in scene_dict.items() if k not in ("load", "dynamic", "output")}
modal |= {"analysis": "modal", "modal": {"count": 12}}
modes = np.array(ff.solve_modal(ff.Scene.from_dict(modal)).frequencies_hz)

if MPI.COMM_WORLD.rank == 0:
    dt, duration = scene.dynamic.dt, scene.dynamic.duration
    data = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    free = data["time"] >= scene.load[0].history[-1][0]          # after the strike
    v = data["struck_vz"][free]
    v = v - v.mean()                                             # the rigid-body part is constant
    peaks = np.array(spectrum_peaks(v, 1.0 / dt))
    newmark = np.arctan(math.pi * modes * dt) / (math.pi * dt)   # where Newmark rings each mode
    peaks = peaks[peaks < newmark[-1] + 1.0 / duration]           # within the computed modes
    L, t, E, rho = scene.mesh.size[0], scene.mesh.size[2], scene.material.E, scene.material.rho
    f_eb = 22.373 / (2 * math.pi * L**2) * math.sqrt(E * t**2 / (12 * rho))
    print(f"{scene.title}: {summary['dofs']} dofs, {summary['steps']} Newmark steps of {1e6 * dt:.0f} us to "
          f"{1e3 * summary['time_reached']:.0f} ms, {summary['wall_time_s']:.1f} s; energy balance error "
          f"{summary['energy_balance_error']:.1e}")
    print(f"  spectrum of the struck point's velocity, resolution 1 / duration = {1 / duration:.0f} Hz:")
    print("    peak [Hz]   mode [Hz]   mode under Newmark [Hz]   difference [Hz]")
    worst = 0.0
    for p in peaks:
        k = int(np.argmin(np.abs(newmark - p)))
        worst = max(worst, abs(p - newmark[k]))
        print(f"    {p:9.1f}   {modes[k]:9.1f}   {newmark[k]:23.1f}   {p - newmark[k]:+15.1f}")
    print(f"  largest difference {worst:.1f} Hz; first flexural mode {modes[0]:.1f} Hz "
          f"(Euler-Bernoulli free-free {f_eb:.1f} Hz)")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy.signal.windows import blackmanharris
    spec = np.abs(np.fft.rfft(v * blackmanharris(2 * v.size)[v.size:], 8 * v.size))
    freq = np.fft.rfftfreq(8 * v.size, dt)
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(freq / 1e3, 20 * np.log10(spec / spec.max() + 1e-12), lw=0.8, label="struck point velocity (Newmark)")
    for i, f in enumerate(newmark):
        ax.axvline(f / 1e3, color="tab:red", lw=0.6, ls="--", label="modes (under Newmark)" if i == 0 else None)
    ax.set(xlim=(0, 1.1 * newmark[-1] / 1e3), ylim=(-60, 5), xlabel="frequency [kHz]", ylabel="dB",
           title=scene.title)
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "spectrum.png", dpi=100)
    print(f"  wrote {out}/spectrum.png, probes.csv, energy.csv, results.json")
