"""What a term is: one named piece of the total potential energy (or, without an energy, of the residual),
written once on a Context that says how the body's configurations relate to the mesh the forms live on.

Three ways of writing equilibrium share the terms:
- forward: the mesh is the rest shape; u is the unknown displacement (static, modal, dynamics).
- on a designed rest shape: the rest shape is mesh + d (the adjoint design); G = I + grad d maps the
  mesh to the rest shape, F = I + grad u G^-1, rest volume dX = det G dx.
- inverse: the mesh is the deformed shape and the rest positions mesh + v are the unknowns: the same
  formulas with d = v and u = -v (then F = G^-1), residual = the virtual work of every term.
A term never needs to know which: it writes psi(F) dV, rho g . u dV, T . u dA with the Context's F,
volume(...) and area(...).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from dolfinx import mesh as dmesh
import ufl

from fem_forms.physics.parameters import Parameters
from fem_forms.physics.supports import LoadFactor


@dataclass
class Context:
    """Kinematics, measures and parameters the terms are written with."""
    mesh: dmesh.Mesh
    u: object                              # displacement as it appears in the forms (UFL expression)
    dx: ufl.Measure
    ds: ufl.Measure                        # boundary measure tagged with the surface loads' regions
    regions: dict                          # load index -> the ds ids of its facets
    parameters: Parameters
    load: LoadFactor
    rest_map: object = None                # G = dX/dx (None: the mesh is the rest shape)
    pressure: object = None                # the mixed formulation's pressure field, else None
    deformation: object = None             # F written directly (the inverse problem), else from u
    extra: dict = field(default_factory=dict)   # what later terms need (time, old values, history)
    dx_regions: ufl.Measure | None = None  # dx tagged with the body loads' volume groups
    body_regions: dict = field(default_factory=dict)   # load index -> the dx ids of its cells
    thermal_strain: object = None          # alpha (T - T_ref), a UFL scalar, when temperature is coupled in

    @property
    def F(self):
        """Deformation gradient dx/dX."""
        if self.deformation is not None:
            return self.deformation
        grad_u = ufl.grad(self.u)
        if self.rest_map is not None:
            grad_u = grad_u * ufl.inv(self.rest_map)
        return ufl.Identity(len(self.u)) + grad_u

    def volume(self, density, region: int | None = None) -> ufl.Form:
        """int density dX over the rest shape (or over the cells of one body-load region)."""
        dx = self.dx if region is None else self.dx_regions(region)
        if self.rest_map is None:
            return density * dx
        return density * ufl.det(self.rest_map) * dx

    def area(self, density, region: int) -> ufl.Form:
        """int density dA over the rest shape's facets of one ds region."""
        if self.rest_map is None:
            return density * self.ds(region)
        n = ufl.FacetNormal(self.mesh)
        m = ufl.inv(self.rest_map).T * n
        return density * ufl.det(self.rest_map) * ufl.sqrt(ufl.dot(m, m)) * self.ds(region)

    def rest_area_vector(self):
        """N dA / da: the rest shape's outward area vector per mesh facet area."""
        n = ufl.FacetNormal(self.mesh)
        if self.rest_map is None:
            return n
        return ufl.det(self.rest_map) * ufl.inv(self.rest_map).T * n


class Term:
    """One named contribution. Conservative terms give `energy(ctx)` (their residual and tangent come from
    ufl.derivative); others give `virtual_work(ctx, v)`, added to the residual as it is. A conservative term
    may also give `first_variation(ctx, v)`, its energy's derivative in the displacement direction v
    written with ufl.diff, which the inverse problem uses (faster kernels there, same derivative)."""
    name: str = "term"

    def energy(self, ctx: Context) -> ufl.Form | None:
        return None

    def virtual_work(self, ctx: Context, v) -> ufl.Form | None:
        return None

    @property
    def conservative(self) -> bool:
        return type(self).virtual_work is Term.virtual_work


# load type (the [[load]] type key) -> builder(spec, index in scene.load, mesh) -> Term
LOAD_TERMS: dict[str, Callable] = {}


def register_load(kind: str) -> Callable:
    """Class decorator: the term builds from a [[load]] table whose type is `kind`."""
    def add(cls):
        LOAD_TERMS[kind] = cls
        return cls
    return add
