"""What a layout design aims at: probes snapped to displacement nodes with target positions (in the coordinates
that count) and target angles (a segment between two probes turned about an axis); the mismatch J and dJ/du for
the adjoint's right-hand side, and the part's size that scales the positions' misses."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import SolveError
from fem_forms.meshes import mesh_size
from fem_forms.output.probes import nearest_nodes


@dataclass
class TargetAngle:
    """A segment's rotation about an axis as a target: the segment from probe `start` to probe `end` (indices into
    the targets' points), the angle (radians) it should turn by about the unit vector `axis`."""
    start: int
    end: int
    angle: float
    axis: np.ndarray


class TargetPoints:
    """Probes snapped to their nearest displacement node (on the lowest rank owning one as near), their target
    positions (only the `counted` coordinates count) and target angles (a segment between two probes turned about
    an axis): the mismatch, and its derivative with respect to the owned displacement dofs."""

    def __init__(self, V: fem.FunctionSpace, points: np.ndarray, targets: np.ndarray, length: float,
                 counted: np.ndarray | None = None, angles: tuple = ()):
        self.points, self.targets, self.length = np.atleast_2d(points), np.atleast_2d(targets), length
        self.counted = np.ones_like(self.points) if counted is None else np.asarray(counted, dtype=float)
        self.angles = tuple(angles)
        comm = V.mesh.comm
        self.node, self.at = nearest_nodes(V, self.points)      # the snapped nodes (local index on their owner)
        self.comm = comm
        for a in self.angles:
            if np.linalg.norm(self._frame(a)[0]) < 1e-9 * length:
                raise SolveError("layout design: a target angle's segment lies along its axis (its probes snapped "
                                 "to the same line): no rotation about it to measure")

    def positions(self, u: fem.Function) -> np.ndarray:
        """x_p + u(x_p) of every probe, on every rank."""
        local = np.zeros_like(self.points)
        for i, k in enumerate(self.node):
            if k >= 0:
                local[i] = u.x.array[3 * k:3 * k + 3]
        return self.at + self.comm.allreduce(local, op=MPI.SUM)

    def misses(self, u: fem.Function, x: np.ndarray | None = None) -> np.ndarray:
        """Position minus target of every probe, 0 in the coordinates that do not count (x: the positions, if
        known)."""
        return ((self.positions(u) if x is None else x) - self.targets) * self.counted

    def _frame(self, a: TargetAngle) -> tuple[np.ndarray, np.ndarray]:
        """(the rest segment's part across the axis, the axis cross it): the turned segment s has the angle
        atan2(b . s, a . s) about the axis (right-handed)."""
        s0 = self.at[a.end] - self.at[a.start]
        across = s0 - (s0 @ a.axis) * a.axis
        return across, np.cross(a.axis, across)

    def _angles(self, x: np.ndarray) -> list[tuple[float, np.ndarray]]:
        """Each target angle's (turned angle, d angle / d segment) at the positions x: atan2(n, c) of the
        segment's components c, n along the frame, its derivative (c b - n a) / (c^2 + n^2)."""
        out = []
        for a in self.angles:
            across, normal = self._frame(a)
            s = x[a.end] - x[a.start]
            c, n = across @ s, normal @ s
            out.append((float(np.arctan2(n, c)), (c * normal - n * across) / max(c * c + n * n, 1e-300)))
        return out

    def turned(self, u: fem.Function, x: np.ndarray | None = None) -> np.ndarray:
        """Each target angle's segment's rotation about its axis (radians, in (-pi, pi])."""
        return np.array([t for t, _ in self._angles(self.positions(u) if x is None else x)])

    def angle_misses(self, u: fem.Function, x: np.ndarray | None = None) -> np.ndarray:
        """Turned minus target angle of each target angle (radians, wrapped into [-pi, pi))."""
        target = np.array([a.angle for a in self.angles])
        return np.mod(self.turned(u, x) - target + np.pi, 2 * np.pi) - np.pi

    def mismatch(self, u: fem.Function) -> float:
        """J = 1/2 sum |miss|^2 / L^2 over the positions + 1/2 sum (angle miss)^2 (radians)."""
        x = self.positions(u)
        return 0.5 * float(np.sum(self.misses(u, x) ** 2)) / self.length ** 2 + \
            0.5 * float(np.sum(self.angle_misses(u, x) ** 2))

    def allowed(self, reach: float, reach_angle: float) -> float:
        """J when every position target is missed by `reach` (m) and every angle by `reach_angle` (radians): one
        budget, so a target nearer than its reach leaves room for another to be farther."""
        positions = int(np.count_nonzero(self.counted.any(axis=1)))
        return 0.5 * (positions * reach ** 2 / self.length ** 2 + len(self.angles) * reach_angle ** 2)

    def gradient(self, u: fem.Function, out: PETSc.Vec) -> None:
        """dJ/du into `out` (owned entries)."""
        out.set(0.0)
        x = self.positions(u)
        slope = self.misses(u, x) / self.length ** 2
        for a, miss, (_, d_angle) in zip(self.angles, self.angle_misses(u, x), self._angles(x)):
            slope[a.end] += miss * d_angle
            slope[a.start] -= miss * d_angle
        for i, k in enumerate(self.node):
            if k >= 0:
                out.array[3 * k:3 * k + 3] += slope[i]


def part_length(model) -> float:
    """The part's size for the mismatch's scale: its bounding box's diagonal (all ranks)."""
    x = model.mesh.geometry.x
    comm = model.mesh.comm
    lo = np.min(comm.allgather(x.min(axis=0) if len(x) else np.full(3, np.inf)), axis=0)
    hi = np.max(comm.allgather(x.max(axis=0) if len(x) else np.full(3, -np.inf)), axis=0)
    return float(np.linalg.norm(hi - lo)) or mesh_size(model.mesh)
