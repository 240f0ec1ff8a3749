"""# A dog-bone test fitted, and the actuator cast from the fitted silicone

A maker pulls a dog-bone of Ecoflex 00-30 and records stretch and nominal stress (demos/data/
ecoflex_00_30_dogbone.csv: generated from the library's Ecoflex 00-30 Yeoh parameters, C10 = 7.35 kPa,
C20 = 122 Pa, with 2 % Gaussian noise, seed 49: a stand-in for a real test, said so). `fem-forms fit` fits
Yeoh to it (the same code runs here: fit.json, fit.png in OUT/fit); then the PneuNet actuator of
demos/pneunet_actuator.py, cast in that silicone (demos/scenes/fitted_pneunet.toml: the scene's own
`fit = {...}` runs the fit when it is read), is inflated by volume control twice: with the two-term Yeoh fit
(the silicone stiffens as it stretches) and with a one-term fit of the same test (neo-Hookean: no
stiffening). Writes curl.png: the tip angle against the chamber pressure for both.

Run: `.venv/bin/python demos/fitted_actuator.py [OUT_DIR] [H]` (H the cell size in m, default 0.007: its
pressures are 4 % above those of 0.006, its run 36 s against 58 s serial).
"""
import sys
from pathlib import Path

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms.analyses import run_analysis
from fem_forms.materials.fitting import fit, read_test
from fem_forms.output.fit_report import write_fit

here = Path(__file__).parent
sys.path.insert(0, str(here / "geometry"))
import pneunet  # noqa: E402

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/fitted_actuator")
h = float(sys.argv[2]) if len(sys.argv) > 2 else 0.007
comm = MPI.COMM_WORLD
ff.quiet_jit()

test = read_test(here / "data" / "ecoflex_00_30_dogbone.csv", "uniaxial")
yeoh = fit("yeoh", [test], terms=2)
if comm.rank == 0:
    write_fit(yeoh, out / "fit")
    pneunet.build(out / "pneunet.msh", h, layer=pneunet.LAYER)
comm.barrier()

curves, results = {}, {}
for terms, label in ((2, "yeoh, 2 terms"), (1, "neo-hookean (yeoh, 1 term)")):
    scene = ff.Scene.from_file(here / "scenes" / "fitted_pneunet.toml",
                               overrides={"mesh.file": str(out / "pneunet.msh"), "material.0.fit.terms": terms})
    folder = out / f"terms_{terms}"
    s = run_analysis(scene, folder)                 # as `fem-forms run`: probes.csv holds the load path
    if comm.rank == 0:
        cav = s["cavities"]["chambers"]
        rows = pneunet.curve_from_probes(folder / "probes.csv", cav["volume"] - cav["volume_change"])
        curves[label] = np.array([(0.0, 0.0, 0.0)] + rows)
        results[label] = s

if comm.rank == 0:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for label, c in curves.items():
        ax.plot(c[:, 1] / 1e3, c[:, 2], "o-", ms=3, label=label)
    ax.set_xlabel("chamber pressure [kPa]")
    ax.set_ylabel("tip angle [deg]")
    ax.set_title("PneuNet of fitted Ecoflex 00-30: curl against pressure", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "curl.png", dpi=120)
    e = yeoh.errors
    print(f"fit of {Path(test.source).name} ({len(test.stretch)} points): yeoh C10 = {yeoh.parameters['C10']:.1f} "
          f"+- {e['C10']:.1f} Pa, C20 = {yeoh.parameters['C20']:.2f} +- {e['C20']:.2f} Pa, rms relative error "
          f"{np.sqrt(np.mean(yeoh.relative_errors[0] ** 2)):.4f}; Drucker-stable in uniaxial from "
          f"{yeoh.stable['uniaxial'][0]:.3g} to {yeoh.stable['uniaxial'][1]:.3g}")
    for label, c in curves.items():
        s, m = results[label], results[label]["materials"][0]
        peak = int(np.argmax(c[:, 1]))
        print(f"{label}: C10 = {m['C10']:.1f} Pa, C20 = {m.get('C20') or 0.0:.2f} Pa; {s['load_steps']} load steps, "
              f"{s['newton_iterations']} Newton iterations, converged {s['converged']}; at "
              f"{c[-1, 0] * 1e6:.1f} ml: pressure {c[-1, 1] / 1e3:.3f} kPa, tip angle {c[-1, 2]:.2f} deg; "
              f"highest pressure {c[peak, 1] / 1e3:.3f} kPa at {c[peak, 0] * 1e6:.2f} ml")
    print(f"  wrote {out}/fit/fit.json, fit/fit.png, terms_2/, terms_1/ (results.json, fields.xdmf), curl.png")
