"""The adjoint rest-shape design: objective, gradient by one adjoint solve, Gauss-Newton products."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.design.bordered_adjoint import Border
from fem_forms.design.forward_on_rest import ForwardOnRest
from fem_forms.errors import InputError, SolveError
from fem_forms.meshes import mesh_size
from fem_forms.output.probes import nearest_nodes
from fem_forms.solvers.linear import make_ksp


class AdjointDesign:
    """J(d) = 1/2 m^T W m + 1/2 d^T R d with m = d + u(d) the mismatch (deformed minus target
    position), W the matching weight (mass matrix of the matched volume over its volume, or 1/n at
    the matched points' dofs) and R the regularisation (smoothness * stiffness of grad d, stay_close *
    mass). The gradient needs one adjoint solve K^T mu = W m: dJ/dd = W m - B^T mu + R d, with
    B = dR_u/dd. Gauss-Newton products H p = A^T W A p + R p, A = I - K^-1 B, reuse K's factors (K is not
    symmetric under a follower pressure: the transposes are K's own)."""

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
        # MUMPS LU, each overridable under its own prefix (operators set as they are assembled)
        self.ksp = make_ksp(None, "lu", "fem_forms_adjoint_", comm=comm)
        self.ksp_C = make_ksp(None, "lu", "fem_forms_adjoint_c_", comm=comm)
        self.ksp_N = make_ksp(None, "lu", "fem_forms_adjoint_n_", comm=comm)
        self.N: PETSc.Mat | None = None
        # the rest shape stays attached where the body is supported: d is fixed (0) on supported dofs
        fixed = [bc.dof_indices()[0] for bc in fwd.bcs]
        self.fixed = np.unique(np.concatenate(fixed)) if fixed else np.empty(0, dtype=np.int32)
        self.fixed = self.fixed[self.fixed < self.n]
        self.vec = lambda: self.W.createVecLeft()
        self.pinned = np.empty(0, PETSc.IntType)     # global rows of C held (a part standing on a table)
        self.free_direction = self._free = None
        if fwd.standing is not None:
            local, self.pinned = _pinned_dofs(fwd.standing)
            self.free_direction = fwd.standing.normal
            self.fixed = np.unique(np.concatenate([self.fixed, local])).astype(self.fixed.dtype)
            e = self.vec()
            e.array[:] = np.tile(self.free_direction, self.n // 3)
            w = self.W * e
            self._free = (w, e.dot(w))
        self.evaluations = 0
        self.last_failure = ""
        # volume control: the cavities' pressures are unknowns beside u, their equations depend on d (the rest
        # cavity's volume): the adjoint and the sensitivities are the bordered system's
        self.border = Border(fwd.scalars, fwd.residual, fwd.u) if fwd.scalars else None
        self.c_d = [fem.form(ufl.derivative(sc.equation, fwd.d, test)) for sc in fwd.scalars]
        self._c_d: list = []                      # their vectors at the last linearisation

    def _add_contact(self, fwd: ForwardOnRest) -> None:
        """The contact's Hessian (barrier and friction) at the last equilibrium into K; the barrier's into B (it
        depends on X + u: on the held sole dofs it changes nothing, elsewhere, where a point outside the target's
        sole comes within dhat, it does); the friction's into C = K - B (its slips are measured from the rest shape:
        on u alone). C's held rows are then the identity's."""
        x, standing = fwd.u.vector, fwd.standing
        fwd.driver.arrays.add_hessian(x, self.K)
        for A, add in ((self.B, lambda A: standing.add_barrier_hessian(x, A)),
                       (self.C, lambda A: standing.add_friction_hessian(x, A, fwd.driver.arrays.constrained))):
            A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
            add(A)
            A.assemble()
        self.C.zeroRowsColumns(self.pinned, 1.0)

    def _solve_K(self, rhs: PETSc.Vec, transposed: bool = False) -> PETSc.Vec:
        """K x = rhs (K^T x = rhs with `transposed`: the adjoint's, K not symmetric under a follower pressure) with
        homogeneous conditions on supported dofs (K was assembled with them)."""
        fpetsc.set_bc(rhs, self.fwd.bcs, scale=0.0)
        x = rhs.duplicate()
        (self.ksp.solveTranspose if transposed else self.ksp.solve)(rhs, x)
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
        self._Wm = self.weigh(m)
        return 0.5 * m.dot(self._Wm) + 0.5 * d.dot(self.R * d)

    def weigh(self, m: PETSc.Vec) -> PETSc.Vec:
        """W m; for a part standing on a table, with the mismatch's mean along the table's normal taken out: how high
        the part rests is the barrier's (within contact.distance), not the design's."""
        Wm = self.W * m
        if self._free is not None:
            w, c = self._free
            Wm.axpy(-w.dot(m) / c, w)
        return Wm

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
        if fwd.standing is not None:
            self._add_contact(fwd)
            self.ksp.setOperators(self.K)
        self.ksp_C.setOperators(self.C)
        if self.border is not None:               # the border's vectors and solves, once for this state
            self.border.linearise(lambda r: self._solve_K(r, transposed=True), self._solve_K)
            self._c_d = [Border.vector(f) for f in self.c_d]
        d = self.vec()
        d.array[:] = fwd.d.x.array[:self.n]
        g = self._Wm + self.R * d
        g.axpy(-1.0, self._adjoint_shape_term(self._Wm.copy()))
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
        q = self.vec()
        q.array[:] = s
        return -self._sensitivity(q).array.copy()

    def _sensitivity(self, q: PETSc.Vec) -> PETSc.Vec:
        """K^-1 B q, or with volume control the displacement part of [K R_p; c_u c_p]^-1 [B q; c_d . q]: minus the
        equilibrium's change when d changes by q."""
        Bq = self.vec()
        self.B.mult(q, Bq)
        if self.border is None:
            return self._solve_K(Bq)
        return self.border.forward(self._solve_K(Bq), [c.dot(q) for c in self._c_d])[0]

    def _adjoint_shape_term(self, g: PETSc.Vec) -> PETSc.Vec:
        """B^T K^-T g, or with volume control B^T lambda + sum_i mu_i c_d_i of the bordered adjoint [lambda; mu] of
        [g; 0]: the d-derivative of the equilibrium's constraint weighted by the adjoint."""
        lam = self._solve_K(g, transposed=True)
        mu = []
        if self.border is not None:
            lam, mu = self.border.adjoint(lam)
        out = self._BT(lam)
        for c, mu_i in zip(self._c_d, mu):
            out.axpy(mu_i, c)
        return out

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
        linearised state: the damping limits the predicted change of the deformed shape. Standing on a table, the
        damping also takes damping D p: where the sole slides at Coulomb's limit, moving its rest position along the
        table changes nothing (A p = 0) and only this bounds the step."""
        q = p.copy()
        q.array[self.fixed] = 0.0
        a = q - self._sensitivity(q)
        b = self.weigh(a)
        if self.damping:
            b.axpy(self.damping, self.D * a)
        r = b - self._adjoint_shape_term(b.copy()) + self.R * q
        if self.damping and self._free is not None:
            r.axpy(self.damping, self.D * q)
        r.array[self.fixed] = 0.0
        r.copy(out)

    def precondition(self, r: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = A^-1 N^-1 A^-T r = C^-1 K N^-1 K^T C^-T r: the inverse of the damped Gauss-Newton
        matrix when R = 0 (exact for matching the whole body), a close one otherwise."""
        x = r.copy()
        x.array[self.fixed] = 0.0
        y = self.vec()
        self.ksp_C.solveTranspose(x, y)
        y.array[self.fixed] = 0.0
        z = self.vec()
        self.K.multTranspose(y, z)
        z.array[self.fixed] = 0.0
        w = self.vec()
        self.ksp_N.solve(z, w)
        w.array[self.fixed] = 0.0
        v = self.K * w
        v.array[self.fixed] = 0.0
        self.ksp_C.solve(v, out)
        out.array[self.fixed] = 0.0



def _snap_points(V: fem.FunctionSpace, points: list):
    """Dofs of the mesh vertices nearest each point: (all local dof indices, owned only)."""
    bs = V.dofmap.index_map_bs
    node, _ = nearest_nodes(V, points)
    own = np.array([k * bs + c for k in node if k >= 0 for c in range(bs)], dtype=np.int32)
    return own, own


def _pinned_dofs(standing) -> tuple[np.ndarray, np.ndarray]:
    """The sole's dofs along the table's normal (StandingRest): the rest shape keeps the target's sole height, which
    the table holds. (Free, they would leave the design three directions it cannot tell: a rest shape made higher,
    lower or tilted about its sole lands the same once put down.) Returns (the local indices this rank owns, their
    global rows)."""
    surface = standing.term.surface
    mine = np.isin(surface.owned, standing.sole)
    local = (3 * surface.owned_local[mine] + standing.axis).astype(np.int32)
    rows = (3 * surface.blocks[surface.owned[mine]] + standing.axis).astype(PETSc.IntType)
    return local, rows
