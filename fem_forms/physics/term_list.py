"""The model's terms as one list: found by role, never by position, and every life-cycle hook called on all of
them (an analysis calls the list, never a term it would have to know)."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.physics.terms import Load, Solid, Term


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
        return [t for t in self.all if t.is_array]

    def only_ufl(self, analysis: str, but: tuple = ()) -> None:
        """InputError naming the array terms (energies computed outside UFL) that `analysis` cannot take yet,
        those of the roles `but` aside: left out, their energy would silently be missing."""
        if missing := [t for t in self.arrays if t.role not in but]:
            raise InputError(f"{', '.join(t.name for t in missing)}: not available in {analysis} yet (its "
                             "energy is computed as arrays; static and implicit dynamic solves take it)")

    def _each(self, hook: str, *args) -> None:
        """Call the hook of every term, in scene order."""
        for term in self.all:
            getattr(term, hook)(*args)

    def set_values(self, scene) -> None:
        self._each("set_values", scene)

    def update(self, t: float) -> None:
        self._each("update", t)

    # --- the life cycle, over every term ----------------------------------------------------------
    @property
    def lagged(self) -> list[Term]:
        return [t for t in self.all if t.lagging]

    def lag(self, t: float) -> None:
        """Lagged terms to time (or load factor) t, lagged from the current state."""
        for term in self.lagged:
            term.update(t)

    def state_fields(self) -> dict:
        return {k: f for t in self.all for k, f in t.state_fields().items()}

    def start(self, state) -> None:
        self._each("start", state)

    def resume(self, t: float) -> None:
        self._each("resume", t)

    def saved(self) -> list[dict]:
        return [t.saved() for t in self.all]

    def restore(self, values: list[dict]) -> None:
        for term, v in zip(self.all, values):
            term.restore(v)

    def inadmissible(self, x: PETSc.Vec) -> str | None:
        return next((why for t in self.all if (why := t.inadmissible(x)) is not None), None)

    def report(self, x: PETSc.Vec) -> dict:
        """Every term's report, merged (tables of the same name, such as two springs', joined)."""
        out: dict = {}
        for t in self.all:
            for k, v in t.report(x).items():
                out[k] = {**out[k], **v} if isinstance(v, dict) and isinstance(out.get(k), dict) else v
        return out

    def stored_energies(self, x: PETSc.Vec) -> dict[str, float]:
        out: dict[str, float] = {}
        for t in self.all:
            for k, v in t.stored_energies(x).items():
                out[k] = out.get(k, 0.0) + v
        return out

    def watch_events(self) -> None:
        self._each("watch_events")

    def step_event(self, x: PETSc.Vec) -> str:
        """The first term's event over the time step ending at x ('' if none)."""
        return next((e for t in self.all if (e := t.step_event(x))), "")

    def step_dissipation(self, x: PETSc.Vec) -> float:
        return sum(t.step_dissipation(x) for t in self.all)

    def support_forces(self, x: PETSc.Vec) -> np.ndarray:
        return np.vstack([np.zeros((0, 3))] + [t.support_forces(x) for t in self.all])

    def surface_forces(self, body: str, x: PETSc.Vec) -> tuple | None:
        return next((f for t in self.all if (f := t.surface_forces(body, x)) is not None), None)

    def output_fields(self) -> list:
        return [f for t in self.all for f in t.output_fields()]

    @property
    def energy_columns(self) -> set:
        return {c for t in self.all for c in t.energy_columns}
