"""Optimisers of the adjoint design: damped Gauss-Newton (default) and PETSc TAO bounded L-BFGS."""
from __future__ import annotations

import time

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.design.adjoint import AdjointDesign
from fem_forms.design.forward_on_rest import ForwardOnRest
from fem_forms.design.parameters import InverseResult, target_scene
from fem_forms.meshes import LoadedMesh, load_mesh, mesh_size
from fem_forms.physics.cavities import cavity_report
from fem_forms.scene import Scene
from fem_forms.solvers.linear import make_ksp, make_tao

class _GaussNewtonOperator:
    """PETSc shell-matrix and shell-preconditioner context for the damped Gauss-Newton matrix."""

    def __init__(self, design: AdjointDesign):
        self.design = design

    def mult(self, mat, x, y):
        self.design.gauss_newton_product(x, y)

    def apply(self, pc, x, y):
        self.design.precondition(x, y)


# J is known to about this relative precision: the forward solves converge to 1e-9..1e-10 of the load
# scale (measured: J at trial points within 1e-8 J of each other once the gradient vanishes)
J_PRECISION = 1e-8


def _gauss_newton(design: AdjointDesign, spec, J_stop: float, history: list, scale_len: float):
    """Gauss-Newton with Levenberg-Marquardt damping: each step solves (A^T (W + lam D) A + R) s = -g
    by CG, matrix-free through K's factors and preconditioned by the inverse-elastostatics tangent
    (AdjointDesign.precondition). D, an H1 inner product, damps the predicted change of the deformed
    shape: the step shortens along the directions where the linearised forward map is least reliable,
    where a line search would shorten all of it. The step is kept when J falls by a fair share of the
    model's prediction, and lam shrinks or grows with that agreement (Nielsen's rule). Trial forward
    solves start from the linear predictor u + du(s) and do not fall back to load continuation (a
    failed trial is a rejected step)."""
    comm = design.fwd.mesh.comm
    n = design.n
    d = np.zeros(n)
    bound = spec.max_move
    H = PETSc.Mat().createPython(((n, None), (n, None)), _GaussNewtonOperator(design), comm=comm)
    H.setUp()
    cg = make_ksp(H, "cg-python", "fem_forms_gn_", {"ksp_rtol": 1e-3, "ksp_max_it": 200},
                  python_pc=_GaussNewtonOperator(design))
    out = design.evaluate(d)
    if out is None:
        return d, False, "no forward equilibrium at the target shape itself", 0
    J, g = out
    history.append({"J": J, "cg": 0})
    u_ok = design.fwd.u.x.array[:n].copy()
    lam, grow = 1e-3, 2.0
    dot = lambda a, b: comm.allreduce(float(a @ b), op=MPI.SUM)
    for it in range(1, spec.iterations + 1):
        gv, sv, Hs = design.vec(), design.vec(), design.vec()
        gv.array[:] = -g
        design.set_damping(lam)
        cg.solve(gv, sv)
        design.damping = 0.0
        trial = d + sv.array
        if bound is not None:
            trial = np.clip(trial, -bound, bound)
        trial[design.fixed] = 0.0
        s = trial - d
        sv.array[:] = s
        design.gauss_newton_product(sv, Hs)
        predicted = -(dot(g, s) + 0.5 * dot(s, Hs.array))
        J_trial = design.forward(trial, guess=u_ok + design.linear_response(s), fallback=False)
        rho = (J - J_trial) / predicted if J_trial is not None and predicted > 0 else -1.0
        if rho > 1e-4:
            d, J = trial, J_trial
            g = design.linearise()
            u_ok = design.fwd.u.x.array[:n].copy()
            lam, grow = lam * max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), 2.0
        else:
            design.fwd.u.x.array[:n] = u_ok
            design.fwd.u.x.scatter_forward()
            design.fwd.d.x.array[:n] = d
            design.fwd.d.x.scatter_forward()
            lam, grow = lam * grow, 2.0 * grow
        history.append({"J": J, "cg": cg.getIterationNumber(), "damping": lam, "ratio": rho,
                        "accepted": bool(rho > 1e-4)})
        if J <= J_stop:
            return d, True, f"mismatch below tolerance, J = {J:.3e}", it
        if np.sqrt(dot(g, g)) <= spec.tolerance * abs(J):
            return d, True, f"relative gradient below tolerance, J = {J:.3e}", it
        if rho > 1e-4 and comm.allreduce(float(np.abs(s).max()) if n else 0.0, op=MPI.MAX) <= 1e-14 * scale_len:
            return d, True, f"step below round-off, J = {J:.3e}", it
        if J_trial is not None and predicted <= J_PRECISION * abs(J):
            return d, True, f"predicted decrease {predicted:.1e} below the precision of J = {J:.3e}", it
        if lam > 1e12:
            why = f"; the last trial had no forward equilibrium: {design.last_failure}" if J_trial is None else ""
            return d, J <= J_stop, f"no descent found at iteration {it} (damping {lam:.1e}), J = {J:.3e}{why}", it
    return d, False, f"no convergence in {spec.iterations} iterations, J = {J:.3e}", spec.iterations


