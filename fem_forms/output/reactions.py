"""Support reactions and the global equilibrium check of a solved model.

Reactions: the residual R(u) = f_int - f_ext (model.residual: dPi/du plus non-conservative virtual
work) assembled at the answer WITHOUT the Dirichlet rows. At a free dof R vanishes (equilibrium); at a
held dof it is the force the support must add for equilibrium, i.e. the force the support exerts on
the body. Per support and component, R is summed over the dofs that support holds (owned dofs only,
then summed over ranks). A component a support does not hold gets 0: a roller exerts no force along
its free direction. A dof held by several supports counts for the first of them in scene order, so
the reactions add up to the total support force exactly once.

Applied loads: each load term's resultant, integrated directly (not summed from the assembled
vector): the force along a constant direction e is minus the derivative of the load's energy in the
direction e (gravity: int rho g . e dX with the density field; dead traction: int T . e dA) or minus
its virtual work at v = e (follower pressure: -int p J F^-T N . e dA, on the deformed surface).
"""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.scene.spec import fix_names


def support_forces(model, b: PETSc.Vec | None = None) -> np.ndarray:
    """(number of fixes, 3): the force each support exerts on the body, summed over all ranks. `b`: the residual
    to read them from (a dynamic run's, with the inertia; its owner destroys it), else the model's, assembled."""
    own = b is None
    if own:
        b = fpetsc.assemble_vector(model.compiled("residual"))
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        for term in model.terms.arrays:                      # contact at a held node is part of its reaction
            term.add_gradient(model.unknown.vector, b)
        b.assemble()
    residual = b.array                                   # owned entries only
    held = np.zeros(len(residual), dtype=bool)
    forces = np.zeros((len(model.scene.fix), 3))
    for bc, (fix, component) in zip(model.bcs, model.support_owners):
        dofs = bc.dof_indices()[0]
        dofs = dofs[dofs < len(residual)]
        dofs = dofs[~held[dofs]]
        held[dofs] = True
        forces[fix, component] += residual[dofs].sum()
    if own:
        b.destroy()
    total = np.zeros_like(forces)
    model.mesh.comm.Allreduce(forces, total, op=MPI.SUM)
    return total


def applied_load(model) -> np.ndarray:
    """Resultant [Fx, Fy, Fz] of all load terms at the current state and load factor (all ranks)."""
    ctx = model.context
    loads = model.loads
    if not loads:
        return np.zeros(3)
    shape = model.unknown.ufl_shape
    direction = fem.Constant(model.mesh, PETSc.ScalarType(np.zeros(shape)))
    v = ufl.as_vector([direction[i] for i in range(3)])     # its displacement part
    parts = []
    for term in loads:
        energy = term.energy(ctx)
        if energy is not None:           # a first variation by hand where there is one (UFL 2022.2 cannot take
            by_hand = term.first_variation(ctx, v)   # d det F along a Constant in a mixed space)
            parts.append(by_hand if by_hand is not None else ufl.derivative(energy, model.unknown, direction))
        work = term.virtual_work(ctx, v)
        if work is not None:
            parts.append(work)
    form = fem.form(sum(parts[1:], parts[0]))
    out = np.zeros(3)
    for i in range(3):
        value = np.zeros(shape)
        value[i] = 1.0
        direction.value = value
        out[i] = -model.mesh.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM)
    return out


# reactions and loads are "above round-off" when their scale exceeds this many times the residual norm the
# solve was accepted at (N): below it their sum is the solver's noise, and a ratio of two noises (0.84 was
# seen on a freely expanding heated strip whose reactions and loads were both ~1e-13 N) would read as an error
ROUNDOFF_FACTOR = 1e3


def equilibrium_error(reactions: np.ndarray, load: np.ndarray, noise: float = 0.0) -> float | None:
    """|sum of reactions + applied load| relative to the larger of |applied load| and the sum of the
    reactions' magnitudes; None when that scale is within ROUNDOFF_FACTOR of the solve's residual `noise`
    (N) or zero: then only the absolute imbalance means anything."""
    scale = max(float(np.linalg.norm(load)), float(np.linalg.norm(reactions, axis=1).sum()))
    if scale <= ROUNDOFF_FACTOR * noise or scale == 0.0:
        return None
    return equilibrium_imbalance(reactions, load) / scale


def equilibrium_imbalance(reactions: np.ndarray, load: np.ndarray) -> float:
    """|sum of reactions + applied load| in N."""
    return float(np.linalg.norm(reactions.sum(axis=0) + load))


def reaction_report(model, noise: float = 0.0) -> dict:
    """results.json entries: reactions {fix name: [Fx, Fy, Fz]}, applied_load, equilibrium_imbalance (N: of
    the reactions, the obstacles' contact forces and the applied load) and
    equilibrium_error (relative; null when loads and reactions are at the round-off of a solve whose
    accepted residual norm is `noise`, N)."""
    forces = support_forces(model)
    load = applied_load(model)
    held = np.vstack([forces, model.terms.support_forces(model.unknown.vector)])
    return {"reactions": {n: f.tolist() for n, f in zip(fix_names(model.scene.fix), forces)},
            "applied_load": load.tolist(),
            "equilibrium_error": equilibrium_error(held, load, noise),
            "equilibrium_imbalance": equilibrium_imbalance(held, load)}
