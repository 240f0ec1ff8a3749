"""Friction against the obstacles, lagged (IPC): over a step, each contact node's normal force and tangent plane are
held at their lagged values and its slip is measured from its anchor (where the step started, or where a designed
rest shape was put down), so friction is a smooth potential Newton can minimise. A static load step re-lags at its
equilibrium and solves again until the normal forces settle (IPC's lagging iterations): one big step then lands
where many small ones do, instead of sliding on the near-zero normal forces of the step's start."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from petsc4py import PETSc

from fem_forms.physics.contact.barrier import barrier_first
from fem_forms.physics.contact.friction import LaggedFriction, tangent_basis


@dataclass
class Lag:
    """What a step's friction is measured from: each surface node's anchor (n, 3), the slip eps, each obstacle's move
    over the step, and the normal forces (n,) it was last lagged with."""
    anchors: np.ndarray
    eps: float
    moves: list
    forces: np.ndarray = field(default_factory=lambda: np.zeros(0))


def lag_friction(term, p: np.ndarray, lag: Lag) -> list:
    """Per obstacle (None where frictionless or untouched) the LaggedFriction of the nodes within dhat at positions p,
    with the obstacles where they are now: normal forces and tangent planes at p, slips from lag's anchors. Records
    the nodes' normal forces against frictional obstacles in lag.forces."""
    surface = term.surface
    lag.forces = np.zeros(surface.size)
    out = []
    for ob, move in zip(term.obstacles, lag.moves):
        d, g = ob.derivatives(p, order=1)
        act = np.flatnonzero((d < term.dhat) & (d > 0))
        lam = -term.kappa * surface.area[act] * barrier_first(d[act], term.dhat)
        if ob.friction > 0:                         # what friction grips with: the re-lag's measure
            lag.forces[act] += lam
        out.append(LaggedFriction(act, lam, tangent_basis(g[act]), lag.anchors[act], ob.friction, lag.eps, move)
                   if ob.friction > 0 and len(act) else None)
    return out


def relag(term, x: PETSc.Vec, tolerance: float) -> float:
    """The relative change of the obstacles' friction's normal forces (sum |new - old| / sum |new|, 0 without
    friction) if it were re-lagged at the state x (anchors kept), the same on every rank; re-lagged only when that
    exceeds `tolerance` (else the state keeps the lag it was solved with: its residual stays at tolerance)."""
    lag = term.lag
    if lag is None or not any(ob.friction > 0 for ob in term.obstacles):
        return 0.0
    old, kept = lag.forces, term.friction
    term.friction = lag_friction(term, term.surface.positions(x), lag)
    new = lag.forces
    total = float(np.abs(new).sum())
    change = float(np.abs(new - old).sum()) / total if total > 0 else (0.0 if not np.abs(old).sum() else 1.0)
    change = term.surface.comm.bcast(change, root=0)
    if change <= tolerance:
        term.friction, lag.forces = kept, old
    return change
