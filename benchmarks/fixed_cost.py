"""Benchmark: the fixed cost of a whole `fem-forms run` process, as users see it.

Two cases (issue 12, "Speed where users feel it"):

static   The P2 beam of static_beam.py at 40x4x4 cells (19,683 dofs, direct solver), as a whole
         process, against the same solve written with bare dolfinx/PETSc as a whole process:
           bare              solve only, no output;
           bare+fields       solve, then an XDMF file with the P1 displacement and a DG0 von Mises
                             stress (cheaper than what `fem-forms run` writes);
           bare+same         solve, then what `fem-forms run` computes by default, computed the same way
                             (Cauchy stress and Green strain L2-projected, von Mises at the P1 nodes,
                             stress/strain/displacement at the probe, the support's reaction; XDMF, JSON);
           ours-no-picture   `fem-forms run` with --set output.picture=false (fields, CSV, JSON);
           ours              `fem-forms run` with the default outputs (fields, PNG picture, CSV, JSON).
         The fair ratios are ours-no-picture / bare+same (the package's own cost: same numbers,
         same work) and ours / bare (what a user of the default CLI pays over a bare script that
         writes nothing).
inverse  The Chen-size silicone arm of inverse_methods.py (40x14x14 box, 47,040 tetrahedra, direct
         method, one load step) run by `fem-forms run`: the design time (results.json
         design_time_s: mesh, forms, Newton) and the whole process (design, the independent forward
         check on the rest mesh as written: by default the forward residual at the target
         and the tangent's inertia there, `[inverse] check = "equilibrium"`; files, picture), and a
         process that only imports dolfinx and exits (what every dolfinx script pays on top of its work).

Processes run interleaved (round robin), each case --repeat times (default 3); the table gives
medians and the 1-minute load average before the first and after the last run (the machine is
shared: 15-35 % noise). FFCx's cache must be warm: one untimed run of each command comes first.

Run: `.venv/bin/python benchmarks/fixed_cost.py [--repeat 3] [--only static|inverse]`
(about 2 minutes); writes its section of benchmarks/fixed_cost.md unless --no-write. To compare with
an older commit under the same load: `git archive OLD fem_forms | tar -x -C /tmp/old` and add
`--before /tmp/old` (its runs are interleaved with these and reported as '@before').
"""
from __future__ import annotations

import sys

