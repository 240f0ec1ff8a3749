"""The bare prototype of benchmarks/contact_schemes.py's rocking hemisphere (issue 47 item 6): the same scene written
inline in dolfinx 0.5.2, PETSc and numpy, importing nothing from fem_forms. Backward Euler as an incremental
potential (Li et al. 2020): E(u) = int rho/(2 dt^2) |u - u_n - dt v_n|^2 + psi(F) - rho g . u dx + kappa sum_i A_i
b(d_i) + sum_i mu lambda_i f0(|slip_i|), psi the compressible neo-Hookean mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2,
b the IPC barrier on each surface node's height above the floor (A_i its third of the surface triangles' area,
kappa from E dhat / h at dhat / 2, then scaled so the start's push carries the weight), friction lagged per step
(normal forces, anchors at the step's start, eps = 1e-3 x diagonal x dt). Newton on E: the UFL Hessian plus the
nodes' 3x3 contact blocks, LU (MUMPS), the step capped so no node reaches the floor (a plane's CCD), an Armijo
backtracking line search on E, converged at 1e-9 of the step's first residual or 1e-10 of the weight's.

    .venv/bin/python benchmarks/contact_bare.py MESH.msh [DURATION]

prints one JSON line: steps, Newton iterations, wall seconds (the march alone), and the centre's and low point's
displacements at every step (for the period).

    .venv/bin/python benchmarks/contact_bare.py

(about 10 minutes, alone on the machine) runs it and `fem-forms` with backward Euler on the issue's mesh
(contact_schemes.make_hemisphere), three times each, one process per run, and writes benchmarks/contact_bare.md:
steps, Newton iterations, wall time (median; fem_forms's is its results.json wall_time_s, the whole run after the
mesh is read), the period against rolling without slip."""
from __future__ import annotations

import json
import math
import sys
import time

import gmsh
from dolfinx import fem, geometry, mesh as dmesh
from dolfinx.fem import petsc as fpetsc
from dolfinx.io import gmshio
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

R, E, NU, RHO, FRICTION, G = 0.05, 1e6, 0.4, 1100.0, 0.8, 9.81
FLOOR, DT, SPIN = -R - 5e-5, 2e-3, 1.6                # floor height (m), step (s), rad/s about y at (0, 0, -R)
DEBUG = False
PROBES = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -0.04]])


def barrier(d, dhat):
    return np.where(d < dhat, -(d - dhat) ** 2 * np.log(np.minimum(d, dhat) / dhat), 0.0)


def barrier_1(d, dhat):
    r = np.minimum(d, dhat) / dhat
    return np.where(d < dhat, (dhat - d) * (2 * np.log(r) - 1 / r + 1), 0.0)


def barrier_2(d, dhat):
    q = dhat / np.minimum(d, dhat)
    return np.where(d < dhat, (q + 2) * q + 2 * np.log(q) - 3, 0.0)


def f0(y, eps):
    return np.where(y < eps, -y ** 3 / (3 * eps ** 2) + y ** 2 / eps + eps / 3, y)


def surface(mesh, Q):
    """(surface dofs of Q, their lumped areas): each exterior triangle's third to each of its vertices (P1)."""
    mesh.topology.create_connectivity(2, 3)
    facets = dmesh.exterior_facet_indices(mesh.topology)
    mesh.topology.create_connectivity(2, 0)
    f2v = mesh.topology.connectivity(2, 0).array.reshape(-1, 3)[facets]
    c2v = mesh.topology.connectivity(3, 0).array.reshape(-1, 4)
    v2d = np.empty(mesh.topology.index_map(0).size_local, dtype=np.int64)
    v2d[c2v] = Q.dofmap.list.array.reshape(-1, 4)          # P1: a cell's dofs in its vertices' order
    tri = v2d[f2v]
    X = Q.tabulate_dof_coordinates()
    area = 0.5 * np.linalg.norm(np.cross(X[tri[:, 1]] - X[tri[:, 0]], X[tri[:, 2]] - X[tri[:, 0]]), axis=1)
    nodes, inverse = np.unique(tri, return_inverse=True)
    lumped = np.bincount(inverse, np.repeat(area / 3, 3), len(nodes))
    edges = np.linalg.norm(X[tri[:, 1]] - X[tri[:, 0]], axis=1)
    return nodes, lumped, float(edges.mean())


