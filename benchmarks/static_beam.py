"""Benchmark: the sagging beam solved by fem_forms against the same solve written with bare dolfinx/PETSc.

A 1 x 0.1 x 0.1 m neo-Hookean beam (E 1e8 Pa, nu 0.3, rho 1000 kg/m^3), clamped at x = 0, under
gravity; P2 tetrahedra, quadrature degree 4. Three mesh sizes (40x4x4, 60x6x6, 80x8x8 boxes: 19,683,
61,347 and 139,587 dofs), each with the direct (MUMPS LU on a BAIJ matrix) and the iterative (CG +
GAMG with the rigid-body near-nullspace on an AIJ matrix) linear path.

"ours" is ``fem_forms.solve_static(scene)`` (mesh, space, forms, SNES with continuation and the
acceptance checks, final energy). "bare" builds the same mesh, space and energy inline and drives
``PETSc.SNES`` with the same options directly (benchmarks/bare_snes.py); it imports nothing from fem_forms.

Every (size, linear path, implementation, repeat) runs in its own subprocess, so the peak resident
memory (``ru_maxrss``) belongs to that one run. Each subprocess first does a tiny solve of the same
kind (4x1x1 cells) to load the JIT-compiled forms and initialise PETSc/MUMPS, then the timed one.
The table reports the median of the repeats.

Columns (ours / bare in each cell):
  assembly  time inside the residual, Jacobian and energy assembly callbacks (ours also counts its
            acceptance-check residual assemblies, as fem_forms reports them);
  solve     wall time of the nonlinear solve phase (compiled forms -> converged SNES, for ours the
            whole ``newton.solve``) minus assembly: linear solves, SNES, matrix/solver set-up, checks;
  total     wall time from scene to solution, mesh creation included (for ours all of
            ``solve_static``);
  total CPU process CPU time of the same region: on a shared machine wall times of identical
            PETSc work vary by 30 % between runs, CPU time far less, so the CPU ratio is the
            better measure of our overhead.

Run (about 12 minutes for the full table on a 2-core machine):
    .venv/bin/python benchmarks/static_beam.py            # all sizes -> stdout and benchmarks/static_beam.md
    .venv/bin/python benchmarks/static_beam.py --quick    # 19,683 dofs only (about 1 minute)
"""
from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SIZES = [(40, 4, 4), (60, 6, 6), (80, 8, 8)]        # 19,683 / 61,347 / 139,587 dofs with P2
WARMUP_CELLS = (4, 1, 1)
KINDS = ("direct", "iterative")
IMPLS = ("ours", "bare")

# The problem, as plain numbers shared by both paths.
LENGTH, WIDTH = 1.0, 0.1
E, NU, RHO = 1.0e8, 0.3, 1000.0
GRAVITY = (0.0, 0.0, -9.81)
DEGREE, QUADRATURE = 2, 4

# The bare path's PETSc options, written out literally. The "ours" worker reports the options
# fem_forms actually uses and the parent checks that they are identical (no silent drift).
BARE_SNES = {"snes_type": "newtonls", "snes_max_it": 50, "snes_rtol": 1e-9, "snes_atol": 0.0,
             "snes_stol": 1e-11, "snes_linesearch_max_it": 40, "snes_linesearch_type": "bt"}
