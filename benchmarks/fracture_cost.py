"""Benchmark: what a phase field costs, and how mesh size and the staggered tolerance trade accuracy for time.

1. Cost per load step: the verification manual's centre-cracked plate (a quarter, one layer of P1 tetrahedra,
   a = 0.15, l = 0.015, h = l/3 along the crack: 11,748 dofs), 16 displacement steps to 1.3x the critical one,
   with [fracture] and without it (the same scene purely elastic); medians of 3 runs after one that compiled the
   forms; one core.
2. Accuracy against time: the notched bar (E = Gc = 1, l = 0.1, cut through by a notch at mid-length, pulled to
   30x its cracking strain) at h = l/2, l/4, l/8 with tolerance 1e-4, and at h = l/4 with tolerances 1e-3, 1e-5:
   the crack area against the section (the phase field's surface energy over Gc: Bourdin's correction says
   A (1 + 3 h / (8 l))), the peak force against the finest tightest run, sweeps and wall time.

Run: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fracture_cost.py` (about 5 minutes). Writes
benchmarks/fracture_cost.md.
"""
from __future__ import annotations

import math
import statistics
import sys
import time
from pathlib import Path

import fem_forms as ff

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "verification" / "geometry"))
import centre_crack  # noqa: E402

A_CRACK, ELL, H_FINE = 0.15, 0.015, 0.005


def plate(mesh: Path, fracture: bool) -> ff.Scene:
    sigma_c = math.sqrt(1.0 * 1e-3 * (1 + 3 * H_FINE / (8 * ELL)) / (math.pi * A_CRACK / math.cos(math.pi * A_CRACK)))
    d = {"title": "centre crack", "mesh": {"generator": "file", "file": str(mesh)},
         "material": {"model": "linear", "E": 1.0, "nu": 0.0}, "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                 {"where": {"axis": "y", "at": 0.0}, "components": ["y"]},
                 {"where": {"axis": "z", "at": 0.0}, "components": ["z"]},
                 {"name": "pull", "where": {"axis": "y", "at": 0.75}, "components": ["y"],
                  "value": [0.0, 1.3 * sigma_c * 0.75, 0.0]}],
         "solver": {"steps": 16, "max_step": 1 / 16}, "output": {"picture": False, "fields": False}}
    if fracture:
        d["fracture"] = {"toughness": 1e-3, "length": ELL,
                         "notch": [{"where": {"box": [[-1e-7, -1e-7, -1e-7], [A_CRACK, 1e-7, 0.0100001]]}}]}
    return ff.Scene.from_dict(d)


def bar(h_over_l: float, tolerance: float) -> ff.Scene:
    cells = round(1.0 / (0.1 * h_over_l))
    return ff.Scene.from_dict({
        "mesh": {"size": [1.0, 0.1, 0.1], "cells": [cells, 1, 1]},
        "material": {"model": "linear", "E": 1.0, "nu": 0.0}, "discretization": {"degree": 1},
        "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"]
        + [{"name": "pull", "where": {"axis": "x", "at": 1.0}, "components": ["x"], "value": [3.0, 0.0, 0.0]}],
        "fracture": {"toughness": 1.0, "length": 0.1, "tolerance": tolerance,
                     "notch": [{"where": {"box": [[0.5, 0.0, 0.0], [0.5, 0.1, 0.1]]}}]},
        "solver": {"steps": 30, "max_step": 1 / 30}, "output": {"picture": False, "fields": False}})


def timed(scene: ff.Scene, runs: int = 3) -> tuple[float, dict]:
    ff.solve_static(scene)                                   # compiles the forms
    times, summary = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = ff.solve_static(scene)
        times.append(time.perf_counter() - t0)
        summary = result.summary()
    return statistics.median(times), summary


def main() -> None:
    ff.quiet_jit()
    mesh = centre_crack.build(Path("/tmp/fracture_cost_plate.msh"), ell=ELL, h_fine=H_FINE)
    lines = ["# What a phase field costs (benchmarks/fracture_cost.py)", "",
             "## Cost per load step: the centre-cracked plate, 16 steps to 1.3x the critical displacement", "",
             "| scene | dofs | load steps | sweeps | Newton iterations | wall time | per load step | x elastic |",
             "|---|---|---|---|---|---|---|---|"]
    elastic_step = None
    for fracture in (False, True):
        wall, s = timed(plate(mesh, fracture))
        per = wall / s["load_steps"]
        elastic_step = elastic_step or per
        lines.append(f"| {'with [fracture] (AT1)' if fracture else 'elastic'} | {s['dofs']:,} | {s['load_steps']} | "
                     f"{s.get('staggered_sweeps', 0)} | {s['newton_iterations']} | {wall:.2f} s | {per:.3f} s | "
                     f"{per / elastic_step:.1f}x |")
        print(lines[-1], flush=True)
    lines += ["", "## Accuracy against time: the notched bar cut through (A = 0.01, l = 0.1)", "",
              "| h / l | tolerance | crack area / A | Bourdin 1 + 3h/(8l) | peak force vs finest | sweeps | wall time |",
              "|---|---|---|---|---|---|---|"]
    cases = [(1 / 8, 1e-5), (1 / 2, 1e-4), (1 / 4, 1e-4), (1 / 8, 1e-4), (1 / 4, 1e-3), (1 / 4, 1e-5)]
    reference = None
    for h_over_l, tol in cases:
        wall, s = timed(bar(h_over_l, tol), runs=3)
        peak = s["peak_force"]["pull"]
        reference = reference or peak
        lines.append(f"| 1/{round(1 / h_over_l)} | {tol:g} | {s['crack_area'] / 0.01:.4f} | "
                     f"{1 + 3 * h_over_l / 8:.4f} | {100 * (peak / reference - 1):+.2f} % | {s['staggered_sweeps']} | "
                     f"{wall:.2f} s |")
        print(lines[-1], flush=True)
    lines += ["", "Medians of 3 runs after one that compiled the forms; one core; these machines vary 15-35 % run "
              "to run. The first bar row (h = l/8, tolerance 1e-5) is the reference of the peak column."]
    (HERE / "fracture_cost.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
