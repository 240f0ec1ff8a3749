"""Benchmark: the cost of one transient heat step (backward Euler, P1 temperature) at about 100k dofs.

A unit cube of 45^3 x 6 tetrahedra (97,336 P1 dofs), k = 1, rho c = 1, dt = 0.01: the face x = 0 follows a
temperature history, the face x = 1 convects (h = 10). Each run builds the problem anew and takes
`--steps` steps; every step is timed on its own (HeatSolver.solve: set time and 1/dt, residual assembly,
the linear solve, the acceptance check, commit). Step 1 assembles and factors (or builds the multigrid
hierarchy); later steps of the same dt reuse it. Compared with bare dolfinx/PETSc on the same forms
(matrix assembled and factored once, per step: right-hand side with lifting, one KSP solve).

Run: `.venv/bin/python benchmarks/thermal_step.py [--runs 3] [--steps 10] [--no-write]` (about 2 minutes);
writes benchmarks/thermal_step.md unless --no-write.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import statistics
import time

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc
import ufl

import fem_forms as ff
from fem_forms.meshes import load_mesh
from fem_forms.physics.thermal import HeatForms, temperature_space
from fem_forms.solvers.thermal_step import HeatSolver
from fem_forms.state import State

HERE = Path(__file__).resolve().parent
N, DT = 45, 0.01


def scene(linear: str) -> ff.Scene:
    return ff.Scene.from_dict({
        "analysis": "thermal", "mesh": {"size": [1.0, 1.0, 1.0], "cells": [N, N, N]},
        "material": {"E": 1e9, "nu": 0.3, "rho": 1.0}, "discretization": {"degree": 1},
        "thermal": {"conductivity": 1.0, "specific_heat": 1.0, "boundary": [
            {"where": {"axis": "x", "at": 0.0}, "temperature": {"history": [[0.0, 0.0], [1.0, 100.0]]}},
            {"where": {"axis": "x", "at": 1.0}, "convection": {"h": 10.0, "ambient": 0.0}}]},
        "dynamic": {"duration": 1.0, "dt": DT}, "solver": {"linear": linear}})


def ours(linear: str, steps: int) -> tuple[list[float], int, float]:
    """Step times of fem_forms' heat step; (times, dofs, final max T)."""
    sc = scene(linear)
    loaded = load_mesh(sc.mesh, MPI.COMM_WORLD, degree=1)
    T = fem.Function(temperature_space(loaded.mesh, 1), name="temperature")
    state = State({"temperature": T})
    forms = HeatForms(sc.thermal, 1.0, loaded, T, state.old["temperature"], True, 2)
    solver = HeatSolver(forms, state, linear_kind=linear)
    times = []
    for k in range(steps):
        MPI.COMM_WORLD.barrier()
        t0 = time.perf_counter()
        out = solver.step(k * DT, DT)
        MPI.COMM_WORLD.barrier()
        times.append(time.perf_counter() - t0)
        assert out.accepted, out.why
    dofs = T.function_space.dofmap.index_map.size_global
    return times, dofs, MPI.COMM_WORLD.allreduce(float(T.x.array.max()), op=MPI.MAX)