BARE_LINEAR = {
    "direct": {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"},
    "iterative": {"ksp_type": "cg", "ksp_rtol": 1e-8, "ksp_max_it": 1000, "pc_type": "gamg",
                  "pc_gamg_type": "agg", "pc_gamg_square_graph": 2, "pc_gamg_threshold": 0.02,
                  "mg_levels_ksp_type": "chebyshev", "mg_levels_pc_type": "jacobi",
                  "mg_levels_esteig_ksp_type": "cg"},
}
BARE_MAT_TYPE = {"direct": "baij", "iterative": "aij"}


def p2_dofs(cells) -> int:
    n, m, k = cells
    return (2 * n + 1) * (2 * m + 1) * (2 * k + 1) * 3


def peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0    # Linux: KiB


# ============================================================================ ours (fem_forms)
def scene_dict(cells, kind: str) -> dict:
    return {
        "title": "benchmark beam",
        "mesh": {"generator": "box", "size": [LENGTH, WIDTH, WIDTH], "cells": list(cells),
                 "cell": "tetrahedron"},
        "material": {"model": "neo-hookean", "E": E, "nu": NU, "rho": RHO},
        "discretization": {"degree": DEGREE},          # quadrature degree: the package's choice
        "fix": [{"where": {"axis": "x", "at": 0.0}}],
        "load": [{"type": "gravity", "g": list(GRAVITY)}],
        "solver": {"linear": kind},
        "output": {"picture": False, "fields": False},
    }


def run_ours(cells, kind: str) -> dict:
    sys.path.insert(0, str(ROOT))
    import fem_forms as ff
    from fem_forms.solvers import snes

    ff.quiet_jit()
    # record what the driver really used (options, matrix type) and count its assembly callbacks;
    # the wrappers cost a Python call each (microseconds)
    seen = {"options": None, "mat_type": None, "calls": {"R": 0, "J": 0, "E": 0}}
    build = snes.SNESDriver.rebuild

    def recording_build(self):
        build(self)
        seen["options"], seen["mat_type"] = dict(self.options), self.A.getType()
    snes.SNESDriver.rebuild = recording_build
    for key, name in (("R", "_residual"), ("J", "_jacobian"), ("E", "_objective")):
        def counted(self, *a, _f=getattr(snes.SNESDriver, name), _k=key):
            seen["calls"][_k] += 1
            return _f(self, *a)
        setattr(snes.SNESDriver, name, counted)

    warm = ff.solve_static(ff.Scene.from_dict(scene_dict(WARMUP_CELLS, kind)))
    assert warm.report.converged, warm.report.message
    del warm
    gc.collect()
    seen["calls"] = {"R": 0, "J": 0, "E": 0}

    scene = ff.Scene.from_dict(scene_dict(cells, kind))
    t0, c0 = time.perf_counter(), time.process_time()
    res = ff.solve_static(scene)
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    rep = res.report
    return {"dofs": res.model.dofs, "converged": rep.converged, "newton": rep.newton_iterations,
            "krylov": rep.krylov_iterations, "pc_builds": rep.preconditioner_builds,
            "linear_solver": rep.linear_solver, "assembly": rep.assembly_time, "solve": rep.solve_time,
            "total": total, "cpu": cpu, "max_u": res.max_displacement, "energy": res.energy,
            "residual": rep.residual_norm, "quadrature": scene.discretization.quadrature,
            "options": seen["options"], "mat_type": seen["mat_type"], "calls": seen["calls"]}


# ============================================================================ bare dolfinx/PETSc
def bare_solve(cells, kind: str) -> dict:
    """The same beam with plain dolfinx 0.5.2 and petsc4py calls."""
    import numpy as np
    import ufl
    from dolfinx import fem, mesh as dmesh
    from mpi4py import MPI
    from petsc4py import PETSc

    from bare_snes import BareSNES

    t0, c0 = time.perf_counter(), time.process_time()
    comm = MPI.COMM_WORLD
    msh = dmesh.create_box(comm, [np.zeros(3), np.array([LENGTH, WIDTH, WIDTH])], list(cells),
                           cell_type=dmesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", DEGREE))
    u = fem.Function(V)
    fdim = msh.topology.dim - 1
    clamped = dmesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[0], 0.0))
    bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                           fem.locate_dofs_topological(V, fdim, clamped), V)]

    mu = E / (2.0 * (1.0 + NU))
    lmbda = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU))
    dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": QUADRATURE})
    F = ufl.Identity(3) + ufl.grad(u)
    J = ufl.det(F)
    I1 = ufl.tr(F.T * F)
    psi = 0.5 * mu * (I1 - 3) - mu * ufl.ln(J) + 0.5 * lmbda * ufl.ln(J) ** 2
    g = fem.Constant(msh, PETSc.ScalarType(GRAVITY))
    Pi = psi * dx - RHO * ufl.dot(g, u) * dx
    R = ufl.derivative(Pi, u, ufl.TestFunction(V))
    dR = ufl.derivative(R, u, ufl.TrialFunction(V))

    t_solve = time.perf_counter()
    L, a, energy = fem.form(R), fem.form(dR), fem.form(Pi)
    solver = BareSNES(u, L, a, energy, bcs, {**BARE_SNES, **BARE_LINEAR[kind]}, mat_type=BARE_MAT_TYPE[kind],
                      near_nullspace=bare_rigid_modes(V) if kind == "iterative" else None)
    snes = solver.snes
    solver.solve()
    t_end, c_end = time.perf_counter(), time.process_time()

    out = {"dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs,
           "converged": snes.getConvergedReason() > 0, "newton": snes.getIterationNumber(),
           "krylov": snes.getLinearSolveIterations(),
           "linear_solver": kind, "assembly": solver.assembly, "solve": t_end - t_solve - solver.assembly,
           "total": t_end - t0, "cpu": c_end - c0, "calls": solver.calls, "mat_type": solver.A.getType()}
    # checks outside the timed region
    vals = u.x.array.reshape(-1, 3)
    out["max_u"] = comm.allreduce(float(np.linalg.norm(vals, axis=1).max()), op=MPI.MAX)
    out["energy"] = comm.allreduce(fem.assemble_scalar(energy), op=MPI.SUM)
    solver.destroy()
    return out


