"""A roly-poly toy pushed over rocks back on the floor (dynamics with contact and friction; GIF).

    python demos/rocking_toy.py OUT_DIR

The toy: a solid rubber hemisphere (R 5 cm, dome down) with a short cylindrical head (radius 2 cm, height
4 cm) on its flat face (E 1 MPa, nu 0.4, 1100 kg/m^3). It first settles on a frictional floor (mu 0.8)
under its own weight, then is pushed: a rotation of 1.6 rad/s about the contact point. Its centre of mass
lies below the dome's centre, so it rolls out, stops and rocks back, the floor's friction keeping the dome
from slipping. The tilt is read from two probes on its axis; the rocking period is compared with rolling
without slip for small amplitude, T = 2 pi sqrt(I_P / (m g d)) (I_P: moment of inertia about the contact
point, d: the centre of mass's depth below the dome's centre). Writes motion.gif and tilt.png.

Measured (2,532 dofs, 203 steps, 50-90 s): period 0.882 s against 0.839 s (+5 %, amplitude 13.7 deg) on one
CPU, 0.854 s (+2 %) on another: stick and slip on the floor switch on the last bits, so the motion differs
from machine to machine as a repeated experiment does. The dome's centre also drifts sideways (~5 mm, across the
push): unexplained yet (mesh asymmetry growing, the lagged friction, or rolling's own instability), printed so
that it is seen.
"""
import math
from pathlib import Path
import sys

from mpi4py import MPI
import numpy as np

import fem_forms as ff
from fem_forms.analyses.dynamic import run as run_dynamic

SCENE = Path(__file__).parent / "scenes" / "rocking_toy.toml"
R, r, H, RHO, G = 0.05, 0.02, 0.04, 1100.0, 9.81      # the toy's dome and cylinder, as in its scene and CAD file


def masses() -> tuple[float, float]:
    """The hemisphere's and the cylinder's mass."""
    return RHO * 2 / 3 * math.pi * R ** 3, RHO * math.pi * r * r * H


def rolling_period() -> float:
    """Small-amplitude rolling without slip: closed forms of the hemisphere and the cylinder."""
    mh, mc = masses()
    m = mh + mc
    zc = (mh * -3 * R / 8 + mc * H / 2) / m                  # centre of mass height above the dome's centre
    i_centre = 2 / 5 * mh * R * R + mc * (r * r / 4 + H * H / 3)     # about a horizontal axis through the centre
    i_contact = i_centre - m * zc * zc + m * (R + zc) ** 2            # moved to the contact point, R below it
    return 2 * math.pi * math.sqrt(i_contact / (m * G * -zc))


def crossings(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Times where y changes sign (linear interpolation)."""
    k = np.flatnonzero(np.sign(y[1:]) != np.sign(y[:-1]))
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    summary = run_dynamic(ff.Scene.from_file(SCENE), out / "run")
    if MPI.COMM_WORLD.rank != 0:
        return
    h = np.genfromtxt(out / "run" / "probes.csv", delimiter=",", names=True)
    dz = H + h["head_uz"] - h["centre_uz"]
    tilt = np.degrees(np.arctan2(h["head_ux"] - h["centre_ux"], dz))
    cross = crossings(h["time"], tilt)
    period = 2 * float(np.mean(np.diff(cross)))
    print(f"{summary['dofs']} dofs, {summary['steps']} steps, {summary['newton_iterations']} Newton iterations, "
          f"{summary['wall_time_s']:.1f} s, intersection free {summary['intersection_free']}")
    print(f"largest tilt {np.abs(tilt).max():.2f} deg; tilt back through upright at {', '.join(f'{c:.3f}' for c in cross)} s")
    print(f"rocking period {period:.4f} s (rolling without slip, small amplitude: {rolling_period():.4f} s)")
    print(f"sideways drift of the dome's centre up to {1e3 * np.abs(h['centre_uy']).max():.2f} mm (the push is in x)")
    force = summary["contact"]["floor"]["force"]
    print(f"floor force at the end {force[2]:.4f} N up, {math.hypot(force[0], force[1]):.4f} N along the floor "
          f"(weight {sum(masses()) * G:.4f} N); energy balance error {summary['energy_balance_error']:.2e}")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(h["time"], tilt)
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tilt [deg]")
    ax.set_title("roly-poly toy pushed over: it rocks back")
    fig.tight_layout()
    fig.savefig(out / "tilt.png", dpi=120)
    print(f"wrote {out / 'run' / 'motion.gif'}, {out / 'tilt.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "rocking_toy_out"))
