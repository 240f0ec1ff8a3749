"""Contact on a designed rest shape (the adjoint inverse design of a part standing on a table): the surface follows
the rest shape mesh + d, whose sole (the target's nodes within the barrier's range) keeps the target's height above
the table; friction is lagged with its slips measured from the rest shape (a part that sticks keeps its sole where it
was put down, whatever path the design took to this d), so its Hessian, which the adjoint needs apart, depends on u
alone."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.physics.contact.lagging import Lag, lag_friction
from fem_forms.physics.contact.term import SLIP_RATE


@dataclass
class StandingRest:
    """A contact term whose part's rest shape is mesh + d (`offset`), standing on obstacles whose normal at the
    target's contact points is the coordinate axis `axis` (`normal`: the unit vector). The sole (`sole`: the
    target's surface nodes within the barrier's range) keeps its height along that axis in the rest shape: a soft
    part is cast with the sole it stands on, which the table then holds flat (to within the barrier's gap)."""
    term: object
    offset: fem.Function
    normal: np.ndarray
    axis: int
    sole: np.ndarray

    @classmethod
    def of(cls, term) -> "StandingRest":
        """From the contact term of a designed rest shape; InputError when the target touches no obstacle or touches
        one whose normal there is not along a coordinate axis (a table, a box's face)."""
        rest = term.mesh_rest
        near = [ob.distance(rest) < term.dhat for ob in term.obstacles]
        sole = np.flatnonzero(np.any(near, axis=0))
        if not len(sole):
            raise InputError(f"contact: the target touches no obstacle (none within contact.distance = "
                             f"{term.dhat:.3g} m of it); a part standing on a table is designed from a target resting "
                             "on it")
        normals = np.concatenate([ob.derivatives(rest[m], order=1)[1] for ob, m in zip(term.obstacles, near)])
        normal = normals.mean(axis=0)
        if np.linalg.norm(normal) < 0.5:
            raise InputError("contact: the target touches obstacles on opposite sides (held between them): a part "
                             "standing on a table is designed with the table below it")
        normal /= np.linalg.norm(normal)
        axis = int(np.argmax(np.abs(normal)))
        if np.abs(normals[:, axis]).min() < 1.0 - 1e-9:
            raise InputError("contact: a part standing on obstacles is designed where they are flat with a normal "
                             "along x, y or z at the target's contact points (a table, a box's face); this target "
                             "touches a slope or a curved obstacle")
        return cls(term, term.rest_offset, np.eye(3)[axis] * np.sign(normal[axis]), axis, sole)

    def follow_rest(self) -> float:
        """The surface's rest positions at mesh + d; their smallest distance to the obstacles (m: the rest shape
        must be put down above them)."""
        t = self.term
        t.surface.rest = t.mesh_rest + t.surface.displacement(self.offset.vector)
        return min(float(ob.distance(t.surface.rest).min()) for ob in t.obstacles)

    def lag(self) -> None:
        """Friction anchored at the rest shape put down (its normal forces and tangent planes at the current state:
        at rest, none), eps of the whole load: one quasi-static step from rest, which the static solve then re-lags
        at each equilibrium until the normal forces settle (lagging.py), as a static run of the rest shape does."""
        t = self.term
        t.lag = Lag(t.surface.rest.copy(), SLIP_RATE * t.diagonal, [np.zeros(3)] * len(t.obstacles))
        t.friction = lag_friction(t, t.surface.positions(t.state), t.lag)

    def add_barrier_hessian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """The obstacles' barrier Hessian alone into A (all rows): the barrier depends on X + u, so the rest shape
        moves it as u does."""
        self.term.add_hessian(x, A, np.empty(0, PETSc.IntType), friction=False)

    def add_friction_hessian(self, x: PETSc.Vec, A: PETSc.Mat, constrained: np.ndarray) -> None:
        """The anchored friction's Hessian alone into A, constrained rows and columns left out."""
        self.term.add_hessian(x, A, constrained, barrier=False)
