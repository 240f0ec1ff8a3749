"""Benchmark: a soft ball thrown onto a rigid floor against Hertz's impact (issue 47, item 1).

A rubber ball (R 20 mm, E 1 MPa, nu 0.4, 1100 kg/m^3) falls at 1 m/s onto a frictionless rigid plane, starting
0.2 mm above it. Hertz's quasi-static impact (Johnson, Contact Mechanics, 11.4): contact time
t_c = 2.868 (m^2 / (R E*^2 v))^(1/5), peak force F = 4/3 E* sqrt(R) delta^(3/2) with the largest approach
delta = (15 m v^2 / (16 E* sqrt(R)))^(2/5), E* = E / (1 - nu^2). The model is a quarter of the ball (symmetry
planes x = 0 and y = 0 held normal to themselves), tetrahedra of `fine` size within `zone` of the lowest point,
growing to `coarse`; the default scheme (Newmark) and dt 0.1 ms, with and without the refinement of the step at
the impact (`dynamic.refine_events`), P1 and P2, two meshes, two barrier distances, and the same ball at 0.1 m/s.
Measured from probes.csv: the time the floor pushes (its force above 1 % of the peak) and the peak force (x 4
for the whole ball), wall time of one process each.

Run: `.venv/bin/python benchmarks/hertz_impact.py` (about 10 minutes). Writes benchmarks/hertz_impact.md.
"""
from __future__ import annotations

import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from contact_schemes import one      # the same one-run entry: a scene run as `fem-forms run` does

HERE = Path(__file__).resolve().parent
R, E, NU, RHO, V, GAP = 0.02, 1e6, 0.4, 1100.0, 1.0, 2e-4


def hertz(v: float = V) -> tuple[float, float]:
    """(contact time s, peak force N) of the whole ball thrown at v."""
    m = RHO * 4 / 3 * math.pi * R ** 3
    es = E / (1 - NU * NU)
    delta = (15 * m * v * v / (16 * es * math.sqrt(R))) ** 0.4
    return 2.868 * (m * m / (R * es * es * v)) ** 0.2, 4 / 3 * es * math.sqrt(R) * delta ** 1.5


def quarter_ball(path: Path, fine: float, coarse: float, zone: float) -> Path:
    """The part x >= 0, y >= 0 of the ball of radius R centred at (0, 0, R), graded toward its lowest point (the
    verification manual's Hertz geometry, not cut at the equator)."""
    spec = importlib.util.spec_from_file_location("hertz_hemisphere", HERE.parent / "verification" / "geometry" /
                                                  "hertz_hemisphere.py")
    geometry = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(geometry)
    return geometry.build(path, R, fine, coarse, zone, whole_ball=True, spread=3.0)


def scene(mesh: Path, degree: int, refine: int, v: float = V, dt: float = 1e-4) -> dict:
    t_c, _ = hertz(v)
    return {"title": "ball thrown onto a floor", "analysis": "dynamic", "mesh": {"generator": "file", "file": str(mesh)},
            "material": {"model": "neo-hookean", "E": E, "nu": NU, "rho": RHO},
            "discretization": {"degree": degree},
            "fix": [{"name": "sym_x", "where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                    {"name": "sym_y", "where": {"axis": "y", "at": 0.0}, "components": ["y"]}],
            "dynamic": {"duration": GAP / v + 1.3 * t_c, "dt": dt, "refine_events": refine, "output_every": 1000,
                        "initial_velocity": [0.0, 0.0, -v]},
            "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -GAP], "normal": [0, 0, 1]}]},
            "output": {"picture": False, "fields": False}}


def measure(out: Path) -> tuple[float, float]:
    """(contact time, peak force) of the whole ball from probes.csv (the floor's force, x 4)."""
    h = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    t, f = h["time"], 4 * h["floor_Fz"]
    on = f > 0.01 * f.max()
    k = np.flatnonzero(on)
    # the first and last instants with force, each interpolated to where the force crosses 1 % of the peak
    lo, hi, level = k[0], k[-1], 0.01 * f.max()
    start = t[lo - 1] + (level - f[lo - 1]) * (t[lo] - t[lo - 1]) / (f[lo] - f[lo - 1])
    end = t[hi] + (f[hi] - level) * (t[hi + 1] - t[hi]) / (f[hi] - f[hi + 1]) if hi + 1 < len(t) else t[hi]
    return end - start, float(f.max())


def run(sc: dict, work: Path) -> tuple[dict, Path, float]:
    work.mkdir(parents=True, exist_ok=True)
    (work / "scene.json").write_text(json.dumps(sc))
    out = work / "out"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    t = time.perf_counter()
    subprocess.run([sys.executable, __file__, "--one", str(work / "scene.json"), str(out)], env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.loads((out / "results.json").read_text()), out, time.perf_counter() - t


def row(label: str, sc: dict, work: Path) -> str:
    r, out, wall = run(sc, work)
    tc, fm = measure(out)
    t_c, f_max = hertz(-sc["dynamic"]["initial_velocity"][2])
    return (f"| {label} | {r['dofs']} | {r['steps']} ({r.get('refined_steps', 0)}) | {r['newton_iterations']} | "
            f"{wall:.1f} s | {1e3 * tc:.2f} ms ({100 * (tc / t_c - 1):+.1f} %) | {fm:.2f} N "
            f"({100 * (fm / f_max - 1):+.1f} %) |")


def main() -> None:
    work = Path(tempfile.mkdtemp())
    t_c, f_max = hertz()
    lines = ["# A soft ball thrown onto a rigid floor, against Hertz's impact", "",
             f"Generated by `benchmarks/hertz_impact.py` (see its docstring). Hertz at 1 m/s: contact time "
             f"{1e3 * t_c:.2f} ms, peak force {f_max:.1f} N. One process per run, one core, Newmark.", "",
             "| run | dofs | steps (refined) | Newton iterations | wall | contact time against Hertz | "
             "peak force against Hertz |", "|---|---|---|---|---|---|---|"]
    coarse = quarter_ball(work / "ball-1mm.msh", 1e-3, 4e-3, 8e-3)
    fine = quarter_ball(work / "ball-0.5mm.msh", 5e-4, 4e-3, 8e-3)
    runs = [("1 m/s, P1, 1 mm, dt 0.1 ms, refine_events 0", scene(coarse, 1, 0)),
            ("1 m/s, P1, 1 mm, dt 0.1 ms, refine_events 4", scene(coarse, 1, 4)),
            ("1 m/s, P1, 1 mm, dt 0.4 ms, refine_events 0", scene(coarse, 1, 0, dt=4e-4)),
            ("1 m/s, P1, 1 mm, dt 0.4 ms, refine_events 4", scene(coarse, 1, 4, dt=4e-4)),
            ("1 m/s, P1, 0.5 mm, dt 0.1 ms", scene(fine, 1, 4)),
            ("1 m/s, P2, 1 mm, dt 0.1 ms", scene(coarse, 2, 4)),
            ("1 m/s, P1, 1 mm, contact.distance 10 um (default 35 um)",
             dict(scene(coarse, 1, 4), contact={**scene(coarse, 1, 4)["contact"], "distance": 1e-5})),
            ("0.1 m/s, P1, 0.5 mm, dt 0.2 ms", scene(fine, 1, 4, v=0.1, dt=2e-4))]
    for i, (label, sc) in enumerate(runs):
        lines.append(row(label, sc, work / f"run{i}"))
        print(lines[-1], flush=True)
    (HERE / "hertz_impact.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--one"]:
        one(*sys.argv[2:4])
    else:
        main()
