"""The bare dolfinx 0.5.2 / petsc4py Newton solve the benchmarks measure fem_forms against: one PETSc SNES on
compiled residual, tangent and energy forms, written once for fixed_cost.py, static_beam.py and dynamic_bare.py.
It imports nothing from fem_forms: it is the reference."""
from __future__ import annotations

import time
from typing import Any, Sequence

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc


class BareSNES:
    """SNES on u with residual form L, tangent form a and energy form `energy` (the objective of the line
    search), Dirichlet conditions bcs and the PETSc `options` (written under `prefix`). The callbacks add
    their wall time to `assembly` and count themselves in `calls` ("R", "J", "E").

    The options stay in PETSc's database until `destroy()`: some (mg_levels_*, mat_mumps_*) are read only
    when the preconditioner is set up, inside the first solve."""

    def __init__(self, u: fem.Function, L: fem.FormMetaClass, a: fem.FormMetaClass,
                 energy: fem.FormMetaClass, bcs: Sequence[fem.DirichletBCMetaClass], options: dict[str, Any],
                 mat_type: str = "baij", prefix: str = "bare_",
                 near_nullspace: PETSc.NullSpace | None = None) -> None:
        self.u, self.L, self.a, self.energy, self.bcs = u, L, a, energy, list(bcs)
        self.comm = u.function_space.mesh.comm
        self.assembly = 0.0
        self.calls = {"R": 0, "J": 0, "E": 0}
        self.b = fpetsc.create_vector(L)
        self.x = self.b.copy()
        self.A = fpetsc.create_matrix(a, mat_type)
        if near_nullspace is not None:
            self.A.setNearNullSpace(near_nullspace)
        self._option_names = [prefix + k for k in options]
        opts = PETSc.Options()
        for k, v in options.items():
            opts[prefix + k] = v
        self.snes = PETSc.SNES().create(self.comm)
        self.snes.setOptionsPrefix(prefix)
        self.snes.setFunction(self._residual, self.b)
        self.snes.setJacobian(self._jacobian, self.A)
        self.snes.setObjective(self._objective)
        self.snes.setFromOptions()

    def set_state(self, xv: PETSc.Vec) -> None:
        xv.copy(self.u.vector)
        self.u.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def solve(self) -> int:
        """Newton from the current u; u holds the result. Returns SNES's converged reason (> 0: converged)."""
        self.u.vector.copy(self.x)
        self.snes.solve(None, self.x)
        self.set_state(self.x)
        return self.snes.getConvergedReason()

    def destroy(self) -> None:
        """Destroy the SNES, the matrix and the vectors, and remove the options this solver wrote."""
        opts = PETSc.Options()
        for name in self._option_names:
            opts.delValue(name)
        for obj in (self.snes, self.A, self.b, self.x):
            obj.destroy()

    def _residual(self, snes: PETSc.SNES, xv: PETSc.Vec, bv: PETSc.Vec) -> None:
        t = time.perf_counter()
        self.set_state(xv)
        with bv.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(bv, self.L)
        fpetsc.apply_lifting(bv, [self.a], bcs=[self.bcs], x0=[xv], scale=-1.0)
        bv.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fpetsc.set_bc(bv, self.bcs, xv, -1.0)
        self.assembly += time.perf_counter() - t
        self.calls["R"] += 1

    def _jacobian(self, snes: PETSc.SNES, xv: PETSc.Vec, Am: PETSc.Mat, Pm: PETSc.Mat) -> None:
        t = time.perf_counter()
        Am.zeroEntries()
        fpetsc.assemble_matrix(Am, self.a, bcs=self.bcs)
        Am.assemble()
        self.assembly += time.perf_counter() - t
        self.calls["J"] += 1

    def _objective(self, snes: PETSc.SNES, xv: PETSc.Vec) -> float:
        t = time.perf_counter()
        self.set_state(xv)
        value = self.comm.allreduce(fem.assemble_scalar(self.energy), op=MPI.SUM)
        self.assembly += time.perf_counter() - t
        self.calls["E"] += 1
        return value if np.isfinite(value) else 1e300
