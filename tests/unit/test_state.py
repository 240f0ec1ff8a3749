"""State changes only through commit/rollback: a cut-back leaves no trace in fields or history variables.
History lives on a quadrature space, filled by fem.Expression (STACK.md: quadrature spaces cannot be
interpolated into in dolfinx 0.5.2)."""
import basix
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.solvers import continuation, snes
from fem_forms.state import State

QDEG = 2


def quadrature_history(u: fem.Function):
    """A scalar history variable on the degree-2 quadrature space and its update |u|^2 at the points."""
    mesh = u.function_space.mesh
    element = ufl.FiniteElement("Quadrature", mesh.ufl_cell(), QDEG, quad_scheme="default")
    Q = fem.FunctionSpace(mesh, element)
    h = fem.Function(Q, name="h")
    points, _ = basix.make_quadrature(basix.CellType.tetrahedron, QDEG)
    expr = fem.Expression(ufl.dot(u, u), points)
    ncells = mesh.topology.index_map(3).size_local
    cells = np.arange(ncells, dtype=np.int32)
    dofs = Q.dofmap.list.array.reshape(-1, len(points))[:ncells]

    def update():
        values = h.x.array.copy()
        values[dofs.ravel()] = expr.eval(cells).ravel()
        return values
    return h, update


def small_space():
    mesh = dmesh.create_unit_cube(MPI.COMM_WORLD, 2, 2, 2)
    return fem.VectorFunctionSpace(mesh, ("Lagrange", 1))


def test_commit_updates_history_and_rollback_restores_everything():
    V = small_space()
    u = fem.Function(V)
    u.x.array[:] = 1.0
    h, update = quadrature_history(u)
    state = State({"u": u})
    state.add_history("h", h, update)
    state.commit()
    assert np.allclose(h.x.array, 3.0)                 # |(1, 1, 1)|^2 at every quadrature point
    assert np.allclose(state.old["u"].x.array, 1.0)
    u.x.array[:] = 2.0
    h.x.array[:] = -7.0                                # a trial value that must not survive
    state.rollback()
    assert np.allclose(u.x.array, 1.0) and np.allclose(h.x.array, 3.0)
    u.x.array[:] = 2.0
    state.commit()
    assert np.allclose(h.x.array, 12.0) and np.allclose(state.old["h"].x.array, 12.0)
    assert state.commits == 2


def test_a_rejected_load_step_leaves_no_trace_in_the_history():
    """Continuation with one step forced to fail: the history equals its update at the accepted answer,
    and was committed once per accepted step (plus the start), never for the rejected one."""
    V = small_space()
    u = fem.Function(V)
    v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
    target = fem.Constant(V.mesh, np.array([0.3, -0.1, 0.2]))
    lam = fem.Constant(V.mesh, 1.0)
    energy = 0.5 * ufl.dot(u - lam * target, u - lam * target) * ufl.dx
    residual = ufl.derivative(energy, u, v)
    h, update = quadrature_history(u)
    state = State({"u": u})
    state.add_history("h", h, update)
    calls = {"n": 0}

    def reject_once():
        calls["n"] += 1
        return "forced rejection" if calls["n"] == 1 else None

    def set_load(value):
        lam.value = value
    problem = snes.NonlinearProblem(u, residual, ufl.derivative(residual, u, du), [], energy=energy,
                                    set_load=set_load, inadmissible=reject_once, state=state)
    report = continuation.solve(problem, steps=1)
    assert report.converged
    accepted = sum(1 for s in report.steps if s.accepted)
    assert len(report.steps) == accepted + 1                 # exactly one rejection
    assert state.commits == accepted + 1                     # start + accepted steps only
    assert np.allclose(u.x.array.reshape(-1, 3), [0.3, -0.1, 0.2])
    assert np.allclose(h.x.array, 0.3**2 + 0.1**2 + 0.2**2)
