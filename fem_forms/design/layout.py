"""Two-material layout design (SIMP): where to put the stiffer material so that the loaded part reaches targets.

A density rho_e in [0, 1] per cell chooses between two materials: psi = (1 - w) psi_soft + w psi_stiff with
w = rho_bar^p (Bendsoe 1989's penalisation, p = 3 by default: intermediate densities cost stiffness for their
volume) of the filtered density rho_f = M rho, M_ij = H_ij v_j / sum_k H_ik v_k, H_ij = max(0, r - |c_i - c_j|)
between cell centres c and with cell volumes v (the density filter of Bruns & Tortorelli 2001: a smallest feature
of about r, no checkerboards), projected to rho_bar by a smoothed Heaviside (sharper stage by stage). The mismatch
is J = 1/2 sum_p |x_p + u(x_p) - t_p|^2 / L^2 (L the part's size), plus 1/2 (theta - theta_t)^2 for each target
angle (a segment between two probes turned about an axis, radians); its gradient takes one adjoint solve
K^T lambda = dJ/du at the equilibrium and dJ/dw = -d/dw [R(u, w) . lambda], chained through the SIMP law, the
projection and the filter's transpose (and the density, where the two materials' differ and gravity acts).

The design vector is global (every rank holds all cells, in an order of their own by centre): the filter and the
optimizer see the same numbers on every rank count."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
from scipy import sparse
from scipy.spatial import cKDTree
import ufl

from fem_forms.errors import SolveError
from fem_forms.meshes import mesh_size
from fem_forms.output.probes import nearest_nodes
from fem_forms.physics.scalars import coupling_forms
from fem_forms.solvers.linear import make_ksp


@dataclass
class LayoutMaterial:
    """psi = (1 - w) psi_soft + w psi_stiff, w a DG0 Function (the SIMP weight of each cell) the design sets."""
    soft: object
    stiff: object
    weight: fem.Function
    name: str = "layout"

    def psi(self, F):
        return (1 - self.weight) * self.soft.psi(F) + self.weight * self.stiff.psi(F)


class CellVector:
    """The DG0 space's owned cells as one global vector on every rank, in an order of their own (by centre, so
    the same on every rank count): gather, fill, volumes, centres."""

    def __init__(self, space: fem.FunctionSpace):
        self.space = space
        comm = self.comm = space.mesh.comm
        self.n_owned = space.dofmap.index_map.size_local
        if not np.array_equal(space.dofmap.list.array[:self.n_owned], np.arange(self.n_owned)):
            raise RuntimeError("CellVector: the DG0 dofs are not numbered as the cells (dolfinx 0.5.2 does)")
        counts = comm.allgather(self.n_owned)
        self.start = int(sum(counts[:comm.rank]))
        self.size = int(sum(counts))
        centres = np.concatenate(comm.allgather(space.tabulate_dof_coordinates()[:self.n_owned]))
        key = np.round(centres / (1e-9 * max(float(np.ptp(centres)), 1e-300)))
        self.order = np.lexsort(key.T[::-1])            # position k of the vector holds rank-order cell order[k]
        self.centres = centres[self.order]
        q = ufl.TestFunction(space)
        self.volumes = self.gather(fpetsc.assemble_vector(fem.form(q * ufl.dx)).array[:self.n_owned])

    def gather(self, owned: np.ndarray) -> np.ndarray:
        """The owned entries of every rank as the global vector."""
        return np.concatenate(self.comm.allgather(np.asarray(owned, dtype=float)))[self.order]

    def fill(self, f: fem.Function, values: np.ndarray) -> None:
        """f's owned entries from the global vector, ghosts updated."""
        ranked = np.empty(self.size)
        ranked[self.order] = values
        f.x.array[:self.n_owned] = ranked[self.start:self.start + self.n_owned]
        f.x.scatter_forward()


def density_filter(centres: np.ndarray, volumes: np.ndarray, radius: float) -> sparse.csr_matrix:
    """M with rho_f = M rho: the cone-weighted, volume-weighted average over cells within `radius`."""
    tree = cKDTree(centres)
    dist = tree.sparse_distance_matrix(tree, radius, output_type="coo_matrix")
    H = sparse.coo_matrix((radius - dist.data, (dist.row, dist.col)), shape=dist.shape).tocsr()
    H.setdiag(radius)                        # each cell's own weight r, whether or not scipy kept distance 0
    H = H @ sparse.diags(volumes)
    return sparse.diags(1.0 / np.asarray(H.sum(axis=1)).ravel()) @ H


