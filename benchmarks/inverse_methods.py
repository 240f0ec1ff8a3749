"""Benchmark: cost of each rest-shape design method as a ratio to one forward solve on the same mesh,
and the Chen et al. (2014) comparison (47,077-tet silicone part designed in 7.07 s).

Each configuration runs in its own process (so JIT and memory do not leak between rows); inside it a
warm-up run compiles the forms, then the median of --repeat timed runs is reported. Times are the
whole design call (mesh creation, assembly, solves, no JIT), without the forward check and output.

Run: `.venv/bin/python benchmarks/inverse_methods.py [--quick] [--repeat 3]` (about 5 minutes);
`mpirun -n 2` variants are launched by the script itself. Writes benchmarks/inverse_methods.md.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def beam(cells, E=1e6, nu=0.3, rho=1100.0, size=(1.0, 0.1, 0.1), steps=4) -> dict:
    return {"title": "bench", "analysis": "inverse",
            "mesh": {"generator": "box", "size": list(size), "cells": list(cells)},
            "material": {"model": "neo-hookean", "E": E, "nu": nu, "rho": rho},
            "discretization": {"degree": 1},
            "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81]}],
            "solver": {"steps": steps}}


# the Chen et al. material (silicone, E 0.68 MPa, nu 0.45, rho 958) on a thick arm of 47,040 tetrahedra
CHEN = dict(cells=(40, 14, 14), E=0.68e6, nu=0.45, rho=958.0, size=(0.2, 0.05, 0.05), steps=1)


def worker(args) -> None:
    """One configuration in this process: prints a JSON line with the median time."""
    import fem_forms as ff
    from fem_forms.analyses import inverse
    from fem_forms.analyses.static.solve import solve_static
    from mpi4py import MPI
    ff.quiet_jit()
    d = json.loads(args.scene)
    scene = ff.Scene.from_dict(d)
    method = args.method
    times, info = [], {}
    for k in range(args.repeat + 1):
        MPI.COMM_WORLD.barrier()
        t = time.perf_counter()
        if method == "forward":
            scene.analysis = "static"
            r = solve_static(scene)
            ok, its = r.report.converged, r.report.newton_iterations
        else:
            scene.inverse.method = method
            r = inverse.design_rest_shape(scene)
            ok, its = r.converged, r.iterations
        dt = MPI.COMM_WORLD.allreduce(time.perf_counter() - t, op=MPI.MAX)
        if k > 0:                        # the first run pays JIT compilation
            times.append(dt)
        info = {"converged": ok, "iterations": its}
    if MPI.COMM_WORLD.rank == 0:
        import resource
        print(json.dumps({"time": statistics.median(times), "times": times,
                          "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, **info}))


TIMEOUT = 240.0     # seconds per configuration (warm-up + repeats); slower ones are reported as such


def run(scene: dict, method: str, repeat: int, ranks: int = 1) -> dict:
    cmd = [sys.executable, __file__, "--worker", "--method", method, "--scene", json.dumps(scene),
           "--repeat", str(repeat)]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    if ranks > 1:                        # serial runs let OpenBLAS use both cores
        cmd = ["mpirun", "-n", str(ranks), "--bind-to", "none"] + cmd
        env["OPENBLAS_NUM_THREADS"] = "1"
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"error": f"not finished in {TIMEOUT:.0f} s ({repeat + 1} runs)"}
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        return {"error": (p.stderr.strip().splitlines() or ["failed"])[-1]}
    return json.loads(lines[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--method", default="direct")
    ap.add_argument("--scene", default="")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.worker:
        return worker(args)
    sizes = [(20, 2, 2)] if args.quick else [(20, 2, 2), (40, 4, 4)]
    rows = ["| case | dofs | method | converged | iterations | median time [s] | ratio to forward |",
            "|---|---|---|---|---|---|---|"]
    for E in (1e7, 1e6):
        for cells in sizes:
            scene = beam(cells, E=E)
            dofs = 3 * (cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1)
            fwd = run(scene, "forward", args.repeat)
            for method in ("forward", "direct", "adjoint", "fixed-point"):
                r = fwd if method == "forward" else run(scene, method, args.repeat)
                if "error" in r:
                    rows.append(f"| beam E={E:.0e} | {dofs} | {method} | error: {r['error'][:60]} | | | |")
                    continue
                ratio = r["time"] / fwd["time"] if "time" in fwd else float("nan")
                rows.append(f"| beam E={E:.0e} | {dofs} | {method} | {r['converged']} | {r['iterations']} | "
                            f"{r['time']:.3f} | {ratio:.2f} |")
            print("\n".join(rows[-4:]), flush=True)
    chen = beam(**CHEN)
    dofs = 3 * 41 * 15 * 15
    rows.append("")
    rows.append("Chen et al. 2014 reference: 47,077 tetrahedra designed in 7.07 s. Ours, 47,040 tetrahedra "
                "(thick arm 0.2 x 0.05 x 0.05 m, E 0.68 MPa, nu 0.45, rho 958, gravity), direct method:")
    rows.append("")
    rows.append("| ranks | linear solver | dofs | converged | Newton iterations | median time [s] | peak memory [MB/rank] |")
    rows.append("|---|---|---|---|---|---|---|")
    variants = (("MUMPS LU, one factor per load step (default)", {}),
                ("MUMPS LU, factored every Newton iteration", {"ksp_type": "preonly", "snes_lag_preconditioner": 1}),
                ("GMRES + GAMG", {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-6}))
    for ranks in (1, 2):
        for name, petsc in variants:
            sc = json.loads(json.dumps(chen))
            sc["solver"]["petsc"] = petsc
            r = run(sc, "direct", args.repeat, ranks)
            if "error" in r:
                rows.append(f"| {ranks} | {name} | {dofs} | error: {r['error'][:60]} | | | |")
            else:
                rows.append(f"| {ranks} | {name} | {dofs} | {r['converged']} | {r['iterations']} | "
                            f"{r['time']:.2f} | {r['peak_mb']:.0f} |")
            print(rows[-1], flush=True)
    fwd = run(chen, "forward", args.repeat)
    if "error" not in fwd:
        rows.append(f"| 1 | forward solve on the same mesh (reference) | {dofs} | {fwd['converged']} | "
                    f"{fwd['iterations']} | {fwd['time']:.2f} | {fwd['peak_mb']:.0f} |")
    text = "\n".join(rows) + "\n"
    print(text)
    if not args.quick:
        (HERE / "inverse_methods.md").write_text(text)


if __name__ == "__main__":
    main()
