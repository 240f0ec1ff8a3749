"""Inverse rest-shape design: the shape to fabricate so that, under the scene's loads, it deforms into
the target shape (the scene's mesh).

Three methods share one check:
- direct (default): inverse elastostatics. Equilibrium is written on the known target configuration
  x with the rest positions X = x + v(x) as unknowns: F = (I + grad_x v)^-1, and the forward weak form
  pulled to the target (P : grad eta F j dx, gravity rho j dx with j = det(I + grad v) = 1/J). With
  P1 tetrahedra or Q1 hexahedra this is the exact discrete inverse of the forward problem.
- adjoint: minimise J(d) (mismatch on chosen points/region, smoothness, shape preservation) over
  rest shapes mesh + d subject to forward equilibrium, gradient by one adjoint solve, PETSc TAO BLMVM.
- fixed-point: the backward-displacement baseline rest <- target - u(rest).
Every designed shape is checked before it is handed out: written as a mesh file, read back through
the file loader, solved forward by the static analysis, and compared with the target.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc

from .. import newton, output, rest_shape
from ..errors import InputError, SolveError
from ..linear import rigid_body_modes
from ..loads import LoadFactor, load_regions, locate_facets, supports
from ..materials import first_piola_kirchhoff
from ..meshes import LoadedMesh, load_mesh, mesh_size
from ..model import build_material, _quadrature_points
from ..scene import MeshSpec, Scene


@dataclass
class InverseResult:
    method: str
    v: fem.Function                 # rest minus target position, on the target mesh
    loaded: LoadedMesh
    converged: bool
    iterations: int
    message: str = ""
    history: list = field(default_factory=list)
    solve_time: float = 0.0
    forward_solves: int = 0


def target_scene(scene: Scene) -> MeshSpec:
    """The target shape's mesh: [inverse] target if given, else the scene's mesh."""
    if scene.inverse.target is not None:
        return MeshSpec(generator="file", file=scene.inverse.target)
    return scene.mesh


# --------------------------------------------------------------------------------- direct method
def _pulled_back_loads(scene: Scene, loaded: LoadedMesh, eta, F, j, dx, quad: dict):
    """External virtual work of the scene's loads written on the target (deformed) configuration."""
    mesh = loaded.mesh
    tags, ids = load_regions(loaded, scene.load)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=quad)
    n = ufl.FacetNormal(mesh)
    rho = scene.material.rho
    ext = 0
    for i, spec in enumerate(scene.load):
        if spec.type == "gravity":                      # rho per rest volume: rho dX = rho j dx
            ext = ext + rho * j * ufl.dot(fem.Constant(mesh, PETSc.ScalarType(spec.g)), eta) * dx
        elif spec.type == "traction":                   # per rest area: dA = j |F^T n| da
            T = fem.Constant(mesh, PETSc.ScalarType(spec.value))
            dA = j * ufl.sqrt(ufl.dot(F.T * n, F.T * n))
            ext = ext + sum(dA * ufl.dot(T, eta) * ds(k) for k in ids[i])
        else:                                           # follower pressure acts on the known surface
            ext = ext - sum(spec.pressure * ufl.dot(n, eta) * ds(k) for k in ids[i])
    return ext