@dataclass
class TargetAngle:
    """A segment's rotation about an axis as a target: the segment from probe `start` to probe `end` (indices into
    the targets' points), the angle (radians) it should turn by about the unit vector `axis`."""
    start: int
    end: int
    angle: float
    axis: np.ndarray


class TargetPoints:
    """Probes snapped to their nearest displacement node (on the lowest rank owning one as near), their target
    positions (only the `counted` coordinates count) and target angles (a segment between two probes turned about
    an axis): the mismatch, and its derivative with respect to the owned displacement dofs."""

    def __init__(self, V: fem.FunctionSpace, points: np.ndarray, targets: np.ndarray, length: float,
                 counted: np.ndarray | None = None, angles: tuple = ()):
        self.points, self.targets, self.length = np.atleast_2d(points), np.atleast_2d(targets), length
        self.counted = np.ones_like(self.points) if counted is None else np.asarray(counted, dtype=float)
        self.angles = tuple(angles)
        comm = V.mesh.comm
        self.node, self.at = nearest_nodes(V, self.points)      # the snapped nodes (local index on their owner)
        self.comm = comm
        for a in self.angles:
            if np.linalg.norm(self._frame(a)[0]) < 1e-9 * length:
                raise SolveError("layout design: a target angle's segment lies along its axis (its probes snapped "
                                 "to the same line): no rotation about it to measure")

    def positions(self, u: fem.Function) -> np.ndarray:
        """x_p + u(x_p) of every probe, on every rank."""
        local = np.zeros_like(self.points)
        for i, k in enumerate(self.node):
            if k >= 0:
                local[i] = u.x.array[3 * k:3 * k + 3]
        return self.at + self.comm.allreduce(local, op=MPI.SUM)

    def misses(self, u: fem.Function) -> np.ndarray:
        """Position minus target of every probe, 0 in the coordinates that do not count."""
        return (self.positions(u) - self.targets) * self.counted

    def _frame(self, a: TargetAngle) -> tuple[np.ndarray, np.ndarray]:
        """(the rest segment's part across the axis, the axis cross it): the turned segment s has the angle
        atan2(b . s, a . s) about the axis (right-handed)."""
        s0 = self.at[a.end] - self.at[a.start]
        across = s0 - (s0 @ a.axis) * a.axis
        return across, np.cross(a.axis, across)

    def turned(self, u: fem.Function) -> np.ndarray:
        """Each target angle's segment's rotation about its axis (radians, in (-pi, pi])."""
        x = self.positions(u)
        out = []
        for a in self.angles:
            across, normal = self._frame(a)
            s = x[a.end] - x[a.start]
            out.append(np.arctan2(normal @ s, across @ s))
        return np.array(out)

    def angle_misses(self, u: fem.Function) -> np.ndarray:
        """Turned minus target angle of each target angle (radians, wrapped into [-pi, pi))."""
        target = np.array([a.angle for a in self.angles])
        return np.mod(self.turned(u) - target + np.pi, 2 * np.pi) - np.pi

    def mismatch(self, u: fem.Function) -> float:
        """J = 1/2 sum |miss|^2 / L^2 over the positions + 1/2 sum (angle miss)^2 (radians)."""
        return 0.5 * float(np.sum(self.misses(u) ** 2)) / self.length ** 2 + \
            0.5 * float(np.sum(self.angle_misses(u) ** 2))

    def allowed(self, reach: float, reach_angle: float) -> float:
        """J when every position target is missed by `reach` (m) and every angle by `reach_angle` (radians)."""
        positions = int(np.count_nonzero(self.counted.any(axis=1)))
        return 0.5 * (positions * reach ** 2 / self.length ** 2 + len(self.angles) * reach_angle ** 2)

    def gradient(self, u: fem.Function, out: PETSc.Vec) -> None:
        """dJ/du into `out` (owned entries)."""
        out.set(0.0)
        slope = self.misses(u) / self.length ** 2
        if self.angles:
            x, misses = self.positions(u), self.angle_misses(u)
            for a, miss in zip(self.angles, misses):
                across, normal = self._frame(a)
                s = x[a.end] - x[a.start]
                c, n = across @ s, normal @ s
                d_angle = (c * normal - n * across) / (c * c + n * n)       # d atan2(n, c) / ds
                slope[a.end] += miss * d_angle
                slope[a.start] -= miss * d_angle
        for i, k in enumerate(self.node):
            if k >= 0:
                out.array[3 * k:3 * k + 3] += slope[i]


@dataclass
class PlacedDensity:
    """The density field the layout sets where gravity acts: rho_body + rho_bar (rho_placed - rho_body)."""
    field: fem.Function
    body: float
    placed: float


NEAR_HALVINGS = 3      # a layout the near solve misses is approached in steps of 1/2, 1/4, 1/8 of the way