def bare_rigid_modes(V):
    """The six rigid-body modes of the vector P2 space, orthonormalised (Gram-Schmidt)."""
    import numpy as np
    from petsc4py import PETSc

    n = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:n]
    modes = np.zeros((6, n, 3))
    for i in range(3):
        modes[i, :, i] = 1.0
    modes[3, :, 0], modes[3, :, 1] = -x[:, 1], x[:, 0]
    modes[4, :, 1], modes[4, :, 2] = -x[:, 2], x[:, 1]
    modes[5, :, 0], modes[5, :, 2] = x[:, 2], -x[:, 0]
    vecs = []
    for m in modes:
        v = PETSc.Vec().createMPI((3 * n, PETSc.DECIDE), bsize=3, comm=V.mesh.comm)
        v.array[:] = m.ravel()
        for w in vecs:
            v.axpy(-v.dot(w), w)
        v.normalize()
        vecs.append(v)
    return PETSc.NullSpace().create(vectors=vecs, comm=V.mesh.comm)


def run_bare(cells, kind: str) -> dict:
    import logging
    logging.disable(logging.INFO)                   # FFCx compile chatter
    warm = bare_solve(WARMUP_CELLS, kind)
    assert warm["converged"]
    gc.collect()
    res = bare_solve(cells, kind)
    res.update(quadrature=QUADRATURE, options={**BARE_SNES, **BARE_LINEAR[kind]})
    return res


# ============================================================================ driver
def worker(impl: str, cells, kind: str) -> None:
    res = (run_ours if impl == "ours" else run_bare)(cells, kind)
    res["peak_mib"] = peak_mib()
    print("RESULT " + json.dumps(res), flush=True)


def run_worker(impl: str, cells, kind: str, timeout: float) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", impl, kind,
           *(str(c) for c in cells)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout, cwd=ROOT)
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"{impl} {kind} {cells} failed (exit {p.returncode}):\n{p.stdout[-2000:]}\n"
                           f"{p.stderr[-4000:]}")
    return json.loads(lines[-1][len("RESULT "):])


def median(rs: list, key: str) -> float:
    return statistics.median(r[key] for r in rs)


