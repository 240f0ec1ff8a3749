"""Bound constraints lower <= u <= upper on the one unknown of a NonlinearProblem, for PETSc's VI solvers
(vinewtonrsls): the bound vectors in the unknown's layout, refreshed before every solve (a bound may be a
field's committed old value, which changes between steps: damage irreversibility d >= d_old), and the
residual measure a bounded solve is judged by (the KKT violation, not the raw residual)."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

Bound = fem.Function | float | None      # None (or +-inf): unbounded on that side

# The line search of vinewtonrsls with the energy objective, measured in petsc4py 3.18 on
# tests/system/bounded_field.py (l 0.2, quartic k 20 and 200, both bounds active, from d = 0): bt calls the
# objective (9-11 times), the energy falls at every iterate, 4-5 Newton steps; l2 converges too but with
# 200-300 objective calls and a rising energy at k 20; basic and cp never call it (basic: rising energy,
# 6-7 steps); nleqerr stops with an error (its KSP sees the full vector against the reduced system).
VI_LINE_SEARCH = "bt"
# A dof counts as sitting on a bound within this distance: PETSc's own active-set test
# (SNESVIGetActiveSetIS, 1e-8 absolute), so our KKT measure judges the state as the VI solver did.
ACTIVE = 1e-8


class Bounds:
    """lower <= u <= upper for a driver's unknown. Constrained (Dirichlet) dofs keep their set_bc values:
    there the bounds are widened to contain the prescribed value, so bounds never contradict supports."""

    def __init__(self, u: fem.Function, bounds: tuple[Bound, Bound], bcs: list):
        self.u, self.bcs = u, bcs
        self.lower_spec, self.upper_spec = bounds
        self.lower, self.upper = u.vector.copy(), u.vector.copy()
        self.refresh()

    def refresh(self) -> None:
        """Fill the bound vectors from their Functions or numbers, and widen them at constrained dofs."""
        for vec, spec, infinite in ((self.lower, self.lower_spec, PETSc.NINFINITY),
                                    (self.upper, self.upper_spec, PETSc.INFINITY)):
            if isinstance(spec, fem.Function):
                if not self.u.function_space.mesh.comm.allreduce(spec.vector.getSizes() == vec.getSizes(),
                                                                 op=MPI.LAND):
                    raise ValueError(f"bound {spec.name!r} is not in the unknown's dof layout")
                spec.vector.copy(vec)
            else:
                value = infinite if spec is None or np.isinf(spec) else float(spec)
                vec.set(value)
        prescribed = self.lower.copy()
        fpetsc.set_bc(prescribed, self.bcs)           # lower, with the Dirichlet values on constrained dofs
        self.lower.pointwiseMin(self.lower, prescribed)
        self.upper.copy(prescribed)
        fpetsc.set_bc(prescribed, self.bcs)
        self.upper.pointwiseMax(self.upper, prescribed)
        prescribed.destroy()
        for vec in (self.lower, self.upper):
            vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        crossed = bool(self.lower.array_r.size and np.any(self.lower.array_r > self.upper.array_r))
        if self.u.function_space.mesh.comm.allreduce(crossed, op=MPI.LOR):      # every rank raises together
            raise ValueError("a lower bound lies above its upper bound")

    def install(self, snes: PETSc.SNES) -> None:
        """Refresh the bounds and hand them to `snes` (a VI type: options() sees to it; others ignore bounds)."""
        self.refresh()                            # options() made the type a VI one (a user's non-VI type too)
        snes.setVariableBounds(self.lower, self.upper)

    def kkt_violation(self, x: PETSc.Vec, r: PETSc.Vec) -> None:
        """Turn the residual r (energy gradient) at x into its KKT violation, in place: at a lower bound only
        r < 0 (the energy would fall going up) violates, at an upper bound only r > 0; free dofs keep r."""
        xa, ra = x.array_r, r.array
        at_lower = xa <= self.lower.array_r + ACTIVE
        at_upper = xa >= self.upper.array_r - ACTIVE
        ra[at_lower] = np.minimum(ra[at_lower], 0.0)
        ra[at_upper] = np.maximum(ra[at_upper], 0.0)


def on_supports(x: PETSc.Vec, bcs: list) -> bool:
    """Whether x holds every Dirichlet value exactly (then a residual's lifting A (g - x) is zero: SNES's iterates
    after the first, whose Newton steps vanish on the supports). dolfinx's lifting assembles the tangent's element
    matrices of every cell touching a support, as costly as the tangent where supports touch most cells
    (measured on a one-layer slab held on z = 0: 80 % of a staggered fracture run's residual time)."""
    y = x.copy()
    fpetsc.set_bc(y, bcs)
    y.axpy(-1.0, x)
    same = y.norm(PETSc.NormType.INFINITY) == 0.0
    y.destroy()
    return same


def options(merged: dict, user_options: dict, bounds: Bounds | None) -> None:
    """A bounded problem's SNES options, in place: a VI type unless the user chose one (a user's non-VI type
    is replaced: bounds it would ignore are no option), and its line search (nothing without `bounds`)."""
    if bounds is None:
        return
    if not str(user_options.get("snes_type", "")).startswith("vi"):
        merged["snes_type"] = "vinewtonrsls"
    if "snes_linesearch_type" not in user_options:
        merged["snes_linesearch_type"] = VI_LINE_SEARCH