class LayoutGradient:
    """J(rho) and dJ/drho for one model whose material is a LayoutMaterial: `solve(model)` runs its equilibrium
    along the load path, `near(model)` (optional) from a nearby layout's equilibrium in one step.
    `domain` (a boolean per cell, design order): where the placed material may go (elsewhere w = 0)."""

    def __init__(self, model, weight: fem.Function, cells: CellVector, targets: TargetPoints, radius: float,
                 penalty: float, solve, domain: np.ndarray | None = None, density: PlacedDensity | None = None,
                 near=None):
        self.model, self.weight, self.cells, self.targets = model, weight, cells, targets
        self.penalty, self.solve, self.near, self.density = penalty, solve, near, density
        self._last = None                                 # the last layout solved (rho_bar)
        self.domain = np.ones(cells.size) if domain is None else np.asarray(domain, dtype=float)
        self.beta = 0.0                                   # the projection's sharpness (the optimizer raises it)
        self.radius = radius
        self.filter = density_filter(cells.centres, cells.volumes, radius)
        if model.unknown is not model.u:
            raise SolveError("layout design: the displacement formulation only (no mixed u-p yet)")
        lam = self.adjoint = fem.Function(model.V, name="adjoint")
        work = ufl.replace(model.residual, {ufl.TestFunction(model.V): lam})
        q = ufl.TestFunction(weight.function_space)
        self.dwork_dw = fem.form(ufl.derivative(work, weight, q))
        self.dwork_dm = None
        if density is not None and density.placed != density.body:
            dm = ufl.algorithms.expand_derivatives(ufl.derivative(work, density.field, q))
            self.dwork_dm = None if dm.empty() else fem.form(dm)
        self.K = fpetsc.create_matrix(model.compiled("jacobian"))
        self.ksp = make_ksp(None, "lu", "fem_forms_layout_", comm=model.mesh.comm)
        self.border = Border(model) if model.global_scalars() else None
        self.evaluations = 0

    def projected(self, rho_f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rho_bar, d rho_bar / d rho_f): the filtered density projected by a smoothed Heaviside of sharpness
        beta at 1/2 (Wang, Lazarov & Sigmund 2011; beta 0 leaves it as it is), 0 outside the domain."""
        b = self.beta
        if b == 0:
            return rho_f * self.domain, self.domain.copy()
        t, den = np.tanh(b * (rho_f - 0.5)), 2 * np.tanh(b * 0.5)
        return (np.tanh(b * 0.5) + t) / den * self.domain, b * (1 - t ** 2) / den * self.domain

    def layout(self, rho: np.ndarray) -> np.ndarray:
        """rho_bar: how much of each cell is the placed material."""
        return self.projected(self.filter @ rho)[0]

    def fraction(self, rho: np.ndarray) -> tuple[float, np.ndarray]:
        """The placed fraction of the domain's volume, sum v rho_bar / V_domain, and its gradient."""
        rho_bar, slope = self.projected(self.filter @ rho)
        v = self.cells.volumes * self.domain / float(self.cells.volumes @ self.domain)
        return float(v @ rho_bar), self.filter.T @ (v * slope)

    def set_layout(self, rho_bar: np.ndarray) -> None:
        """The model's weight (rho_bar^p) and density fields for a layout."""
        self.cells.fill(self.weight, rho_bar ** self.penalty)
        if self.density is not None:
            d = self.density
            self.cells.fill(d.field, d.body + rho_bar * (d.placed - d.body))

    def value(self, rho: np.ndarray) -> float:
        """J at rho (the equilibrium solved from the last state)."""
        report = self.equilibrium(self.layout(rho))
        self.evaluations += 1
        if not report.converged:
            raise SolveError(f"layout design: no equilibrium for this layout ({report.message})")
        return self.targets.mismatch(self.model.u)

    def equilibrium(self, rho_bar: np.ndarray):
        """The model's equilibrium with layout rho_bar: `solve(model)` (from the state it has) where there is no
        `near` solver or no layout solved yet; else `near(model)` from the last layout's equilibrium, and where
        that fails through layouts between the two (halving the way, NEAR_HALVINGS times at most), and only then
        `solve` from rest. A trial layout of the optimizer may lie far from the last one."""
        if self.near is None or self._last is None:
            return self._solved(rho_bar, self.solve)
        start, t, step = self._last, 0.0, 1.0
        while step >= 0.5 ** NEAR_HALVINGS:           # each success moves >= 1/8 of the way, each failure halves
            saved = self._state()
            report = self._solved(start + min(t + step, 1.0) * (rho_bar - start), self.near, keep_last=False)
            if report.converged:
                t = min(t + step, 1.0)
                if t == 1.0:
                    self._last = rho_bar
                    return report
            else:
                self._restore(saved)
                step *= 0.5
        return self._from_rest(rho_bar)

    def _solved(self, rho_bar: np.ndarray, solve, keep_last: bool = True):
        self.set_layout(rho_bar)
        report = solve(self.model)
        if report.converged and keep_last:
            self._last = rho_bar
        return report

    def _from_rest(self, rho_bar: np.ndarray):
        """The scene's load path from rest (the displacement and the global scalars at 0)."""
        self._restore((np.zeros_like(self.model.unknown.x.array), [0.0] * len(self.model.global_scalars())))
        return self._solved(rho_bar, self.solve)

    def _state(self) -> tuple:
        return self.model.unknown.x.array.copy(), [float(s.value.value) for s in self.model.global_scalars()]

    def _restore(self, state: tuple) -> None:
        self.model.unknown.x.array[:] = state[0]
        for scalar, value in zip(self.model.global_scalars(), state[1]):
            scalar.value.value = value

    def _adjoint(self) -> None:
        """K^T lambda = dJ/du at the current equilibrium (lambda = 0 on supported dofs)."""
        model = self.model
        self.K.zeroEntries()
        fpetsc.assemble_matrix(self.K, model.compiled("jacobian"), bcs=model.bcs)
        self.K.assemble()
        self.ksp.setOperators(self.K)
        rhs = self.K.createVecLeft()
        self.targets.gradient(model.u, rhs)
        lam = self._solve_transposed(rhs)
        if self.border is not None:
            lam = self.border.adjoint(lam, self._solve_transposed)
        self.adjoint.x.array[:len(lam.array)] = lam.array
        self.adjoint.x.scatter_forward()

    def _solve_transposed(self, rhs: PETSc.Vec) -> PETSc.Vec:
        """K^T x = rhs with x = 0 on supported dofs (rhs zeroed there first)."""
        fpetsc.set_bc(rhs, self.model.bcs, scale=0.0)
        x = self.K.createVecRight()
        self.ksp.solveTranspose(rhs, x)
        if self.ksp.getConvergedReason() < 0:
            raise SolveError(f"layout design: the adjoint solve failed ({self.ksp.getConvergedReason()})")
        return x

    def _cellwise(self, form: fem.Form) -> np.ndarray:
        """-d/d(field) of R . lambda per cell (design order)."""
        vec = fpetsc.assemble_vector(form)
        return -self.cells.gather(vec.array[:self.cells.n_owned])

    def gradient(self, rho: np.ndarray) -> np.ndarray:
        """dJ/drho at the state `value(rho)` left: one adjoint solve."""
        self._adjoint()
        rho_bar, slope = self.projected(self.filter @ rho)
        dJ = self._cellwise(self.dwork_dw) * self.penalty * rho_bar ** (self.penalty - 1)
        if self.dwork_dm is not None:
            dJ = dJ + self._cellwise(self.dwork_dm) * (self.density.placed - self.density.body)
        return self.filter.T @ (dJ * slope)


