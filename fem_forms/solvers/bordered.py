"""The augmented Newton system of a problem with global scalars (physics/scalars.py), inside the one SNES:

    [K    R_p] [du]     [R]
    [c_u  c_p] [dp] = - [c]

SNES works on an augmented Vec X = [u; p_1..p_m] (global size N + m; rank 0 owns the m scalar entries after
its field entries, so every rank's field entries are the first n of its local array). The Jacobian is a
python MATSHELL applying the bordered operator; the KSP is `preonly` with a python PC applying its exact
inverse by bordering: K is factored (or preconditioned) once per Newton iteration by an inner KSP with the
driver's linear options, B = K^-1 R_p costs m solves with that factor, then the m x m Schur system
S dp = r_p - c_u.K^-1 r_f (S = c_p - c_u.B) and du = K^-1 r_f - B dp."""
from __future__ import annotations

from contextlib import contextmanager

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.physics.scalars import GlobalScalar, coupling_forms
from fem_forms.solvers.constrained_stability import ConstrainedStability
from fem_forms.solvers.multiplier_merit import MultiplierMerit

# the inner K solve's options prefix (under the driver's) and the option families it takes from the driver
INNER = "K_"
_LINEAR = ("ksp_", "pc_", "mat_", "mg_")


class Bordered:
    """The augmented vectors, the bordered Jacobian and its inverse for one SNESDriver with global scalars."""

    def __init__(self, driver, scalars: list[GlobalScalar]):
        self.drv, self.scalars, self.m = driver, list(scalars), len(scalars)
        self.comm = driver.comm
        self.root = self.comm.rank == 0
        V = driver.p.u.function_space
        self.n = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        forms = coupling_forms(self.scalars, driver.p.residual, driver.p.u)
        self.R_p = [fem.form(f) for f in forms["R_p"]]
        self.c_u = [fem.form(f) for f in forms["c_u"]]
        self.c = [fem.form(f) for f in forms["c"]]
        self.c_p = [[f if f is None or isinstance(f, (int, float)) else fem.form(f) for f in row]
                    for row in forms["c_p"]]
        self.Rp_vecs = [fpetsc.create_vector(f) for f in self.R_p]
        self.cu_vecs = [fpetsc.create_vector(f) for f in self.c_u]
        self.B = [v.duplicate() for v in self.Rp_vecs]           # K^-1 R_p
        self.S = np.zeros((self.m, self.m))
        local = self.n + (self.m if self.root else 0)
        self.X = PETSc.Vec().createMPI((local, PETSc.DECIDE), comm=self.comm)
        self.F = self.X.duplicate()
        self.J = PETSc.Mat().createPython(((local, PETSc.DECIDE), (local, PETSc.DECIDE)), context=self,
                                          comm=self.comm)
        self.J.setUp()
        self._xf, self._bf = driver.x.duplicate(), driver.b.duplicate()
        self._rf, self._zf = driver.x.duplicate(), driver.x.duplicate()
        self.ksp = None
        if driver.bounds is not None or driver.arrays.caps:
            raise ValueError("global scalars: bounds and capping array terms are not supported")
        self.stability = ConstrainedStability.of(self)     # volume control: only stable states, and a merit to
        self.merit = MultiplierMerit(self, driver.p.energy) if self.stability is not None else None   # descend
        if driver.p.state is not None:                   # committed and rolled back with the problem's fields
            for s in self.scalars:
                driver.p.state.add_scalar(s.name, s.value)

    # -- layout ----------------------------------------------------------------------------------
    def values(self) -> np.ndarray:
        """The scalars' current values (the Constants'), the same on every rank."""
        return np.array([float(s.value.value) for s in self.scalars])

    def set_values(self, values: np.ndarray) -> None:
        for s, v in zip(self.scalars, values):
            s.value.value = v

    def pack(self, xf: PETSc.Vec) -> PETSc.Vec:
        """self.X = [xf's owned entries; the scalars' values (rank 0)]."""
        X = self.X
        X.array[: self.n] = xf.array_r[: self.n]
        if self.root:
            X.array[self.n:] = self.values()
        return X

    def unpack(self, X: PETSc.Vec, xf: PETSc.Vec, scalars: bool = True) -> np.ndarray:
        """xf (ghosts updated) from X's field part; with `scalars`, also set the Constants. Returns the
        scalar part, broadcast from rank 0."""
        xf.array[: self.n] = X.array_r[: self.n]
        xf.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        p = self.comm.bcast(X.array_r[self.n:].copy() if self.root else None, root=0)
        if scalars:
            self.set_values(p)
        return p

    def equations(self) -> np.ndarray:
        """c_i(u, p) at the current state (every rank)."""
        return np.array([self.comm.allreduce(fem.assemble_scalar(c), op=MPI.SUM) for c in self.c])

    @contextmanager
    def unloaded(self):
        """The scalars at 0 for the duration (the driver's load scale: the state u = 0, p = 0)."""
        saved = self.values()
        self.set_values(np.zeros(self.m))
        try:
            yield
        finally:
            self.set_values(saved)

    def set_field_state(self, X: PETSc.Vec) -> PETSc.Vec:
        """Put the field part of X into the forms' Function; that part as a Vec (owned by this object)."""
        self.unpack(X, self._xf, scalars=False)
        self.drv.set_state(self._xf)
        return self._xf

    def field_curvature(self, Y: PETSc.Vec) -> tuple[float, np.ndarray]:
        """(Y_u . K Y_u, c_u_i . Y_u) of the field part Y_u of Y, K the last assembled tangent."""
        self.unpack(Y, self._rf, scalars=False)
        self.drv.A.mult(self._rf, self._zf)
        return self._rf.dot(self._zf), np.array([cu.dot(self._rf) for cu in self.cu_vecs])

    # -- SNES callbacks ----------------------------------------------------------------------------
    def residual(self, snes, X: PETSc.Vec, F: PETSc.Vec) -> None:
        """F = [R(u, p) as the driver assembles it (Dirichlet rows x - g); c(u, p)]."""
        self.unpack(X, self._xf)
        self.drv.residual(self._xf, self._bf)
        F.array[: self.n] = self._bf.array_r[: self.n]
        c = self.equations()
        if self.root:
            F.array[self.n:] = c

    def _assemble_border(self, forms, vecs) -> None:
        for f, v in zip(forms, vecs):
            with v.localForm() as vl:
                vl.set(0.0)
            fpetsc.assemble_vector(v, f)
            v.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            fpetsc.set_bc(v, self.drv.p.bcs, scale=0.0)      # constrained dofs take no part in the border

    def jacobian(self, snes, X: PETSc.Vec, J: PETSc.Mat, P: PETSc.Mat) -> None:
        """Assemble K (the driver's, Dirichlet rows as it makes them), the border vectors and c_p; factor K,
        solve K B_j = R_p_j and form the Schur complement S = c_p - c_u.B."""
        self.unpack(X, self._xf)
        drv = self.drv
        drv.tangent(self._xf, drv.A)
        self._assemble_border(self.R_p, self.Rp_vecs)
        self._assemble_border(self.c_u, self.cu_vecs)
        P = drv.preconditioning_matrix(drv.A)             # multigrid's AIJ or LDL^T's SBAIJ copy, or A
        if drv.pmg is not None:
            drv.pmg.refresh(self.ksp, P)
        self.ksp.setOperators(drv.A, P)
        self.ksp.setUp()
        self.Cp = np.array([[0.0 if f is None else float(f) if isinstance(f, (int, float))
                             else self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM) for f in row]
                            for row in self.c_p])
        for rp, b in zip(self.Rp_vecs, self.B):
            self._solve_K(rp, b)
        self.S = self.Cp - np.array([[cu.dot(b) for b in self.B] for cu in self.cu_vecs])
        if self.stability is not None:
            self.stability.tangent(self.S, self.ksp)
            if self.merit is not None:
                self.merit.tangent(self.stability.q)
        J.assemble()                                      # a new operator state: SNES/KSP see the change

    def _solve_K(self, r: PETSc.Vec, z: PETSc.Vec) -> None:
        """z = K^-1 r with the inner KSP (NaN if it failed)."""
        self.ksp.solve(r, z)
        if self.ksp.getConvergedReason() < 0:       # NaN: SNES stops with a diverged reason, no exception
            z.set(np.nan)
        z.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    # -- MATSHELL: the bordered operator -----------------------------------------------------------
    def mult(self, mat, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = [K x_f + R_p x_p; c_u.x_f + c_p x_p]."""
        p = self.unpack(x, self._rf, scalars=False)
        self.drv.A.mult(self._rf, self._zf)
        for rp, pj in zip(self.Rp_vecs, p):
            self._zf.axpy(pj, rp)
        y.array[: self.n] = self._zf.array_r[: self.n]
        tail = np.array([cu.dot(self._rf) for cu in self.cu_vecs]) + self.Cp @ p
        if self.root:
            y.array[self.n:] = tail

    # -- python PC: the exact bordered inverse -----------------------------------------------------
    def setUp(self, pc) -> None:
        """Nothing to do: the Jacobian callback factored K and formed S."""

    def apply(self, pc, r: PETSc.Vec, z: PETSc.Vec) -> None:
        """z = J^-1 r: a = K^-1 r_f, dp = S^-1 (r_p - c_u.a), z_f = a - B dp."""
        r_p = self.unpack(r, self._rf, scalars=False)
        self._solve_K(self._rf, self._zf)
        rhs = r_p - np.array([cu.dot(self._zf) for cu in self.cu_vecs])
        try:
            dp = np.linalg.solve(self.S, rhs)
        except np.linalg.LinAlgError:               # a singular Schur complement: the constraint is lost
            dp = np.full(self.m, np.nan)
        for b, dpj in zip(self.B, dp):
            self._zf.axpy(-dpj, b)
        z.array[: self.n] = self._zf.array_r[: self.n]
        if self.root:
            z.array[self.n:] = dp
        if self.merit is not None:
            self.merit.direction(dp)

    # -- driver hooks --------------------------------------------------------------------------------
    def options(self, merged: dict) -> None:
        """Move the driver's linear options (ksp_, pc_, mat_, mg_) to the inner K solve's prefix, in place,
        tightening an iterative K solve; the outer KSP applies the bordered inverse once. A saddle point (p a
        Lagrange multiplier) has no energy to descend: the line search is `basic` (full Newton steps), the
        one the driver uses for problems without an energy; a retry descends a merit where one exists."""
        for k in [k for k in merged if k.startswith(_LINEAR)]:
            merged[INNER + k] = merged.pop(k)
        if merged.get(INNER + "ksp_type", "preonly") != "preonly":
            merged[INNER + "ksp_rtol"] = min(float(merged.get(INNER + "ksp_rtol", 1e-12)), 1e-12)
        merged.update({"ksp_type": "preonly", "pc_type": "python", "snes_linesearch_type": "basic"})
        if self.merit is not None:
            self.merit.options(merged)
        if self.stability is not None and merged.get(INNER + "pc_type") == "cholesky":   # K's negative pivots
            merged.setdefault(INNER + "mat_mumps_icntl_13", 1)      # are counted: ScaLAPACK's root front's are not
        if any(k.startswith(("snes_lag_",)) for k in merged):
            raise ValueError("global scalars: factor reuse and lagged Jacobians are not supported")

    def install(self, snes: PETSc.SNES, prefix: str) -> None:
        """Hand SNES the augmented residual and Jacobian and the bordered inverse; (re)make the inner KSP."""
        snes.setFunction(self.residual, self.F)
        snes.setJacobian(self.jacobian, self.J)
        if self.merit is not None:
            self.merit.install(snes)
        pc = snes.getKSP().getPC()
        pc.setType("python")
        pc.setPythonContext(self)
        if self.ksp is not None:
            self.ksp.destroy()
        self.ksp = PETSc.KSP().create(self.comm)
        self.ksp.setOptionsPrefix(prefix + INNER)
        self.ksp.setFromOptions()

    def solve(self, snes: PETSc.SNES, xf: PETSc.Vec) -> None:
        """SNES on X = [xf; p], then xf and the Constants from its answer."""
        snes.solve(None, self.pack(xf))
        self.unpack(self.X, xf)

    def residual_norm(self, field_norm: float) -> float:
        """The augmented residual's norm at the current state, from the field residual's (inf, not NaN, for a
        non-finite one: acceptance compares it with "greater than", which NaN never is)."""
        n = float(np.sqrt(field_norm ** 2 + np.sum(self.equations() ** 2)))
        return n if np.isfinite(n) else np.inf