def _lbfgs(design: AdjointDesign, spec, J_stop: float, history: list, mesh):
    """PETSc TAO bounded L-BFGS (BLMVM) on z = sqrt(m / V) d, m the lumped mass, V the volume: steps
    then approximate the L2 inner product and do not degrade as the mesh is refined."""
    fwd, n, comm = design.fwd, design.n, design.fwd.mesh.comm
    w = ufl.TestFunction(fwd.V)
    one = fem.Constant(mesh, PETSc.ScalarType((1.0, 1.0, 1.0)))
    lumped = fpetsc.assemble_vector(fem.form(ufl.dot(w, one) * fwd.dx))
    lumped.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    volume = comm.allreduce(float(lumped.array[:n].sum()) / 3, op=MPI.SUM)
    scale = np.sqrt(np.abs(lumped.array[:n]) / volume)    # a first step d -= mismatch, as fixed point
    x = design.vec()
    x.set(0.0)

    def objgrad(tao, xv, gv):
        out = design.evaluate(xv.array / scale)
        if out is None:                          # no equilibrium there: a line-search step too far
            gv.set(0.0)
            return 1e30
        gv.array[:] = out[1] / scale
        history.append({"J": out[0]})
        return out[0]

    def converged(tao):
        its, f, gnorm = tao.getSolutionStatus()[:3]
        if f <= J_stop:
            tao.setConvergedReason(8)            # TAO_CONVERGED_USER: mismatch small enough
        elif gnorm <= spec.tolerance * abs(f):
            tao.setConvergedReason(4)            # TAO_CONVERGED_GRTOL
        elif its >= spec.iterations:
            tao.setConvergedReason(-2)           # TAO_DIVERGED_MAXITS
        else:
            tao.setConvergedReason(0)

    tao = make_tao(comm, "blmvm", "fem_forms_tao_")
    tao.setObjectiveGradient(objgrad, x.duplicate())
    lb, ub = x.duplicate(), x.duplicate()
    big = 1e20 if spec.max_move is None else spec.max_move
    lb.array[:] = -big * scale
    ub.array[:] = big * scale
    lb.array[design.fixed] = 0.0
    ub.array[design.fixed] = 0.0
    tao.setVariableBounds(lb, ub)
    tao.setConvergenceTest(converged)
    tao.solve(x)
    reason, its = tao.getConvergedReason(), tao.getIterationNumber()
    d = x.array / scale
    tao.destroy()
    return d, reason > 0, f"TAO BLMVM reason {reason} after {its} iterations", its

def solve_adjoint(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Minimise J over rest shapes mesh + d subject to forward equilibrium. Converged when the
    mismatch J falls below 1/2 (tolerance x mesh size)^2, or the gradient below tolerance x J."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    fwd = ForwardOnRest(scene, material, loaded)
    V = fwd.V
    design = AdjointDesign(fwd)
    spec = scene.inverse
    size = mesh_size(loaded.mesh)
    J_stop = 0.5 * (spec.tolerance * size) ** 2
    history: list = []
    if spec.optimizer == "lbfgs":
        d, ok, msg, its = _lbfgs(design, spec, J_stop, history, loaded.mesh)
    else:
        d, ok, msg, its = _gauss_newton(design, spec, J_stop, history, size)
    final = design.evaluate(d, gradient=False)            # the forward state at the answer
    ok = ok and final is not None
    v = fem.Function(V, name="rest_minus_target")
    v.x.array[:design.n] = d
    v.x.scatter_forward()
    res = InverseResult("adjoint", v, loaded, ok, its, msg, history=history, forward_solves=fwd.solves,
                        physics=fwd.physics, free_direction=design.free_direction)
    if final is not None:
        res.deformed_offset = fem.Function(V, name="deformed_minus_target")
        res.deformed_offset.x.array[:] = v.x.array + fwd.u.x.array
    res.cavities = cavity_report(fwd.terms)     # the pressure and the rest volume at the design's equilibrium
    res.solve_time = time.perf_counter() - t0
    return res
