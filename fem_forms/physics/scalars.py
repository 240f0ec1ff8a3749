"""Global scalar unknowns (a cavity's pressure under volume control, a Lagrange multiplier of a mean-value
constraint) solved monolithically with the field: each is a fem.Constant the residual form uses, with one
scalar equation c(u, p) = 0 of its own. The coupling forms default to UFL derivatives: UFL 2022.2 cannot
take ufl.derivative with respect to a Constant, so d/dp goes through ufl.variable and ufl.diff instead."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
import ufl


@dataclass
class GlobalScalar:
    """A named scalar unknown p (its value lives in `value`, a fem.Constant the residual form references)
    with its equation c(u, p) = 0 (`equation`: a UFL functional; the driver's norm measures it beside the
    field residual, so scale it to the residual's units where they differ much). The couplings are derived
    when left None: `coupling` dR/dp (a vector form in the residual's test function), `gradient` dc/du (a
    vector form), `slope` dc/dp (a scalar form or a number). `multiplier` = k when p is the Lagrange multiplier of
    c = 0 in the problem's energy E(u, p), its coupling k dc/du (and c independent of p): the bordered Newton
    then has a merit function to descend (solvers/multiplier_merit.py)."""
    name: str
    value: fem.Constant
    equation: ufl.Form
    coupling: ufl.Form | None = None
    gradient: ufl.Form | None = None
    slope: ufl.Form | float | None = None
    multiplier: float | None = None


def derivative_wrt_constant(form: ufl.Form, constant: fem.Constant) -> ufl.Form | None:
    """d form / d constant, integral by integral (ufl.diff on a ufl.variable put in the Constant's place);
    None when the form does not depend on the Constant."""
    var = ufl.variable(constant)
    integrals = []
    for itg in form.integrals():
        integrand = ufl.replace(itg.integrand(), {constant: var})
        if integrand == itg.integrand():
            continue
        integrals.append(itg.reconstruct(integrand=ufl.diff(integrand, var)))
    return ufl.Form(integrals) if integrals else None


def coupling_forms(scalars: list[GlobalScalar], residual: ufl.Form, u: fem.Function) -> dict:
    """The UFL forms of the bordered Newton system: "R_p" (dR/dp_j, vector forms), "c_u" (dc_i/du, vector
    forms in the residual's test function), "c" (c_i) and "c_p" (dc_i/dp_j: forms, numbers or None for 0)."""
    if not isinstance(residual, ufl.Form) and any(s.coupling is None for s in scalars):
        raise ValueError("a compiled residual cannot be differentiated: give each GlobalScalar its coupling")
    v = residual.arguments()[0] if isinstance(residual, ufl.Form) else ufl.TestFunction(u.function_space)
    R_p = [s.coupling if s.coupling is not None else derivative_wrt_constant(residual, s.value)
           for s in scalars]
    for s, f in zip(scalars, R_p):
        if f is None:
            raise ValueError(f"the residual does not depend on global scalar {s.name!r}: nothing couples it")
    c_u = [s.gradient if s.gradient is not None else ufl.derivative(s.equation, u, v) for s in scalars]
    c_p = [[s_i.slope if i == j and s_i.slope is not None else derivative_wrt_constant(s_i.equation, s_j.value)
            for j, s_j in enumerate(scalars)] for i, s_i in enumerate(scalars)]
    return {"R_p": R_p, "c_u": c_u, "c": [s.equation for s in scalars], "c_p": c_p}