if __name__ == "__main__" and "--bare-worker" in sys.argv:
    # ======================================================= bare dolfinx 0.5.2 (a process of its own)
    import logging

    import numpy as np
    import ufl
    from dolfinx import fem, geometry, io, mesh as dmesh
    from dolfinx.fem import petsc as fpetsc
    from mpi4py import MPI
    from petsc4py import PETSc

    from bare_snes import BareSNES

    logging.disable(logging.INFO)
    LENGTH, WIDTH, E, NU, RHO = 1.0, 0.1, 1e8, 0.3, 1000.0
    comm = MPI.COMM_WORLD
    msh = dmesh.create_box(comm, [np.zeros(3), np.array([LENGTH, WIDTH, WIDTH])], [40, 4, 4],
                           cell_type=dmesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
    u = fem.Function(V)
    clamped = dmesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[0], 0.0))
    bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), fem.locate_dofs_topological(V, 2, clamped), V)]
    mu = E / (2.0 * (1.0 + NU))
    lmbda = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU))
    dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": 4})
    F = ufl.Identity(3) + ufl.grad(u)
    J = ufl.det(F)
    psi = 0.5 * mu * (ufl.tr(F.T * F) - 3) - mu * ufl.ln(J) + 0.5 * lmbda * ufl.ln(J) ** 2
    g = fem.Constant(msh, PETSc.ScalarType((0, 0, -9.81)))
    Pi = psi * dx - RHO * ufl.dot(g, u) * dx
    R = ufl.derivative(Pi, u, ufl.TestFunction(V))
    L, a, energy = fem.form(R), fem.form(ufl.derivative(R, u, ufl.TrialFunction(V))), fem.form(Pi)
    solver = BareSNES(u, L, a, energy, bcs, {
        "snes_type": "newtonls", "snes_max_it": 50, "snes_rtol": 1e-9, "snes_atol": 0.0, "snes_stol": 1e-11,
        "snes_linesearch_max_it": 40, "snes_linesearch_type": "bt", "ksp_type": "preonly", "pc_type": "lu",
        "pc_factor_mat_solver_type": "mumps"})
    solver.solve()
    snes = solver.snes
    assert snes.getConvergedReason() > 0
    if "--fields" in sys.argv:
        out = sys.argv[sys.argv.index("--fields") + 1]
        V1 = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
        u1 = fem.Function(V1, name="displacement")
        u1.interpolate(u)
        sigma = (mu * (F * F.T - ufl.Identity(3)) + lmbda * ufl.ln(J) * ufl.Identity(3)) / J
        s = ufl.dev(sigma)
        W = fem.FunctionSpace(msh, ("DG", 0))
        vm = fem.Function(W, name="von_mises")
        vm.interpolate(fem.Expression(ufl.sqrt(1.5 * ufl.inner(s, s)), W.element.interpolation_points()))
        with io.XDMFFile(comm, out + "/fields.xdmf", "w") as f:
            f.write_mesh(msh)
            f.write_function(u1)
            f.write_function(vm)
    if "--same" in sys.argv:
        # what `fem-forms run` computes and writes by default, the way it does (fem_forms/output/recovery.py):
        # Cauchy stress and Green strain L2-projected on the scalar P2 space (one mass matrix, CG + Jacobi to
        # 1e-12 per component), von Mises at the P1 nodes, stress/strain/displacement at the tip probe,
        # the support's reaction (the residual without supports, summed over its dofs), XDMF + JSON
        import json
        out = sys.argv[sys.argv.index("--same") + 1]
        S = fem.FunctionSpace(msh, ("Lagrange", 2))
        M = fpetsc.assemble_matrix(fem.form(ufl.TrialFunction(S) * ufl.TestFunction(S) * dx))
        M.assemble()
        ksp = PETSc.KSP().create(comm)
        ksp.setOperators(M)
        ksp.setType("cg")
        ksp.getPC().setType("jacobi")
        ksp.setTolerances(rtol=1e-12, atol=0.0, max_it=1000)
        rhs, sol = M.createVecRight(), M.createVecLeft()
        T2 = fem.TensorFunctionSpace(msh, ("Lagrange", 2))

        def project(expr):
            bt = fpetsc.assemble_vector(fem.form(ufl.inner(expr, ufl.TestFunction(T2)) * dx))
            bt.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            cols = bt.array.reshape(-1, 9)
            f = fem.Function(T2)
            vals = f.x.array[: cols.size].reshape(-1, 9)
            for j in range(9):
                rhs.array[:] = cols[:, j]
                ksp.solve(rhs, sol)
                vals[:, j] = sol.array
            f.x.scatter_forward()
            return f

        sigma = (mu * (F * F.T - ufl.Identity(3)) + lmbda * ufl.ln(J) * ufl.Identity(3)) / J
        s_h, e_h = project(sigma), project(0.5 * (F.T * F - ufl.Identity(3)))
        V1 = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
        u1 = fem.Function(V1, name="displacement")
        u1.interpolate(u)
        s1 = fem.Function(fem.TensorFunctionSpace(msh, ("Lagrange", 1)))
        s1.interpolate(s_h)
        st = s1.x.array.reshape(-1, 3, 3)
        dev = st - np.einsum("nii->n", st)[:, None, None] / 3 * np.eye(3)
        vm = fem.Function(fem.FunctionSpace(msh, ("Lagrange", 1)), name="von_mises")
        vm.x.array[:] = np.sqrt(1.5 * np.einsum("nij,nij->n", dev, dev))
        tip = np.array([[LENGTH, WIDTH / 2, WIDTH / 2]])
        tree = geometry.BoundingBoxTree(msh, 3)
        cells = geometry.compute_colliding_cells(msh, geometry.compute_collisions(tree, tip), tip)
        probe = {}
        if len(cells.links(0)):
            c = cells.links(0)[:1]
            probe = {"displacement": u.eval(tip, c).tolist(), "stress": s_h.eval(tip, c).tolist(),
                     "strain": e_h.eval(tip, c).tolist()}
        r = fpetsc.assemble_vector(L)
        r.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dofs = bcs[0].dof_indices()[0]
        owned = dofs[dofs < V.dofmap.index_map.size_local * 3]
        reaction = comm.allreduce(np.array([r.array[owned[owned % 3 == k]].sum() for k in range(3)]), op=MPI.SUM)
        probes = comm.gather(probe, root=0)
        with io.XDMFFile(comm, out + "/fields.xdmf", "w") as f:
            f.write_mesh(msh)
            f.write_function(u1)
            f.write_function(vm)
        if comm.rank == 0:
            with open(out + "/results.json", "w") as f:
                json.dump({"probe": next(p for p in probes if p), "reaction": reaction.tolist(),
                           "max_von_mises": float(vm.x.array.max())}, f)
    print(f"BARE its={snes.getIterationNumber()} max_u={np.abs(u.x.array).max():.9e}")
    sys.exit(0)

import argparse
import json
import os
import resource
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PY = sys.executable