def table(results: dict) -> str:
    head = ("| dofs | linear | Newton its | assembly s | solve s | total s | total CPU s | peak MiB | "
            "ratio wall | ratio CPU |\n"
            "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    rows = []
    for (cells, kind), by in results.items():
        o, b = by["ours"], by["bare"]
        cell = lambda k, f: f"{median(o, k):{f}} / {median(b, k):{f}}"   # noqa: E731
        its_o = "/".join(sorted({str(r["newton"]) for r in o}))
        its_b = "/".join(sorted({str(r["newton"]) for r in b}))
        rows.append(f"| {o[0]['dofs']:,} | {kind} | {its_o} / {its_b} | {cell('assembly', '.2f')} | "
                    f"{cell('solve', '.2f')} | {cell('total', '.2f')} | {cell('cpu', '.2f')} | "
                    f"{cell('peak_mib', '.0f')} | {median(o, 'total') / median(b, 'total'):.2f} | "
                    f"{median(o, 'cpu') / median(b, 'cpu'):.2f} |")
    return head + "\n".join(rows) + "\n"


def check(results: dict) -> list:
    """Same problem, same options, same answer: anything else makes the comparison meaningless."""
    notes = []
    for (cells, kind), by in results.items():
        o, b = by["ours"][0], by["bare"][0]
        tag = f"{p2_dofs(cells):,} dofs {kind}"
        if o["options"] != b["options"]:
            notes.append(f"WARNING {tag}: PETSc options differ: ours {o['options']} bare {b['options']}")
        if kind == "iterative" and (o["mat_type"], b["mat_type"]) == ("seqbaij", "seqaij"):
            notes.append(f"{tag}: ours assembles the tangent as BAIJ (2.5-3x faster) and gives GAMG an AIJ copy "
                         f"(fem_forms/solvers/snes.py); bare assembles AIJ, as a dolfinx script would")
        elif o["quadrature"] != b["quadrature"] or o["mat_type"] != b["mat_type"]:
            notes.append(f"WARNING {tag}: quadrature/matrix type differ: {o['quadrature']}/{o['mat_type']} "
                         f"vs {b['quadrature']}/{b['mat_type']}")
        if not all(r["converged"] for r in by["ours"] + by["bare"]):
            notes.append(f"WARNING {tag}: a run did not converge")
        du = abs(o["max_u"] - b["max_u"]) / abs(b["max_u"])
        de = abs(o["energy"] - b["energy"]) / abs(b["energy"])
        calls = lambda c: f"{c['R']}/{c['J']}/{c['E']}"   # noqa: E731
        notes.append(f"{tag}: max |u| {o['max_u']:.6e} m (ours) vs {b['max_u']:.6e} m (bare), rel. diff "
                     f"{du:.1e}; energy rel. diff {de:.1e}; assembly calls residual/Jacobian/energy "
                     f"{calls(o['calls'])} (ours) vs {calls(b['calls'])} (bare)")
    return notes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smallest size (19,683 dofs) only")
    ap.add_argument("--runs", type=int, default=3, help="repeats per configuration (median reported)")
    ap.add_argument("--kinds", default=",".join(KINDS), help="linear paths: direct,iterative")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "static_beam.md"),
                    help="markdown file to write ('' for none)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds allowed per subprocess")
    ap.add_argument("--worker", nargs=5, metavar=("IMPL", "KIND", "NX", "NY", "NZ"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        impl, kind, *cells = args.worker
        worker(impl, tuple(int(c) for c in cells), kind)
        return

    sizes = SIZES[:1] if args.quick else SIZES
    kinds = [k for k in args.kinds.split(",") if k]
    t_start = time.perf_counter()
    results: dict = {}
    loads = []
    for cells in sizes:
        for kind in kinds:
            by = {"ours": [], "bare": []}
            for r in range(args.runs):
                # alternate the order so that drift in machine speed does not favour one side
                for impl in (IMPLS if r % 2 == 0 else IMPLS[::-1]):
                    loads.append(os.getloadavg()[0])
                    res = run_worker(impl, cells, kind, args.timeout)
                    by[impl].append(res)
                    print(f"  {p2_dofs(cells):>7,} dofs {kind:9s} {impl:4s} run {r + 1}: "
                          f"{res['newton']} Newton, assembly {res['assembly']:.2f} s, solve "
                          f"{res['solve']:.2f} s, total {res['total']:.2f} s, {res['peak_mib']:.0f} MiB",
                          file=sys.stderr, flush=True)
            results[(cells, kind)] = by
    wall = time.perf_counter() - t_start

    md = ["# Static sagging beam: fem_forms (ours) against bare dolfinx/PETSc (bare)", "",
          f"1 x 0.1 x 0.1 m neo-Hookean beam (E {E:g} Pa, nu {NU}, rho {RHO:g} kg/m^3) clamped at x = 0 "
          f"under gravity; P{DEGREE} tetrahedra, quadrature degree {QUADRATURE}; SNES newtonls with the "
          "bt line search on the energy; direct = MUMPS LU (BAIJ), iterative = CG + GAMG with the "
          "rigid-body near-nullspace (AIJ). Serial, OPENBLAS_NUM_THREADS=1, each run in its own process "
          f"after a warm-up solve (JIT excluded); median of {args.runs} runs; each cell is ours / bare; "
          "ratios are ours / bare.", "",
          table(results),
          "assembly: wall time in the residual/Jacobian/energy assembly callbacks (ours includes its "
          "acceptance-check residuals); solve: wall time of the nonlinear-solve phase minus assembly "
          "(linear solves, SNES, set-up, checks); total: wall time from scene to solution, mesh creation "
          "included; total CPU: process CPU time (user + system) of the same region, much less sensitive "
          "than wall time to other jobs on the machine; peak: ru_maxrss of the run's process (imports "
          "included). Ratios are medians of ours over medians of bare.", "",
          *[f"- {n}" for n in check(results)], "",
          f"Machine: {platform.node()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
          f"1-minute load average sampled before each run: {min(loads):.2f} to {max(loads):.2f} (the "
          "benchmark itself accounts for about 1; more means other jobs shared the cores and wall times "
          f"are noisy). Benchmark wall time {wall / 60:.1f} min.", ""]
    text = "\n".join(md)
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
