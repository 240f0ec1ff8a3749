"""The one SNES driver: compiled residual/tangent/energy forms, PETSc objects and callbacks for one
nonlinear problem, with the energy as line-search objective where one exists."""
from __future__ import annotations

from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
import itertools
import math
import time
from typing import Callable

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from dolfinx.fem.forms import FormMetaClass
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms import progress
from fem_forms.solvers import bounds as vi, linear, pc_matrix, pmultigrid, polish
from fem_forms.solvers.linear import roundoff_floor  # noqa: F401 (snes.roundoff_floor, used by the inverse check)
from fem_forms.solvers.array_terms import ArrayTerms
from fem_forms.solvers.bordered import Bordered
from fem_forms.solvers.energy_memo import EnergyMemo
from fem_forms.solvers import preconditioner_reuse
from fem_forms.solvers.preconditioner_reuse import PreconditionerReuse
from fem_forms.solvers.reports import SolveReport, StepRecord  # noqa: F401 (snes.SolveReport: the drivers' reports)
from fem_forms.state import State


_REASONS = {getattr(PETSc.SNES.ConvergedReason, n): n for n in dir(PETSc.SNES.ConvergedReason)
            if not n.startswith("_")}


@dataclass
class NonlinearProblem:
    """Residual R(u) = 0 (and tangent dR/du) with optional energy whose gradient R is."""
    u: fem.Function
    residual: ufl.Form | fem.Form      # UFL, or compiled already (Model.compiled)
    jacobian: ufl.Form | fem.Form
    bcs: list
    energy: ufl.Form | fem.Form | None = None
    set_load: Callable[[float], None] | None = None     # continuation parameter setter
    inadmissible: Callable[[], str | None] | None = None  # why a state is unphysical, or None
    state: State | None = None         # fields and history committed/rolled back with the steps (default: u)
    array_terms: list = field(default_factory=list)   # physics.terms.ArrayTerm: energies as arrays (lumped mass)
    bounds: tuple | None = None        # (lower, upper): fem.Function (e.g. State.old["damage"]), float or None
    scalars: list = field(default_factory=list)   # physics.scalars.GlobalScalar: solved with u (bordered.py)
    relag: bool = True                 # a static step re-lags lagged friction at its equilibrium (continuation.py)


def as_compiled(form) -> fem.Form:
    """A UFL form compiled, or a form compiled already (a Model's, shared with its checks) as it is."""
    return form if isinstance(form, FormMetaClass) else fem.form(form)


_DRIVER_IDS = itertools.count()


