"""Fracture that follows the stable path (Pham & Marigo's second-order stability): a converged damage-displacement
state of the alternate minimization is a stationary point of E(u, d), not necessarily a minimum. A homogeneous bar
past its elastic limit stays homogeneous under the staggered solve, a saddle once the bar is longer than about
pi l sqrt(2/3) (AT1); a symmetric specimen damages both sides alike. After each converged step the energy's
Hessian [[K_uu, K_ud], [K_du, K_dd]] is restricted to the active set (free displacement dofs, damage dofs strictly
between their bounds d_old and 1; displacement nodes on a crack's line left out), scaled by its diagonal, and its
inertia counted (MUMPS LDL^T); with a negative eigenvalue, SLEPc's spectrum slicing gives the most negative one's
mode, the state is pushed along it (the damage growing where the mode is largest, kept within its bounds) and the
step solved again from there."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import SolveError
from fem_forms.model import Model
from fem_forms.solvers import linear
from fem_forms.solvers.slicing import eigensolve_interval, inertia_below

ACTIVE = 1e-6        # a damage dof is active this far inside its bounds (d_old + ACTIVE < d < 1 - ACTIVE)
UNSTABLE = -1e-8     # a scaled eigenvalue below this is negative (round-off in the diagonal scaling is ~1e-12)
PUSH = 0.1           # the push moves the damage by at most this along the mode
CRACK_LINE = 0.8     # displacement nodes with d at least this (g(d) <= 0.04 of the stiffness left) are in the crack


def stable_path(model: Model) -> StablePath | None:
    """The check of a static run's phase field; None without one, with fracture.stable_path = false, or where the
    run's linear solver is iterative (the check factorizes the energy's Hessian, which a run too large for a direct
    solver cannot afford: said in a warning); the run's report then says stable_path: false."""
    fracture = getattr(model.scene, "fracture", None)
    if fracture is None or not model.sub_problems():
        return None
    V = model.u.function_space
    dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    iterative = linear.choose(model.scene.solver.linear, dofs) == "iterative"
    if not fracture.stable_path or iterative:
        if fracture.stable_path:
            model.warnings.append("fracture.stable_path: not checked, the run's linear solver is iterative (the "
                                  "check factorizes the energy's Hessian; solver.linear = \"direct\" checks it)")
        for t in model.terms:
            if "damage" in t.state_fields():
                t.stable_path, t.bifurcations = False, []
        return None
    return StablePath(model)


