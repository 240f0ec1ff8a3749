"""What results.json says of each obstacle after a solve: the force it exerts, the area touching it, the largest
pressure, the points within the barrier's range, and (with friction) how much of Coulomb's cone the tangential
forces use: a part that is to stand must not slide."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from fem_forms.physics.contact.barrier import barrier_first


def obstacle_reports(term, x: PETSc.Vec) -> dict:
    """{obstacle name: {force (N, by the obstacle on the part), area (m^2 of the rest surface's triangles whose
    nodes are all within dhat), max_pressure (Pa), active_points (nodes within dhat), and with friction
    friction_force (N, the tangential part of force), friction_use (the largest |f_t| / (mu f_n) over the active
    nodes: 1 is on the cone, sliding) and sliding_points (nodes whose slip in the step passed the friction's
    smoothing eps: kinetic, not sticking)}} at the state x."""
    surface = term.surface
    p = surface.positions(x)
    out = {}
    friction = term.friction or [None] * len(term.obstacles)
    for ob, (act, d, *_), (_, nodal), fr in zip(term.obstacles, term._gaps(p), term.nodal_forces(x), friction):
        pressure = -term.kappa * barrier_first(d, term.dhat)
        touching = np.zeros(surface.size, bool)
        touching[act] = True
        entry = {"force": nodal.sum(axis=0).tolist(),
                 "area": float(surface.face_areas()[touching[surface.faces].all(axis=1)].sum()),
                 "max_pressure": float(pressure.max(initial=0.0)), "active_points": int(len(act))}
        if fr is not None:
            tangential = nodal[len(act):]                   # nodal_forces: the pushes, then the friction nodes'
            use = np.linalg.norm(tangential, axis=1) / (fr.mu * np.maximum(fr.normal_force, 1e-300))
            slip = np.linalg.norm(fr.slip(p), axis=1)
            entry.update(friction_force=tangential.sum(axis=0).tolist(), friction_use=float(use.max(initial=0.0)),
                         sliding_points=int(np.sum(slip >= fr.eps)))
        out[ob.name] = entry
    return out
