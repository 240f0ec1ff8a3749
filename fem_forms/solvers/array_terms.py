"""The array terms of one nonlinear problem (energies computed outside UFL: a lumped mass, a contact
barrier) summed into the SNES callbacks beside the UFL forms, and their step cap as a line-search pre-check."""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.physics.array_term import ArrayTerm


def constrained_dofs(V: fem.FunctionSpace, bcs: list) -> np.ndarray:
    """Global indices (unrolled, sorted) of every rank's Dirichlet dofs of the space V."""
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    local = [bc.dof_indices()[0][: bc.dof_indices()[1]] for bc in bcs]
    local = np.unique(np.concatenate(local)).astype(np.int64) if local else np.empty(0, np.int64)
    owned = imap.local_to_global((local // bs).astype(np.int32)).astype(np.int64) * bs + local % bs
    return np.unique(np.concatenate(V.mesh.comm.allgather(owned))).astype(PETSc.IntType)


class ArrayTerms:
    """The sum of a problem's array terms, as the SNES residual, Jacobian and objective callbacks add it."""

    def __init__(self, terms: list[ArrayTerm], V: fem.FunctionSpace, bcs: list, tangent: fem.Form):
        self.terms = list(terms)
        self.V, self.bcs, self.tangent = V, bcs, tangent   # the tangent form gives the lifting matrix its pattern
        self.last_cap = 1.0                      # the fraction the last Newton direction was scaled by
        self._H = None                           # the terms' unfiltered Hessian, for the lifting only
        self._constrained = None

    @property
    def constrained(self) -> np.ndarray:
        """Global indices of every rank's Dirichlet dofs, gathered on first use (a term that adds off-diagonal
        Hessian entries needs them; the lumped mass does not)."""
        if self._constrained is None:
            self._constrained = constrained_dofs(self.V, self.bcs)
        return self._constrained

    @property
    def widens(self) -> bool:
        """Whether some term adds Hessian entries outside the forms' pattern (self-contact): the tangent is AIJ."""
        return any(getattr(t, "widens_pattern", False) for t in self.terms)

    @property
    def caps(self) -> bool:
        """Whether some term can cap a step (the pre-check is installed only then)."""
        return any(t.caps for t in self.terms)

    def add_gradient(self, x: PETSc.Vec, b: PETSc.Vec, lifting: bool = True) -> None:
        """Every term's gradient into the residual b (before set_bc writes the Dirichlet rows), with the
        lifting the UFL part gets from apply_lifting: where x is off the Dirichlet values g (a start
        state), the free rows gain H_fc (g - x_c), H the terms' Hessian at x. Inside SNES x is on them
        (Newton steps are zero on constrained rows): the caller passes lifting=False there, saving a
        vector, a set_bc and a global norm per residual."""
        if not self.terms:
            return
        for t in self.terms:
            t.add_gradient(x, b)
        b.assemble()                             # entries set on other ranks' rows, if a term did
        if not lifting:
            return
        w = x.duplicate()
        w.set(0.0)
        fpetsc.set_bc(w, self.bcs, x, 1.0)       # g - x on the Dirichlet dofs, 0 elsewhere
        if w.norm(PETSc.NormType.INFINITY) > 0.0:
            if self._H is None:
                self._H = fpetsc.create_matrix(self.tangent, "aij")
                # its first assembly squeezes out the unused preallocation: a contact that spreads to new
                # nodes later adds new nonzeros (a finger pressed on a ball failed here with PETSc error 63)
                self._H.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
            self._H.zeroEntries()
            self._H.assemble()                   # assembled, as MatAXPY (triangle contact's Hessian) needs
            for t in self.terms:
                t.add_hessian(x, self._H, np.empty(0, PETSc.IntType))
            self._H.assemble()
            hw = b.duplicate()
            self._H.mult(w, hw)
            b.axpy(1.0, hw)                      # its Dirichlet rows are set_bc's to overwrite
            hw.destroy()
        w.destroy()

    def add_hessian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """Every term's Hessian into the assembled tangent, Dirichlet rows and columns left out. New nonzeros are
        allowed on every rank first: a term that allows them only where it adds entries (add_entries) changes
        MatAssemblyEnd's collective steps on those ranks alone, and 2 ranks hung there (a part falling onto the
        floor with contact nodes on one rank only)."""
        if self.terms:
            A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        for t in self.terms:
            t.add_hessian(x, A, self.constrained)
        if self.terms:
            A.assemble()

    @property
    def relags(self) -> bool:
        """Whether some term lags a friction a static step re-lags at its equilibrium (contact with obstacles)."""
        return any(hasattr(t, "relag") for t in self.terms)

    def relag(self, x: PETSc.Vec, tolerance: float) -> float:
        """Each such term re-lagged at x where its normal forces changed by more than `tolerance`; the largest
        relative change."""
        return max((t.relag(x, tolerance) for t in self.terms if hasattr(t, "relag")), default=0.0)

    def energy(self, x: PETSc.Vec) -> float:
        """The terms' energy at x (each term's is the same on every rank), for the line-search objective."""
        return sum(t.energy_value(x) for t in self.terms)

    def max_step(self, x: PETSc.Vec, dx: PETSc.Vec) -> float:
        """The smallest safe fraction over the terms of the step x -> x + dx."""
        local = min((t.max_step(x, dx) for t in self.terms if t.caps), default=1.0)
        return x.comm.tompi4py().allreduce(local, op=MPI.MIN)     # one step for all ranks, whatever a term did

    def safe_move(self, x: PETSc.Vec, target: PETSc.Vec) -> bool:
        """Whether the whole move x -> target passes the terms' step filter (a start state the supports' new
        values or a predictor made; True without capping terms)."""
        if not self.caps:
            return True
        dx = target.copy()
        dx.axpy(-1.0, x)
        safe = dx.norm(PETSc.NormType.INFINITY) == 0.0 or self.max_step(x, dx) >= 1.0
        dx.destroy()
        return safe

    def safe_share(self, x: PETSc.Vec, step) -> float:
        """The safe fraction of the move x -> x + step (step: the owned entries' array); 1 without capping terms."""
        if not self.caps:
            return 1.0
        dx = x.copy()
        dx.array[:] = step[: len(dx.array)]
        share = self.max_step(x, dx)
        dx.destroy()
        return share

    def precheck(self, x: PETSc.Vec, y: PETSc.Vec) -> bool:
        """PETSc's line-search pre-check: newtonls tries x - lambda y (lambda = 1 first), so the step is
        dx = -y; scale y by the safe fraction of that step. Returns whether y changed."""
        dx = y.copy()
        dx.scale(-1.0)
        s = self.max_step(x, dx)
        dx.destroy()
        if not 0.0 <= s <= 1.0:                  # a term's bug: stop the solve rather than step unsafely
            raise ValueError(f"max_step gave {s}: a safe fraction of the step lies in [0, 1]")
        # 0: the state is already unsafe (an obstacle moved onto it): no step, the line search fails, the step is cut
        self.last_cap = s
        if s < 1.0:
            y.scale(s)
            return True
        return False

    def install(self, snes: PETSc.SNES) -> None:
        """Cap the Newton direction before the line search's first trial, if some term can cap."""
        if self.caps:
            snes.setLineSearchPreCheck(self.precheck)

