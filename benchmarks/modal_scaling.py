"""Modal analysis cost as the mesh grows: time and peak memory for the 10 lowest modes.

A steel cantilever 1 x 0.25 x 0.25 m (P2 tetrahedra, 4n x n x n cells) is solved two ways:
Krylov-Schur with shift-and-invert about 0 and MUMPS LU ("direct"), or the same with CG + GAMG
(rigid-body near-nullspace, rtol 1e-10) as the inner solver ("iterative"). Each is run as

- ours: `fem_forms.analyses.modal.solve_modal(scene)`, end to end (mesh, forms, assembly,
  eigensolve, mass normalisation, signs, effective masses); the eigensolve part is also timed;
- bare: the same K and M (assembled once by fem_forms, not timed) handed to a slepc4py EPS set up
  directly with the same settings; only EPS setup + solve is timed.

Each run is a fresh process, so its peak resident memory (getrusage ru_maxrss) is its own.
The table reports medians over --repeats runs (fewer for the large, slow rows: see "runs").

Run: `.venv/bin/python benchmarks/modal_scaling.py [--write]` (about 8 minutes on 2 cores;
the iterative rows stop at 60k dofs, where they already take minutes).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
COUNT = 10


def scene_dict(n: int, kind: str) -> dict:
    return {"title": f"cantilever n={n}", "analysis": "modal",
            "mesh": {"size": [1.0, 0.25, 0.25], "cells": [4 * n, n, n]},
            "material": {"model": "linear", "E": 2.0e11, "nu": 0.3, "rho": 7800.0},
            "discretization": {"degree": 2},
            "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "solver": {"linear": kind},
            "modal": {"count": COUNT}}


def bare_eps(K, M, kind: str, V):
    """SLEPc set up by hand: the reference for our wrapper's overhead."""
    from petsc4py import PETSc
    from slepc4py import SLEPc
    from fem_forms.solvers import linear
    eps = SLEPc.EPS().create(K.getComm())
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(nev=COUNT)
    eps.setTolerances(1e-10, 200)
    eps.setTarget(0.0)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    ksp = st.getKSP()
    if kind == "direct":
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
    else:
        K.setNearNullSpace(linear.rigid_body_modes(V))
        opts = PETSc.Options()
        for k, v in linear.ITERATIVE.items():
            opts["bare_" + k] = v
        opts["bare_ksp_rtol"] = 1e-10
        opts["bare_ksp_max_it"] = 2000
        ksp.setOptionsPrefix("bare_")
        ksp.setFromOptions()
    return eps


def child(n: int, kind: str, impl: str) -> dict:
    """One measurement in this (fresh) process."""
    sys.path.insert(0, str(ROOT))
    import numpy as np
    import fem_forms as ff
    from fem_forms.analyses.modal import assemble_operators, solve_modal
    from fem_forms.model import build_model
    ff.quiet_jit()
    scene = ff.Scene.from_dict(scene_dict(n, kind))
    row = {"n": n, "kind": kind, "impl": impl}
    if impl == "ours":
        t0 = time.perf_counter()
        res = solve_modal(scene)
        row["total_s"] = time.perf_counter() - t0
        row["eigensolve_s"] = res.eigensolve_time_s
        row["dofs"] = res.model.dofs
        row["freqs"] = res.frequencies_hz.tolist()
    else:
        model = build_model(scene)
        model.load.set(0.0)
        ops = assemble_operators(model, kind)
        t0 = time.perf_counter()
        eps = bare_eps(ops.K, ops.M, kind, model.V)
        eps.solve()
        lam = []
        for i in range(COUNT):                        # a modal analysis needs the vectors too
            vr = ops.K.createVecRight()
            lam.append(eps.getEigenpair(i, vr).real)
        row["eigensolve_s"] = time.perf_counter() - t0
        lam = np.sort(lam)
        row["dofs"] = model.dofs
        row["freqs"] = (np.sqrt(lam) / (2 * np.pi)).tolist()
    row["maxrss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return row


def run_child(n: int, kind: str, impl: str) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, __file__, "--child", str(n), kind, impl], env=env,
                       capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[3, 5, 8, 11], help="n of 4n x n x n cells")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--repeat-below", type=int, default=10_000, help="rows above this many dofs run once")
    ap.add_argument("--iterative-max", type=int, default=60_000, help="largest dofs for the iterative rows")
    ap.add_argument("--write", action="store_true", help="also write benchmarks/modal_scaling.md")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        n, kind, impl = args.child
        print(json.dumps(child(int(n), kind, impl)))
        return

    t_start = time.perf_counter()
    run_child(args.sizes[0], "direct", "ours")        # warm the JIT cache: not measured
    lines = ["| dofs | inner solver | ours total [s] | ours eigensolve [s] | bare eigensolve [s] | "
             "ours/bare | ours peak RSS [MB] | bare peak RSS [MB] | f1 [Hz] | max rel. diff ours-bare "
             "| runs |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    print("\n".join(lines), flush=True)
    for n in args.sizes:
        dofs = 3 * (8 * n + 1) * (2 * n + 1) ** 2
        for kind in ("direct", "iterative"):
            if kind == "iterative" and dofs > args.iterative_max:
                continue
            reps = args.repeats if dofs <= args.repeat_below else 1
            runs = {"ours": [], "bare": []}
            for _ in range(reps):                     # alternate, so machine load hits both alike
                for impl in ("ours", "bare"):
                    runs[impl].append(run_child(n, kind, impl))
            med = {impl: {k: statistics.median(r[k] for r in rs)
                          for k in ("eigensolve_s", "maxrss_mb")} for impl, rs in runs.items()}
            ours_total = statistics.median(r["total_s"] for r in runs["ours"])
            fo, fb = runs["ours"][0]["freqs"], runs["bare"][0]["freqs"]
            diff = max(abs(a - b) / b for a, b in zip(fo, fb))
            line = (f"| {runs['ours'][0]['dofs']:,} | {'MUMPS LU' if kind == 'direct' else 'CG+GAMG'} | "
                    f"{ours_total:.2f} | {med['ours']['eigensolve_s']:.2f} | "
                    f"{med['bare']['eigensolve_s']:.2f} | "
                    f"{med['ours']['eigensolve_s'] / med['bare']['eigensolve_s']:.2f} | "
                    f"{med['ours']['maxrss_mb']:.0f} | {med['bare']['maxrss_mb']:.0f} | {fo[0]:.3f} | "
                    f"{diff:.1e} | {reps} |")
            lines.append(line)
            print(line, flush=True)
    total = time.perf_counter() - t_start
    print(f"\n(total benchmark time {total:.0f} s)")
    if args.write:
        (HERE / "modal_scaling.md").write_text(
            "# Modal scaling: 10 lowest modes of a clamped steel block, P2 tetrahedra\n\n"
            "Produced by `benchmarks/modal_scaling.py` (serial, OPENBLAS_NUM_THREADS=1, one fresh process "
            "per run; medians over `runs`). \"ours\" is `solve_modal` end to end; \"bare\" is a slepc4py EPS "
            "set up by hand on the same assembled K and M (EPS setup + solve only). "
            "The ratio ours/bare compares the eigensolves.\n\n" + "\n".join(lines) +
            f"\n\nTotal benchmark time {total:.0f} s.\n")


if __name__ == "__main__":
    main()
