"""Stress recovery: a continuous field from the cellwise stresses of a displacement solution.

Method: global L2 projection onto the displacement's own continuous Lagrange space (P1/P2 on
tetrahedra, Q1/Q2 on hexahedra), one tensor field per quantity: find s_h in V_k^{3x3} with
    int s_h : t dx = int sigma(u_h) : t dx     for all t in V_k^{3x3},
the right-hand side integrated at the same quadrature points as the equilibrium forms, so no
intermediate sampling (no cell midpoints, no quadrature-space copy) enters. The mass matrix has its own
exact rule (2 x degree, positive weights: physics/quadrature.py), so it is positive definite whatever
rule the energy uses (a P2 tetrahedron mass on the 4-point rule is singular: CG failed). It is
assembled once per model and solved by CG with a Jacobi preconditioner (its condition number does not
grow with refinement: a fixed, small number of iterations); one scalar mass matrix serves all nine
components.

Why this one: it uses every quadrature point of every cell around a point with the weights of the
integral, so a value on a surface or at a corner is a weighted fit of all neighbouring cells, not
whichever cell contains the point; it is the same in serial and under MPI (one global linear solve,
ghosts updated); and it needs nothing beyond assembly (superconvergent patch recovery needs patch
assembly across ranks, a nodal average of cell values is only first-order accurate at surfaces).
What it costs and how accurate it is was measured on a known stress field (README, "Stresses at
points"): one extra assembly and a CG solve per recovered tensor, a small fraction of a Newton step.
"""
from __future__ import annotations

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.physics import quadrature
from fem_forms.solvers.linear import make_ksp

RTOL = 1e-12              # the projection is solved far below the discretisation error


class Recovery:
    """L2 projection of UFL expressions (scalar, vector or tensor valued) onto continuous Lagrange
    spaces of one degree. One scalar mass matrix and its CG solver serve every component: the
    right-hand side is assembled once on the blocked space, and each component column is solved with
    the scalar matrix (a blocked 3x3 mass matrix would be 81 times larger and assembled ~10x slower)."""

    def __init__(self, mesh, degree: int, quadrature_degree: int):
        self.mesh = mesh
        self.degree = degree
        cell = mesh.topology.cell_name()
        self.dx = ufl.Measure("dx", domain=mesh, metadata=quadrature.metadata(cell, quadrature_degree))
        self.mass_dx = ufl.Measure("dx", domain=mesh, metadata=quadrature.mass_metadata(cell, degree))
        self._scalar = None                        # (space, KSP, mass matrix, work vectors)
        self._spaces: dict = {}                    # value shape -> blocked space

    def space(self, shape: tuple) -> fem.FunctionSpace:
        """The continuous Lagrange space for values of `shape` (() scalar, (3,) vector, (3, 3) tensor)."""
        if shape not in self._spaces:
            element = ("Lagrange", self.degree)
            if shape == ():
                V = fem.FunctionSpace(self.mesh, element)
            elif len(shape) == 1:
                V = fem.VectorFunctionSpace(self.mesh, element, dim=shape[0])
            else:
                V = fem.TensorFunctionSpace(self.mesh, element, shape=shape)
            self._spaces[shape] = V
        return self._spaces[shape]

    def _mass_solver(self):
        if self._scalar is None:
            S = self.space(())
            s, t = ufl.TrialFunction(S), ufl.TestFunction(S)
            M = fpetsc.assemble_matrix(fem.form(ufl.inner(s, t) * self.mass_dx))
            M.assemble()
            ksp = make_ksp(M, "mass", "fem_forms_recovery_",
                           {"ksp_rtol": RTOL, "ksp_atol": 0.0, "ksp_max_it": 1000})
            rhs, sol = M.createVecRight(), M.createVecLeft()
            self._scalar = (S, ksp, M, rhs, sol)
        return self._scalar

    def project(self, expr, name: str) -> fem.Function:
        """The L2 projection of `expr` (a UFL expression of the solution) as a new Function."""
        S, ksp, _, rhs, sol = self._mass_solver()
        V = self.space(tuple(expr.ufl_shape))
        if not np.array_equal(V.dofmap.list.array, S.dofmap.list.array):
            raise RuntimeError(f"recovery of {name}: scalar and blocked spaces numbered their nodes differently")
        b = fpetsc.assemble_vector(fem.form(ufl.inner(expr, ufl.TestFunction(V)) * self.dx))
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        bs = V.dofmap.index_map_bs
        columns = b.array.reshape(-1, bs)          # owned nodes x components
        f = fem.Function(V, name=name)
        values = f.x.array[: columns.size].reshape(-1, bs)
        for j in range(bs):
            rhs.array[:] = columns[:, j]
            ksp.solve(rhs, sol)
            if ksp.getConvergedReason() <= 0:
                raise RuntimeError(f"recovery of {name}: CG did not converge ({ksp.getConvergedReason()})")
            values[:, j] = sol.array
        f.x.scatter_forward()
        b.destroy()
        return f
