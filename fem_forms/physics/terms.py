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
import numpy as np
from petsc4py import PETSc
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


class ArrayTerm:
    """A piece of the energy computed outside UFL (a lumped mass, a contact barrier) as arrays, at the
    solver's state x (a PETSc Vec in the unknown's dof layout, owned entries). It joins the UFL terms in
    the same Newton solve, energy line search and step cap (fem_forms.solvers.array_terms)."""
    name: str = "array term"

    def energy(self, x: PETSc.Vec) -> float:
        """The term's energy at x, summed over ranks (the same value on every rank)."""
        raise NotImplementedError

    def add_gradient(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Add dE/dx into the residual b: into b.array (owned entries), or by b.setValues(ADD_VALUES) (the
        caller assembles b after every term). Rows of Dirichlet dofs may get anything: set_bc follows."""
        raise NotImplementedError

    def add_hessian(self, x: PETSc.Vec, A: PETSc.Mat, constrained: np.ndarray) -> None:
        """Add d2E/dx2 into the assembled tangent A (BAIJ or AIJ; the caller assembles it afterwards),
        leaving out the rows and columns in `constrained` (global indices of the Dirichlet dofs, all ranks,
        sorted): those stay the identity rows the UFL assembly made. `add_entries` does both."""
        raise NotImplementedError

    def max_step(self, x: PETSc.Vec, dx: PETSc.Vec) -> float:
        """The largest safe fraction (0, 1] of the step x -> x + dx (the same on every rank)."""
        return 1.0

    @property
    def caps(self) -> bool:
        """Whether the term can cap a step (it overrides max_step)."""
        return type(self).max_step is not ArrayTerm.max_step


def add_entries(A: PETSc.Mat, rows: np.ndarray, cols: np.ndarray, values: np.ndarray,
                constrained: np.ndarray) -> None:
    """Add the (row, col, value) triplets (global indices, any rank's rows) into A, except those in a
    constrained row or column. The entries must lie in A's sparsity pattern."""
    keep = ~(np.isin(rows, constrained) | np.isin(cols, constrained))
    rows, cols, values = rows[keep], cols[keep], values[keep]
    order = np.argsort(rows, kind="stable")
    rows, cols, values = rows[order], cols[order], values[order]
    starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]]) if len(rows) else []
    for i, j in zip(starts, list(starts[1:]) + [len(rows)]):
        A.setValues(int(rows[i]), cols[i:j].astype(PETSc.IntType), values[i:j],
                    addv=PETSc.InsertMode.ADD_VALUES)


# load type (the [[load]] type key) -> builder(spec, index in scene.load, mesh) -> Term
LOAD_TERMS: dict[str, Callable] = {}


def register_load(kind: str) -> Callable:
    """Class decorator: the term builds from a [[load]] table whose type is `kind`."""
    def add(cls):
        LOAD_TERMS[kind] = cls
        return cls
    return add
