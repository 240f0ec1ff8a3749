"""Benchmark: what the rubber models cost against neo-Hookean, per Newton iteration, and their form compile
time from an empty cache.

The cantilever of benchmarks/materials_cost.py (400 x 40 x 20 mm, P2 tetrahedra, 19,683 dofs) under its own
weight, its shear modulus the same in every model (mu0 = 3.85 MPa, nu 0.3): neo-Hookean (the package's
compressible one), Yeoh with C10 alone and one Ogden term with alpha = 2 (both the split neo-Hookean energy:
the same problem, so the cost per iteration compares kernels), three Ogden terms (Ogden's 1972 exponents,
scaled to mu0), Gent (Jm 30), Arruda-Boyce (lambda_m 3). Each model runs in its own process and form
cache (HOME set to a folder of its own): two solves, the second warm; the first round starts from an empty cache
(compile = the first solve less the second). The models take turns, ROUNDS times (3): the ratios to
neo-Hookean are taken within a round (these machines drift 15-35 % over minutes) and their median quoted. One
core. The target (issue 49): Ogden at most 1.5x neo-Hookean per Newton iteration.

Run: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/rubber_cost.py` (about 6 minutes). Writes
benchmarks/rubber_cost.md.
"""
from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from fem_forms.materials.isochoric import ARRUDA_BOYCE_SERIES  # noqa: E402
L, B, H = 0.4, 0.04, 0.02
MU0, NU = 1e7 / 2.6, 0.3
BULK = 2 * MU0 * (1 + NU) / (3 * (1 - 2 * NU))
OGDEN_ALPHA = (1.3, 5.0, -2.0)
OGDEN_MU = tuple(m * MU0 / 0.4225e6 for m in (0.63e6, 0.0012e6, -0.01e6))   # sum mu alpha / 2 = MU0
MATERIALS = {
    "neo-hookean": {"model": "neo-hookean", "E": 1e7, "nu": NU},
    "yeoh, C10 only": {"model": "yeoh", "C10": MU0 / 2, "bulk": BULK},
    "ogden, 1 term (alpha 2)": {"model": "ogden", "mu": [MU0], "alpha": [2.0], "bulk": BULK},
    "ogden, 3 terms": {"model": "ogden", "mu": list(OGDEN_MU), "alpha": list(OGDEN_ALPHA), "bulk": BULK},
    "gent (Jm 30)": {"model": "gent", "mu": MU0, "Jm": 30.0, "bulk": BULK},
    "arruda-boyce (lambda_m 3)": {"model": "arruda-boyce", "mu": MU0 / sum(2 * i * c * 3.0 ** (i - 1) / 9.0 ** (i - 1)
                                                                 for i, c in enumerate(ARRUDA_BOYCE_SERIES, 1)),
                                  "lambda_m": 3.0, "bulk": BULK},
}


def scene(material: dict):
    import fem_forms as ff
    return ff.Scene.from_dict({
        "title": material["model"], "mesh": {"size": [L, B, H], "cells": [40, 4, 4]},
        "material": {**material, "rho": 1000.0}, "discretization": {"degree": 2},
        "fix": [{"where": {"axis": "x", "at": 0.0}}], "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81 * 5]}],
        "solver": {"steps": 2}, "output": {"picture": False, "fields": False}})


def measure(name: str) -> dict:
    """One model in this process: two solves, the second warm (the first compiles when the cache is empty)."""
    import fem_forms as ff
    ff.quiet_jit()
    runs = []
    for _ in range(2):
        t0 = time.perf_counter()
        result = ff.solve_static(scene(MATERIALS[name]))
        runs.append(time.perf_counter() - t0)
        assert result.report.converged, name
    return {"name": name, "dofs": result.model.dofs, "iterations": result.report.newton_iterations,
            "wall": runs[1], "assembly": result.report.assembly_time, "compile": runs[0] - runs[1]}


def run_one(name: str, home: str) -> dict:
    env = dict(os.environ, HOME=home, OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, __file__, "--one", name], env=env, capture_output=True, text=True,
                       cwd=HERE.parent)
    if p.returncode != 0:
        raise SystemExit(f"{name}: {p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    if len(sys.argv) > 2 and sys.argv[1] == "--one":
        print(json.dumps(measure(sys.argv[2])))
        return
    rounds = int(os.environ.get("ROUNDS", "3"))
    homes = {name: tempfile.mkdtemp() for name in MATERIALS}     # each model's own form cache, empty at first
    runs: dict = {name: [] for name in MATERIALS}
    for k in range(rounds):           # rounds of every model in turn: a slow spell of the machine hits all alike
        for name in MATERIALS:
            runs[name].append(run_one(name, homes[name]))
            print(f"round {k + 1}: {name}: {runs[name][-1]['wall']:.2f} s", flush=True)
    ref = runs["neo-hookean"]
    rows = []
    for name, rs in runs.items():
        per = lambda r, key: r[key] / r["iterations"]                           # noqa: E731
        ratio = [per(r, "wall") / per(n, "wall") for r, n in zip(rs, ref)]
        ratio_asm = [per(r, "assembly") / per(n, "assembly") for r, n in zip(rs, ref)]
        m = statistics.median
        rows.append(f"| {name} | {rs[0]['dofs']:,} | {rs[-1]['iterations']} | {m(r['wall'] for r in rs):.2f} s | "
                    f"{m(r['assembly'] for r in rs):.2f} s | {m(ratio_asm):.2f}x | {m(ratio):.2f}x "
                    f"({min(ratio):.2f}-{max(ratio):.2f}) | {rs[0]['compile']:.1f} s |")
    for home in homes.values():
        shutil.rmtree(home, ignore_errors=True)
    load = os.getloadavg()[0]
    lines = ["# Rubber models: cost against neo-Hookean", "",
             "Generated by `benchmarks/rubber_cost.py` (see its docstring): the P2 cantilever under 5 g, the same "
             f"initial shear modulus in every model; {rounds} rounds of every model in turn (one warm solve each, one "
             f"core, each model in its own process and form cache), medians over the rounds, the ratios taken within "
             f"each round (their range in brackets); compile from the first round's empty cache (load average "
             f"{load:.1f} at the end).", "",
             "| model | dofs | Newton iterations | solve | assembly (residual + tangent) | assembly per iteration, "
             "against neo-Hookean | solve per iteration, against neo-Hookean | form compile (empty cache) |",
             "|---|---|---|---|---|---|---|---|", *rows]
    (HERE / "rubber_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
