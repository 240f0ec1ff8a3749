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

from .. import newton, output, probes, rest_shape
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
    # deformed minus target position at the design's own equilibrium (None: exactly the target, as
    # for the direct method); the adjoint method's partial or regularised goals leave a mismatch
    deformed_offset: fem.Function | None = None


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
                          prefix="fem_forms_inverse_", reuse_factor=True)
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
        self._driver: newton.SNESDriver | None = None
        self._problem: newton.NonlinearProblem | None = None
        self._u_ok = self.u.x.array.copy()

    def inadmissible(self):
        ncells = self.mesh.topology.index_map(3).size_local
        vals = self._jexpr.eval(np.arange(ncells, dtype=np.int32))
        jmin = self.mesh.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        return None if np.isfinite(jmin) and jmin > 0 else f"inverted elements (min det = {jmin:.3g})"

    def solve(self, fallback: bool = True) -> newton.SolveReport:
        """Equilibrium for the current d, warm-started from the current u; if that fails and
        `fallback`, load continuation from zero (costly: trial steps of an optimiser skip it)."""
        self.solves += 1
        if self._driver is None:          # forms compiled and matrix created once for all solves
            self._problem = newton.NonlinearProblem(self.u, self.residual, self.jacobian, self.bcs,
                                                    energy=self.energy, set_load=None,
                                                    inadmissible=self.inadmissible)
            self._driver = newton.SNESDriver(self._problem, dict(self.scene.solver.petsc),
                                             self.scene.solver.linear, "fem_forms_fwd_")
        problem = self._problem
        problem.set_load = None
        self.load.set(1.0)
        rep = newton.solve(problem, driver=self._driver)
        if not rep.converged and fallback:
            self.u.x.array[:] = 0.0
            problem.set_load = self.load.set
            rep = newton.solve(problem, steps=max(self.scene.solver.steps, 4),
                               max_cutbacks=self.scene.solver.max_cutbacks, driver=self._driver)
        if rep.converged:
            self._u_ok = self.u.x.array.copy()
        else:
            self.u.x.array[:] = self._u_ok
        return rep


