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

from dataclasses import dataclass
from typing import Callable

from dolfinx import fem, mesh as dmesh
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.physics.context import Context  # noqa: F401 (the terms are written on it)
from fem_forms.physics.histories import piecewise_linear


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
    is_array: bool = False             # an ArrayTerm (physics/array_term.py): energy as arrays, not UFL
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

    # --- the life cycle every analysis calls without knowing the term (PolyFEM's forms have the same shape) ---
    # lagged quantities (friction's normal forces, moving obstacles): `update(t)` at every step's start, also
    # in a static run without histories, where t is the load factor
    lagging: bool = False
    energy_columns: tuple = ()         # the dynamic energy account's columns this term fills (stored_energies)
    step_histories: tuple = ()         # per-step tables its output keeps in a static run (output/histories.py kinds)

    def state_fields(self) -> dict:
        """The fields this term adds to the State beside the unknown (committed and rolled back with it)."""
        return {}

    def warnings(self) -> list[str]:
        """What the run should warn about this term on this mesh (found in `prepare`)."""
        return []

    def start(self, state) -> None:
        """A new solve begins: history and time back to their start values, committed in `state`."""

    def resume(self, t: float) -> None:
        """Continue at time t from a restored checkpoint (its fields restored with the State)."""

    def saved(self) -> dict:
        """Numbers of its own beside the State's fields that a checkpoint carries (a barrier's raised stiffness);
        JSON-able."""
        return {}

    def restore(self, values: dict) -> None:
        """Take back what `saved()` gave (a --restart, before `resume`)."""

    def settle(self, factor: float) -> float:
        """A start from rest: scale this term's numerical stiffness (a barrier's) by `factor`, the one that best
        balances the other terms' force at the start, within the term's bounds; the factor applied (1: none)."""
        return 1.0

    def inadmissible(self, x: PETSc.Vec) -> str | None:
        """Why the state x cannot be accepted (an intersection), or None: checked on every accepted step."""
        return None

    def sub_problem(self, solid: "Solid", ctx: Context) -> "SubProblem | None":
        """A problem in a field of its own that alternates with the displacement's (the damage), or None."""
        return None

    def report(self, x: PETSc.Vec) -> dict:
        """results.json entries of this term at the state x (the end of a run)."""
        return {}

    def stored_energies(self, x: PETSc.Vec) -> dict[str, float]:
        """Energies this term stores at x, by the energy account's column (`energy_columns`)."""
        return {}

    def watch_events(self) -> None:
        """A time march will ask step_event after each step: remember what it needs from each step's start."""

    def step_event(self, x: PETSc.Vec) -> str:
        """What happened to this term over the time step ending at x that the march resolves with shorter steps
        ('impact', 'stick-slip': contact), or '' (the same on every rank)."""
        return ""

    def step_dissipation(self, x: PETSc.Vec) -> float:
        """Energy this term dissipated over the current step up to x (J), for the energy account."""
        return 0.0

    def support_forces(self, x: PETSc.Vec) -> np.ndarray:
        """(k, 3) forces this term's supports exert on the body at x (they hold it as [[fix]] does)."""
        return np.zeros((0, 3))

    def surface_forces(self, body: str, x: PETSc.Vec) -> tuple | None:
        """(nodes, (n, 3) forces, BoundarySurface): the force the named body exerts on each node of the surface
        (the same on every rank), or None if this term has no such body."""
        return None

    def output_fields(self) -> list:
        """Fields of its own written with the run's fields (the damage), as they are."""
        return []

    def holds(self, model, modes: list) -> np.ndarray | None:
        """(k, len(modes)): what of each rigid mode (a Vec of the unknown) this term's supports resist at rest,
        rows of the Gram matrix of held motion (the rigid-motion check); None: it holds nothing."""
        return None

    # what to tell a user whose body this term's supports leave free (appended to the rigid-motion error)
    support_hint: str | None = None

    def add_output_field(self, name: str, f) -> None:
        """Add this term's share of the [output] field `name` (e.g. contact_pressure) into the P1 Function f."""


@dataclass
class SubProblem:
    """A term's own field and its energy with u frozen, minimised between `lower` (the committed field,
    with `irreversible`) and `upper`; alternated with the displacement until both change less than
    `tolerance` (at most `max_iterations` sweeps), each sweep's step over-relaxed by `relaxation`."""
    field: fem.Function
    energy: ufl.Form
    upper: float
    irreversible: bool
    tolerance: float
    max_iterations: int
    relaxation: float = 1.0


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

    def near_limit(self, ctx: Context, said: str = "") -> str | None:
        """Why no state may exist much beyond the current one (a Gent solid whose chains nearly lock), or None
        (also when `said`, the solve's message, says it already): said when a solve stops short of its load."""
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

    def viscous_work(self, start: Context, end: Context) -> ufl.Form | None:
        """The work of a viscous history over a step from start's u to end's (None: no viscous history)."""
        return None

    # why results.json reports no stored energy for this solid (None: it does)
    energy_caveat: str | None = None

    @property
    def quadrature_history(self) -> bool:
        """Whether its stress depends on history stored at the quadrature points (plastic, Prony)."""
        return self.is_plastic


def _constant_value(v):
    """A scene value as a Constant takes it: a vector as a tuple, a number as it is."""
    return tuple(v) if isinstance(v, (list, tuple)) else v


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

    value_key: str | None = None       # the [[load]] key held in the Constant `value` (g, value, pressure)

    def declare(self, spec, mesh: dmesh.Mesh) -> None:
        """Create this load's Constants from its [[load]] table (by default `value` from `value_key`)."""
        if self.value_key is not None:
            self.value = fem.Constant(mesh, PETSc.ScalarType(_constant_value(getattr(spec, self.value_key))))

    def set_spec(self, spec) -> None:
        """Take new values of this load's [[load]] table into its Constants."""
        if self.value_key is not None:
            self.value.value = getattr(spec, self.value_key)

    def set_values(self, scene) -> None:
        self.history = list(scene.load[self.index].history or [])
        self.set_spec(scene.load[self.index])

    def factor_at(self, t: float) -> float:
        """The load's history at time t (1 without a history)."""
        return piecewise_linear(self.history, t)

    def update(self, t: float) -> None:
        self.factor.value = self.factor_at(t)


# the kinds of solid, most specific first: (priority, builder(scene, material, mesh, name, binding, regions) ->
# Solid, or None where the scene does not ask for that kind); the elastic solid takes what no other does
SOLID_KINDS: list[tuple[int, Callable]] = []


def register_solid(priority: int) -> Callable:
    """Function decorator: a kind of solid the scene may ask for; builders are tried by priority, highest first."""
    def add(builder):
        SOLID_KINDS.append((priority, builder))
        SOLID_KINDS.sort(key=lambda kind: -kind[0])
        return builder
    return add


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