BEAM = """title = "benchmark beam 19,683 dofs"
[mesh]
generator = "box"
size = [1.0, 0.1, 0.1]
cells = [40, 4, 4]
cell = "tetrahedron"
[material]
model = "neo-hookean"
E = 1.0e8
nu = 0.3
rho = 1000.0
[discretization]
degree = 2
[[fix]]
where = { axis = "x", at = 0.0 }
[[load]]
type = "gravity"
g = [0.0, 0.0, -9.81]
[solver]
linear = "direct"
[output.probes]
tip = [1.0, 0.05, 0.05]
"""

# CHEN in inverse_methods.py
CHEN = """title = "Chen-size silicone arm"
analysis = "inverse"
[mesh]
generator = "box"
size = [0.2, 0.05, 0.05]
cells = [40, 14, 14]
[material]
model = "neo-hookean"
E = 0.68e6
nu = 0.45
rho = 958.0
[discretization]
degree = 1
[[fix]]
where = { axis = "x", at = 0.0 }
[[load]]
type = "gravity"
g = [0.0, 0.0, -9.81]
[solver]
steps = 1
"""


def commands(tmp: Path, only: str | None, env: dict, before_env: dict | None) -> dict:
    """name -> (command, environment, results folder of an inverse run or None)."""
    (tmp / "beam.toml").write_text(BEAM)
    (tmp / "chen.toml").write_text(CHEN)
    (tmp / "bare").mkdir(exist_ok=True)
    ff = [PY, "-m", "fem_forms", "run"]
    cmds = {}
    for tag, e in (("", env), ("@before", before_env)):
        if e is None:
            continue
        if only in (None, "static"):
            if not tag:
                cmds["bare"] = ([PY, __file__, "--bare-worker"], e, None)
                cmds["bare+fields"] = ([PY, __file__, "--bare-worker", "--fields", str(tmp / "bare")], e, None)
                cmds["bare+same"] = ([PY, __file__, "--bare-worker", "--same", str(tmp / "bare")], e, None)
            cmds["ours-no-picture" + tag] = (ff + [str(tmp / "beam.toml"), "--out", str(tmp / f"beam_np{tag}"),
                                                   "--set", "output.picture=false"], e, None)
            cmds["ours" + tag] = (ff + [str(tmp / "beam.toml"), "--out", str(tmp / f"beam{tag}")], e, None)
        if only in (None, "inverse"):
            if not tag:          # what any dolfinx script pays to start and stop: interpreter, imports, exit
                cmds["dolfinx start+exit"] = ([PY, "-c", "import ufl, dolfinx.fem.petsc"], e, None)
            cmds["inverse" + tag] = (ff + [str(tmp / "chen.toml"), "--out", str(tmp / f"chen{tag}")], e,
                                     tmp / f"chen{tag}")
    return cmds


def static_rows(med, mcpu, times, tag="") -> list:
    rows = ["| static P2 beam, 19,683 dofs, direct | process wall [s] | runs [s] | process CPU [s] |",
            "|---|---:|---|---:|"]
    for k in ("bare", "bare+fields", "bare+same", "ours-no-picture" + tag, "ours" + tag):
        rows.append(f"| {k} | {med[k]:.2f} | {' '.join(f'{t:.2f}' for t in times[k])} | {mcpu[k]:.2f} |")
    o, onp = "ours" + tag, "ours-no-picture" + tag
    return rows + ["", f"- same outputs computed the same way (recovered stresses, probe, reaction, fields, no "
                       f"picture): {onp} / bare+same = **{med[onp] / med['bare+same']:.2f}x** wall, "
                       f"{mcpu[onp] / mcpu['bare+same']:.2f}x CPU (target 1.1x)",
                   f"- against bare writing the cheaper DG0 von Mises field and no probe stresses: {onp} / "
                   f"bare+fields = {med[onp] / med['bare+fields']:.2f}x wall, "
                   f"{mcpu[onp] / mcpu['bare+fields']:.2f}x CPU",
                   f"- default CLI (fields and PNG) against bare solve only: {o} / bare = "
                   f"**{med[o] / med['bare']:.2f}x** wall, {mcpu[o] / mcpu['bare']:.2f}x CPU; against bare+fields "
                   f"{med[o] / med['bare+fields']:.2f}x wall; the picture costs about {med[o] - med[onp]:.2f} s", ""]


