"""A term computed as arrays beside the UFL terms (a contact barrier, a lumped mass): its energy, gradient,
Hessian and step cap at the solver's state, joined to the UFL forms in the same Newton solve."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from fem_forms.physics.terms import Term


class ArrayTerm(Term):
    """A piece of the energy computed outside UFL (a lumped mass, a contact barrier) as arrays, at the
    solver's state x (a PETSc Vec in the unknown's dof layout, owned entries). It sits in the model's
    TermList like any term (role, keys, fields, set_values, update) but gives no UFL form: it joins the UFL
    terms in the same Newton solve, energy line search and step cap (fem_forms.solvers.array_terms)."""
    name: str = "array term"
    is_array = True

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