def solve_direct(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Inverse elastostatics with load continuation (secant predictor, automatic cut-back)."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    mesh = loaded.mesh
    mat = build_material(scene, material)
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", scene.discretization.degree))
    v = fem.Function(V, name="rest_minus_target")
    quad = {"quadrature_degree": scene.discretization.quadrature}
    dx = ufl.Measure("dx", domain=mesh, metadata=quad)
    load = LoadFactor(mesh)
    bcs = supports(V, loaded, scene.fix, load, sign=-1.0)
    eta = ufl.TestFunction(V)
    Finv = ufl.Identity(3) + ufl.grad(v)                 # dX/dx
    F = ufl.inv(Finv)
    j = ufl.det(Finv)
    P = first_piola_kirchhoff(mat, F)
    residual = ufl.inner(P, ufl.grad(eta) * F) * j * dx \
        - load.constant * _pulled_back_loads(scene, loaded, eta, F, j, dx, quad)
    jacobian = ufl.derivative(residual, v, ufl.TrialFunction(V))
    points, _ = _quadrature_points(mesh, scene.discretization.quadrature)
    jexpr = fem.Expression(j, points)
    ncells = mesh.topology.index_map(3).size_local

    def inadmissible():
        vals = jexpr.eval(np.arange(ncells, dtype=np.int32))
        jmin = mesh.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        return None if np.isfinite(jmin) and jmin > 0 else f"inverted rest-shape elements (min det = {jmin:.3g})"

    problem = newton.NonlinearProblem(v, residual, jacobian, bcs, energy=None, set_load=load.set,
                                      inadmissible=inadmissible)
    options = {"snes_linesearch_type": "basic", **scene.solver.petsc}
    report = newton.solve(problem, options, steps=scene.solver.steps, max_cutbacks=scene.solver.max_cutbacks,
                          linear_kind=scene.solver.linear, near_nullspace=lambda: rigid_body_modes(V),
                          prefix="fem_forms_inverse_")
    res = InverseResult("direct", v, loaded, report.converged, report.newton_iterations, report.message,
                        history=[{"load": s.load, "iterations": s.iterations, "accepted": s.accepted,
                                  "reason": s.reason, "note": s.note} for s in report.steps])
    res.solve_time = time.perf_counter() - t0
    return res


# ----------------------------------------------------------- forward problem on a rest shape mesh + d
class ForwardOnRest:
    """Forward equilibrium of the body whose rest shape is (target mesh + d), written on the fixed
    target mesh: X = x + d(x), G = dX/dx = I + grad d, F = I + grad u G^-1, dX = det G dx.
    Provides the energy, its derivatives in u and in d (ufl.derivative), and warm-started solves."""

    def __init__(self, scene: Scene, material, loaded: LoadedMesh, V: fem.FunctionSpace):
        self.scene, self.loaded, self.V = scene, loaded, V
        mesh = loaded.mesh
        self.mesh = mesh
        self.mat = build_material(scene, material)
        self.d = fem.Function(V, name="rest_minus_target")
        self.u = fem.Function(V, name="displacement")
        quad = {"quadrature_degree": scene.discretization.quadrature}
        self.dx = ufl.Measure("dx", domain=mesh, metadata=quad)
        self.load = LoadFactor(mesh)
        self.bcs = supports(V, loaded, scene.fix, self.load)
        G = ufl.Identity(3) + ufl.grad(self.d)
        Ginv = ufl.inv(G)
        jG = ufl.det(G)
        F = ufl.Identity(3) + ufl.grad(self.u) * Ginv
        tags, ids = load_regions(loaded, scene.load)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=quad)
        n = ufl.FacetNormal(mesh)
        W = 0
        for i, spec in enumerate(scene.load):
            if spec.type == "gravity":
                W = W + scene.material.rho * ufl.dot(fem.Constant(mesh, PETSc.ScalarType(spec.g)), self.u) * jG * self.dx
            elif spec.type == "traction":
                T = fem.Constant(mesh, PETSc.ScalarType(spec.value))
                dA = jG * ufl.sqrt(ufl.dot(Ginv.T * n, Ginv.T * n))
                W = W + sum(ufl.dot(T, self.u) * dA * ds(k) for k in ids[i])
            else:
                raise InputError(f"inverse.method = {scene.inverse.method!r}: follower pressure is supported "
                                 "by the direct method only")
        self.energy = self.mat.psi(F) * jG * self.dx - (self.load.constant * W if not isinstance(W, int) else 0)
        w = ufl.TestFunction(V)
        self.residual = ufl.derivative(self.energy, self.u, w)
        self.jacobian = ufl.derivative(self.residual, self.u, ufl.TrialFunction(V))
        self.dres_dd = ufl.derivative(self.residual, self.d, ufl.TrialFunction(V))
        points, _ = _quadrature_points(mesh, scene.discretization.quadrature)
        self._jexpr = fem.Expression(ufl.det(F) * jG, points)
        self.solves = 0
        self._u_ok = self.u.x.array.copy()

    def inadmissible(self):
        ncells = self.mesh.topology.index_map(3).size_local
        vals = self._jexpr.eval(np.arange(ncells, dtype=np.int32))
        jmin = self.mesh.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        return None if np.isfinite(jmin) and jmin > 0 else f"inverted elements (min det = {jmin:.3g})"

    def solve(self) -> newton.SolveReport:
        """Equilibrium for the current d, warm-started from the last solution; falls back to load
        continuation from zero if the warm start fails."""
        self.solves += 1
        problem = newton.NonlinearProblem(self.u, self.residual, self.jacobian, self.bcs, energy=self.energy,
                                          set_load=None, inadmissible=self.inadmissible)
        self.load.set(1.0)
        opts = dict(self.scene.solver.petsc)
        rep = newton.solve(problem, opts, prefix="fem_forms_fwd_", linear_kind=self.scene.solver.linear)
        if not rep.converged:
            self.u.x.array[:] = 0.0
            problem.set_load = self.load.set
            rep = newton.solve(problem, opts, steps=max(self.scene.solver.steps, 4),
                               max_cutbacks=self.scene.solver.max_cutbacks, prefix="fem_forms_fwd_",
                               linear_kind=self.scene.solver.linear)
        if rep.converged:
            self._u_ok = self.u.x.array.copy()
        else:
            self.u.x.array[:] = self._u_ok
        return rep


