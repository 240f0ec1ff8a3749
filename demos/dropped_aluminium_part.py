"""# The sound of a dropped aluminium bar

An aluminium bar 300 x 30 x 10 mm (E = 70 GPa, nu = 0.33, rho = 2700 kg/m^3), the struck bar's size, falls
at 1 m/s (a 5 cm drop) onto a hard floor tilted 2 degrees, so that one end strikes first. The dynamic run
(Newmark, 5 us steps, P2) resolves the contact: the barrier of `[contact]` pushes on the surface nodes near the
floor. `[sound.impact]` records that obstacle's force on every node at every step, projects it on the free bar's
modes (all below 20 kHz, SLEPc, about the rest shape; the six rigid-body modes left out), drives each mode as a
damped oscillator at 44.1 kHz and, after the run, lets them ring for 2 s; heard as the pressure the surface
radiates half a metre to the side (`impact.wav`, `impact_spectrogram.png`). The script prints the contact,
the WAV's strongest spectral peaks next to the nearest mode, and the first flexural mode against
Euler-Bernoulli (free-free, (beta L)^2 = 22.373); it draws the WAV's spectrum with the modes marked.

Run: `.venv/bin/python demos/dropped_aluminium_part.py [OUT_DIR]` (also under `mpirun -n 2`: the same numbers).
"""
import math
import sys
from pathlib import Path

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms.analyses.dynamic import run as run_dynamic
from fem_forms.output.sound import read_wav

here = Path(__file__).parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/dropped_aluminium_part")

ff.quiet_jit()
scene = ff.Scene.from_file(here / "scenes" / "dropped_aluminium_part.toml")
summary = run_dynamic(scene, out)
s = summary["impact_sound"]

if MPI.COMM_WORLD.rank == 0:
    modes = np.array(s["frequencies_hz"])
    L, t, E, rho = scene.mesh.size[0], scene.mesh.size[2], scene.material.E, scene.material.rho
    f_eb = 22.373 / (2 * math.pi * L**2) * math.sqrt(E * t**2 / (12 * rho))
    print(f"{scene.title}: {summary['dofs']} dofs, {summary['steps']} Newmark steps of "
          f"{1e6 * scene.dynamic.dt:.0f} us to {1e3 * summary['time_reached']:.1f} ms, {summary['wall_time_s']:.1f} s; "
          f"energy balance error {summary['energy_balance_error']:.1e}")
    print(f"  contact with the {s['obstacle']}: from {1e3 * s['contact_start_s']:.3f} to {1e3 * s['contact_end_s']:.3f} ms "
          f"({1e3 * s['contact_time_s']:.2f} ms), peak force {s['peak_force_N']:.0f} N at "
          f"{1e3 * s['peak_force_time_s']:.3f} ms, impulse {1e3 * s['impulse_Ns']:.1f} mN s")
    print(f"  {s['modes_used']} elastic modes below {s['up_to_hz']:.0f} Hz ({s['rigid_modes']} rigid-body modes left "
          f"out); first flexural {modes[0]:.1f} Hz (Euler-Bernoulli {f_eb:.1f} Hz, {100 * (modes[0] / f_eb - 1):+.2f} %)")

    # the WAV's spectrum: the strongest peaks (the package's peak finder) and their levels
    rate, pcm = read_wav(out / s["wav"])
    from scipy.signal.windows import blackmanharris
    spec = np.abs(np.fft.rfft(pcm * blackmanharris(2 * pcm.size)[pcm.size:]))
    db = 20 * np.log10(spec / spec.max() + 1e-15)
    freq = np.fft.rfftfreq(pcm.size, 1.0 / rate)
    peaks = np.array(s["peaks_hz"])
    level = db[np.rint(peaks * pcm.size / rate).astype(int)]
    print(f"  heard: {s['heard']}, {s['duration_s']:.0f} s at {rate} Hz -> {out / s['wav']}")
    print("    peak [Hz]   level [dB]   nearest mode [Hz]   difference [%]")
    for k in np.argsort(level)[::-1][:6]:
        m = modes[int(np.argmin(np.abs(modes - peaks[k])))]
        print(f"    {peaks[k]:9.1f}   {level[k]:10.1f}   {m:17.1f}   {100 * (peaks[k] / m - 1):+14.3f}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(freq / 1e3, db, lw=0.6, label="impact.wav")
    for i, f in enumerate(modes):
        ax.axvline(f / 1e3, color="tab:red", lw=0.6, ls="--", label="modes of the free bar" if i == 0 else None)
    ax.set(xlim=(0, 20), ylim=(-90, 5), xlabel="frequency [kHz]", ylabel="dB", title=f"{scene.title}: spectrum")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "spectrum.png", dpi=100)
    print(f"  wrote {out}/spectrum.png, impact_spectrogram.png, impact.wav, results.json")
