"""The path every analysis shares: scene -> mesh -> function space -> total potential energy (UFL)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from .kinematics import deformation_gradient
from .loads import LoadFactor, external_work, supports
from .materials import Material, as_material, make_material
from .meshes import LoadedMesh, load_mesh
from .scene import Scene


@dataclass
class Model:
    """A discretised scene: mesh, displacement space and field, supports, loads and the energy."""
    scene: Scene
    loaded: LoadedMesh
    V: fem.FunctionSpace
    u: fem.Function
    material: Material
    dx: ufl.Measure
    load: LoadFactor
    bcs: list
    energy: ufl.Form               # total potential energy Pi(u) = int psi(F) - W_ext
    residual: ufl.Form             # dPi/du [v] (+ follower pressure virtual work)
    jacobian: ufl.Form             # d residual / du
    conservative: bool             # True when residual is the exact gradient of energy

    @property
    def mesh(self):
        return self.loaded.mesh

    @property
    def dofs(self) -> int:
        im = self.V.dofmap.index_map
        return im.size_global * self.V.dofmap.index_map_bs

    def min_jacobian(self) -> float:
        """Smallest det F over the cells' quadrature points (all ranks): < 0 means inverted."""
        F = deformation_gradient(self.u)
        points, _ = _quadrature_points(self.mesh, self.dx.metadata()["quadrature_degree"])
        expr = fem.Expression(ufl.det(F), points)
        ncells = self.mesh.topology.index_map(self.mesh.topology.dim).size_local
        vals = expr.eval(np.arange(ncells, dtype=np.int32))
        local = float(vals.min()) if vals.size else np.inf
        return self.mesh.comm.allreduce(local, op=MPI.MIN)

    def inadmissible(self) -> str | None:
        """Why the current state is not physical (inverted elements), or None."""
        if self.scene.material.model == "linear" and self.scene.analysis == "static":
            return None                                  # small-strain theory: J has no meaning
        jmin = self.min_jacobian()
        if not np.isfinite(jmin) or jmin <= 0:
            return f"inverted elements (smallest det F = {jmin:.3g})"
        return None


def _quadrature_points(mesh, degree: int):
    import basix
    cell = {"tetrahedron": basix.CellType.tetrahedron,
            "hexahedron": basix.CellType.hexahedron}[mesh.topology.cell_name()]
    return basix.make_quadrature(cell, max(degree, 1))


def build_material(scene: Scene, override=None) -> Material:
    if override is not None:
        return as_material(override)
    m = scene.material
    return make_material(m.model, E=m.E, nu=m.nu, mu=m.mu, lmbda=m.lmbda, C10=m.C10, C01=m.C01)


def build_model(scene: Scene, material=None, comm: MPI.Comm = MPI.COMM_WORLD) -> Model:
    """Mesh, P_k vector space, supports and the total potential energy for a scene."""
    loaded = load_mesh(scene.mesh, comm)
    mesh = loaded.mesh
    mat = build_material(scene, material)
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", scene.discretization.degree))
    u = fem.Function(V, name="displacement")
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": scene.discretization.quadrature})
    load = LoadFactor(mesh)
    bcs = supports(V, loaded, scene.fix, load)
    W, pressure = external_work(u, loaded, scene.load, scene.material.rho, load, dx)
    F = deformation_gradient(u)
    energy = mat.psi(F) * dx
    if W is not None:
        energy = energy - W
    v = ufl.TestFunction(V)
    residual = ufl.derivative(energy, u, v)
    p_res = pressure(v, F)
    if p_res is not None:
        residual = residual + p_res
    jacobian = ufl.derivative(residual, u, ufl.TrialFunction(V))
    return Model(scene, loaded, V, u, mat, dx, load, bcs, energy, residual, jacobian, p_res is None)
