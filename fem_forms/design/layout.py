"""Two-material layout design (SIMP): where to put the stiffer material so that the loaded part reaches targets.

A density rho_e in [0, 1] per cell chooses between two materials: psi = (1 - w) psi_soft + w psi_stiff with
w = rho_bar^p (Bendsoe 1989's penalisation, p = 3 by default: intermediate densities cost stiffness for their
volume) of the filtered density rho_f = M rho, M_ij = H_ij v_j / sum_k H_ik v_k, H_ij = max(0, r - |c_i - c_j|)
between cell centres c and with cell volumes v (the density filter of Bruns & Tortorelli 2001: a smallest feature
of about r, no checkerboards), projected to rho_bar by a smoothed Heaviside (sharper stage by stage). The mismatch
is J = 1/2 sum_p |x_p + u(x_p) - t_p|^2 / L^2 (L the part's size), plus 1/2 (theta - theta_t)^2 for each target
angle (a segment between two probes turned about an axis, radians: design/layout_targets.py); its gradient takes
one adjoint solve K^T lambda = dJ/du at the equilibrium (1 + m transposed solves with m volume-controlled cavities,
and m forward ones for the start below: design/bordered_adjoint.py) and dJ/dw = -d/dw [R(u, w) . lambda], chained through the SIMP law, the
projection and the filter's transpose (and the density, where the two materials' differ and gravity acts). The
factor of K that solve leaves also starts the next layout's Newton from the first-order change of the equilibrium
(design/layout_predictor.py).

The design vector is global (every rank holds all cells, in an order of their own by centre): the filter and the
optimizer see the same numbers on every rank count."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc
from scipy import sparse
from scipy.spatial import cKDTree
import ufl

from fem_forms.errors import SolveError
from fem_forms.design.bordered_adjoint import Border
from fem_forms.design.layout_predictor import LayoutPredictor, by_density
from fem_forms.design.layout_targets import TargetPoints
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
class PlacedDensity:
    """The density field the layout sets where gravity acts: rho_body + rho_bar (rho_placed - rho_body)."""
    field: fem.Function
    body: float
    placed: float


NEAR_HALVINGS = 3      # a layout the near solve misses is approached in steps of at least 1/2^3 of the way


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
        dm = by_density(work, density, q)
        self.dwork_dm = None if dm is None else fem.form(dm)
        self.K = fpetsc.create_matrix(model.compiled("jacobian"))
        self.ksp = make_ksp(None, "lu", "fem_forms_layout_", comm=model.mesh.comm)
        self.border = Border(model.global_scalars(), model.residual, model.u) if model.global_scalars() else None
        self.predictor = None                             # made (its form compiled) at the first prediction
        self._factored_here = False                       # K is factored at the state the model holds
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
        """The model's weight and density fields for a layout."""
        w, m = self.fields(rho_bar)
        self.cells.fill(self.weight, w)
        if m is not None:
            self.cells.fill(self.density.field, m)

    def fields(self, rho_bar: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """The weight rho_bar^p and the density rho_body + rho_bar (rho_placed - rho_body) (None without a density
        field) per cell of a layout."""
        d = self.density
        return rho_bar ** self.penalty, None if d is None else d.body + rho_bar * (d.placed - d.body)

    def value(self, rho: np.ndarray) -> float:
        """J at rho (the equilibrium solved from the last state)."""
        return self.value_of_layout(self.layout(rho))

    def value_of_layout(self, rho_bar: np.ndarray) -> float:
        """J of the layout rho_bar (projected densities) at its equilibrium."""
        report = self.equilibrium(rho_bar)
        self.evaluations += 1
        if not report.converged:
            raise SolveError(f"layout design: no equilibrium for this layout ({report.message})")
        return self.targets.mismatch(self.model.u)

    def equilibrium(self, rho_bar: np.ndarray):
        """The model's equilibrium with layout rho_bar: `solve(model)` (from the state it has) where there is no
        `near` solver or no layout solved yet; else `near(model)` from the last layout's equilibrium moved by its
        first-order change (predict), and where that fails through layouts between the two (each failure halves the
        step, each success doubles it again, never below 1/2^NEAR_HALVINGS of the way), and only then `solve` from
        rest. A trial layout of the optimizer may lie far from the last one (measured: docs/analyses/design.md)."""
        if self.near is None or self._last is None:
            return self._solved(rho_bar, self.solve)
        start, t, step = self._last, 0.0, 1.0
        while step >= 0.5 ** NEAR_HALVINGS:           # t and step stay multiples of the smallest step
            saved = self._state()
            to = rho_bar if t + step >= 1.0 else start + (t + step) * (rho_bar - start)
            self.predict(to)                             # from the factored equilibrium only: t = 0
            report = self._solved(to, self.near, keep_last=False)
            if report.converged:
                t += step
                if t >= 1.0:
                    self._last = rho_bar
                    return report
                step = min(2.0 * step, 1.0 - t)
            else:
                self._restore(saved)
                step *= 0.5
        return self.from_rest(rho_bar)

    def predict(self, rho_bar: np.ndarray) -> bool:
        """Move the state by its first-order change towards layout rho_bar (design/layout_predictor.py) where K is
        factored at that very state (the gradient was taken there and nothing solved since: the optimizer takes
        one at every layout); whether it moved."""
        if not self._factored_here:
            return False
        if self.predictor is None:
            self.predictor = LayoutPredictor(self.model, self.weight, self.density)
        (w, m), (w0, m0) = self.fields(rho_bar), self.fields(self._last)
        self.cells.fill(self.predictor.dw, w - w0)
        if self.predictor.dm is not None:
            self.cells.fill(self.predictor.dm, m - m0)
        du, dp = self.predictor.move(self._solve, self.border)
        u = self.model.unknown
        u.x.array[:len(du.array)] += du.array
        u.x.scatter_forward()
        for scalar, change in zip(self.model.global_scalars(), dp):
            scalar.value.value = float(scalar.value.value) + float(change)
        self._factored_here = False
        return True

    def _solved(self, rho_bar: np.ndarray, solve, keep_last: bool = True):
        """`solve` with layout rho_bar; with `keep_last`, the last layout solved becomes this one, or none (and
        the state rest) where it failed: no later near solve starts from a state that is no layout's."""
        self.set_layout(rho_bar)
        self._factored_here = False
        report = solve(self.model)
        if keep_last:
            self._last = rho_bar if report.converged else None
            if not report.converged:
                self._restore(self._rest())
        return report

    def from_rest(self, rho_bar: np.ndarray):
        """The scene's load path from rest (the displacement and the global scalars at 0)."""
        self._restore(self._rest())
        return self._solved(rho_bar, self.solve)

    def _rest(self) -> tuple:
        return np.zeros_like(self.model.unknown.x.array), [0.0] * len(self.model.global_scalars()), False

    def _state(self) -> tuple:
        """The unknown, the global scalars and whether K is factored there."""
        return (self.model.unknown.x.array.copy(), [float(s.value.value) for s in self.model.global_scalars()],
                self._factored_here)

    def _restore(self, state: tuple) -> None:
        self.model.unknown.x.array[:] = state[0]
        for scalar, value in zip(self.model.global_scalars(), state[1]):
            scalar.value.value = value
        self._factored_here = state[2]

    def _adjoint(self) -> None:
        """K^T lambda = dJ/du at the current equilibrium (lambda = 0 on supported dofs); K's factor stays for the
        next layout's start (predict)."""
        model = self.model
        self._factored_here = False
        self.K.zeroEntries()
        fpetsc.assemble_matrix(self.K, model.compiled("jacobian"), bcs=model.bcs)
        self.K.assemble()
        self.ksp.setOperators(self.K)
        rhs = self.K.createVecLeft()
        self.targets.gradient(model.u, rhs)
        lam = self._solve_transposed(rhs)
        if self.border is not None:
            self.border.linearise(self._solve_transposed, self._solve)
            lam = self.border.adjoint(lam)[0]
        self.adjoint.x.array[:len(lam.array)] = lam.array
        self.adjoint.x.scatter_forward()
        self._factored_here = self._last is not None

    def _solve_transposed(self, rhs: PETSc.Vec) -> PETSc.Vec:
        """K^T x = rhs with x = 0 on supported dofs (rhs zeroed there first)."""
        return self._with_factor(rhs, self.ksp.solveTranspose)

    def _solve(self, rhs: PETSc.Vec) -> PETSc.Vec:
        """K x = rhs with x = 0 on supported dofs (rhs zeroed there first): the prediction's and the border's."""
        return self._with_factor(rhs, self.ksp.solve)

    def _with_factor(self, rhs: PETSc.Vec, solve) -> PETSc.Vec:
        """`solve(rhs, x)` with K's factor, rhs zeroed on supported dofs first."""
        fpetsc.set_bc(rhs, self.model.bcs, scale=0.0)
        x = self.K.createVecRight()
        solve(rhs, x)
        if self.ksp.getConvergedReason() < 0:
            raise SolveError(f"layout design: a solve with K's factor failed ({self.ksp.getConvergedReason()})")
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