def bare(linear: str, steps: int) -> tuple[list[float], float]:
    """The same step in bare dolfinx/PETSc: A = M/dt + K + h ds assembled once, KSP kept."""
    sc = scene(linear)
    mesh = load_mesh(sc.mesh, MPI.COMM_WORLD, degree=1).mesh
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    T, T0 = fem.Function(V), fem.Function(V)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    dx = ufl.Measure("dx", metadata={"quadrature_degree": 2})
    fdim = mesh.topology.dim - 1
    from dolfinx import mesh as dmesh
    right = dmesh.locate_entities_boundary(mesh, fdim, lambda x: np.isclose(x[0], 1.0))
    tags = dmesh.meshtags(mesh, fdim, right, np.full(len(right), 1, dtype=np.int32))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata={"quadrature_degree": 2})
    inv_dt, h, Tb = (fem.Constant(mesh, PETSc.ScalarType(x)) for x in (1 / DT, 10.0, 0.0))
    a = fem.form(inv_dt * u * v * dx + ufl.inner(ufl.grad(u), ufl.grad(v)) * dx + h * u * v * ds(1))
    L = fem.form(inv_dt * T0 * v * dx)
    left = dmesh.locate_entities_boundary(mesh, fdim, lambda x: np.isclose(x[0], 0.0))
    bc = fem.dirichletbc(Tb, fem.locate_dofs_topological(V, fdim, left), V)
    A = fpetsc.assemble_matrix(a, bcs=[bc])
    A.assemble()
    ksp = PETSc.KSP().create(mesh.comm)
    ksp.setOperators(A)
    opts = PETSc.Options()
    pre = f"bare_{linear}_"
    ksp.setOptionsPrefix(pre)
    if linear == "direct":
        opts[pre + "ksp_type"], opts[pre + "pc_type"], opts[pre + "pc_factor_mat_solver_type"] = "preonly", "lu", "mumps"
    else:
        opts[pre + "ksp_type"], opts[pre + "pc_type"], opts[pre + "ksp_rtol"] = "cg", "gamg", 1e-8
    ksp.setFromOptions()
    b = fpetsc.create_vector(L)
    times = []
    for k in range(steps):
        MPI.COMM_WORLD.barrier()
        t0 = time.perf_counter()
        Tb.value = 100.0 * (k + 1) * DT
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, L)
        fpetsc.apply_lifting(b, [a], bcs=[[bc]])
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fpetsc.set_bc(b, [bc])
        ksp.solve(b, T.vector)
        T.x.scatter_forward()
        T0.x.array[:] = T.x.array
        MPI.COMM_WORLD.barrier()
        times.append(time.perf_counter() - t0)
    return times, MPI.COMM_WORLD.allreduce(float(T.x.array.max()), op=MPI.MAX)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    ff.quiet_jit()
    comm = MPI.COMM_WORLD
    load0 = os.getloadavg()[0]
    rows = []
    for linear in ("direct", "iterative"):
        ours(linear, 1)                                   # warm the JIT cache
        bare(linear, 1)
        mine, theirs, firsts, bare_firsts = [], [], [], []
        for _ in range(args.runs):                        # interleaved: the load drifts
            t, dofs, tmax = ours(linear, args.steps)
            firsts.append(t[0])
            mine += t[1:]
            tb, bmax = bare(linear, args.steps)
            bare_firsts.append(tb[0])
            theirs += tb[1:]
            assert abs(tmax - bmax) <= 1e-6 * max(abs(bmax), 1.0), (tmax, bmax)
        rows.append((linear, dofs, statistics.median(firsts), statistics.median(mine),
                     statistics.median(bare_firsts), statistics.median(theirs)))
    load1 = os.getloadavg()[0]
    if comm.rank != 0:
        return
    head = ("| linear solver | dofs | ours: step 1 | ours: later steps | bare: step 1 | bare: later steps | "
            "later steps ours / bare |\n|---|---|---|---|---|---|---|")
    lines = [head] + [f"| {k} | {d:,} | {f:.3f} s | {m:.3f} s | {bf:.3f} s | {bm:.3f} s | {m / bm:.2f} |"
                      for k, d, f, m, bf, bm in rows]
    table = "\n".join(lines)
    print(table)
    print(f"{comm.size} rank(s), {args.runs} runs x {args.steps} steps, load average {load0:.1f} -> {load1:.1f}")
    if not args.no_write:
        text = (HERE / "thermal_step.md").read_text() if (HERE / "thermal_step.md").exists() else ""
        marker = f"<!-- {comm.size} rank(s) -->"
        section = (f"{marker}\n### {comm.size} MPI rank(s)\n\n{table}\n\nMedians over {args.runs} runs x "
                   f"{args.steps - 1} later steps (step 1: median of {args.runs}); 1-minute load average "
                   f"{load0:.1f} before, {load1:.1f} after.\n")
        parts = text.split("<!-- ")
        kept = [p for p in parts[1:] if not p.startswith(f"{comm.size} rank(s) -->")]
        (HERE / "thermal_step.md").write_text((parts[0] or HEADER) + "".join("<!-- " + p for p in kept) + section)


HEADER = """# Cost of one transient heat step (benchmarks/thermal_step.py)

Backward Euler, P1 temperature on a unit cube of 45^3 x 6 tetrahedra (97,336 dofs), prescribed temperature
history on x = 0, convection on x = 1, dt = 0.01. "ours" is fem_forms' HeatSolver step (the one SNES
driver with `ksponly`, tangent and factor or multigrid hierarchy kept while dt is unchanged; set time,
residual assembly, solve, finite check, commit); "bare" assembles the same matrix once and solves each
step with a kept KSP (right-hand side with lifting, one solve). Step 1 assembles and factors. Our later
steps assemble the full residual twice (SNES's right-hand side and the residual after the solve that
accepts the step; the driver's finite-start check is skipped for heat, `solve_step(check_start=False)`)
where bare assembles one mass-term right-hand side: that is the overhead in the last column. The
machine is shared with other jobs (2 cores): timings are medians and the load average is given.

"""

if __name__ == "__main__":
    main()