# --------------------------------------------------------------------------------- adjoint method
class AdjointDesign:
    """J(d) = 1/2 m^T W m + 1/2 d^T R d with m = d + u(d) the mismatch (deformed minus target
    position), W the matching weight (mass matrix of the matched volume over its volume, or 1/n at
    the matched points' dofs) and R the regularisation (smoothness * stiffness of grad d, stay_close *
    mass). The gradient needs one adjoint solve K mu = W m: dJ/dd = W m - B^T mu + R d, with
    B = dR_u/dd. Gauss-Newton products H p = A^T W A p + R p, A = I - K^-1 B, reuse K's factors."""

    def __init__(self, fwd: ForwardOnRest):
        self.fwd = fwd
        spec = fwd.scene.inverse
        mesh, V = fwd.mesh, fwd.V
        comm = mesh.comm
        dx = fwd.dx
        trial, test = ufl.TrialFunction(V), ufl.TestFunction(V)
        self.n = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        if spec.match_points is not None:
            _, owned = _snap_points(V, spec.match_points)
            diag = fpetsc.create_vector(fem.form(ufl.dot(fem.Constant(mesh, PETSc.ScalarType((0, 0, 0))), test) * dx))
            diag.set(0.0)
            diag.array[owned] = 1.0 / len(spec.match_points)
            W = PETSc.Mat().createAIJ(((self.n, None), (self.n, None)), nnz=1, comm=comm)
            W.setDiagonal(diag)
            W.assemble()
            self.W = W
        else:
            dxm = dx
            if spec.match_region is not None:
                from dolfinx import mesh as dmesh
                lo = np.array(spec.match_region.lo)[:, None]
                hi = np.array(spec.match_region.hi)[:, None]
                tol = 1e-9 * mesh_size(mesh)
                cells = dmesh.locate_entities(mesh, 3, lambda x: np.all((x >= lo - tol) & (x <= hi + tol), axis=0))
                if comm.allreduce(len(cells), op=MPI.SUM) == 0:
                    raise InputError("inverse.match_region: contains no cell of the mesh")
                tags = dmesh.meshtags(mesh, 3, np.sort(cells).astype(np.int32), 1)
                dxm = ufl.Measure("dx", domain=mesh, subdomain_data=tags, metadata=dx.metadata())(1)
            vol = comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * dxm)), op=MPI.SUM)
            self.W = fpetsc.assemble_matrix(fem.form(ufl.dot(trial, test) / vol * dxm))
            self.W.assemble()
        reg = fem.Constant(mesh, 0.0) * ufl.dot(trial, test) * dx
        if spec.smoothness > 0:
            reg = reg + spec.smoothness * ufl.inner(ufl.grad(trial), ufl.grad(test)) * dx
        if spec.stay_close > 0:
            reg = reg + spec.stay_close * ufl.dot(trial, test) * dx
        self.R = fpetsc.assemble_matrix(fem.form(reg))
        self.R.assemble()
        # damping metric of the Levenberg-Marquardt steps, applied to the predicted change of the
        # deformed shape: an H1 inner product over the body's volume (L2 alone lets rough steps by)
        volume = comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * dx)), op=MPI.SUM)
        ell = mesh_size(mesh)
        h1 = (ufl.dot(trial, test) + ell ** 2 * ufl.inner(ufl.grad(trial), ufl.grad(test))) / volume * dx
        self.D = fpetsc.assemble_matrix(fem.form(h1))
        self.D.assemble()
        self.damping = 0.0
        self.K_form = fem.form(fwd.jacobian)
        self.B_form = fem.form(fwd.dres_dd)
        self.C_form = fem.form(fwd.jacobian - fwd.dres_dd)    # K - B = K A: inverse elastostatics' tangent
        self.K = fpetsc.create_matrix(self.K_form)
        self.B = fpetsc.create_matrix(self.B_form)
        self.C = fpetsc.create_matrix(self.C_form)
        self.ksp = _lu(comm, "fem_forms_adjoint_")
        self.ksp_C = _lu(comm, "fem_forms_adjoint_c_")
        self.ksp_N = _lu(comm, "fem_forms_adjoint_n_")
        self.N: PETSc.Mat | None = None
        # the rest shape stays attached where the body is supported: d is fixed (0) on supported dofs
        fixed = [bc.dof_indices()[0] for bc in fwd.bcs]
        self.fixed = np.unique(np.concatenate(fixed)) if fixed else np.empty(0, dtype=np.int32)
        self.fixed = self.fixed[self.fixed < self.n]
        self.vec = lambda: self.W.createVecLeft()
        self.evaluations = 0
        self.last_failure = ""

    def _solve_K(self, rhs: PETSc.Vec) -> PETSc.Vec:
        """K x = rhs with homogeneous conditions on supported dofs (K was assembled with them)."""
        fpetsc.set_bc(rhs, self.fwd.bcs, scale=0.0)
        x = rhs.duplicate()
        self.ksp.solve(rhs, x)
        if self.ksp.getConvergedReason() < 0:
            raise SolveError(f"adjoint: linear solve failed ({self.ksp.getConvergedReason()})")
        return x

    def forward(self, dvec: np.ndarray, guess: np.ndarray | None = None, fallback: bool = True):
        """J at d (None if there is no forward equilibrium at d), solved from `guess` for u (owned
        dofs) or else from the last state."""
        fwd = self.fwd
        fwd.d.x.array[:self.n] = dvec
        fwd.d.x.scatter_forward()
        if guess is not None:
            fwd.u.x.array[:self.n] = guess
            fwd.u.x.scatter_forward()
        rep = fwd.solve(fallback)
        self.evaluations += 1
        if not rep.converged:
            self.last_failure = rep.message
            return None
        m, d = self.vec(), self.vec()
        d.array[:] = dvec
        m.array[:] = dvec + fwd.u.x.array[:self.n]
        self._Wm = self.W * m
        return 0.5 * m.dot(self._Wm) + 0.5 * d.dot(self.R * d)

    def linearise(self) -> np.ndarray:
        """Gradient of J (owned dofs) at the last forward state; assembles and factorises K and B
        there, for the Gauss-Newton products and linear_response that follow."""
        fwd = self.fwd
        self.K.zeroEntries()
        fpetsc.assemble_matrix(self.K, self.K_form, bcs=fwd.bcs)
        self.K.assemble()
        self.B.zeroEntries()
        fpetsc.assemble_matrix(self.B, self.B_form)
        self.B.assemble()
        self.ksp.setOperators(self.K)
        self.C.zeroEntries()
        fpetsc.assemble_matrix(self.C, self.C_form, bcs=fwd.bcs)
        self.C.assemble()
        self.ksp_C.setOperators(self.C)
        d = self.vec()
        d.array[:] = fwd.d.x.array[:self.n]
        mu = self._solve_K(self._Wm.copy())
        g = self._Wm + self.R * d
        g.axpy(-1.0, self._BT(mu))
        out = g.array.copy()
        out[self.fixed] = 0.0
        return out

    def evaluate(self, dvec: np.ndarray, gradient: bool = True):
        """(J, gradient on owned dofs or None) at d; None if there is no forward equilibrium at d."""
        J = self.forward(dvec)
        if J is None:
            return None
        return J, (self.linearise() if gradient else None)

    def linear_response(self, s: np.ndarray) -> np.ndarray:
        """du = -K^-1 B s: first-order change of the equilibrium u when d changes by s (owned dofs),
        at the last linearised state; a predictor for the next forward solve."""
        q, Bq = self.vec(), self.vec()
        q.array[:] = s
        self.B.mult(q, Bq)
        return -self._solve_K(Bq).array.copy()

    def _BT(self, y: PETSc.Vec) -> PETSc.Vec:
        z = self.vec()
        self.B.multTranspose(y, z)
        return z

    def set_damping(self, lam: float) -> None:
        """Damping of the Gauss-Newton products; (re)factorises N = W + lam D + R for the
        preconditioner."""
        self.damping = lam
        N = self.D.copy()
        N.scale(lam)
        N.axpy(1.0, self.W, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        N.axpy(1.0, self.R, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        self.ksp_N.setOperators(N)
        if self.N is not None:
            self.N.destroy()
        self.N = N

    def gauss_newton_product(self, p: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = (A^T (W + damping D) A + R) p on free dofs, A = I - K^-1 B = K^-1 C, at the last
        linearised state: the damping limits the predicted change of the deformed shape."""
        q = p.copy()
        q.array[self.fixed] = 0.0
        Bq = self.vec()
        self.B.mult(q, Bq)
        a = q - self._solve_K(Bq)
        b = self.W * a
        if self.damping:
            b.axpy(self.damping, self.D * a)
        r = b - self._BT(self._solve_K(b.copy())) + self.R * q
        r.array[self.fixed] = 0.0
        r.copy(out)

    def precondition(self, r: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = A^-1 N^-1 A^-T r = C^-1 K N^-1 K C^-T r: the inverse of the damped Gauss-Newton
        matrix when R = 0 (exact for matching the whole body), a close one otherwise."""
        x = r.copy()
        x.array[self.fixed] = 0.0
        y = self.vec()
        self.ksp_C.solveTranspose(x, y)
        y.array[self.fixed] = 0.0
        z = self.K * y
        z.array[self.fixed] = 0.0
        w = self.vec()
        self.ksp_N.solve(z, w)
        w.array[self.fixed] = 0.0
        v = self.K * w
        v.array[self.fixed] = 0.0
        self.ksp_C.solve(v, out)
        out.array[self.fixed] = 0.0


class _GaussNewtonOperator:
    """PETSc shell-matrix and shell-preconditioner context for the damped Gauss-Newton matrix."""

    def __init__(self, design: AdjointDesign):
        self.design = design

    def mult(self, mat, x, y):
        self.design.gauss_newton_product(x, y)

    def apply(self, pc, x, y):
        self.design.precondition(x, y)


def _lu(comm, prefix: str) -> PETSc.KSP:
    """A direct (MUMPS LU) solver whose options can be overridden under `prefix`."""
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    opts = PETSc.Options()
    for k, val in {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}.items():
        if not opts.hasName(prefix + k):
            opts[prefix + k] = val
    ksp.setFromOptions()
    return ksp


def _snap_points(V: fem.FunctionSpace, points: list):
    """Dofs of the mesh vertices nearest each point: (all local dof indices, owned only)."""
    bs = V.dofmap.index_map_bs
    nown = V.dofmap.index_map.size_local
    X = V.tabulate_dof_coordinates()[:nown]
    comm = V.mesh.comm
    own = []
    for p in points:
        dist = np.linalg.norm(X - np.asarray(p), axis=1) if len(X) else np.array([np.inf])
        k = int(np.argmin(dist))
        best = comm.allreduce(float(dist[k]), op=MPI.MIN)
        rank = comm.allreduce(comm.rank if dist[k] <= best else comm.size, op=MPI.MIN)
        if comm.rank == rank:
            own += [k * bs + c for c in range(bs)]
    own = np.array(own, dtype=np.int32)
    return own, own


# J is known to about this relative precision: the forward solves converge to 1e-9..1e-10 of the load
# scale (measured: J at trial points within 1e-8 J of each other once the gradient vanishes)
J_PRECISION = 1e-8


def _gauss_newton(design: AdjointDesign, spec, J_stop: float, history: list, scale_len: float):
    """Gauss-Newton with Levenberg-Marquardt damping: each step solves (A^T (W + lam D) A + R) s = -g
    by CG, matrix-free through K's factors and preconditioned by the inverse-elastostatics tangent
    (AdjointDesign.precondition). D, an H1 inner product, damps the predicted change of the deformed
    shape: the step shortens along the directions where the linearised forward map is least reliable,
    where a line search would shorten all of it. The step is kept when J falls by a fair share of the
    model's prediction, and lam shrinks or grows with that agreement (Nielsen's rule). Trial forward
    solves start from the linear predictor u + du(s) and do not fall back to load continuation (a
    failed trial is a rejected step)."""
    comm = design.fwd.mesh.comm
    n = design.n
    d = np.zeros(n)
    bound = spec.max_move
    H = PETSc.Mat().createPython(((n, None), (n, None)), _GaussNewtonOperator(design), comm=comm)
    H.setUp()
    cg = PETSc.KSP().create(comm)
    cg.setOptionsPrefix("fem_forms_gn_")
    cg.setType("cg")
    pc = cg.getPC()
    pc.setType("python")
    pc.setPythonContext(_GaussNewtonOperator(design))
    cg.setTolerances(rtol=1e-3, max_it=200)
    cg.setOperators(H)
    cg.setFromOptions()
    out = design.evaluate(d)
    if out is None:
        return d, False, "no forward equilibrium at the target shape itself", 0
    J, g = out
    history.append({"J": J, "cg": 0})
    u_ok = design.fwd.u.x.array[:n].copy()
    lam, grow = 1e-3, 2.0
    dot = lambda a, b: comm.allreduce(float(a @ b), op=MPI.SUM)
    for it in range(1, spec.iterations + 1):
        gv, sv, Hs = design.vec(), design.vec(), design.vec()
        gv.array[:] = -g
        design.set_damping(lam)
        cg.solve(gv, sv)
        design.damping = 0.0
        trial = d + sv.array
        if bound is not None:
            trial = np.clip(trial, -bound, bound)
        trial[design.fixed] = 0.0
        s = trial - d
        sv.array[:] = s
        design.gauss_newton_product(sv, Hs)
        predicted = -(dot(g, s) + 0.5 * dot(s, Hs.array))
        J_trial = design.forward(trial, guess=u_ok + design.linear_response(s), fallback=False)
        rho = (J - J_trial) / predicted if J_trial is not None and predicted > 0 else -1.0
        if rho > 1e-4:
            d, J = trial, J_trial
            g = design.linearise()
            u_ok = design.fwd.u.x.array[:n].copy()
            lam, grow = lam * max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), 2.0
        else:
            design.fwd.u.x.array[:n] = u_ok
            design.fwd.u.x.scatter_forward()
            design.fwd.d.x.array[:n] = d
            design.fwd.d.x.scatter_forward()
            lam, grow = lam * grow, 2.0 * grow
        history.append({"J": J, "cg": cg.getIterationNumber(), "damping": lam, "ratio": rho,
                        "accepted": bool(rho > 1e-4)})
        if J <= J_stop:
            return d, True, f"mismatch below tolerance, J = {J:.3e}", it
        if np.sqrt(dot(g, g)) <= spec.tolerance * abs(J):
            return d, True, f"relative gradient below tolerance, J = {J:.3e}", it
        if rho > 1e-4 and comm.allreduce(float(np.abs(s).max()) if n else 0.0, op=MPI.MAX) <= 1e-14 * scale_len:
            return d, True, f"step below round-off, J = {J:.3e}", it
        if J_trial is not None and predicted <= J_PRECISION * abs(J):
            return d, True, f"predicted decrease {predicted:.1e} below the precision of J = {J:.3e}", it
        if lam > 1e12:
            why = f"; the last trial had no forward equilibrium: {design.last_failure}" if J_trial is None else ""
            return d, J <= J_stop, f"no descent found at iteration {it} (damping {lam:.1e}), J = {J:.3e}{why}", it
    return d, False, f"no convergence in {spec.iterations} iterations, J = {J:.3e}", spec.iterations


def _lbfgs(design: AdjointDesign, spec, J_stop: float, history: list, mesh):
    """PETSc TAO bounded L-BFGS (BLMVM) on z = sqrt(m / V) d, m the lumped mass, V the volume: steps
    then approximate the L2 inner product and do not degrade as the mesh is refined."""
    fwd, n, comm = design.fwd, design.n, design.fwd.mesh.comm
    w = ufl.TestFunction(fwd.V)
    one = fem.Constant(mesh, PETSc.ScalarType((1.0, 1.0, 1.0)))
    lumped = fpetsc.assemble_vector(fem.form(ufl.dot(w, one) * fwd.dx))
    lumped.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    volume = comm.allreduce(float(lumped.array[:n].sum()) / 3, op=MPI.SUM)
    scale = np.sqrt(np.abs(lumped.array[:n]) / volume)    # a first step d -= mismatch, as fixed point
    x = design.vec()
    x.set(0.0)

    def objgrad(tao, xv, gv):
        out = design.evaluate(xv.array / scale)
        if out is None:                          # no equilibrium there: a line-search step too far
            gv.set(0.0)
            return 1e30
        gv.array[:] = out[1] / scale
        history.append({"J": out[0]})
        return out[0]

    def converged(tao):
        its, f, gnorm = tao.getSolutionStatus()[:3]
        if f <= J_stop:
            tao.setConvergedReason(8)            # TAO_CONVERGED_USER: mismatch small enough
        elif gnorm <= spec.tolerance * abs(f):
            tao.setConvergedReason(4)            # TAO_CONVERGED_GRTOL
        elif its >= spec.iterations:
            tao.setConvergedReason(-2)           # TAO_DIVERGED_MAXITS
        else:
            tao.setConvergedReason(0)

    tao = PETSc.TAO().create(comm)
    tao.setOptionsPrefix("fem_forms_tao_")
    tao.setType("blmvm")
    tao.setObjectiveGradient(objgrad, x.duplicate())
    lb, ub = x.duplicate(), x.duplicate()
    big = 1e20 if spec.max_move is None else spec.max_move
    lb.array[:] = -big * scale
    ub.array[:] = big * scale
    lb.array[design.fixed] = 0.0
    ub.array[design.fixed] = 0.0
    tao.setVariableBounds(lb, ub)
    tao.setConvergenceTest(converged)
    tao.setFromOptions()
    tao.solve(x)
    reason, its = tao.getConvergedReason(), tao.getIterationNumber()
    d = x.array / scale
    tao.destroy()
    return d, reason > 0, f"TAO BLMVM reason {reason} after {its} iterations", its


def solve_adjoint(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Minimise J over rest shapes mesh + d subject to forward equilibrium. Converged when the
    mismatch J falls below 1/2 (tolerance x mesh size)^2, or the gradient below tolerance x J."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    V = fem.VectorFunctionSpace(loaded.mesh, ("Lagrange", scene.discretization.degree))
    fwd = ForwardOnRest(scene, material, loaded, V)
    design = AdjointDesign(fwd)
    spec = scene.inverse
    size = mesh_size(loaded.mesh)
    J_stop = 0.5 * (spec.tolerance * size) ** 2
    history: list = []
    if spec.optimizer == "lbfgs":
        d, ok, msg, its = _lbfgs(design, spec, J_stop, history, loaded.mesh)
    else:
        d, ok, msg, its = _gauss_newton(design, spec, J_stop, history, size)
    final = design.evaluate(d, gradient=False)            # the forward state at the answer
    ok = ok and final is not None
    v = fem.Function(V, name="rest_minus_target")
    v.x.array[:design.n] = d
    v.x.scatter_forward()
    res = InverseResult("adjoint", v, loaded, ok, its, msg, history=history, forward_solves=fwd.solves)
    if final is not None:
        res.deformed_offset = fem.Function(V, name="deformed_minus_target")
        res.deformed_offset.x.array[:] = v.x.array + fwd.u.x.array
    res.solve_time = time.perf_counter() - t0
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
    mismatch_max: float             # largest distance of the forward-solved shape from the target
    static: object                  # the StaticResult of the forward solve from the rest shape
    problems: list
    design_gap_max: float = np.inf  # ... from the deformed shape the design predicted
    matched_mismatch_max: float | None = None   # ... from the target on the matched points/region


def _matched_vertices(spec, pts_target: np.ndarray, size: float) -> np.ndarray | None:
    """Mask of the target's vertices an adjoint objective matches (None: the whole body)."""
    if spec.method != "adjoint" or (spec.match_points is None and spec.match_region is None):
        return None
    mask = np.zeros(len(pts_target), dtype=bool)
    if spec.match_points is not None:
        from scipy.spatial import cKDTree
        mask[cKDTree(pts_target).query(np.asarray(spec.match_points, dtype=float))[1]] = True
    else:
        tol = 1e-9 * size
        lo, hi = np.asarray(spec.match_region.lo), np.asarray(spec.match_region.hi)
        mask = np.all((pts_target >= lo - tol) & (pts_target <= hi + tol), axis=1)
    return mask


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
    designed = output.gather_mesh(mesh, output.node_values(res.deformed_offset)) \
        if res.deformed_offset is not None else target
    groups = output.gather_facet_groups(res.loaded)
    problems = []
    if comm.rank == 0:
        points, cells, ctype = gathered
        write_ok = True
        try:
            rest_shape.write_volume_mesh(out / "rest_shape.msh", points, cells, ctype, groups)
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
    pts_design = comm.bcast(designed[0] if comm.rank == 0 else None, root=0)
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
    def largest(dist, where=None):
        dist = dist if where is None else dist[where]
        return comm.allreduce(float(dist.max()) if len(dist) else 0.0, op=MPI.MAX)

    to_target = np.linalg.norm(deformed - pts_target[idx], axis=1)
    mismatch = largest(to_target)
    gap = largest(np.linalg.norm(deformed - pts_design[idx], axis=1))
    matched = _matched_vertices(scene.inverse, pts_target, size)
    matched_max = None if matched is None else largest(to_target, matched[idx])
    tol = scene.inverse.check_tolerance or 1e-3 * size
    if gap > tol:
        what = "the target" if res.deformed_offset is None else "the shape the design predicted"
        problems.append(f"the forward solve from the rest shape lands {gap:.3g} m from {what} "
                        f"(tolerance {tol:.3g} m): another equilibrium, the design is not usable")
    return ForwardCheck(mismatch, static, problems, gap, matched_max)


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
    loaded = load_mesh(target_scene(scene))
    V = fem.VectorFunctionSpace(loaded.mesh, ("Lagrange", scene.discretization.degree))
    probes.evaluate(fem.Function(V), scene.output.probes)       # a probe outside the target: bad input
    res = METHODS[scene.inverse.method](scene, material, loaded)
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
        summary["design_gap_max"] = check.design_gap_max
        if check.matched_mismatch_max is not None:
            summary["matched_mismatch_max"] = check.matched_mismatch_max
        summary["rest_mesh"] = str((out / "rest_shape.msh"))
        summary["rest_surface"] = str((out / "rest_shape.stl"))
        from .static import max_norm
        summary["max_rest_offset"] = max_norm(res.v)
        offsets = probes.evaluate(res.v, scene.output.probes)
        summary["probes"] = {n: {"point": p, "rest_position": (np.array(p) + offsets[n]).tolist()}
                             for n, p in scene.output.probes.items()}
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
              f"lands within {check.mismatch_max:.3g} m of the target"
              + ("" if check.matched_mismatch_max is None else
                 f" ({check.matched_mismatch_max:.3g} m where matched)") + f" -> {out}")
    if problems:
        raise SolveError(f"{scene.title}: no usable rest shape: {'; '.join(problems)}")
    return summary