class SNESDriver:
    """Compiled forms, PETSc objects and callbacks for one problem, reused across load steps."""

    DEFAULTS = {"snes_type": "newtonls", "snes_max_it": 50, "snes_rtol": 1e-9, "snes_atol": 0.0,
                "snes_stol": 1e-11, "snes_linesearch_max_it": 40}

    def __init__(self, problem: NonlinearProblem, options: dict | None = None, linear_kind: str = "auto",
                 prefix: str = "fem_forms_", near_nullspace: Callable[[], PETSc.NullSpace] | None = None,
                 reuse_factor: bool | str = False, keep_preconditioner: bool = False):
        self.p = problem
        self._load_scale: float | None = None        # measured on first use (load_scale), or given
        self.history: list[float] = []               # the residual norms of the last solve, one per iteration
        self.reuse_factor = reuse_factor
        # the multigrid hierarchy may outlive a solve (time steps: the next step's tangent is close)
        self.keep_preconditioner = keep_preconditioner
        self.comm = problem.u.function_space.mesh.comm
        V = problem.u.function_space
        self.dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
        self.linear_kind = linear.choose(linear_kind, self.dofs)
        self.user_options = dict(options or {})
        self.prefix = f"{prefix}{next(_DRIVER_IDS)}_"   # one per driver: options of two drivers never mix
        self.near_nullspace = near_nullspace
        self.L, self.a = as_compiled(problem.residual), as_compiled(problem.jacobian)
        # global scalars (Lagrange multipliers) make a saddle point: no energy line search
        self.E = as_compiled(problem.energy) if problem.energy is not None and not problem.scalars else None
        self.energy_memo = EnergyMemo(self.comm)      # the line search's f(x_k), evaluated by the last one
        self.arrays = ArrayTerms(problem.array_terms, problem.u.function_space, problem.bcs, self.a)
        self.bounds = vi.Bounds(problem.u, problem.bounds, problem.bcs) if problem.bounds is not None else None
        self.b = fpetsc.create_vector(self.L)
        self.x = self.b.copy()
        self.bordered = Bordered(self, problem.scalars) if problem.scalars else None
        self.assembly_time = 0.0
        self.load_factor = 1.0           # for progress reports; set by the continuation
        # staggered sub-solves, contact: a failed line search near the answer is accepted even unpolished, and its
        # polish is kept however far it moves u (polish.py)
        self.polish_stuck = False
        self.newton_cap: int | None = None   # fewer Newton iterations than the options allow (near a limit point)
        self.rebuild()

    # -- PETSc objects -------------------------------------------------------------------------
    def rebuild(self) -> None:
        """(Re)create the tangent matrix and the SNES from the current linear kind, factor reuse and user
        options. Done at start; callers must call it after a failed step (a diverged SNES's vectors can make
        the next solve report convergence in 0 iterations, seen with dolfinx 0.5.2), after changing `linear_kind`,
        `reuse_factor` or `user_options`, and when the operator changes under a kept factor (a new dt)."""
        merged = dict(self.DEFAULTS)
        merged["snes_linesearch_type"] = "bt" if self.E is not None else "basic"
        V = self.p.u.function_space
        merged.update(linear.options(self.linear_kind, symmetric=self.E is not None,
                                     reuse_factor=self.reuse_factor, degree=pmultigrid.degree(V)))
        merged.update(self.user_options)
        pmultigrid.drop_unused(merged, self.user_options)
        vi.options(merged, self.user_options, self.bounds)     # bounded: vinewtonrsls and its line search
        pc_matrix.prefer_ldlt(merged, self.user_options, symmetric=self.p.energy is not None)  # an energy's tangent
        # BAIJ assembles 2.5-3x faster, MUMPS takes it (LDL^T from an SBAIJ copy), multigrid builds from an AIJ
        # copy (self.P); others get AIJ
        mumps = merged.get("pc_type") in ("lu", "cholesky") and merged.get("pc_factor_mat_solver_type") == "mumps"
        self.multigrid = merged.get("pc_type") in ("gamg", "hypre", "mg")
        self.pmg = pmultigrid.for_driver(getattr(self, "pmg", None), V, merged)
        if getattr(self, "P", None) is not None:
            self.P.destroy()
        block = (mumps or self.multigrid) and not self.arrays.widens      # a widened pattern: AIJ (MatAXPY)
        fmt = pc_matrix.copy_format(merged, "baij" if block else "aij")
        self.P = pc_matrix.PreconditioningMatrix(fmt, self.near_nullspace) if fmt else None
        self.A = fpetsc.create_matrix(self.a, "baij" if block else "aij")
        self._A_norm = None
        if self.bordered is not None:
            self.bordered.options(merged)        # K's linear options move to the inner solve
        self._clear_options()
        opts = PETSc.Options()
        for k, v in merged.items():
            opts[self.prefix + k] = v
        snes = PETSc.SNES().create(self.comm)
        snes.setOptionsPrefix(self.prefix)
        snes.setFunction(self._residual, self.b)
        # PCSetFromOptions asks MUMPS for a factor of the preconditioning matrix already: one of the copy's format
        snes.setJacobian(self._jacobian, self.A, self.A if self.P is None else self.P.placeholder(self.A))
        if self.E is not None:
            snes.setObjective(self._objective)
        snes.setMonitor(self._monitor)
        snes.setFromOptions()
        self.max_it = snes.getTolerances()[3]      # the options' Newton limit; newton_cap may lower it per step
        if self.bordered is not None:
            self.bordered.install(snes, self.prefix)    # augmented residual, bordered Jacobian and inverse
        self.arrays.install(snes)                # the array terms' step cap, if any
        # kept in the database (under this driver's own prefix) until the driver is gone: the factor's
        # and the multigrid levels' options (mat_mumps_icntl_*, mg_levels_*) are read at the first solve
        self.options = merged
        # multigrid set-up costs ~30 CG iterations: keep it across Newton steps while that is cheaper
        self.pc_reuse = (PreconditionerReuse(snes, self.comm)
                         if self.multigrid and "snes_lag_preconditioner" not in merged else None)
        if getattr(self, "snes", None) is not None:
            self.snes.destroy()
        self.snes = snes

    def _clear_options(self) -> None:
        """Remove this driver's options from PETSc's database."""
        opts = PETSc.Options()
        for k in getattr(self, "options", {}):
            opts.delValue(self.prefix + k)

    def destroy(self) -> None:
        """Free the PETSc objects and this driver's options now (a driver built for one solve)."""
        for obj in (self.snes, self.A, getattr(self, "P", None), getattr(self, "pmg", None), self.b, self.x):
            if obj is not None:
                obj.destroy()
        self._clear_options()

    def __del__(self):
        try:
            self._clear_options()
        except Exception:                 # PETSc already finalised at interpreter exit
            pass

    def set_state(self, x: PETSc.Vec) -> None:
        """Put x (a Vec of the unknown) into the forms' Function."""
        x.copy(self.p.u.vector)
        self.p.u.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def _residual(self, snes, x, b) -> None:
        t = time.perf_counter()
        self.set_state(x)
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, self.L)
        if self.p.bcs and not vi.on_supports(x, self.p.bcs):      # on them the lifting adds exactly zero
            fpetsc.apply_lifting(b, [self.a], bcs=[self.p.bcs], x0=[x], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.arrays.add_gradient(x, b, lifting=snes is None)   # SNES's own iterates sit on the Dirichlet values
        fpetsc.set_bc(b, self.p.bcs, x, -1.0)
        self.assembly_time += time.perf_counter() - t

    def _jacobian(self, snes, x, A, P) -> None:
        t = time.perf_counter()
        A.zeroEntries()
        fpetsc.assemble_matrix(A, self.a, bcs=self.p.bcs)
        A.assemble()
        self.arrays.add_hessian(x, A)
        self._A_norm = None                      # the round-off floor's |K|_inf, taken once per tangent
        if snes is not None and self.P is not None:
            if self.pc_reuse is None or self.pc_reuse.decide():
                P, new = self.P.refresh(A)
                if new:        # handed to SNES inside its Jacobian callback: it gives P to the KSP right after
                    snes.setJacobian(self._jacobian, A, P)
                if self.pmg is not None:
                    self.pmg.refresh(snes.getKSP(), P)
        self.assembly_time += time.perf_counter() - t

    def preconditioning_matrix(self, A: PETSc.Mat) -> PETSc.Mat:
        """The matrix the preconditioner is built from, with the tangent A's current values: A itself, or its
        copy in the format the preconditioner needs (pc_matrix.py); a solver outside SNES (bordered.py)."""
        return A if self.P is None else self.P.refresh(A)[0]

    def energy(self, x: PETSc.Vec) -> float:
        """The energy the line search minimises (UFL forms and array terms) at x; 1e300 where it is not finite."""
        return self._objective(None, x)

    def _objective(self, snes, x) -> float:
        memo = self.energy_memo if snes is not None and not self.arrays.terms else None   # array terms: not kept
        if memo is not None and (kept := memo.lookup(snes, x)) is not None:
            return kept
        t = time.perf_counter()
        self.set_state(x)
        value = self.comm.allreduce(fem.assemble_scalar(self.E), op=MPI.SUM)
        value += self.arrays.energy(x)
        self.assembly_time += time.perf_counter() - t
        value = value if math.isfinite(value) else 1e300   # NaN (e.g. ln J, J<0): reject the step
        return memo.keep(snes, x, value) if memo is not None else value

    def _monitor(self, snes, it, fnorm) -> None:
        """Record the residual; from the first Newton step on, converge also at the round-off floor
        (PETSc tests convergence right after this call). Asking for less than round-off allows makes
        the energy line search fail on noise and costs cut-backs (measured: 8 Newton steps for 4)."""
        self.history.append(float(fnorm))
        progress.report("newton", load=self.load_factor, iteration=int(it), residual=float(fnorm))
        if it > 0:
            snes.setTolerances(atol=max(self.base_atol(), self.roundoff_floor(1.0)))

    # -- public ----------------------------------------------------------------------------------
    def residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """The residual at x into b, as SNES sees it (Dirichlet rows x - g; array terms, lifting included)."""
        self._residual(None, x, b)

    def tangent(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """The tangent at x into A (Dirichlet rows the identity; array terms' Hessians added)."""
        self._jacobian(None, x, A, A)

    def residual_norm(self, projected: bool = True) -> float:
        """Assemble the residual at the current u, independently of SNES, and return its norm (with bounds
        and `projected`: the norm of its KKT violation, bounds.Bounds.kkt_violation)."""
        x = self.p.u.vector.copy()
        r = self.b.duplicate()
        self._residual(None, x, r)
        if projected and self.bounds is not None:
            self.bounds.kkt_violation(x, r)
        n = self.bordered.residual_norm(r.norm()) if self.bordered is not None else r.norm()
        x.destroy()
        r.destroy()
        return n

    def _finite_residual(self, x: PETSc.Vec) -> bool:
        r = self.b.duplicate()
        self._residual(None, x, r)
        ok = bool(np.isfinite(r.norm()))
        r.destroy()
        return ok

    def _linear_extension(self, x_old: PETSc.Vec) -> None:
        """Moving only the constrained dofs inverted some cells (thin or sliver cells at the boundary):
        start instead from one linear step from the last state, which carries the Dirichlet increment
        smoothly into the interior (x = x_old - K^-1 R(x_old), R's constrained rows x_old - g)."""
        x_old = x_old.copy()
        r = self.b.duplicate()
        self._residual(None, x_old, r)
        self._jacobian(None, x_old, self.A, self.A)
        ksp = linear.make_ksp(self.A, "lu", prefix=f"{self.prefix}extension_")
        dx = r.duplicate()
        ksp.solve(r, dx)
        x_old.axpy(-1.0, dx)
        x_old.copy(self.x)
        self.x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        for obj in (ksp, dx, r, x_old):
            obj.destroy()

    def load_scale(self, refresh: bool = False) -> float:
        """Residual norm of the unloaded state (u = 0) under the current load: the scale that
        convergence and acceptance are measured against. Computed once per driver (again with `refresh`:
        the loads, the rest shape or another field changed)."""
        if refresh or self._load_scale is None:
            u = self.p.u
            saved = u.x.array.copy()
            u.x.array[:] = 0.0
            with self.bordered.unloaded() if self.bordered is not None else nullcontext():
                self._load_scale = self.residual_norm(projected=False)
            u.x.array[:] = saved
        return self._load_scale

    @property
    def known_load_scale(self) -> float | None:
        """The load scale if it has been measured (or given), else None."""
        return self._load_scale

    def use_load_scale(self, value: float) -> None:
        """Measure convergence against `value` (a caller that knows the full load's scale: arc length)."""
        self._load_scale = value

    def base_atol(self) -> float:
        """SNES's absolute tolerance: the user's snes_atol, else 1e-10 of the load scale once known
        (a close first guess must not be asked for 1e-9 of its own tiny residual)."""
        if "snes_atol" in self.user_options:
            return float(self.user_options["snes_atol"])
        scale = self._load_scale
        return 1e-10 * scale if scale is not None else float(self.options.get("snes_atol", 0.0))

    def roundoff_floor(self, safety: float = 1e3) -> float:
        """The residual norm round-off allows at the current state: safety x machine epsilon x
        |K|_inf x |u|_inf x sqrt(n). Stiff (nearly incompressible) materials make it reach 1e-6
        relative. With safety 1 it is still above the noise measured on the 19,683-dof P2 beam
        (residuals stall at 0.1 of it), low enough not to cost accuracy (1e-8 of the load scale there)."""
        if self._A_norm is None:                 # a kept tangent keeps its norm (no MatNorm per iteration)
            self._A_norm = self.A.norm(PETSc.NormType.INFINITY)
        return roundoff_floor(self._A_norm, self.p.u.vector, safety)

    def solve_step(self, check_start: bool = True) -> StepRecord:
        """One SNES solve from the current u at the current load, moved onto the supports' (new) values so that
        Newton directions vanish on them. `check_start`: if that move makes the residual non-finite or crosses a
        contact, start from a linear extension instead (still crossing: the step fails); a caller whose supports
        never move (dynamics) skips this extra assembly."""
        self.history: list[float] = []
        self.p.u.vector.copy(self.x)
        if check_start:
            x_old = self.x.copy()
        fpetsc.set_bc(self.x, self.p.bcs)
        self.x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        if check_start:
            if not self._finite_residual(self.x) or not self.arrays.safe_move(x_old, self.x):
                self._linear_extension(x_old)
            safe = self.arrays.safe_move(x_old, self.x)
            x_old.destroy()
            if not safe:
                return StepRecord(0.0, 0, [], "SUPPORTS_CROSS_CONTACT", False)
        self.snes.setTolerances(atol=self.base_atol(), max_it=min(self.max_it, self.newton_cap or self.max_it))
        if self.bounds is not None:
            self.bounds.install(self.snes)           # refreshed: a bound may be a committed old value
        builds0 = 0
        if self.pc_reuse is not None:
            if not self.keep_preconditioner:
                self.pc_reuse.start_solve()
            builds0 = self.pc_reuse.rebuilds
        if self.bordered is not None:
            self.bordered.solve(self.snes, self.x)  # on [u; p], the Constants set from its answer
        else:
            self.snes.solve(None, self.x)
        reason = self.snes.getConvergedReason()
        iterations, krylov = self.snes.getIterationNumber(), self.snes.getLinearSolveIterations()
        if self.E is not None:
            reason, its, kits = polish.polish(self, reason)
            iterations, krylov = iterations + its, krylov + kits
        self.set_state(self.x)
        return StepRecord(0.0, iterations, self.history,
                          _REASONS.get(reason, str(reason)), reason > 0 or polish.stuck_at_equilibrium(self, reason),
                          krylov_iterations=krylov,
                          preconditioner_builds=self.pc_reuse.rebuilds - builds0 if self.pc_reuse else 0)

    def set_line_search(self, kind: str) -> None:
        """petsc4py 3.18 has no SNESGetLineSearch: set the type through the options database, with every
        other snes_linesearch_* option of this driver (a new type starts from PETSc's defaults)."""
        opts = PETSc.Options()
        settings = {k: v for k, v in self.options.items() if k.startswith("snes_linesearch_")}
        settings["snes_linesearch_type"] = kind
        for k, v in settings.items():
            opts[self.prefix + k] = v
        self.snes.setFromOptions()
        for k in settings:                       # back to the driver's own settings
            if k in self.options:
                opts[self.prefix + k] = self.options[k]
            else:
                opts.delValue(self.prefix + k)
        self.arrays.install(self.snes)           # a new type may drop the step cap (seen: a polish crossed)

    @contextmanager
    def factor_kept(self):
        """SNES solves inside keep the LU factor that preconditions this driver's Krylov solve (REUSED_FACTOR: one
        factor per load or time step) instead of factoring anew at their start: a polish after a stalled line search
        is still Newton on the fresh tangent (contact steps: 76 -> 50 factorizations in 50 steps, 70 ms each at 7.7k
        P2 dofs). Without such a factor (LU per iteration, multigrid, a lag the user set) nothing changes."""
        keep = (self.reuse_factor is True and self.options.get("ksp_type") not in (None, "preonly")
                and "snes_lag_preconditioner" not in self.user_options and self.pc_reuse is None)
        if keep:
            preconditioner_reuse.set_lag(self.snes, preconditioner_reuse.KEEP)
        try:
            yield
        finally:
            if keep:                            # the options' lag again (a new factor at the next solve's start)
                preconditioner_reuse.set_lag(self.snes, int(self.options["snes_lag_preconditioner"]))

    def stale_preconditioner_failed(self) -> bool:
        """Whether the last linear solve ran with a kept preconditioner (its failure: the retry builds a fresh one)."""
        return self.pc_reuse is not None and self.pc_reuse.last_solve_reused

