"""The Context a term is written on: kinematics (F, rest and deformed positions), measures and parameters.

Three ways of writing equilibrium share it (physics/terms.py): forward (the mesh is the rest shape), on a
designed rest shape (G = I + grad d maps the mesh to it) and inverse (the mesh is the deformed shape)."""
from __future__ import annotations

from dataclasses import dataclass, field

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
    rest_offset: object = None             # rest shape minus mesh (None: the mesh is the rest shape)
    materials: object = None               # MaterialRegions: which material each cell is made of
    loaded: object = None                  # the LoadedMesh (groups, tags) the terms may select from

    @property
    def F(self):
        """Deformation gradient dx/dX."""
        if self.deformation is not None:
            return self.deformation
        grad_u = ufl.grad(self.u)
        if self.rest_map is not None:
            grad_u = grad_u * ufl.inv(self.rest_map)
        return ufl.Identity(len(self.u)) + grad_u

    @property
    def rest_position(self):
        """X, the rest position of each mesh point (UFL vector)."""
        x = ufl.SpatialCoordinate(self.mesh)
        return x if self.rest_offset is None else x + self.rest_offset

    @property
    def position(self):
        """x = X + u, the deformed position of each mesh point (UFL vector)."""
        return self.rest_position + self.u

    def volume(self, density, region: int | None = None, dx: ufl.Measure | None = None) -> ufl.Form:
        """int density dX over the rest shape (or over the cells of one body-load region; or with the
        measure `dx`, e.g. a mass matrix's own rule)."""
        if dx is None:
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
