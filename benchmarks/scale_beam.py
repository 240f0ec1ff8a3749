"""Benchmark: the sagging beam on the iterative path (ours: CG + the P2 -> P1 p-multigrid with GAMG below;
bare: CG + GAMG on P2, both with the rigid-body near-nullspace) from about 10 thousand to 1 million P2 dofs,
serial and on 2 MPI ranks, ours against bare dolfinx/PETSc.

The problem, options and the bare implementation are those of benchmarks/static_beam.py (imported,
not repeated): a 1 x 0.1 x 0.1 m neo-Hookean beam, E 1e8 Pa, nu 0.3, rho 1000, clamped at x = 0 under
gravity, P2 tetrahedra, quadrature degree 4. Each row reports dofs, Newton iterations, Krylov (CG)
iterations per Newton step, wall time, time per dof and peak memory (largest rank). Every run is its
own process (`mpirun -n 2 --bind-to none` for 2 ranks) that first solves a tiny beam to load the JIT
forms; the table gives medians over --runs repeats.

`--profile` instead runs ours once under cProfile at --profile-cells and reports the share of the
static solve spent outside compiled code (PETSc, dolfinx C++ and FFCx kernels): the Python overhead
of fem_forms itself.

Run: .venv/bin/python benchmarks/scale_beam.py [--runs 3] [--max-cells 160]   (about 30 minutes)
     .venv/bin/python benchmarks/scale_beam.py --profile                       (about 1 minute)
Writes benchmarks/scale_beam.md (or scale_beam_profile.md).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import static_beam as sb                                  # noqa: E402  (the shared problem and bare solve)

SIZES = [(30, 3, 3), (40, 4, 4), (80, 8, 8), (120, 12, 12), (160, 16, 16)]   # 8,967 ... 1,048,707 dofs
KIND = "iterative"


def worker(impl: str, cells) -> None:
    """One timed solve in this process (all ranks); rank 0 prints a RESULT line."""
    import resource
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    if impl == "ours":
        res = sb.run_ours(cells, KIND)
    else:
        res = sb.run_bare(cells, KIND)
    peak = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, op=MPI.MAX)
    total_peak = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, op=MPI.SUM)
    res["total"] = comm.allreduce(res["total"], op=MPI.MAX)
    if comm.rank == 0:
        res.update(peak_mib=peak, total_peak_mib=total_peak, ranks=comm.size)
        print("RESULT " + json.dumps(res), flush=True)


def run(impl: str, cells, ranks: int, timeout: float = 1800.0) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
               OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", impl, *(str(c) for c in cells)]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks), "--bind-to", "none"] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout, cwd=ROOT)
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"{impl} {cells} on {ranks} ranks failed (exit {p.returncode}):\n{p.stderr[-3000:]}")
    return json.loads(lines[-1][len("RESULT "):])


def profile(cells) -> str:
    """cProfile of ours at one size: time in compiled code versus Python (fem_forms, dolfinx, ufl)."""
    import cProfile
    import pstats
    sys.path.insert(0, str(ROOT))
    import fem_forms as ff
    ff.quiet_jit()
    warm = ff.solve_static(ff.Scene.from_dict(sb.scene_dict(sb.WARMUP_CELLS, KIND)))
    assert warm.report.converged
    scene = ff.Scene.from_dict(sb.scene_dict(cells, KIND))
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    res = ff.solve_static(scene)
    prof.disable()
    wall = time.perf_counter() - t0
    stats = pstats.Stats(prof).stats
    compiled, python = {}, {}
    for (fname, _line, func), (_cc, _nc, tottime, _ct, _callers) in stats.items():
        bucket = compiled if fname == "~" else python
        key = func if fname == "~" else f"{Path(fname).parent.name}/{Path(fname).name}:{func}"
        bucket[key] = bucket.get(key, 0.0) + tottime
    t_compiled, t_python = sum(compiled.values()), sum(python.values())
    ours = {k: v for k, v in python.items() if k.startswith("fem_forms/") or k.startswith("analyses/")}
    lines = [f"# Profile of one static solve (ours), {res.model.dofs:,} dofs, {KIND} path, serial", "",
             f"Wall time {wall:.2f} s ({res.report.newton_iterations} Newton iterations, "
             f"{res.report.krylov_iterations} CG iterations). cProfile attributes {t_compiled:.2f} s to "
             f"compiled calls (PETSc, dolfinx C++, FFCx kernels, numpy) and {t_python:.2f} s "
             f"({100 * t_python / (t_compiled + t_python):.1f} %) to Python code, of which "
             f"{sum(ours.values()):.3f} s ({100 * sum(ours.values()) / (t_compiled + t_python):.2f} %) is in "
             "fem_forms itself.", "",
             "| compiled call | self time [s] |", "|---|---:|"]
    lines += [f"| `{k}` | {v:.2f} |" for k, v in sorted(compiled.items(), key=lambda kv: -kv[1])[:8]]
    lines += ["", "| Python function | self time [s] |", "|---|---:|"]
    lines += [f"| `{k}` | {v:.3f} |" for k, v in sorted(python.items(), key=lambda kv: -kv[1])[:8]]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--max-cells", type=int, default=160, help="largest box length in cells (160: 1M dofs)")
    ap.add_argument("--ranks", default="1,2")
    ap.add_argument("--out", default="scale_beam.md", help="table file name in benchmarks/")
    ap.add_argument("--sizes", type=int, nargs="*", help="only these box lengths in cells (30 40 80 120 160)")
    ap.add_argument("--impls", default="ours,bare", help="ours,bare or ours (bare columns left empty)")
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--profile-cells", type=int, nargs=3, default=(80, 8, 8))
    ap.add_argument("--worker", nargs=4, metavar=("IMPL", "NX", "NY", "NZ"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        impl, *cells = args.worker
        return worker(impl, tuple(int(c) for c in cells))
    if args.profile:
        text = profile(tuple(args.profile_cells))
        print(text)
        (HERE / "scale_beam_profile.md").write_text(text)
        return

    ranks = [int(r) for r in args.ranks.split(",")]
    sizes = [c for c in SIZES if c[0] <= args.max_cells and (not args.sizes or c[0] in args.sizes)]
    impls = args.impls.split(",")
    t_start, loads, rows = time.perf_counter(), [], {}
    for cells in sizes:
        for n in ranks:
            by = {"ours": [], "bare": []}
            for r in range(args.runs):
                for impl in (impls if r % 2 == 0 else impls[::-1]):
                    loads.append(os.getloadavg()[0])
                    res = run(impl, cells, n)
                    by[impl].append(res)
                    print(f"  {res['dofs']:>9,} dofs {n} rank(s) {impl:4s} run {r + 1}: {res['newton']} Newton, "
                          f"{res['krylov']} CG, total {res['total']:.2f} s, {res['peak_mib']:.0f} MiB",
                          file=sys.stderr, flush=True)
            rows[(cells, n)] = by
            write_table(rows, args, sizes, loads, t_start)     # after every row: a stopped run keeps them


def write_table(rows: dict, args, sizes: list, loads: list, t_start: float) -> None:
    """benchmarks/scale_beam.md from the rows measured so far."""
    def krylov(r: dict) -> float:
        return r["krylov"] / max(r["newton"], 1)

    head = ["| dofs | ranks | Newton its (each run) | multigrid builds (first run) | CG its per Newton step (first run) "
            "| total s | µs per dof | peak MiB per rank | ratio to bare |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    body, serial = [], {}
    for (cells, n), by in rows.items():
        o, b = by["ours"], by["bare"]
        med = lambda rs, k: statistics.median(x[k] for x in rs)           # noqa: E731
        t_o, t_b = med(o, "total"), (med(b, "total") if b else None)
        if n == 1:
            serial[cells] = (t_o, t_b)
        its = lambda rs: "/".join(str(x["newton"]) for x in rs) or "—"      # noqa: E731
        builds = o[0].get("pc_builds", o[0]["newton"])        # bare SNES rebuilds at every Newton step
        spread = f" ({min(x['total'] for x in o):.0f}-{max(x['total'] for x in o):.0f})" if len(o) > 1 else ""
        if b:
            bare = (b[0]["newton"], f"{krylov(b[0]):.1f}", f"{t_b:.2f}", f"{1e6 * t_b / b[0]['dofs']:.1f}",
                    f"{med(b, 'peak_mib'):.0f}", f"{t_o / t_b:.2f}")
        else:
            bare = ("—",) * 6
        body.append(f"| {o[0]['dofs']:,} | {n} | {its(o)} / {its(b)} | {builds} / {bare[0]} | "
                    f"{krylov(o[0]):.1f} / {bare[1]} | {t_o:.2f}{spread} / {bare[2]} | "
                    f"{1e6 * t_o / o[0]['dofs']:.1f} / {bare[3]} | "
                    f"{med(o, 'peak_mib'):.0f} / {bare[4]} | {bare[5]} |")
    speed = []
    for (cells, n), by in rows.items():
        if n > 1 and cells in serial:
            t_o = statistics.median(x["total"] for x in by["ours"])
            t_b = statistics.median(x["total"] for x in by["bare"]) if by["bare"] else None
            bare = f"{serial[cells][1] / t_b:.2f}" if t_b and serial[cells][1] else "—"
            speed.append(f"| {by['ours'][0]['dofs']:,} | {serial[cells][0] / t_o:.2f} | {bare} |")
    n0 = min(n for _, n in rows)
    done = [c for c in sizes if (c, n0) in rows]
    first, last = rows[(done[0], n0)]["ours"][0], rows[(done[-1], n0)]["ours"][0]
    growth = krylov(last) / krylov(first)
    pending = [c for c in sizes if not any(key[0] == c for key in rows)]
    md = ["# Scale: sagging beam on the iterative path, ours / bare", "",
          f"Problem as in static_beam.md (P2 tetrahedra, quadrature degree 4, rtol 1e-8 CG). Ours preconditions "
          "CG with the P2 -> P1 p-multigrid (Chebyshev/Jacobi on P2, one GAMG cycle with the rigid-body "
          "near-nullspace on the Galerkin P1 operator; fem_forms/solvers/pmultigrid.py) and keeps it across "
          "Newton steps while that is cheaper than rebuilding (fem_forms/solvers/preconditioner_reuse.py); bare "
          "runs GAMG on the P2 tangent and rebuilds it at every Newton step. "
          f"Each cell is ours / bare; medians of {args.runs} runs (ours' range in parentheses; — : bare not "
          "run in this benchmark), each its own process after a warm-up "
          "solve (JIT excluded); total is the wall time from scene to solution (largest rank); peak is "
          "ru_maxrss of the largest rank. OPENBLAS_NUM_THREADS=1; 2 ranks with `mpirun --bind-to none`.", "",
          *head, *body, "",
          "Parallel speedup (serial time / 2-rank time):", "",
          "| dofs | ours | bare |", "|---:|---:|---:|", *speed, "",
          f"CG iterations per Newton step grow {growth:.2f}x from {first['dofs']:,} to {last['dofs']:,} dofs "
          f"({n0} rank(s), ours).", "",
          f"Machine: {os.cpu_count()} cores, Python {platform.python_version()}; 1-minute load average before "
          f"each run {min(loads):.2f} to {max(loads):.2f}; benchmark wall time "
          f"{(time.perf_counter() - t_start) / 60:.1f} min.", ""]
    if pending:
        md.append(f"Partial: {len(pending)} size(s) not measured yet when this file was written.\n")
    text = "\n".join(md)
    print(text, flush=True)
    (HERE / args.out).write_text(text)


if __name__ == "__main__":
    main()
