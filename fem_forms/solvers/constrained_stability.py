"""Is an equilibrium under volume control stable, and if not, which way does it fall? For a problem whose global
scalars are Lagrange multipliers of its energy (cavity pressures, physics/cavities.py), the bordered matrix
[K C^T; C 0] has K's inertia plus that of -Q, Q = C K^-1 C^T (Haynsworth), and the constrained energy is at a
minimum iff exactly m of its eigenvalues are negative: K's negative eigenvalues plus Q's positive ones. K's are
counted by the LDL^T each Newton iteration factors anyway (Sylvester: MUMPS's negative pivots, INFOG(12)),
beyond those of the path's starting state (its first tangent). A saddle is what a real part
snaps away from: a chamber ballooning at the others' expense, one of two joined balloons taking the air. Its
unstable mode, by inverse iteration with the bordered inverse, gives a retry a start off the saddle: Newton
steps alone never leave a symmetric saddle, since no Newton direction there has a component along the mode."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.solvers.reports import UNSTABLE

# inverse iterations for the unstable mode (near the critical point its eigenvalue is the smallest by far)
MODE_ITERATIONS = 8
# the retry starts this fraction of the saddle's largest displacement away from it along the mode
ESCAPE = 0.02


class ConstrainedStability:
    """The inertia check of one Bordered system's states, and the escape from a saddle for the retry."""

    def __init__(self, bordered):
        self.b = bordered
        self.kappa = np.array([s.multiplier for s in bordered.scalars])
        self.negative: int | None = None         # K's negative eigenvalues at the last tangent (None: unknown)
        self.reference: int | None = None        # ... at the path's starting state
        self.q = np.zeros((bordered.m, bordered.m))   # c_u_i.K^-1 c_u_j at the last tangent
        self.start: tuple | None = None          # (field array, scalar values) a retry starts from
        self.escaped_at: float | None = None     # the load factor of the last escape (one per trial)
        self.counted = False                     # an LDL^T counted K's negative eigenvalues at some tangent

    @staticmethod
    def of(bordered) -> ConstrainedStability | None:
        """The check when every scalar is a Lagrange multiplier of the energy, else None."""
        if bordered.drv.p.energy is None or any(s.multiplier is None for s in bordered.scalars):
            return None
        return ConstrainedStability(bordered)

    def new_path(self) -> None:
        """A continuation starts: its first tangent (at the starting state) is the reference."""
        self.reference, self.start, self.escaped_at = None, None, None

    def tangent(self, S: np.ndarray, ksp: PETSc.KSP) -> None:
        """New tangent, factored by `ksp`: q_ij = -S_ij / k_j (S the Schur complement, R_p_j = k_j c_u_j) and,
        where an LDL^T counted them, K's negative eigenvalues."""
        self.q = -S / self.kappa[None, :]
        pc = ksp.getPC()
        ldlt = pc.getType() == "cholesky" and pc.getFactorSolverType() == "mumps"
        self.negative = pc.getFactorMatrix().getMumpsInfog(12) if ldlt else None
        self.counted = self.counted or self.negative is not None
        self.reference = self.negative if self.reference is None else self.reference

    def instability(self) -> str | None:
        """Why the state of the last tangent is no stable equilibrium under the constraints, or None (stable, or
        unknown without an LDL^T). The last tangent is the one SNES factored at the iterate before the converged
        one: the same inertia in every case measured (two balloons, the PneuNet)."""
        if self.negative is None or self.reference is None or not np.all(np.isfinite(self.q)):
            return None
        lost = self.negative - self.reference
        held = int(np.sum(np.linalg.eigvalsh(0.5 * (self.q + self.q.T)) > 0))
        if lost + held <= self.b.m:
            return None
        return (f"{UNSTABLE}: the tangent lost {lost} positive eigenvalue(s) and the {self.b.m} volume "
                f"constraint(s) hold {self.b.m - held} of them (a saddle point: the part would snap)")

    def unstable_mode(self) -> PETSc.Vec | None:
        """A field direction z with c_u.z = 0 and z.K z < 0 (a new Vec, ghosts updated), or None: inverse
        iteration with the bordered inverse from a start that depends only on the dof coordinates (every
        partition finds the same mode, with the same sign). It finds the constrained eigenvalue smallest in size:
        near the point where stability was lost, the unstable one; far past it possibly a stable one, and then
        there is no escape (the step is halved instead)."""
        b, drv = self.b, self.b.drv
        V = drv.p.u.function_space
        bs = V.dofmap.index_map_bs
        x = V.tabulate_dof_coordinates()[: b.n // bs]
        w = drv.x.duplicate()
        w.array[: b.n] = np.sin(1.0 + x @ [3.1, 5.3, 7.7])[:, None].repeat(bs, axis=1).ravel() + np.tile(
            np.arange(bs) * 0.37, b.n // bs)
        W, Z, z = b.X.duplicate(), b.X.duplicate(), w.duplicate()
        for _ in range(MODE_ITERATIONS):
            fpetsc.set_bc(w, drv.p.bcs, scale=0.0)
            w.normalize()
            W.array[: b.n] = w.array_r[: b.n]
            if b.root:
                W.array[b.n:] = 0.0
            b.apply(None, W, Z)                      # [z; dp] = J^-1 [w; 0]: c_u.z = 0
            w.array[: b.n] = Z.array_r[: b.n]
        fpetsc.set_bc(w, drv.p.bcs, scale=0.0)
        w.normalize()
        drv.A.mult(w, z)
        curvature = w.dot(z)
        for v in (W, Z, z):
            v.destroy()
        if not np.isfinite(curvature) or curvature >= 0.0:
            w.destroy()
            return None
        w.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        return w

    def escape(self, trial: float) -> bool:
        """After the step to `trial` converged to a saddle (the problem's state): keep the saddle pushed along its
        unstable mode as the next attempt's start, once per trial. Returns whether there is one."""
        if self.escaped_at == trial:
            return False
        mode = self.unstable_mode()
        if mode is None:
            return False
        u = self.b.drv.p.u
        scale = ESCAPE * _max_abs(u.x.array, self.b.comm) / max(_max_abs(mode.array_r, self.b.comm), 1e-300)
        with mode.localForm() as local:                 # owned and ghost entries, as u.x.array
            self.start = (u.x.array + scale * local.array_r, self.b.values())
        self.escaped_at = trial
        mode.destroy()
        return True

    def take_start(self, u: fem.Function) -> bool:
        """Put the escape's start into `u` and the scalars (once); whether there was one."""
        if self.start is None:
            return False
        u.x.array[:], values = self.start
        self.b.set_values(values)
        self.start = None
        return True


def _max_abs(values: np.ndarray, comm: MPI.Comm) -> float:
    """The largest |value| on any rank."""
    return comm.allreduce(float(np.max(np.abs(values), initial=0.0)), op=MPI.MAX)