# --------------------------------------------------------------------------------- adjoint method
class AdjointDesign:
    """J(d) = 1/2 mismatch^2 (mean over the matched volume or points) + smoothness/2 int |grad d|^2
    + stay_close/2 int |d|^2; mismatch = deformed position - target = d + u(d)."""

    def __init__(self, fwd: ForwardOnRest):
        self.fwd = fwd
        spec = fwd.scene.inverse
        mesh, V, d, u = fwd.mesh, fwd.V, fwd.d, fwd.u
        comm = mesh.comm
        dx = fwd.dx
        self.point_dofs = None
        if spec.match_points is not None:
            self.point_dofs = _snap_points(V, spec.match_points)
            self.J_match = None
        else:
            if spec.match_region is not None:
                from dolfinx import mesh as dmesh
                lo = np.array(spec.match_region.lo)[:, None]
                hi = np.array(spec.match_region.hi)[:, None]
                tol = 1e-9 * mesh_size(mesh)
                cells = dmesh.locate_entities(mesh, 3, lambda x: np.all((x >= lo - tol) & (x <= hi + tol), axis=0))
                ncell = comm.allreduce(len(cells), op=MPI.SUM)
                if ncell == 0:
                    raise InputError("inverse.match_region: contains no cell of the mesh")
                tags = dmesh.meshtags(mesh, 3, np.sort(cells).astype(np.int32), 1)
                dxm = ufl.Measure("dx", domain=mesh, subdomain_data=tags, metadata=dx.metadata())(1)
            else:
                dxm = dx
            vol = comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * dxm)), op=MPI.SUM)
            self.J_match = 0.5 / vol * ufl.dot(d + u, d + u) * dxm
        J_reg = 0
        if spec.smoothness > 0:
            J_reg = J_reg + 0.5 * spec.smoothness * ufl.inner(ufl.grad(d), ufl.grad(d)) * dx
        if spec.stay_close > 0:
            J_reg = J_reg + 0.5 * spec.stay_close * ufl.dot(d, d) * dx
        self.J_reg = J_reg if not isinstance(J_reg, int) else None
        w = ufl.TestFunction(V)
        parts = [p for p in (self.J_match, self.J_reg) if p is not None]
        self.J_form = fem.form(sum(parts)) if parts else None
        self.dJdu = fem.form(ufl.derivative(self.J_match, u, w)) if self.J_match is not None else None
        self.dJdd = fem.form(ufl.derivative(sum(parts), d, w)) if parts else None
        self.K = fem.form(fwd.jacobian)
        self.B = fem.form(fwd.dres_dd)
        self.evaluations = 0
        # adjoint linear solver: MUMPS LU on the (symmetric) tangent
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix("fem_forms_adjoint_")
        opts = PETSc.Options()
        for k, val in {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}.items():
            opts["fem_forms_adjoint_" + k] = val
        self.ksp.setFromOptions()
        # fixed dofs of d: the rest shape stays attached where the body is supported
        self.fixed = np.unique(np.concatenate([bc.dof_indices()[0] for bc in fwd.bcs])) if fwd.bcs else \
            np.empty(0, dtype=np.int32)

    def _assemble_vec(self, form) -> PETSc.Vec:
        b = fpetsc.assemble_vector(form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return b

    def value_and_gradient(self, dvec: np.ndarray):
        """J and dJ/dd (owned dofs) for d given on owned dofs; None if the forward solve fails."""
        fwd = self.fwd
        n = len(dvec)
        fwd.d.x.array[:n] = dvec
        fwd.d.x.scatter_forward()
        rep = fwd.solve()
        self.evaluations += 1
        if not rep.converged:
            return None
        comm = fwd.mesh.comm
        J = comm.allreduce(fem.assemble_scalar(self.J_form), op=MPI.SUM) if self.J_form else 0.0
        # dJ/du
        if self.point_dofs is not None:
            mis = fwd.d.x.array + fwd.u.x.array
            npts = comm.allreduce(len(self.point_dofs[0]), op=MPI.SUM) // 3 or 1
            J += 0.5 / npts * float(comm.allreduce(np.sum(mis[self.point_dofs[0]] ** 2), op=MPI.SUM))
            rhs = fpetsc.create_vector(fem.form(fwd.residual))
            rhs.set(0.0)
            owned = self.point_dofs[1]
            rhs.array[owned] = mis[owned] / npts
        else:
            rhs = self._assemble_vec(self.dJdu)
        # adjoint: K mu = dJ/du with homogeneous conditions on supported dofs (K is symmetric)
        K = fpetsc.assemble_matrix(self.K, bcs=fwd.bcs)
        K.assemble()
        fpetsc.set_bc(rhs, fwd.bcs, scale=0.0)
        mu = rhs.duplicate()
        self.ksp.setOperators(K)
        self.ksp.solve(rhs, mu)
        if self.ksp.getConvergedReason() < 0:
            return None
        B = fpetsc.assemble_matrix(self.B)
        B.assemble()
        grad = self._assemble_vec(self.dJdd) if self.dJdd is not None else rhs.duplicate()
        if self.dJdd is None:
            grad.set(0.0)
        if self.point_dofs is not None:            # the point mismatch depends on d directly too
            grad.array[self.point_dofs[1]] += rhs.array[self.point_dofs[1]]
        Btmu = grad.duplicate()
        B.multTranspose(mu, Btmu)                  # mu is zero on supported dofs
        grad.axpy(-1.0, Btmu)
        g = grad.array.copy()
        g[self.fixed[self.fixed < n]] = 0.0
        for obj in (K, B, mu, rhs, grad, Btmu):
            obj.destroy()
        return J, g


def _snap_points(V: fem.FunctionSpace, points: list):
    """Dofs of the mesh vertices nearest each point: (all local dof indices incl. ghosts, owned only)."""
    bs = V.dofmap.index_map_bs
    nown = V.dofmap.index_map.size_local
    X = V.tabulate_dof_coordinates()
    comm = V.mesh.comm
    idx_all, idx_own = [], []
    for p in points:
        dist = np.linalg.norm(X - np.asarray(p), axis=1) if len(X) else np.array([np.inf])
        k = int(np.argmin(dist))
        best = comm.allreduce(float(dist[k]), op=MPI.MIN)
        if dist[k] <= best and len(X):
            # the lowest rank holding an owned node at that distance owns the match
            rank = comm.allreduce(comm.rank if (dist[k] <= best and k < nown) else comm.size, op=MPI.MIN)
        else:
            rank = comm.allreduce(comm.size, op=MPI.MIN)
        if comm.rank == rank:
            dofs = [k * bs + c for c in range(bs)]
            idx_all += dofs
            idx_own += dofs
    return np.array(idx_all, dtype=np.int32), np.array(idx_own, dtype=np.int32)


def solve_adjoint(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Minimise J over rest shapes with PETSc TAO (bounded L-BFGS, BLMVM)."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    V = fem.VectorFunctionSpace(loaded.mesh, ("Lagrange", scene.discretization.degree))
    fwd = ForwardOnRest(scene, material, loaded, V)
    design = AdjointDesign(fwd)
    spec = scene.inverse
    comm = loaded.mesh.comm
    x = fpetsc.create_vector(fem.form(fwd.residual))
    x.set(0.0)
    history: list = []
    failed = {"flag": False}

    def objgrad(tao, xv, gv):
        out = design.value_and_gradient(xv.array.copy())
        if out is None:
            failed["flag"] = True
            gv.set(0.0)
            return 1e30
        J, g = out
        gv.array[:] = g
        history.append(J)
        return J

    tao = PETSc.TAO().create(comm)
    tao.setOptionsPrefix("fem_forms_tao_")
    tao.setType("blmvm")
    tao.setObjectiveGradient(objgrad, x.duplicate())
    big = 1e20 if spec.max_move is None else spec.max_move
    lb, ub = x.duplicate(), x.duplicate()
    lb.set(-big)
    ub.set(big)
    n = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    fixed = design.fixed[design.fixed < n]
    lb.array[fixed] = 0.0
    ub.array[fixed] = 0.0
    tao.setVariableBounds(lb, ub)
    tao.setTolerances(gatol=spec.tolerance, grtol=0.0, gttol=0.0)
    tao.setMaximumIterations(spec.iterations)
    tao.setFromOptions()
    tao.solve(x)
    reason = tao.getConvergedReason()
    v = fem.Function(V, name="rest_minus_target")
    v.x.array[:n] = x.array
    v.x.scatter_forward()
    ok = reason > 0 and not failed["flag"]
    msg = f"TAO reason {reason}, J = {history[-1] if history else float('nan'):.3e}"
    if failed["flag"]:
        msg = "a forward solve failed during the optimisation (" + msg + ")"
    res = InverseResult("adjoint", v, loaded, ok, tao.getIterationNumber(), msg,
                        history=[{"J": J} for J in history], forward_solves=fwd.solves)
    res.solve_time = time.perf_counter() - t0
    tao.destroy()
    return res


def solve_fixed_point(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Backward-displacement iteration: rest <- target - u(rest), i.e. d <- -u(d), until the update
    is below tolerance x mesh size."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    V = fem.VectorFunctionSpace(loaded.mesh, ("Lagrange", scene.discretization.degree))
    fwd = ForwardOnRest(scene, material, loaded, V)
    size = mesh_size(loaded.mesh)
    comm = loaded.mesh.comm
    history, ok, msg = [], False, ""
    for k in range(scene.inverse.iterations):
        rep = fwd.solve()
        if not rep.converged:
            msg = f"forward solve failed at iteration {k}: {rep.message}"
            break
        new = -fwd.u.x.array
        change = comm.allreduce(float(np.abs(new - fwd.d.x.array).max()) if new.size else 0.0, op=MPI.MAX)
        fwd.d.x.array[:] = new
        history.append({"iteration": k, "update": change})
        if change <= max(scene.inverse.tolerance, 1e-12) * size:
            ok, msg = True, f"converged: update {change:.3e} m"
            break
        if not np.isfinite(change) or change > 10 * size:
            msg = f"diverged: update {change:.3e} m at iteration {k}"
            break
    else:
        msg = f"no convergence in {scene.inverse.iterations} iterations (last update {history[-1]['update']:.3e} m)"
    v = fem.Function(V, name="rest_minus_target")
    v.x.array[:] = fwd.d.x.array
    res = InverseResult("fixed-point", v, loaded, ok, len(history), msg, history=history,
                        forward_solves=fwd.solves)
    res.solve_time = time.perf_counter() - t0
    return res


METHODS = {"direct": solve_direct, "adjoint": solve_adjoint, "fixed-point": solve_fixed_point}


# ------------------------------------------------------------------------------- checks and output
@dataclass
class ForwardCheck:
    mismatch_max: float
    static: object                  # the StaticResult of the forward solve from the rest shape
    problems: list


def check_rest_shape(scene: Scene, res: InverseResult, out: Path) -> ForwardCheck:
    """Write the rest shape (volume .msh + STL), check it crosses no support plane and does not
    intersect itself, then read it back as a file mesh, solve the forward problem from it and measure
    the largest distance of the deformed shape from the target."""
    from .static import solve_static
    mesh = res.loaded.mesh
    comm = mesh.comm
    size = mesh_size(mesh)
    shift = output.node_values(res.v)
    gathered = output.gather_mesh(mesh, shift)
    target = output.gather_mesh(mesh)
    problems = []
    if comm.rank == 0:
        points, cells, ctype = gathered
        write_ok = True
        try:
            rest_shape.write_volume_mesh(out / "rest_shape.msh", points, cells, ctype)
            faces = rest_shape.boundary_faces(cells, ctype)
            tris = rest_shape.triangles(faces)
            rest_shape.write_stl(out / "rest_shape.stl", points, tris)
        except OSError as e:
            write_ok = False
            problems.append(f"cannot write the rest shape: {e}")
        if write_ok:
            for f in scene.fix:
                if f.where.kind == "plane":
                    depth = rest_shape.crosses_support_plane(points, target[0], f.where.axis, f.where.at,
                                                             1e-6 * size)
                    if depth > 0:
                        problems.append(f"the rest shape crosses the support plane {'xyz'[f.where.axis]} = "
                                        f"{f.where.at} by {depth:.3g} m")
            hits = rest_shape.self_intersections(points, tris)
            if hits:
                problems.append(f"the rest shape's surface intersects itself ({hits} crossing triangle pairs)")
    problems = comm.bcast(problems, root=0)
    pts_rest = comm.bcast(gathered[0] if comm.rank == 0 else None, root=0)
    pts_target = comm.bcast(target[0] if comm.rank == 0 else None, root=0)
    if problems and any("cannot write" in p for p in problems):
        return ForwardCheck(np.inf, None, problems)
    # independent forward check: read the written mesh back and solve the static problem on it
    import copy
    fscene = copy.deepcopy(scene)
    fscene.analysis = "static"
    fscene.mesh = MeshSpec(generator="file", file=out / "rest_shape.msh")
    fscene.output.probes = {}
    try:
        static = solve_static(fscene)
    except InputError as e:
        return ForwardCheck(np.inf, None, problems + [f"the rest shape is not a valid mesh: {e}"])
    if not static.report.converged:
        return ForwardCheck(np.inf, static, problems + [f"the forward solve from the rest shape failed: "
                                                        f"{static.report.message}"])
    from scipy.spatial import cKDTree
    fmesh = static.model.mesh
    X = fmesh.geometry.x
    dist, idx = cKDTree(pts_rest).query(X)
    deformed = X + output.node_values(static.u)
    local = float(np.linalg.norm(deformed - pts_target[idx], axis=1).max()) if len(X) else 0.0
    mismatch = comm.allreduce(local, op=MPI.MAX)
    tol = scene.inverse.check_tolerance or 1e-3 * size
    if mismatch > tol:
        problems.append(f"the forward solve from the rest shape lands {mismatch:.3g} m from the target "
                        f"(tolerance {tol:.3g} m): another equilibrium, the design is not usable")
    return ForwardCheck(mismatch, static, problems)


def picture(path: Path, res: InverseResult, check: ForwardCheck, title: str) -> None:
    """Three panels: the target, the designed rest shape, the forward check (rest shape under load)."""
    mesh = res.loaded.mesh
    target = output.gather_mesh(mesh)
    rest = output.gather_mesh(mesh, output.node_values(res.v))
    fwd = None
    if check.static is not None:
        fm = check.static.model.mesh
        fwd = output.gather_mesh(fm, output.node_values(check.static.u))
    if mesh.comm.rank != 0:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    panels = [("target", target, "tab:blue"), ("rest shape to fabricate", rest, "tab:orange")]
    if fwd is not None:
        panels.append((f"forward check (mismatch {check.mismatch_max:.2g} m)", fwd, "tab:green"))
    allp = np.vstack([p[0] for _, p, _ in panels])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    fig = plt.figure(figsize=(5 * len(panels), 5))
    for k, (name, (pts, cells, ctype), colour) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1, projection="3d")
        faces = rest_shape.boundary_faces(cells, ctype)
        ax.add_collection3d(Poly3DCollection(target[0][rest_shape.boundary_faces(target[1], target[2])],
                                             facecolor=(0.5, 0.5, 0.5, 0.06), edgecolor=(0.3, 0.3, 0.3, 0.08),
                                             linewidths=0.2))
        ax.add_collection3d(Poly3DCollection(pts[faces], facecolor=colour, alpha=0.75,
                                             edgecolor=(0, 0, 0, 0.2), linewidths=0.2))
        output.style_axes(ax, lo, hi)
        ax.set_title(name)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def design_rest_shape(scene: Scene, material=None) -> InverseResult:
    """Run the scene's inverse method (mesh loading and compilation included in solve_time)."""
    t0 = time.perf_counter()
    res = METHODS[scene.inverse.method](scene, material)
    res.solve_time = time.perf_counter() - t0
    return res


def run(scene: Scene, out: Path, echo: bool = False) -> dict:
    """CLI entry: design, check, write outputs; SolveError (exit 3) for any unusable design."""
    t0 = time.perf_counter()
    res = design_rest_shape(scene)
    comm = res.loaded.mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    summary = {"analysis": "inverse", "title": scene.title, "method": res.method,
               "dofs": res.v.function_space.dofmap.index_map.size_global * 3,
               "iterations": res.iterations, "converged": res.converged, "design_time_s": res.solve_time,
               "forward_solves": res.forward_solves, "mpi_ranks": comm.size, "history": res.history}
    problems = [] if res.converged else [f"the {res.method} method did not reach a rest shape: {res.message}"]
    check = None
    if res.converged:
        check = check_rest_shape(scene, res, out)
        problems += check.problems
        summary["target_mismatch_max"] = check.mismatch_max
        summary["rest_mesh"] = str((out / "rest_shape.msh"))
        summary["rest_surface"] = str((out / "rest_shape.stl"))
        from .static import max_norm
        summary["max_rest_offset"] = max_norm(res.v)
        output.write_fields(out / "fields.xdmf", res.loaded.mesh,
                            [output.p1_interpolant(res.v, "rest_minus_target")])
        picture(out / "inverse.png", res, check, scene.title)
    summary["usable"] = not problems
    summary["problems"] = problems
    summary["wall_time_s"] = time.perf_counter() - t0
    output.write_json_atomic(out / "results.json", summary, comm)
    if echo and comm.rank == 0 and not problems:
        print(f"{scene.title}: rest shape by the {res.method} method in {res.iterations} iterations, "
              f"{res.solve_time:.2f} s; largest rest offset {summary['max_rest_offset']:.4g} m; forward check "
              f"lands within {check.mismatch_max:.3g} m of the target -> {out}")
    if problems:
        raise SolveError(f"{scene.title}: no usable rest shape: {'; '.join(problems)}")
    return summary
