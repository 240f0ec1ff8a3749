"""Is a state physical? The smallest value of an expression (det F, a rest-volume ratio) over all quadrature
points of all ranks: compiled once, evaluated after every Newton solve."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np

from fem_forms.physics import quadrature


def quadrature_points(mesh: dmesh.Mesh, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The rule (points, weights) the forms' dx uses at this degree on the mesh's cell (physics/quadrature.py:
    basix's default, or Gauss-Jacobi where the default has a non-positive weight)."""
    return quadrature.points(mesh.topology.cell_name(), degree)


class SmallestValue:
    """min over the quadrature points of every owned cell on every rank of a scalar UFL expression."""

    def __init__(self, expr, mesh: dmesh.Mesh, degree: int):
        self.mesh = mesh
        self.expression = fem.Expression(expr, quadrature_points(mesh, degree)[0])
        self.cells = np.arange(mesh.topology.index_map(mesh.topology.dim).size_local, dtype=np.int32)

    def __call__(self) -> float:
        vals = self.expression.eval(self.cells)
        local = float(vals.min()) if vals.size else np.inf
        return self.mesh.comm.allreduce(local, op=MPI.MIN)

    def positive_or(self, message: str) -> str | None:
        """None if the smallest value is positive and finite, else `message` formatted with {value}."""
        value = self()
        return None if np.isfinite(value) and value > 0 else message.format(value=value)
