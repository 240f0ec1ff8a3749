"""The bounded-field test problem: a scalar P1 field d on the unit square minimizing
int 1/2 (d - t g)^2 + k/4 d^4 (vertex quadrature: nodally decoupled) + l^2/2 |grad d|^2 dx
with lo <= d <= 1, where g = 2x - 0.5 + 0.3 sin(pi y) crosses both bounds. With l = 0 (and k = 0) the
answer is clip(t g, lo, 1) at the nodes. Run as a script (under mpirun) it solves the cases of `cases()`
and writes the nodal values, sorted by coordinates, to a JSON file: `python tests/system/bounded_field.py out.json`."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from fem_forms.solvers.snes import NonlinearProblem, SNESDriver  # noqa: E402
from fem_forms.state import State  # noqa: E402

LO, N = 0.1, 8
VERTEX = {"quadrature_rule": "vertex", "quadrature_degree": 1}


def g_shape(x: np.ndarray) -> np.ndarray:
    return 2.0 * x[0] - 0.5 + 0.3 * np.sin(np.pi * x[1])


def bounded_problem(ell: float = 0.0, k: float = 0.0, lower=LO, upper=1.0, n: int = N,
                    bc_value: float | None = None, comm=MPI.COMM_WORLD):
    """(problem, load constant t, g Function) for the field d; `bc_value`: d prescribed on x = 0."""
    domain = mesh.create_unit_square(comm, n, n)
    V = fem.FunctionSpace(domain, ("Lagrange", 1))
    d, g = fem.Function(V, name="damage"), fem.Function(V, name="g")
    g.interpolate(g_shape)
    t = fem.Constant(domain, 1.0)
    dxv = ufl.dx(metadata=VERTEX)
    ell2, kk = fem.Constant(domain, float(ell) ** 2), fem.Constant(domain, float(k))
    energy = ((0.5 * (d - t * g) ** 2 + 0.25 * kk * d ** 4) * dxv
              + 0.5 * ell2 * ufl.inner(ufl.grad(d), ufl.grad(d)) * ufl.dx)
    residual = ufl.derivative(energy, d, ufl.TestFunction(V))
    jacobian = ufl.derivative(residual, d, ufl.TrialFunction(V))
    bcs = []
    if bc_value is not None:
        dofs = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0))
        bcs = [fem.dirichletbc(bc_value, dofs, V)]
    state = State({"damage": d})
    if lower == "old":
        lower = state.old["damage"]
    p = NonlinearProblem(d, residual, jacobian, bcs, energy=energy, state=state, bounds=(lower, upper))
    return p, t, g


def nodal(f: fem.Function) -> tuple[np.ndarray, np.ndarray]:
    """(coordinates, values) of the owned dofs of a P1 scalar field on all ranks, sorted by coordinates."""
    V = f.function_space
    owned = V.dofmap.index_map.size_local
    xy = V.tabulate_dof_coordinates()[:owned, :2]
    comm = V.mesh.comm
    xy, vals = np.vstack(comm.allgather(xy)), np.concatenate(comm.allgather(f.x.array[:owned]))
    order = np.lexsort((np.round(xy[:, 1], 12), np.round(xy[:, 0], 12)))
    return xy[order], vals[order]


def gradient(drv: SNESDriver) -> np.ndarray:
    """The energy gradient (residual, constrained rows x - g) at the driver's state, owned dofs."""
    x, r = drv.p.u.vector.copy(), drv.b.duplicate()
    drv._residual(None, x, r)
    return r.array.copy()


def cases() -> dict:
    """The cases the 2-rank run repeats: nodal values of the separable, coupled and irreversible solves."""
    out = {}
    for name, kw in (("separable", {}), ("coupled", {"ell": 0.2, "k": 0.5})):
        p, t, g = bounded_problem(**kw)
        rec = SNESDriver(p).solve_step()
        out[name] = {"reason": rec.reason, "values": nodal(p.u)[1].tolist()}
    p, t, g = bounded_problem(ell=0.2, lower="old")
    drv = SNESDriver(p)
    for load in (1.0, 0.5):
        t.value = load
        drv.solve_step()
        p.state.commit()
    out["irreversible"] = {"values": nodal(p.u)[1].tolist()}
    return out


if __name__ == "__main__":
    result = cases()
    if MPI.COMM_WORLD.rank == 0:
        Path(sys.argv[1]).write_text(json.dumps(result))
