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

from dolfinx import fem, mesh as dmesh
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.physics.parameters import Parameters
from fem_forms.physics.supports import LoadFactor
from fem_forms.physics.histories import piecewise_linear


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


class Term:
    """One named contribution. Conservative terms give `energy(ctx)` (their residual and tangent come from
    ufl.derivative); others give `virtual_work(ctx, v)`, added to the residual as it is. A conservative term
    may also give `first_variation(ctx, v)`, its energy's derivative in the displacement direction v
    written with ufl.diff, which the inverse problem uses (faster kernels there, same derivative).

    What a term declares about itself (the model finds terms by these, never by position):
    `role` (what it is to the analyses: "solid", "load", "damping", "inertia", ...), `keys` (the scene
    keys that created it, e.g. ("load", 2)), `fields` (the unknown fields it acts on). `set_values(scene)`
    takes new values of its Constants from a scene (nothing compiles); `update(t)` moves it to time (or
    pseudo-time) t. Optional: `record()` returns the scalars the term wants on a load path's record (e.g. a
    cavity's {"chambers_pressure": ..., "chambers_volume": ...}), the same on every rank; a static run
    writes them as columns of probes.csv after every accepted load step."""
    name: str = "term"
    role: str = "term"
    # the residual takes `first_variation` instead of ufl.derivative of `energy`: for an energy that is exact
    # only where the supports hold (a cavity closed by symmetry planes), so that reactions see the true load
    residual_by_hand: bool = False
    keys: tuple = ()
    fields: tuple = ("displacement",)

    def energy(self, ctx: Context) -> ufl.Form | None:
        return None

    def virtual_work(self, ctx: Context, v) -> ufl.Form | None:
        return None

    def first_variation(self, ctx: Context, v) -> ufl.Form | None:
        """The energy's derivative in direction v written by hand (None: ufl.derivative of `energy`)."""
        return None

    def set_values(self, scene) -> None:
        """Take this term's values from `scene` (same kinds of terms): Constants change, nothing compiles."""

    def prepare(self, ctx: Context) -> None:
        """Check the term against the mesh and compute what it needs once (a cavity: that its walls enclose a
        volume, and that volume); called when the model's Context is made. InputError for what cannot work."""

    def global_scalars(self, model) -> list:
        """The scalar unknowns (physics.scalars.GlobalScalar) this term adds to the model's Newton solve (a
        volume-controlled cavity's pressure); none by default."""
        return []

    def update(self, t: float) -> None:
        """Move to time (or pseudo-time) t; a term without a history has nothing to do."""

    def record(self) -> dict[str, float]:
        """Named scalars of the current (accepted) state for the load path's record: none by default."""
        return {}

    @property
    def conservative(self) -> bool:
        return type(self).virtual_work is Term.virtual_work


class Solid(Term):
    """The solid's own stored energy (elastic or plastic): the one term every model has exactly once.
    It says how stresses are recovered (`pk1`), whether its state carries history (`attach` registers
    it with the State) and when a state lies outside its theory."""
    role = "solid"
    keys = ("material",)
    is_plastic = False
    material: object = None

    def pk1(self, ctx: Context):
        """First Piola-Kirchhoff stress at the context's state (UFL)."""
        raise NotImplementedError

    def attach(self, state, ctx: Context) -> None:
        """Register history variables with the State (none for an elastic solid)."""

    def outside_theory(self, ctx: Context) -> str | None:
        """Why the state lies outside the model's theory, or None."""
        return None

    def elastic_law_energy(self, ctx: Context) -> ufl.Form:
        """int psi dX of the elastic law alone (the stiffness at rest, for Rayleigh damping)."""
        return self.energy(ctx)

    def committed_energy(self, ctx: Context) -> ufl.Form | None:
        """The stored energy at the committed history (the energy account's when plastic work is not counted)."""
        return self.energy(ctx)

    def counts_plastic_work(self, thermal: bool) -> bool:
        """Whether the energy account books this solid's plastic work (`plastic_dissipation`)."""
        return False


