"""The first-order start of a layout's equilibrium from a nearby layout's: at the equilibrium (u, p) of weights w,
a change dw of the weights (and dm of the placed density) moves it by [du; dp] with

    [K    R_p] [du]     [dR/dw dw + dR/dm dm]
    [c_u  c_p] [dp] = - [0                  ]

(no volume constraint c depends on the layout), solved with the factor of K the adjoint left at that equilibrium
(LayoutGradient.gradient) and the border's forward solve (design/bordered_adjoint.py): Newton then starts from
(u + du, p + dp) instead of (u, p), one error order closer to the new equilibrium."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc
import ufl


def by_density(form: ufl.Form, density, direction) -> ufl.Form | None:
    """d(form)/d(placed density field) along `direction`, or None where the two materials' densities are one or
    the form does not depend on it (no gravity)."""
    if density is None or density.placed == density.body:
        return None
    derivative = ufl.algorithms.expand_derivatives(ufl.derivative(form, density.field, direction))
    return None if derivative.empty() else derivative


class LayoutPredictor:
    """The form dR/dw[dw] + dR/dm[dm] of one layout model (dw, dm: DG0 Functions holding the changes) and the
    move it gives with a factored K."""

    def __init__(self, model, weight: fem.Function, density=None):
        self.model = model
        self.dw = fem.Function(weight.function_space, name="weight_change")
        change = ufl.derivative(model.residual, weight, self.dw)
        dm = fem.Function(weight.function_space, name="density_change")
        with_density = by_density(model.residual, density, dm)
        self.dm = None if with_density is None else dm
        self.form = fem.form(change if with_density is None else change + with_density)
        self.rhs = fpetsc.create_vector(self.form)

    def move(self, solve, border=None) -> tuple[PETSc.Vec, np.ndarray]:
        """(du, dp) for the changes in dw and dm: `solve(r)` is K^-1 r with the factor at the equilibrium (0 on
        supported dofs), `border` (linearised there with its forward solves, or None) gives the cavities'
        pressures."""
        rhs = self.rhs
        with rhs.localForm() as local:
            local.set(0.0)
        fpetsc.assemble_vector(rhs, self.form)
        rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        rhs.scale(-1.0)
        du = solve(rhs)
        if border is None:
            return du, np.zeros(0)
        return border.forward(du, np.zeros(len(border.R_p)))
