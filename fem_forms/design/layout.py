"""Two-material layout design (SIMP): where to put the stiffer material so that the loaded part reaches targets.

A density rho_e in [0, 1] per cell chooses between two materials: psi = (1 - w) psi_soft + w psi_stiff with
w = rho_f^p (Bendsoe 1989's penalisation, p = 3 by default: intermediate densities cost stiffness, so the optimum
is nearly black and white) of the filtered density rho_f = M rho, M_ij = H_ij v_j / sum_k H_ik v_k, H_ij =
max(0, r - |c_i - c_j|) between cell centres c and with cell volumes v (the density filter of Bruns & Tortorelli
2001: a smallest feature of about r, no checkerboards). The objective is the probes' mismatch J = 1/2 sum_p
|x_p + u(x_p) - t_p|^2 / L^2 (L the part's size); its gradient takes one adjoint solve K^T lambda = dJ/du at the
equilibrium and dJ/dw = -d/dw [R(u, w) . lambda], chained through the SIMP law and the filter's transpose.

The design vector is global (every rank holds all cells, in the DG0 index map's global order): the filter and the
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
    H = H + sparse.identity(len(centres), format="csr") * radius          # the cell itself (distance 0)
    H = H @ sparse.diags(volumes)
    return sparse.diags(1.0 / np.asarray(H.sum(axis=1)).ravel()) @ H


class TargetPoints:
    """Probes snapped to their nearest displacement node (on the lowest rank owning one as near), and their
    target positions: the mismatch, and its derivative with respect to the owned displacement dofs."""

    def __init__(self, V: fem.FunctionSpace, points: np.ndarray, targets: np.ndarray, length: float):
        self.points, self.targets, self.length = np.atleast_2d(points), np.atleast_2d(targets), length
        comm = V.mesh.comm
        self.n = V.dofmap.index_map.size_local
        X = V.tabulate_dof_coordinates()[:self.n]
        self.node = np.full(len(self.points), -1)
        self.at = np.zeros_like(self.points)                  # the snapped nodes' positions
        for i, p in enumerate(self.points):
            dist = np.linalg.norm(X - p, axis=1) if len(X) else np.array([np.inf])
            k = int(np.argmin(dist))
            best = comm.allreduce(float(dist[k]), op=MPI.MIN)
            owner = comm.allreduce(comm.rank if dist[k] <= best else comm.size, op=MPI.MIN)
            if comm.rank == owner:
                self.node[i] = k
            self.at[i] = comm.allreduce(X[k] if comm.rank == owner else np.zeros(3), op=MPI.SUM)
        self.comm = comm

    def positions(self, u: fem.Function) -> np.ndarray:
        """x_p + u(x_p) of every probe, on every rank."""
        local = np.zeros_like(self.points)
        for i, k in enumerate(self.node):
            if k >= 0:
                local[i] = u.x.array[3 * k:3 * k + 3]
        return self.at + self.comm.allreduce(local, op=MPI.SUM)

    def mismatch(self, u: fem.Function) -> float:
        return 0.5 * float(np.sum((self.positions(u) - self.targets) ** 2)) / self.length ** 2

    def gradient(self, u: fem.Function, out: PETSc.Vec) -> None:
        """dJ/du into `out` (owned entries)."""
        out.set(0.0)
        miss = (self.positions(u) - self.targets) / self.length ** 2
        for i, k in enumerate(self.node):
            if k >= 0:
                out.array[3 * k:3 * k + 3] += miss[i]


class LayoutGradient:
    """J(rho) and dJ/drho for one model whose material is a LayoutMaterial: `solve(model)` runs its equilibrium."""

    def __init__(self, model, weight: fem.Function, cells: CellVector, targets: TargetPoints,
                 radius: float, penalty: float, solve):
        self.model, self.weight, self.cells, self.targets = model, weight, cells, targets
        self.penalty, self.solve = penalty, solve
        self.filter = density_filter(cells.centres, cells.volumes, radius)
        lam = self.adjoint = fem.Function(model.V, name="adjoint")
        test = ufl.TestFunction(model.V)
        if model.unknown is not model.u:
            raise SolveError("layout design: the displacement formulation only (no mixed u-p yet)")
        work = ufl.replace(model.residual, {test: lam})
        self.dwork_dw = fem.form(ufl.derivative(work, weight, ufl.TestFunction(weight.function_space)))
        self.K = fpetsc.create_matrix(model.compiled("jacobian"))
        self.ksp = make_ksp(None, "lu", "fem_forms_layout_", comm=model.mesh.comm)
        self.evaluations = 0

    def weights(self, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rho_f, w = rho_f^p)."""
        rho_f = self.filter @ rho
        return rho_f, rho_f ** self.penalty

    def value(self, rho: np.ndarray) -> float:
        """J at rho (the equilibrium solved from the last state)."""
        _, w = self.weights(rho)
        self.cells.fill(self.weight, w)
        report = self.solve(self.model)
        self.evaluations += 1
        if not report.converged:
            raise SolveError(f"layout design: no equilibrium for this layout ({report.message})")
        return self.targets.mismatch(self.model.u)

    def gradient(self, rho: np.ndarray) -> np.ndarray:
        """dJ/drho at the state `value(rho)` left: one adjoint solve."""
        model = self.model
        self.K.zeroEntries()
        fpetsc.assemble_matrix(self.K, model.compiled("jacobian"), bcs=model.bcs)
        self.K.assemble()
        self.ksp.setOperators(self.K)
        rhs = self.K.createVecLeft()
        self.targets.gradient(model.u, rhs)
        fpetsc.set_bc(rhs, model.bcs, scale=0.0)
        lam = self.K.createVecRight()
        self.ksp.solveTranspose(rhs, lam)
        if self.ksp.getConvergedReason() < 0:
            raise SolveError(f"layout design: the adjoint solve failed ({self.ksp.getConvergedReason()})")
        n = len(lam.array)
        self.adjoint.x.array[:n] = lam.array
        self.adjoint.x.scatter_forward()
        dw = fpetsc.assemble_vector(self.dwork_dw)
        dw.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dJ_dw = -self.cells.gather(dw.array[:self.cells.n_owned])
        rho_f, _ = self.weights(rho)
        dJ_drho_f = dJ_dw * self.penalty * rho_f ** (self.penalty - 1)
        return self.filter.T @ dJ_drho_f


def part_length(model) -> float:
    """The part's size for the mismatch's scale: its bounding box's diagonal (all ranks)."""
    x = model.mesh.geometry.x
    comm = model.mesh.comm
    lo = np.min(comm.allgather(x.min(axis=0) if len(x) else np.full(3, np.inf)), axis=0)
    hi = np.max(comm.allgather(x.max(axis=0) if len(x) else np.full(3, -np.inf)), axis=0)
    return float(np.linalg.norm(hi - lo)) or mesh_size(model.mesh)