def main(path: str, duration: float = 1.2) -> dict:
    comm = MPI.COMM_SELF
    gmsh.initialize()                                  # (0.5.2's gmshio.read_from_msh returns an undefined name)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.merge(path)
        mesh = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=3)[0]
    finally:
        gmsh.finalize()
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
    Q = fem.FunctionSpace(mesh, ("Lagrange", 1))
    nodes, area, h = surface(mesh, Q)
    X = Q.tabulate_dof_coordinates()
    zdofs = 3 * nodes + 2
    diag = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    dhat = 1e-3 * diag
    kappa = E / (h * (-barrier_1(np.array([dhat / 2]), dhat)[0] / dhat))
    u, un, vn = fem.Function(V), fem.Function(V), fem.Function(V)
    w = np.zeros_like(X)
    w[:, 0], w[:, 2] = SPIN * (X[:, 2] + R), -SPIN * X[:, 0]     # omega = (0, SPIN, 0) about (0, 0, -R)
    vn.x.array[:] = w.ravel()
    mu_l, lam_l = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    F = ufl.Identity(3) + ufl.grad(u)
    J = ufl.det(F)
    psi = mu_l / 2 * (ufl.tr(F.T * F) - 3) - mu_l * ufl.ln(J) + lam_l / 2 * ufl.ln(J) ** 2
    inertia = u - un - DT * vn
    g = fem.Constant(mesh, PETSc.ScalarType((0.0, 0.0, -G)))
    energy = (RHO / (2 * DT ** 2) * ufl.dot(inertia, inertia) + psi - RHO * ufl.dot(g, u)) * ufl.dx(
        metadata={"quadrature_degree": 2})
    residual = ufl.derivative(energy, u, ufl.TestFunction(V))
    energy_f, residual_f = fem.form(energy), fem.form(residual)
    jacobian_f = fem.form(ufl.derivative(residual, u, ufl.TrialFunction(V)))
    A = fpetsc.create_matrix(jacobian_f)
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    b = fpetsc.create_vector(residual_f)
    ksp = PETSc.KSP().create(comm)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    weight = RHO * G * comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * ufl.dx)))
    d0 = X[nodes, 2] - FLOOR
    kappa *= weight / np.sum(kappa * area * -barrier_1(d0, dhat))    # the start's push carries the weight
    eps = 1e-3 * diag * DT

    def contact(x, lag):
        """(energy, gradient (n, 3), Hessian blocks (n, 3, 3)) of the barrier and the lagged friction at x."""
        lam, start = lag
        p = X[nodes] + x.reshape(-1, 3)[nodes]
        d = p[:, 2] - FLOOR
        if d.min() <= 0:
            return math.inf, None, None
        grad, hess = np.zeros((len(nodes), 3)), np.zeros((len(nodes), 3, 3))
        grad[:, 2] = kappa * area * barrier_1(d, dhat)
        hess[:, 2, 2] = kappa * area * barrier_2(d, dhat)
        s = p[:, :2] - start[:, :2]
        y = np.linalg.norm(s, axis=1)
        e = kappa * np.sum(area * barrier(d, dhat)) + FRICTION * np.sum(lam * f0(y, eps))
        a = np.where(y < eps, 2 / eps - y / eps ** 2, 1 / np.maximum(y, eps))
        bb = np.where(y < eps, 2 / eps - 2 * y / eps ** 2, 0.0)
        grad[:, :2] += (FRICTION * lam * a)[:, None] * s
        unit = s / np.maximum(y, 1e-300)[:, None]
        uu = unit[:, :, None] * unit[:, None, :]
        inner = a[:, None, None] * (np.eye(2) - uu) + bb[:, None, None] * uu
        inner[y < 1e-12 * eps] = (2 / eps) * np.eye(2)
        hess[:, :2, :2] += (FRICTION * lam)[:, None, None] * inner
        return e, grad, hess

    def total(x_arr, lag):
        u.x.array[:] = x_arr
        e_c = contact(x_arr, lag)[0]
        return fem.assemble_scalar(energy_f) + e_c

    rows = (3 * nodes[:, None] + np.arange(3)).astype(PETSc.IntType)
    probes_cells = geometry.compute_colliding_cells(
        mesh, geometry.compute_collisions(geometry.BoundingBoxTree(mesh, 3), PROBES), PROBES)
    cells = [probes_cells.links(i)[0] for i in range(len(PROBES))]
    history, newton, t0 = [], 0, time.perf_counter()
    steps = int(round(duration / DT))
    for step in range(steps):
        x_old = u.x.array.copy()
        p_old = X[nodes] + x_old.reshape(-1, 3)[nodes]
        lam = kappa * area * -barrier_1(p_old[:, 2] - FLOOR, dhat)
        lag = (lam, p_old)
        un.x.array[:] = x_old
        x = x_old + DT * vn.x.array                               # the constant-velocity guess, if it is admissible
        if contact(x, lag)[0] == math.inf:
            x = x_old.copy()
        r0 = None
        for it in range(50):
            u.x.array[:] = x
            e_c, g_c, h_c = contact(x, lag)
            with b.localForm() as loc:
                loc.set(0.0)
            fpetsc.assemble_vector(b, residual_f)
            b.array[rows.ravel()] += g_c.ravel()
            norm = b.norm()
            r0 = norm if r0 is None else r0
            if norm <= max(1e-9 * r0, 1e-10 * weight):
                break
            A.zeroEntries()
            fpetsc.assemble_matrix(A, jacobian_f)
            A.assemble()
            A.setValuesRCV(rows, rows, h_c.reshape(-1, 9), addv=PETSc.InsertMode.ADD_VALUES)
            A.assemble()
            ksp.setOperators(A)
            dx = b.duplicate()
            ksp.solve(b, dx)
            step_dir = -dx.array
            dz = step_dir[zdofs]
            d = X[nodes, 2] + x[zdofs] - FLOOR
            falling = dz < 0
            alpha = min(1.0, 0.9 * float(np.min(d[falling] / -dz[falling]))) if falling.any() else 1.0
            full = alpha
            e0, slope = total(x, lag), float(b.array @ step_dir)
            while alpha > 1e-3 * full and total(x + alpha * step_dir, lag) > e0 + 1e-4 * alpha * slope:
                alpha *= 0.5
            if alpha <= 1e-3 * full:                      # the energy's round-off cannot judge the step: take it
                alpha = full
            x = x + alpha * step_dir
            newton += 1
            if DEBUG:
                print(step, it, f"{norm:.3e}", alpha, file=sys.stderr)
        u.x.array[:] = x
        vn.x.array[:] = (x - x_old) / DT
        history.append([(step + 1) * DT] + u.eval(PROBES, np.array(cells, dtype=np.int32)).ravel().tolist())
    wall = time.perf_counter() - t0
    return {"steps": steps, "newton_iterations": newton, "wall_time_s": wall, "history": history}


