"""The path every analysis shares: scene -> mesh -> function space -> total potential energy (UFL)."""
from __future__ import annotations

from dataclasses import dataclass

import basix
from dolfinx import fem
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.kinematics import deformation_gradient
from fem_forms.materials import mixed_energy
from fem_forms.materials.hyperelastic import Material, as_material, make_material
from fem_forms.meshes import LoadedMesh, load_mesh
from fem_forms.physics.loads import external_work
from fem_forms.physics.supports import LoadFactor, supports
from fem_forms.scene import Scene


@dataclass
class Model:
    """A discretised scene: mesh, spaces and fields, supports, loads and the energy.

    In the displacement formulation the unknown `state` is the displacement `u` itself; in the mixed
    formulation `state` holds (u, p) on a Taylor-Hood space and `u` is the displacement extracted
    from it by `sync_displacement()` for output."""
    scene: Scene
    loaded: LoadedMesh
    V: fem.FunctionSpace           # displacement space
    u: fem.Function                # displacement (for output, probes, pictures)
    material: Material
    dx: ufl.Measure
    load: LoadFactor
    bcs: list
    energy: ufl.Form               # total potential energy Pi(u) = int psi(F) - W_ext
    residual: ufl.Form             # dPi/du [v] (+ follower pressure virtual work)
    jacobian: ufl.Form             # d residual / du
    conservative: bool             # True when residual is the exact gradient of a minimised energy
    state: fem.Function | None = None   # the unknown (defaults to u)
    u_form: object = None               # displacement as it appears in forms (u, or split(state)[0])
    warnings: list | None = None

    def __post_init__(self):
        self.state = self.state if self.state is not None else self.u
        self.u_form = self.u_form if self.u_form is not None else self.u
        self.warnings = self.warnings or []
        self._jexpr = None

    @property
    def mesh(self):
        return self.loaded.mesh

    @property
    def dofs(self) -> int:
        space = self.state.function_space
        return space.dofmap.index_map.size_global * space.dofmap.index_map_bs

    def sync_displacement(self) -> None:
        """Copy the displacement out of a mixed state (no-op in the displacement formulation)."""
        if self.state is not self.u:
            self.u.interpolate(self.state.sub(0))

    def min_jacobian(self) -> float:
        """Smallest det F over the cells' quadrature points (all ranks): < 0 means inverted."""
        if self._jexpr is None:                       # compiled once per model
            F = deformation_gradient(self.u_form)
            points, _ = _quadrature_points(self.mesh, self.dx.metadata()["quadrature_degree"])
            self._jexpr = fem.Expression(ufl.det(F), points)
        expr = self._jexpr
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
    cell = {"tetrahedron": basix.CellType.tetrahedron,
            "hexahedron": basix.CellType.hexahedron}[mesh.topology.cell_name()]
    return basix.make_quadrature(cell, max(degree, 1))


def build_material(scene: Scene, override=None) -> Material:
    if override is not None:
        return as_material(override)
    m = scene.material
    return make_material(m.model, E=m.E, nu=m.nu, mu=m.mu, lmbda=m.lmbda, C10=m.C10, C01=m.C01)


NEARLY_INCOMPRESSIBLE_NU = 0.49


def build_model(scene: Scene, material=None, comm: MPI.Comm = MPI.COMM_WORLD) -> Model:
    """Mesh, spaces, supports and the total potential energy for a scene (displacement or mixed u-p)."""
    loaded = load_mesh(scene.mesh, comm)
    mesh = loaded.mesh
    mat = build_material(scene, material)
    disc = scene.discretization
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": disc.quadrature})
    load = LoadFactor(mesh)
    warnings = []
    if disc.formulation == "mixed":
        cell = mesh.ufl_cell()
        Wspace = fem.FunctionSpace(mesh, ufl.MixedElement([ufl.VectorElement("Lagrange", cell, 2),
                                                            ufl.FiniteElement("Lagrange", cell, 1)]))
        state = fem.Function(Wspace, name="state")
        u_form, p = ufl.split(state)
        V, _ = Wspace.sub(0).collapse()
        u = fem.Function(V, name="displacement")
        bcs = supports(Wspace.sub(0), loaded, scene.fix, load)
        F = deformation_gradient(u_form)
        density = mixed_energy(mat, F, p)
        test, trial, unknown = ufl.TestFunction(Wspace), ufl.TrialFunction(Wspace), state
        v = ufl.split(test)[0]
    else:
        V = fem.VectorFunctionSpace(mesh, ("Lagrange", disc.degree))
        u = state = u_form = fem.Function(V, name="displacement")
        bcs = supports(V, loaded, scene.fix, load)
        F = deformation_gradient(u)
        density = mat.psi(F)
        test, trial, unknown = ufl.TestFunction(V), ufl.TrialFunction(V), u
        v = test
        nu = scene.material.nu
        if material is None and nu is not None and nu >= NEARLY_INCOMPRESSIBLE_NU:
            warnings.append(f"material.nu = {nu}: nearly incompressible in the displacement formulation "
                            "locks (too stiff); set [discretization] formulation = \"mixed\"")
    W, pressure = external_work(u_form, loaded, scene.load, scene.material.rho, load, dx)
    energy = density * dx
    if W is not None:
        energy = energy - W
    residual = ufl.derivative(energy, unknown, test)
    p_res = pressure(v, F)
    if p_res is not None:
        residual = residual + p_res
    jacobian = ufl.derivative(residual, unknown, trial)
    # the mixed energy is a saddle in (u, p): no line-search objective there
    conservative = p_res is None and disc.formulation != "mixed"
    return Model(scene, loaded, V, u, mat, dx, load, bcs, energy, residual, jacobian, conservative,
                 state=state, u_form=u_form, warnings=warnings)
