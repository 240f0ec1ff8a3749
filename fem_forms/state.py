"""State: the unknown fields, history variables and the old values a load or time step starts from.

State changes only through two doors: `commit()` after an accepted step (history variables are first
brought up to date from the accepted fields, then everything becomes the new old values) and
`rollback()` on a cut-back (every field and history variable returns to the last committed values), so a
rejected step leaves no trace. Old values are fem.Functions, so forms (inertia, plastic flow) can use them.
Global scalar unknowns (fem.Constants, physics/scalars.py) are committed and rolled back with the fields.
"""
from __future__ import annotations

from typing import Callable

from dolfinx import fem
import numpy as np


class State:
    """Named fields (the solver's unknowns and what follows them) and history variables with old copies."""

    def __init__(self, fields: dict[str, fem.Function]):
        self.fields: dict[str, fem.Function] = dict(fields)
        self.history: dict[str, fem.Function] = {}
        self._updates: dict[str, Callable[[], np.ndarray]] = {}
        self.old: dict[str, fem.Function] = {}
        for name, f in self.fields.items():
            self.old[name] = _copy(f, f"{name}_old")
        self.scalars: dict[str, fem.Constant] = {}
        self.old_scalars: dict[str, float] = {}
        self.commits = 0

    def add_scalar(self, name: str, constant: fem.Constant) -> None:
        """A global scalar unknown, committed and rolled back with the fields (adding it again: no change)."""
        if name not in self.scalars:
            self.scalars[name] = constant
            self.old_scalars[name] = float(constant.value)

    def add_history(self, name: str, function: fem.Function, update: Callable[[], np.ndarray]) -> None:
        """A history variable (e.g. on a quadrature space): `update()` returns its new local values,
        computed from the fields being committed (e.g. a return mapping evaluated by fem.Expression)."""
        self.history[name] = function
        self._updates[name] = update
        self.old[name] = _copy(function, f"{name}_old")

    def commit(self) -> None:
        """Accept the current fields: update history variables from them, then make all of it the old state."""
        new = {name: update() for name, update in self._updates.items()}   # all from the committed history
        for name, values in new.items():
            h = self.history[name]
            h.x.array[:] = values
            h.x.scatter_forward()
        for name, f in {**self.fields, **self.history}.items():
            self.old[name].x.array[:] = f.x.array
        for name, c in self.scalars.items():
            self.old_scalars[name] = float(c.value)
        self.commits += 1

    def restore(self, values: dict[str, np.ndarray]) -> None:
        """Set every field and history variable to saved local values and make them the committed state, as
        they were when saved (no history update: the saved history is already the committed one)."""
        for name, f in {**self.fields, **self.history}.items():
            f.x.array[:] = values[name]
            f.x.scatter_forward()
            self.old[name].x.array[:] = f.x.array

    def rollback(self) -> None:
        """Return every field and history variable to the last committed values."""
        for name, f in {**self.fields, **self.history}.items():
            f.x.array[:] = self.old[name].x.array
            f.x.scatter_forward()
        for name, c in self.scalars.items():
            c.value = self.old_scalars[name]

    def change(self, name: str) -> np.ndarray:
        """Current minus committed values of a field (local array, ghosts included)."""
        return self.fields[name].x.array - self.old[name].x.array


def _copy(f: fem.Function, name: str) -> fem.Function:
    g = fem.Function(f.function_space, name=name)
    g.x.array[:] = f.x.array
    return g
