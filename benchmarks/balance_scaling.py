"""Balance design time against mesh size (box parts, tetrahedra, no elasticity): mass-property
assembly, LP set-up, LP solve and binarisation, for the stand, spin and swim goals.

    python benchmarks/balance_scaling.py [--max-cells 200000]     -> balance_scaling.md
"""
import argparse
import time
from pathlib import Path

import numpy as np

import fem_forms as ff
from fem_forms.analyses.balance import _rigid, setting
from fem_forms.analyses.balance.body import Body
from fem_forms.meshes import load_mesh

GOALS = {"stand": {"goal": "stand", "margin_angle": 2.0, "shell": 0.01},
         "spin": {"goal": "spin", "kind": "top", "shell": 0.01},
         "swim": {"goal": "swim", "waterline": 0.05, "shell": 0.01}}


def scene(n: int, goal: dict) -> ff.Scene:
    # a leaning block: origin shifted so it stands on its full base; the goals only need the geometry
    k = max(2, round((n / 6 / 2) ** (1 / 3)))
    return ff.Scene.from_dict({"analysis": "balance", "mesh": {"size": [0.2, 0.2, 0.1], "cells": [2 * k, 2 * k, k]},
                               "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 700.0},
                               "balance": goal})


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-cells", type=int, default=200000)
    args = ap.parse_args()
    rows = []
    for n in (5000, 25000, 100000, args.max_cells):
        for name, goal in GOALS.items():
            sc = scene(n, goal)
            t0 = time.perf_counter()
            mesh = load_mesh(sc.mesh).mesh
            t1 = time.perf_counter()
            body = Body.rest(mesh, sc.balance.shell)
            t2 = time.perf_counter()
            r = _rigid(sc, setting(sc, mesh), body)
            tm = r["timing"]
            cells = mesh.topology.index_map(3).size_global
            rows.append((cells, name, t2 - t1, tm.setup_s, tm.solve_s, tm.lps, tm.binarise_s, r["design_time_s"],
                         r["after"]["carved_fraction"]))
            print(rows[-1], flush=True)
    lines = ["# Balance design time against mesh size", "",
             "Box parts 0.2 x 0.2 x 0.1 m (tetrahedra), rho 700, shell 0.01 m; one process on this machine.",
             "`moments`: per-cell moment integrals and the shell distance; `design`: LP set-up, LP solves,",
             "binarisation and the evaluation of the binary design (before and after).", "",
             "| cells | goal | moments (s) | LP set-up (s) | LP solve (s) | LPs | binarise (s) | design total (s) | carved |",
             "|---|---|---|---|---|---|---|---|---|"]
    for c, g, m, su, so, n, b, tot, cf in rows:
        lines.append(f"| {c} | {g} | {m:.2f} | {su:.3f} | {so:.2f} | {n} | {b:.3f} | {tot:.2f} | {cf:.3f} |")
    Path(__file__).with_suffix(".md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
