"""The sagging part: a static solve under gravity with the current carving, held by the scene's [[fix]].

Carved cells carry the fill density and a stiffness scaled by `fill_stiffness` (an ersatz material,
default 1e-6): the material is wrapped so that its psi(F) is multiplied by a DG0 factor field. The
factor and the density are fem.Functions, so a new carving compiles nothing; no physics module changes,
and other analyses' forms stay as they are. (Removing carved cells from the mesh instead would build a
new mesh, spaces and solver per design and lose the cell correspondence the moments need.)
"""
from __future__ import annotations

import dataclasses

from dolfinx import fem
import numpy as np
from ufl.algorithms import extract_coefficients

from fem_forms.equilibrium import StaticResult, solve_static
from fem_forms.errors import SolveError
from fem_forms.model import Model, build_model
from fem_forms.scene import Load, Scene


class CellwiseStiffness:
    """A material whose energy density is factor(x) psi(F): factor a DG0 field (1 solid, small carved)."""

    def __init__(self, base, factor: fem.Function, name: str):
        self.base, self.factor, self.name = base, factor, name

    def psi(self, F):
        return self.factor * self.base.psi(F)


class SagModel:
    """The static model of the part under gravity, reused for every carving."""

    def __init__(self, scene: Scene, gravity: np.ndarray):
        if not any(ld.type == "gravity" for ld in scene.load):
            scene = dataclasses.replace(scene, load=list(scene.load) + [Load("gravity", g=list(gravity))])
        self.scene = scene
        self._factor_holder = {}
        self.model: Model = build_model(scene, material=_Deferred(scene, self._factor_holder))
        self.factor = self._factor_holder["factor"]

    @property
    def mesh(self):
        return self.model.mesh

    def solve(self, density: np.ndarray, stiffness: np.ndarray) -> StaticResult:
        """Static sag with these cellwise densities and stiffness factors (owned cells)."""
        self.model.parameters.set_density(density)
        n = len(stiffness)
        self.factor.x.array[self.factor.function_space.dofmap.list.array[:n]] = stiffness
        self.factor.x.scatter_forward()
        self.model.u.x.array[:] = 0.0
        result = solve_static(self.scene, model=self.model)
        if not result.report.converged:
            raise SolveError(f"balance: the sag under gravity did not converge: {result.report.message}")
        return result


class _Deferred:
    """Builds the wrapped material on first psi(F), when the mesh exists (build_model makes the mesh)."""

    def __init__(self, scene: Scene, holder: dict):
        self.scene, self.holder = scene, holder
        self.name = f"{scene.material.model} x cellwise stiffness factor"

    def psi(self, F):
        if "factor" not in self.holder:
            # the displacement in F is a dolfinx Function: its space knows the mesh
            mesh = next(c for c in extract_coefficients(F) if isinstance(c, fem.Function)).function_space.mesh
            factor = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name="stiffness_factor")
            factor.x.array[:] = 1.0
            self.holder["factor"] = factor
        return CellwiseStiffness(self.scene.material.material, self.holder["factor"], self.name).psi(F)
