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


class Hemisphere:
    """The scene on the mesh file `path`: forms, matrix, LU and the contact's arrays, as a bare script holds them."""

    def __init__(self, path: str):
        comm = MPI.COMM_SELF
        gmsh.initialize()                              # (0.5.2's gmshio.read_from_msh returns an undefined name)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.merge(path)
            self.mesh = mesh = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=3)[0]
        finally:
            gmsh.finalize()
        V = fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
        self.nodes, self.area, h = surface(mesh, fem.FunctionSpace(mesh, ("Lagrange", 1)))
        self.X = X = fem.FunctionSpace(mesh, ("Lagrange", 1)).tabulate_dof_coordinates()
        self.rows = (3 * self.nodes[:, None] + np.arange(3)).astype(PETSc.IntType)
        diag = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
        self.dhat, self.eps = 1e-3 * diag, 1e-3 * diag * DT
        self.u, self.un, self.vn = fem.Function(V), fem.Function(V), fem.Function(V)
        w = np.zeros_like(X)
        w[:, 0], w[:, 2] = SPIN * (X[:, 2] + R), -SPIN * X[:, 0]     # omega = (0, SPIN, 0) about (0, 0, -R)
        self.vn.x.array[:] = w.ravel()
        self._forms(V)
        self.A = fpetsc.create_matrix(self.jacobian)
        self.A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        self.b = fpetsc.create_vector(self.residual)
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setType("preonly")
        self.ksp.getPC().setType("lu")
        self.ksp.getPC().setFactorSolverType("mumps")
        self.weight = RHO * G * fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * ufl.dx))
        kappa = E / (h * (-barrier_1(np.array([self.dhat / 2]), self.dhat)[0] / self.dhat))
        push = np.sum(kappa * self.area * -barrier_1(X[self.nodes, 2] - FLOOR, self.dhat))
        self.kappa = kappa * self.weight / push                      # the start's push carries the weight

    def _forms(self, V) -> None:
        """The incremental potential's UFL part (inertia, neo-Hookean, gravity), its residual and Hessian."""
        u, un, vn = self.u, self.un, self.vn
        mu_l, lam_l = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
        F = ufl.Identity(3) + ufl.grad(u)
        J = ufl.det(F)
        psi = mu_l / 2 * (ufl.tr(F.T * F) - 3) - mu_l * ufl.ln(J) + lam_l / 2 * ufl.ln(J) ** 2
        inertia = u - un - DT * vn
        g = fem.Constant(self.mesh, PETSc.ScalarType((0.0, 0.0, -G)))
        energy = (RHO / (2 * DT ** 2) * ufl.dot(inertia, inertia) + psi - RHO * ufl.dot(g, u)) * ufl.dx(
            metadata={"quadrature_degree": 2})
        residual = ufl.derivative(energy, u, ufl.TestFunction(V))
        self.energy, self.residual = fem.form(energy), fem.form(residual)
        self.jacobian = fem.form(ufl.derivative(residual, u, ufl.TrialFunction(V)))

    def contact(self, x, lag):
        """(energy, gradient (n, 3), Hessian blocks (n, 3, 3)) of the barrier and the lagged friction at x."""
        lam, start = lag
        p = self.X[self.nodes] + x.reshape(-1, 3)[self.nodes]
        d = p[:, 2] - FLOOR
        if d.min() <= 0:
            return math.inf, None, None
        ka, dhat, eps = self.kappa * self.area, self.dhat, self.eps
        grad, hess = np.zeros((len(d), 3)), np.zeros((len(d), 3, 3))
        grad[:, 2], hess[:, 2, 2] = ka * barrier_1(d, dhat), ka * barrier_2(d, dhat)
        s = p[:, :2] - start[:, :2]
        y = np.linalg.norm(s, axis=1)
        e = np.sum(ka * barrier(d, dhat)) + FRICTION * np.sum(lam * f0(y, eps))
        a = np.where(y < eps, 2 / eps - y / eps ** 2, 1 / np.maximum(y, eps))
        bb = np.where(y < eps, 2 / eps - 2 * y / eps ** 2, 0.0)
        grad[:, :2] += (FRICTION * lam * a)[:, None] * s
        unit = s / np.maximum(y, 1e-300)[:, None]
        uu = unit[:, :, None] * unit[:, None, :]
        inner = a[:, None, None] * (np.eye(2) - uu) + bb[:, None, None] * uu
        inner[y < 1e-12 * eps] = (2 / eps) * np.eye(2)
        hess[:, :2, :2] += (FRICTION * lam)[:, None, None] * inner
        return e, grad, hess

    def total(self, x, lag) -> float:
        self.u.x.array[:] = x
        return fem.assemble_scalar(self.energy) + self.contact(x, lag)[0]

    def newton_direction(self, x, lag) -> tuple[float, np.ndarray | None]:
        """(the residual's norm at x, the Newton direction), the residual left in self.b."""
        self.u.x.array[:] = x
        _, g_c, h_c = self.contact(x, lag)
        with self.b.localForm() as loc:
            loc.set(0.0)
        fpetsc.assemble_vector(self.b, self.residual)
        self.b.array[self.rows.ravel()] += g_c.ravel()
        norm = self.b.norm()
        self.A.zeroEntries()
        fpetsc.assemble_matrix(self.A, self.jacobian)
        self.A.assemble()
        self.A.setValuesRCV(self.rows, self.rows, h_c.reshape(-1, 9), addv=PETSc.InsertMode.ADD_VALUES)
        self.A.assemble()
        self.ksp.setOperators(self.A)
        dx = self.b.duplicate()
        self.ksp.solve(self.b, dx)
        return norm, -dx.array

    def step(self, step: int) -> int:
        """One backward-Euler step (friction lagged at its start); its Newton iterations."""
        x_old = self.u.x.array.copy()
        p_old = self.X[self.nodes] + x_old.reshape(-1, 3)[self.nodes]
        lag = (self.kappa * self.area * -barrier_1(p_old[:, 2] - FLOOR, self.dhat), p_old)
        self.un.x.array[:] = x_old
        x = x_old + DT * self.vn.x.array                    # the constant-velocity guess, if it is admissible
        if self.contact(x, lag)[0] == math.inf:
            x = x_old.copy()
        r0, zdofs = None, 3 * self.nodes + 2
        for it in range(50):
            norm, direction = self.newton_direction(x, lag)
            r0 = norm if r0 is None else r0
            if norm <= max(1e-9 * r0, 1e-10 * self.weight):
                break
            dz, d = direction[zdofs], self.X[self.nodes, 2] + x[zdofs] - FLOOR
            falling = dz < 0
            full = alpha = min(1.0, 0.9 * float(np.min(d[falling] / -dz[falling]))) if falling.any() else 1.0
            e0, slope = self.total(x, lag), float(self.b.array @ direction)
            while alpha > 1e-3 * full and self.total(x + alpha * direction, lag) > e0 + 1e-4 * alpha * slope:
                alpha *= 0.5
            if alpha <= 1e-3 * full:                       # the energy's round-off cannot judge the step: take it
                alpha = full
            x = x + alpha * direction
            if DEBUG:
                print(step, it, f"{norm:.3e}", alpha, file=sys.stderr)
        self.u.x.array[:] = x
        self.vn.x.array[:] = (x - x_old) / DT
        return it


def main(path: str, duration: float = 1.2) -> dict:
    """The march; its steps, Newton iterations, wall time (the march alone) and the probes at every step."""
    scene = Hemisphere(path)
    mesh = scene.mesh
    found = geometry.compute_colliding_cells(
        mesh, geometry.compute_collisions(geometry.BoundingBoxTree(mesh, 3), PROBES), PROBES)
    cells = np.array([found.links(i)[0] for i in range(len(PROBES))], dtype=np.int32)
    history, newton, t0 = [], 0, time.perf_counter()
    steps = int(round(duration / DT))
    for step in range(steps):
        newton += scene.step(step)
        history.append([(step + 1) * DT] + scene.u.eval(PROBES, cells).ravel().tolist())
    return {"steps": steps, "newton_iterations": newton, "wall_time_s": time.perf_counter() - t0, "history": history}


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
