"""Values a user can change that are not material constants: the density field (cellwise, so a design
can carve it) lives here as a fem.Function; a new value or field compiles nothing."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
import numpy as np
import ufl

# UFL sorts the operands of a sum by the repr of the Constants in them, and a Constant's repr holds its
# count as a decimal string: across a digit boundary (9 -> 10, 99 -> 100) the order flips, the form's
# signature changes and a form whose values merely changed compiles again (measured: the tangent of the
# second model built in one process). Counting from 10^9 gives every count the same width.
CONSTANT_COUNT_BASE = 10**9
if ufl.Constant._globalcount < CONSTANT_COUNT_BASE:
    ufl.Constant._globalcount = CONSTANT_COUNT_BASE


class Parameters:
    """The model's changeable fields: `density` is a DG0 Function (kg/m^3 per cell)."""

    def __init__(self, mesh: dmesh.Mesh, density: float):
        self.mesh = mesh
        self.density = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name="density")
        self.set_density(density)

    def set_density(self, value: float | np.ndarray) -> None:
        """A uniform density, or one value per local cell (owned cells first, as the DG0 dofs)."""
        arr = self.density.x.array
        if np.ndim(value) == 0:
            arr[:] = float(value)
        else:
            value = np.asarray(value, dtype=float)
            nown = self.density.function_space.dofmap.index_map.size_local
            arr[:nown] = value[:nown]
        self.density.x.scatter_forward()