class StablePath:
    """The second-order check of one model's phase field, and the push off a saddle; what it found goes into the
    phase field's report (`stable_path`, `bifurcations`)."""

    def __init__(self, model: Model):
        (problem, sub), = model.sub_problems()
        self.model, self.d = model, sub.field
        self.lower, self.upper = problem.bounds
        self.term = next(t for t in model.terms if "damage" in t.state_fields())
        Vd = self.d.function_space
        self.a_uu = model.compiled("jacobian")
        self.a_ud = fem.form(ufl.derivative(model.residual, self.d, ufl.TrialFunction(Vd)))
        self.a_dd = problem.jacobian
        self._blocks = None                # the three blocks' matrices, made once, refilled at every check
        V = model.u.function_space
        self.n_u = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        self.n_d = Vd.dofmap.index_map.size_local
        held = [bc.dof_indices()[0][: bc.dof_indices()[1]] for bc in model.bcs]
        held = np.unique(np.concatenate(held)) if held else np.empty(0, dtype=np.int32)
        self.held_u = held[held < self.n_u]
        scalar, self._u_nodes = V.sub(0).collapse()          # d where each displacement node is
        self._d_at_u = fem.Function(scalar)
        self.free_u = self._free_u()
        self.term.bifurcations = []
        self.term.stable_path = True

    def _free_u(self) -> np.ndarray:
        """The displacement dofs the check moves: not held, and not on a crack's line (d >= CRACK_LINE at the
        node). What stiffness such a node has left is the residual one, a numerical device: stretched, it has
        modes of its own that are no instability of the body and that no push can follow (measured on the torn
        rubber strip: the nodes on the notch's line at its mouth, d = 1, whose move inverts cells at once; the
        last ligament's, d = 0.89-0.90, twisting, after which the displacement's Newton stalls; 0.95 kept the
        latter, 0.9 and 0.8 run clean: 0.8 for a margin)."""
        self._d_at_u.interpolate(self.d)
        n = self._d_at_u.function_space.dofmap.index_map.size_local
        nodes = np.flatnonzero(self._d_at_u.x.array[:n] >= CRACK_LINE)
        bs = self.model.u.function_space.dofmap.index_map_bs
        cracked = (np.asarray(self._u_nodes)[nodes][:, None] + np.arange(bs)).ravel()
        return np.setdiff1d(np.arange(self.n_u), np.concatenate([self.held_u, cracked])).astype(np.int32)

    def _active_d(self) -> np.ndarray:
        d = self.d.x.array[: self.n_d]
        lo = self.lower.x.array[: self.n_d] if isinstance(self.lower, fem.Function) else self.lower
        up = self.upper.x.array[: self.n_d] if isinstance(self.upper, fem.Function) else self.upper
        return np.flatnonzero((d > lo + ACTIVE) & (d < up - ACTIVE)).astype(np.int32)

    def _hessian(self, comm) -> PETSc.Mat:
        """The energy's Hessian in (u, d) as one AIJ matrix (nest layout: each rank's u rows, then its d rows)."""
        forms = (self.a_uu, self.a_ud, self.a_dd)
        if self._blocks is None:
            self._blocks = [fpetsc.create_matrix(a) for a in forms]
        for A, a in zip(self._blocks, forms):
            A.zeroEntries()
            fpetsc.assemble_matrix(A, a)
            A.assemble()
        A_uu, A_ud, A_dd = self._blocks
        A_du = A_ud.transpose(PETSc.Mat())
        nest = PETSc.Mat().createNest([[A_uu, A_ud], [A_du, A_dd]], comm=comm)
        H = nest.convert("aij", PETSc.Mat())
        self._is = nest.getNestISs()[0]
        for A in (A_du, nest):
            A.destroy()
        return H

    def unstable_mode(self) -> tuple[float, np.ndarray, np.ndarray] | None:
        """(scaled eigenvalue, displacement part, damage part: local arrays) of the Hessian's most negative
        eigenvalue on the active set; None where it is positive definite there or no damage dof is active."""
        comm = self.model.mesh.comm
        active = self._active_d()
        if not comm.allreduce(len(active), op=MPI.SUM):
            return None
        self.free_u = self._free_u()
        H = self._hessian(comm)
        is_u, is_d = self._is
        rows = np.concatenate([is_u.getIndices()[self.free_u], is_d.getIndices()[active]]).astype(PETSc.IntType)
        keep = PETSc.IS().createGeneral(rows, comm=comm)
        S = H.createSubMatrix(keep, keep)
        H.destroy()
        scale = S.getDiagonal()
        scale.sqrtabs()
        scale.reciprocal()
        S.diagonalScale(scale, scale)                      # unit diagonal: u and d weigh alike
        S.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        one = S.duplicate()
        one.zeroEntries()
        one.shift(1.0)
        try:
            negative = inertia_below(S, one, UNSTABLE)
            if negative == 0 or negative <= self._elastic_negatives(S, one):
                return None
            lowest = -(S.norm(PETSc.NormType.INFINITY) + 1.0)         # Gershgorin: below every eigenvalue
            found = eigensolve_interval(S, one, lowest, UNSTABLE)
            if not len(found.values):
                return None
            y = found.vectors[0]
            y.pointwiseMult(y, scale)                      # back from the scaled problem
            vu, vd = np.zeros_like(self.model.u.x.array), np.zeros_like(self.d.x.array)
            vu[self.free_u] = y.array[: len(self.free_u)]
            vd[active] = y.array[len(self.free_u):]
            for v in found.vectors:
                v.destroy()
            return float(found.values[0]), vu, vd
        finally:
            for obj in (S, one, scale, keep):
                obj.destroy()

    def _elastic_negatives(self, S: PETSc.Mat, one: PETSc.Mat) -> int:
        """Negative eigenvalues of the displacement block alone (S's first rows on each rank): by Haynsworth,
        In(H) = In(K_uu) + In(K_dd - K_du K_uu^-1 K_ud), so the damage brings an instability only where H has
        more than K_uu (an elastic one, a thin sheet buckling, is not the phase field's to push)."""
        start = S.getOwnershipRange()[0]
        rows = PETSc.IS().createGeneral(np.arange(start, start + len(self.free_u), dtype=PETSc.IntType),
                                        comm=S.getComm())
        K, I = S.createSubMatrix(rows, rows), one.createSubMatrix(rows, rows)
        try:
            return inertia_below(K, I, UNSTABLE)
        finally:
            for obj in (K, I, rows):
                obj.destroy()

    def push(self, load_factor: float) -> bool:
        """Push an unstable state's damage along its mode (growing where the mode is largest, within its bounds)
        and return True; the caller solves the displacement, then the damage, from there. False where the state
        is stable on its active set (or the mode moves no damage)."""
        try:
            mode = self.unstable_mode()
        except SolveError as e:                        # SLEPc found no eigenpair: the state is kept unchecked
            self.gave_up(load_factor, str(e))
            return False
        if mode is None:
            return False
        value, _, vd = mode
        comm = self.model.mesh.comm
        top = comm.allreduce(float(vd[: self.n_d].max(initial=0.0)), op=MPI.MAX)
        bottom = comm.allreduce(float(vd[: self.n_d].min(initial=0.0)), op=MPI.MIN)
        if max(top, -bottom) <= 0.0:
            return False
        sign = 1.0 if top >= -bottom else -1.0
        lo = self.lower.x.array if isinstance(self.lower, fem.Function) else self.lower
        up = self.upper.x.array if isinstance(self.upper, fem.Function) else self.upper
        self.d.x.array[:] = np.clip(self.d.x.array + sign * PUSH / max(top, -bottom) * vd, lo, up)
        self.d.x.scatter_forward()
        self.pending = {"load_factor": load_factor, "eigenvalue": value, "at": self._where(sign * vd)}
        return True

    def kept(self) -> None:
        """The step solved from the last push converged: that push is a bifurcation the run took."""
        self.term.bifurcations.append(self.pending)

    def gave_up(self, load_factor: float, why: str) -> None:
        """No equilibrium was found off the saddle at `load_factor`: the run keeps the unstable state, and says so."""
        self.term.stable_path = False
        self.model.warnings.append(f"fracture: an unstable state was kept at load factor {load_factor:.6g} (no "
                                   f"equilibrium found along its mode: {why})")

    def _where(self, grows: np.ndarray) -> list:
        """The rest position of the node where the damage grows most along the mode (the same on every rank)."""
        V = self.d.function_space
        local = grows[: self.n_d]
        i = int(np.argmax(local)) if len(local) else 0
        best = (float(local[i]) if len(local) else -np.inf, V.mesh.comm.rank)
        _, rank = max(V.mesh.comm.allgather(best))
        x = V.tabulate_dof_coordinates()[i].tolist() if V.mesh.comm.rank == rank else None
        return V.mesh.comm.bcast(x, root=rank)
