"""What a term reports as numbers: scalar integrals compiled once and summed over ranks, and what of a rigid motion
an elastic support's energy holds (the rigid-motion check)."""
from __future__ import annotations

from typing import Callable

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl


class Integrals:
    """Named scalar integrals of one term: each form made by `make()` and compiled on first use, then assembled
    and summed over the ranks of `comm` at every call (collective)."""

    def __init__(self, comm: MPI.Comm):
        self.comm, self._forms = comm, {}

    def __call__(self, name: str, make: Callable[[], ufl.Form]) -> float:
        if name not in self._forms:
            self._forms[name] = fem.form(make())
        return self.comm.allreduce(fem.assemble_scalar(self._forms[name]), op=MPI.SUM)


def held_by_energy(energy: ufl.Form, unknown: fem.Function, modes: list) -> np.ndarray:
    """Rows R with R^T R = the Gram matrix of the support's restoring forces d2E[m_i] . d2E[m_j] for the rigid
    modes m_i, scaled to its largest entry (1: held as firmly as the most held mode; 0: free)."""
    V = unknown.function_space
    w = fem.Function(V)
    form = fem.form(ufl.derivative(ufl.derivative(energy, unknown, ufl.TestFunction(V)), unknown, w))
    forces = []
    for m in modes:
        w.vector.array[:] = m.array
        w.x.scatter_forward()
        b = fpetsc.assemble_vector(form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        forces.append(b)
    gram = np.array([[a.dot(b) for b in forces] for a in forces])
    for b in forces:
        b.destroy()
    gram /= max(float(np.abs(gram).max()), 1e-300)
    values, vectors = np.linalg.eigh(gram)
    return (vectors * np.sqrt(np.clip(values, 0.0, None))).T