def compare() -> None:
    """Both sides on the same mesh, three runs each; the table into contact_bare.md."""
    import os
    import statistics
    import subprocess
    import tempfile
    from pathlib import Path
    here = Path(__file__).resolve().parent
    sys.path.insert(0, str(here))
    import contact_schemes as cs
    work = Path(tempfile.mkdtemp())
    mesh = cs.make_hemisphere(work / "dome.msh")
    T = cs.rolling_period()
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    ours, bare = [], []
    for i in range(3):
        r, out, _ = cs.run(cs.hemisphere(mesh, "backward-euler"), work / f"ours{i}", 4 * cs.LIMIT_S)
        ours.append((r, cs.rocking_period(out)))
        p = subprocess.run([sys.executable, __file__, str(mesh)], env=env, capture_output=True, text=True, check=True)
        b = json.loads(p.stdout.strip().splitlines()[-1])
        h = np.array(b["history"])
        (work / "bare").mkdir(exist_ok=True)
        np.savetxt(work / "bare" / "probes.csv", h, delimiter=",", comments="",
                   header="time,centre_ux,centre_uy,centre_uz,low_ux,low_uy,low_uz")
        bare.append((b, cs.rocking_period(work / "bare")))
    lines = ["# The rocking hemisphere: fem_forms against a bare prototype", "",
             "Generated by `benchmarks/contact_bare.py` (see its docstring): the scene of issue 47 (P1 on the graded "
             "mesh of benchmarks/contact_schemes.py, friction 0.8, dt 2 ms, 600 steps), backward Euler, one core, "
             "medians of 3 runs.", "",
             f"| implementation | steps | Newton iterations | wall | period against rolling {T:.3f} s |",
             "|---|---|---|---|---|"]
    for name, runs in (("fem_forms (`scheme = \"backward-euler\"`)", ours), ("bare dolfinx + numpy prototype", bare)):
        r, period = runs[-1]
        wall = statistics.median(x[0]["wall_time_s"] for x in runs)
        lines.append(f"| {name} | {r['steps']} | {r['newton_iterations']} | {wall:.1f} s | "
                     + (f"{period:.3f} s ({100 * (period / T - 1):+.1f} %) |" if period else "no full swing |"))
    (here / "contact_bare.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) > 1:
        print(json.dumps(main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 1.2)))
    else:
        compare()