def inverse_rows(med, mcpu, times, cpu, extra, tag="") -> list:
    k = "inverse" + tag
    e = extra[k]
    d = statistics.median(e["design"])
    run = statistics.median(e["in_process"])
    f0 = "dolfinx start+exit"
    return ["| Chen-size arm, 47,040 tets, direct method" + (" (before)" if tag else "") +
            " | median [s] | runs [s] |", "|---|---:|---|",
            f"| design (design_time_s) | {d:.2f} | {' '.join(f'{t:.2f}' for t in e['design'])} |",
            f"| whole run, in process (wall_time_s) | {statistics.median(e['in_process']):.2f} | "
            f"{' '.join(f'{t:.2f}' for t in e['in_process'])} |",
            f"| whole `fem-forms run` process | {med[k]:.2f} | {' '.join(f'{t:.2f}' for t in times[k])} |",
            f"| whole `fem-forms run` process, CPU | {mcpu[k]:.2f} | {' '.join(f'{t:.2f}' for t in cpu[k])} |",
            f"| a process that only imports dolfinx and exits | {med[f0]:.2f} | "
            f"{' '.join(f'{t:.2f}' for t in times[f0])} |", "",
            f"- design target 1.5 s: {'met' if d <= 1.5 else 'not met'} ({d:.2f} s)",
            f"- whole run (design, forward check, files, picture) / design = **{run / d:.2f}x** in process "
            f"(target 2x); the process / design = {med[k] / d:.2f}x, of which {med[f0]:.2f} s is any dolfinx "
            f"process's start and exit ({(med[k] - med[f0]) / d:.2f}x without it)",
            f"- forward-check mismatch {max(e['mismatch']):.2g} m; forward check: {_check_text(e['check'][-1])}", ""]


def _check_text(c: dict | None) -> str:
    """The forward check of results.json in a few words (older results have no 'kind')."""
    if not c:
        return "none reported"
    words = f"{c.get('kind', 'path')}, {c['newton_iterations']} Newton steps, {c['krylov_iterations']} Krylov"
    if "start_residual_relative" in c:
        words += f", residual at the target {c['start_residual_relative']:.1e} of the load's"
    if "tangent" in c:
        t = c["tangent"]
        words += (f", tangent {'positive definite' if t['stable'] else 'NOT positive definite'} "
                  f"({t['negative_pivots']} negative pivots)")
    return words


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", choices=("static", "inverse"))
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--root", default=str(ROOT), help="the fem_forms checkout to measure (default: this one)")
    ap.add_argument("--before", help="another checkout (e.g. `git archive` of an older commit) run interleaved "
                                     "with --root, reported as '@before'")
    args = ap.parse_args()

    def environment(root):
        return dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
                    PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        # run from tmp: `python -m` puts the cwd first on sys.path, PYTHONPATH then decides
        cmds = commands(tmp, args.only, environment(args.root), args.before and environment(args.before))
        times = {k: [] for k in cmds}
        cpu = {k: [] for k in cmds}
        extra = {k: {"design": [], "in_process": [], "mismatch": [], "check": []} for k, c in cmds.items() if c[2]}
        for name, (cmd, env, _) in cmds.items():     # warm the JIT cache; check every command works
            p = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tmp)
            if p.returncode:
                sys.exit(f"{name} failed:\n{p.stderr[-3000:]}")
        load0 = os.getloadavg()[0]
        names = list(cmds)
        for r in range(args.repeat):
            for name in (names if r % 2 == 0 else names[::-1]):
                cmd, env, results = cmds[name]
                t, c = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
                p = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tmp)
                times[name].append(time.perf_counter() - t)
                c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu[name].append(c1.ru_utime + c1.ru_stime - c.ru_utime - c.ru_stime)
                if p.returncode:
                    sys.exit(f"{name} failed:\n{p.stderr[-3000:]}")
                if results is not None:
                    s = json.loads((results / "results.json").read_text())
                    extra[name]["design"].append(s["design_time_s"])
                    extra[name]["in_process"].append(s["wall_time_s"])
                    extra[name]["mismatch"].append(s["target_mismatch_max"])
                    extra[name]["check"].append(s.get("forward_check"))
        load1 = os.getloadavg()[0]
    med = {k: statistics.median(v) for k, v in times.items()}
    mcpu = {k: statistics.median(v) for k, v in cpu.items()}
    rows = [f"fem_forms from {args.root}" + (f", '@before' from {args.before}" if args.before else "") +
            f". Medians of {args.repeat} interleaved runs; 1-minute load average {load0:.1f} before, "
            f"{load1:.1f} after (2-core machine, OPENBLAS_NUM_THREADS=1, warm FFCx cache).", ""]
    for tag in ("", "@before") if args.before else ("",):
        if "ours" + tag in med:
            rows += static_rows(med, mcpu, times, tag)
        if "inverse" + tag in med:
            rows += inverse_rows(med, mcpu, times, cpu, extra, tag)
    text = "\n".join(rows)
    print(text)
    if not args.no_write:                        # replace the generated part, keep the notes around it
        md = HERE / "fixed_cost.md"
        begin, end = "<!-- fixed_cost.py: begin -->", "<!-- fixed_cost.py: end -->"
        old = md.read_text() if md.exists() else f"# Fixed cost of `fem-forms run`\n\n{begin}\n{end}\n"
        head, rest = old.split(begin, 1)
        md.write_text(head + begin + "\n" + text + "\n" + end + rest.split(end, 1)[1])


if __name__ == "__main__":
    main()