class Border:
    """The adjoint of the bordered equilibrium (a volume-controlled cavity: its pressure p an unknown beside u,
    R(u, p) = 0 and c(u, p) = 0). With the Jacobian [K R_p; c_u c_p], the adjoint [lambda; mu] solves
    K^T lambda + sum_i c_u_i mu_i = dJ/du and R_p_j . lambda + sum_i c_p_ij mu_i = 0 (J and c do not depend on
    the layout's fields, so dJ/dw is -d/dw (R . lambda) as before): lambda = a - sum_i b_i mu_i from
    a = K^-T dJ/du, b_i = K^-T c_u_i, and the m x m system for mu."""

    def __init__(self, model):
        forms = coupling_forms(model.global_scalars(), model.residual, model.u)
        self.R_p = [fem.form(f) for f in forms["R_p"]]
        self.c_u = [fem.form(f) for f in forms["c_u"]]
        self.c_p = [[fem.form(f) if isinstance(f, ufl.Form) else f for f in row] for row in forms["c_p"]]
        self.comm = model.mesh.comm

    def _number(self, c) -> float:
        """c_p_ij's value: 0 (None), a number, or a form's integral over all ranks."""
        return 0.0 if c is None else float(c) if isinstance(c, (int, float)) else \
            self.comm.allreduce(fem.assemble_scalar(c), op=MPI.SUM)

    @staticmethod
    def _vector(form: fem.Form) -> PETSc.Vec:
        vec = fpetsc.assemble_vector(form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return vec

    def adjoint(self, a: PETSc.Vec, solve_transposed) -> PETSc.Vec:
        """lambda from a = K^-T dJ/du, solving K^T b_i = c_u_i with `solve_transposed`."""
        b = [solve_transposed(self._vector(f)) for f in self.c_u]
        R_p = [self._vector(f) for f in self.R_p]
        M = np.array([[R_p[j].dot(b[i]) - self._number(self.c_p[i][j]) for i in range(len(b))]
                      for j in range(len(R_p))])
        mu = np.linalg.solve(M, np.array([v.dot(a) for v in R_p]))
        for b_i, mu_i in zip(b, mu):
            a.axpy(-mu_i, b_i)
        return a


def part_length(model) -> float:
    """The part's size for the mismatch's scale: its bounding box's diagonal (all ranks)."""
    x = model.mesh.geometry.x
    comm = model.mesh.comm
    lo = np.min(comm.allgather(x.min(axis=0) if len(x) else np.full(3, np.inf)), axis=0)
    hi = np.max(comm.allgather(x.max(axis=0) if len(x) else np.full(3, -np.inf)), axis=0)
    return float(np.linalg.norm(hi - lo)) or mesh_size(model.mesh)





@dataclass
class LayoutResult:
    """The optimised layout: densities (raw and projected, in the design's cell order), J per layout tried."""
    rho: np.ndarray
    rho_bar: np.ndarray
    history: list
    objective: float
    stiff_fraction: float
    iterations: int
    converged: bool


class _Spent(Exception):
    """The optimizer asked for more layouts than it may try."""


STAGES = (1.0, 2.0, 4.0, 8.0, 16.0)     # the projection's sharpness beta, stage by stage
BOUND_TOLERANCE = 1e-3                  # a placed fraction this far over its bound counts as over


def optimize_layout(gradient: LayoutGradient, max_fraction: float, iterations: int = 100, reach: float = 1e-4,
                    on_iteration=None, reach_angle: float = np.radians(0.5)) -> LayoutResult:
    """Of the layouts within the placed fraction's bound that bring every target within about `reach` (m, in its
    counted coordinates; each target angle within `reach_angle`, radians), the one with the least placed material:
    scipy's L-BFGS-B on f = J / J_reach + fraction +
    kappa max(0, fraction - max_fraction)^2 over 0 <= rho <= 1 (J_reach = TargetPoints.allowed: the mismatch
    counts once the targets are farther than `reach`, the material always), in stages of sharper projection
    (STAGES), each from the last one's layout, kappa x100 after a stage that ended over the bound. At most
    `iterations` layouts. Less material is the tie-breaker among the many layouts that reach a few targets; with
    SIMP and the projection that layout is black and white (an intermediate density pays volume for little
    stiffness). Every rank takes rank 0's value and gradient: the same steps everywhere."""
    from scipy.optimize import minimize
    cells, comm = gradient.cells, gradient.cells.comm
    allowed = gradient.targets.allowed(reach, reach_angle)
    rho = np.full(cells.size, max_fraction)
    history, converged, count, kappa, last = [], False, 0, 1e3, {}

    def f(x):
        nonlocal count
        if count >= iterations:
            raise _Spent
        x = comm.bcast(np.asarray(x, dtype=float))
        J = gradient.value(x)
        fraction, d_fraction = gradient.fraction(x)
        over = max(fraction - max_fraction, 0.0)
        history.append(J)
        if on_iteration is not None:
            on_iteration(count, J, fraction)
        count += 1
        last["x"] = x
        value = J / allowed + fraction + kappa * over ** 2
        grad = gradient.gradient(x) / allowed + (1 + 2 * kappa * over) * d_fraction
        return comm.bcast((value, grad))

    stages = STAGES[-min(len(STAGES), iterations):]
    for i, beta in enumerate(stages):
        gradient.beta = beta
        budget = max(1, (iterations - count) // (len(stages) - i))
        try:
            out = minimize(f, rho, jac=True, method="L-BFGS-B", bounds=[(0.0, 1.0)] * cells.size,
                           options={"maxfun": budget, "maxiter": budget})
            rho, done = comm.bcast(np.clip(out.x, 0.0, 1.0)), bool(out.success)
        except _Spent:
            rho, done = last.get("x", rho), False
        over = gradient.fraction(rho)[0] - max_fraction > BOUND_TOLERANCE
        converged = done and i == len(stages) - 1 and not over
        if over:
            kappa = min(100 * kappa, 1e12)
    J = gradient.value(rho)
    return LayoutResult(rho, gradient.layout(rho), history, J, gradient.fraction(rho)[0], count, converged)