class Load(Term):
    """An external load from one [[load]] table: its values are Constants, scaled by the model's load
    factor and by its own `factor` (its history at the current time; 1 without one)."""
    role = "load"

    def __init__(self, spec, index: int, mesh: dmesh.Mesh):
        self.index = index
        self.keys = ("load", index)
        self.history = list(spec.history or [])
        self.factor = fem.Constant(mesh, PETSc.ScalarType(1.0))
        self.declare(spec, mesh)

    def declare(self, spec, mesh: dmesh.Mesh) -> None:
        """Create this load's Constants from its [[load]] table."""

    def set_spec(self, spec) -> None:
        """Take new values of this load's [[load]] table into its Constants."""

    def set_values(self, scene) -> None:
        self.history = list(scene.load[self.index].history or [])
        self.set_spec(scene.load[self.index])

    def factor_at(self, t: float) -> float:
        """The load's history at time t (1 without a history)."""
        return piecewise_linear(self.history, t)

    def update(self, t: float) -> None:
        self.factor.value = self.factor_at(t)


class TermList:
    """The model's terms, declared once, in scene order; found by role, never by position."""

    def __init__(self, terms: list[Term]):
        self.all = list(terms)
        solids = [t for t in self.all if t.role == "solid"]
        if len(solids) != 1:
            raise ValueError(f"a model has exactly one solid term, got {len(solids)}")

    def __iter__(self):
        return iter(self.all)

    def __len__(self) -> int:
        return len(self.all)

    def __add__(self, other):
        return list(self.all) + list(other)

    @property
    def solid(self) -> Solid:
        return next(t for t in self.all if t.role == "solid")

    @property
    def loads(self) -> list[Load]:
        return self.with_role("load")

    def with_role(self, role: str) -> list[Term]:
        return [t for t in self.all if t.role == role]

    @property
    def arrays(self) -> list:
        """The terms whose energy is computed as arrays (ArrayTerm), for the solver's callbacks."""
        return [t for t in self.all if isinstance(t, ArrayTerm)]

    def only_ufl(self, analysis: str) -> None:
        """InputError naming the array terms (energies computed outside UFL) that `analysis` cannot take yet:
        left out, their energy would silently be missing."""
        if self.arrays:
            raise InputError(f"{', '.join(t.name for t in self.arrays)}: not available in {analysis} yet (its "
                             "energy is computed as arrays; static and implicit dynamic solves take it)")

    def set_values(self, scene) -> None:
        for t in self.all:
            t.set_values(scene)

    def update(self, t: float) -> None:
        for term in self.all:
            term.update(t)


class ArrayTerm(Term):
    """A piece of the energy computed outside UFL (a lumped mass, a contact barrier) as arrays, at the
    solver's state x (a PETSc Vec in the unknown's dof layout, owned entries). It sits in the model's
    TermList like any term (role, keys, fields, set_values, update) but gives no UFL form: it joins the UFL
    terms in the same Newton solve, energy line search and step cap (fem_forms.solvers.array_terms)."""
    name: str = "array term"

    def energy_value(self, x: PETSc.Vec) -> float:
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
    constrained row or column. Entries outside A's pattern are allocated: a MatAXPY that widened A (triangle
    contact) resets A's options, and an obstacle's friction block added after it stopped with PETSc error 63
    (a ring on a floor, squeezed until its inner walls met)."""
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
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


# a scene section (e.g. "contact") -> builder(scene, mesh) -> the terms it asks for (none: an empty list)
SCENE_TERMS: dict[str, Callable] = {}


def register_terms(section: str) -> Callable:
    """Function decorator: `builder(scene, mesh) -> list[Term]` declares the terms of a scene section
    (a new kind of physics is one module with one such registration)."""
    def add(builder):
        SCENE_TERMS[section] = builder
        return builder
    return add
