"""The array-term test problem: a soft neo-Hookean block under gravity, held by a spring
k/2 int_Gamma |u - u0|^2 ds on its bottom face, written either as a UFL term of the energy or as an array
term (energy 1/2 (x - x0)^T K_s (x - x0), gradient K_s (x - x0), Hessian K_s from the assembled K_s).
Run as a script (under mpirun) it solves both and writes the iterates to a JSON file:
`python tests/system/array_spring.py out.json`."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from fem_forms.physics.array_term import ArrayTerm, add_entries  # noqa: E402
from fem_forms.solvers.snes import NonlinearProblem, SNESDriver  # noqa: E402

E, NU, RHO, G, K = 3e4, 0.3, 1000.0, 9.81, 1e4
SIZE = (1.0, 0.2, 0.2)
CASES = {"clamped P1": dict(cells=(10, 2, 2), degree=1, clamped=True),     # 297 dofs
         "free P2": dict(cells=(4, 2, 2), degree=2, clamped=False)}         # 675 dofs, held by the spring only
AIJ = {"pc_factor_mat_solver_type": "superlu_dist"}                         # AIJ tangent (MUMPS: BAIJ)


class MatrixSpring(ArrayTerm):
    """1/2 (x - x0)^T K (x - x0) from an assembled matrix K."""
    name = "spring"

    def __init__(self, K: PETSc.Mat, x0: PETSc.Vec):
        self.K, self.x0 = K, x0
        indptr, self.cols, self.values = K.getValuesCSR()
        start = K.getOwnershipRange()[0]
        self.rows = start + np.repeat(np.arange(len(indptr) - 1), np.diff(indptr)).astype(PETSc.IntType)

    def _force(self, x: PETSc.Vec) -> tuple[PETSc.Vec, PETSc.Vec]:
        d = x.copy()
        d.axpy(-1.0, self.x0)
        f = self.K.createVecLeft()
        self.K.mult(d, f)
        return d, f

    def energy_value(self, x: PETSc.Vec) -> float:
        d, f = self._force(x)
        e = 0.5 * d.dot(f)
        d.destroy(), f.destroy()
        return e

    def add_gradient(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        d, f = self._force(x)
        b.array[:] += f.array
        d.destroy(), f.destroy()

    def add_hessian(self, x: PETSc.Vec, A: PETSc.Mat, constrained: np.ndarray) -> None:
        add_entries(A, self.rows, self.cols, self.values, constrained)


def spring_problem(as_array: bool, cells=(10, 2, 2), degree=1, clamped=True, comm=MPI.COMM_WORLD):
    """NonlinearProblem of the block, with the spring as a UFL term or as an array term."""
    msh = mesh.create_box(comm, [[0.0, 0.0, 0.0], list(SIZE)], list(cells), mesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", degree))
    u, v, du = fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    mu, lmbda = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    F = ufl.Identity(3) + ufl.grad(u)
    J = ufl.det(F)
    psi = mu / 2 * (ufl.tr(F.T * F) - 3) - mu * ufl.ln(J) + lmbda / 2 * ufl.ln(J) ** 2
    dx = ufl.dx(metadata={"quadrature_degree": 2 * degree})
    bottom = mesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[2], 0.0))
    tags = mesh.meshtags(msh, 2, bottom, np.ones(len(bottom), dtype=np.int32))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags, metadata={"quadrature_degree": 2 * degree})
    u0 = fem.Function(V)                                   # the spring's anchor: rises along the block
    u0.interpolate(lambda x: np.vstack([0.0 * x[0], 0.0 * x[0], 0.05 * x[0]]))
    Pi = psi * dx - RHO * ufl.dot(ufl.as_vector((0.0, 0.0, -G)), u) * dx
    spring = 0.5 * K * ufl.inner(u - u0, u - u0) * ds(1)
    bcs = []
    if clamped:                                            # x = 0, sharing the edge z = 0 with the spring
        dofs = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0))
        bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), dofs, V)]
    terms = []
    if as_array:
        Ks = fpetsc.assemble_matrix(fem.form(K * ufl.inner(du, v) * ds(1)))
        Ks.assemble()
        terms = [MatrixSpring(Ks, u0.vector.copy())]
    else:
        Pi = Pi + spring
    R = ufl.derivative(Pi, u, v)
    return NonlinearProblem(u, R, ufl.derivative(R, u, du), bcs, energy=Pi, array_terms=terms)


def by_coordinates(V: fem.FunctionSpace, values: np.ndarray) -> np.ndarray | None:
    """Owned nodal values of a vector field gathered to rank 0 and sorted by the nodes' coordinates (the
    same order on any number of ranks); None on other ranks."""
    n = V.dofmap.index_map.size_local
    xyz = np.round(V.tabulate_dof_coordinates()[:n], 12)
    parts = V.mesh.comm.gather((xyz, values[: 3 * n].reshape(-1, 3)), root=0)
    if parts is None:
        return None
    xyz, vals = (np.concatenate(p) for p in zip(*parts))
    return vals[np.lexsort(xyz.T[::-1])]


def solve(problem: NonlinearProblem, options: dict | None = None):
    """(driver, step record, iterates sorted by coordinates on rank 0)."""
    drv = SNESDriver(problem, options)
    iterates = []
    drv.snes.setMonitor(lambda snes, it, fnorm: iterates.append(
        by_coordinates(problem.u.function_space, snes.getSolution().array)))
    rec = drv.solve_step()
    return drv, rec, iterates


def run(case: str, options: dict | None = None) -> dict | None:
    """Both spring variants of one case: histories and iterates (rank 0; None elsewhere)."""
    out = {}
    for kind in ("ufl", "array"):
        _, rec, its = solve(spring_problem(kind == "array", **CASES[case]), options)
        out[kind] = dict(history=rec.residuals, reason=rec.reason, iterations=rec.iterations,
                         iterates=None if its[0] is None else [i.tolist() for i in its])
    return out if MPI.COMM_WORLD.rank == 0 else None


if __name__ == "__main__":
    results = {f"{case}|{name}": run(case, opts) for case in CASES for name, opts in (("baij", None), ("aij", AIJ))}
    if MPI.COMM_WORLD.rank == 0:
        Path(sys.argv[1]).write_text(json.dumps(results))
