"""The heat equation in UFL, backward Euler in time:

    rho c (T - T_old) / dt = div(k grad T) + q,
    -k grad T . n = h (T - T_amb)  (convection)  or  eps sigma_SB (T_abs^4 - T_amb,abs^4)  (radiation),
    T = T_D (prescribed, constant or piecewise linear in time); boundaries not named are insulated.

Every value (k, rho c, 1/dt, h, ambient, emissivity, T_D) is a fem.Constant: a new value or time step
compiles nothing. Radiation makes the residual nonlinear; the one SNES driver solves both cases.
"""
from __future__ import annotations

from dolfinx import fem
from petsc4py import PETSc
import ufl

from fem_forms.meshes import LoadedMesh
from fem_forms.physics.quadrature import metadata as quadrature_metadata
from fem_forms.physics.supports import load_regions, locate_facets
from fem_forms.scene.analyses.thermal_section import ThermalSpec
from fem_forms.physics.histories import piecewise_linear
from fem_forms.physics.regions import MaterialRegions

STEFAN_BOLTZMANN = 5.670374419e-8       # W/(m^2 K^4)


def thermal_constant(material, thermal: ThermalSpec, name: str):
    """A material's own conductivity, specific_heat or expansion, else [thermal]'s (None if neither)."""
    own = getattr(material, name)
    return own if own is not None else getattr(thermal, name)


class HeatForms:
    """Residual, tangent and Dirichlet conditions of one (steady or backward-Euler) heat step for the
    temperature T; `T_old` is the last committed temperature, `source` a heat source per volume (UFL) or None."""

    def __init__(self, thermal: ThermalSpec, materials: list, loaded: LoadedMesh, T: fem.Function,
                 T_old: fem.Function, transient: bool, quadrature: int, source=None, regions=None):
        mesh = loaded.mesh
        V = T.function_space
        self.T, self.thermal = T, thermal

        def const(v: float) -> fem.Constant:
            return fem.Constant(mesh, PETSc.ScalarType(v))

        k = [thermal_constant(m, thermal, "conductivity") for m in materials]
        capacity = [m.rho * (thermal_constant(m, thermal, "specific_heat") or 0.0) for m in materials]
        if len(materials) == 1:
            self.k, self.capacity = const(k[0]), const(capacity[0])
        else:
            regions = regions or MaterialRegions(loaded, materials)
            self.k, self.capacity = regions.field(k, "conductivity"), regions.field(capacity, "heat_capacity")
        self.inv_dt = const(0.0)
        rule = quadrature_metadata(mesh.topology.cell_name(), quadrature)
        dx = ufl.Measure("dx", domain=mesh, metadata=rule)
        tags, regions = load_regions(loaded, thermal.boundary)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags, metadata=rule)
        w = ufl.TestFunction(V)
        R = self.k * ufl.inner(ufl.grad(T), ufl.grad(w)) * dx
        self.physics = ["conduction"]
        if transient:
            R += self.capacity * self.inv_dt * (T - T_old) * w * dx
            self.physics.append("heat capacity (backward Euler)")
        if source is not None:
            R -= source * w * dx
            self.physics.append("heat source")
        self.linear = True
        self.bcs, self._histories = [], []
        fdim = mesh.topology.dim - 1
        zero = const(thermal.absolute_zero)
        for i, b in enumerate(thermal.boundary):
            def on_area(flux, ids=regions[i]):          # int flux w dA over this boundary's facets
                return sum(flux * w * ds(k) for k in ids)
            if b.kind == "temperature":
                value = const(b.value if b.history is None else piecewise_linear(b.history, 0.0))
                dofs = fem.locate_dofs_topological(V, fdim, locate_facets(loaded, b.where))
                self.bcs.append(fem.dirichletbc(value, dofs, V))
                if b.history is not None:
                    self._histories.append((value, b.history))
            elif b.kind == "convection":
                R += on_area(const(b.h) * (T - const(b.ambient)))
            else:
                eps_sigma = const(b.emissivity * STEFAN_BOLTZMANN)
                R += on_area(eps_sigma * ((T - zero) ** 4 - (const(b.ambient) - zero) ** 4))
                self.linear = False
        self.physics += sorted({b.kind for b in thermal.boundary if b.kind != "temperature"})
        self.residual = R
        self.jacobian = ufl.derivative(R, T, ufl.TrialFunction(V))

    def set_time(self, t: float, dt: float | None = None) -> None:
        """Prescribed temperatures at time t; 1/dt for the backward-Euler step ending at t."""
        for value, history in self._histories:
            value.value = piecewise_linear(history, t)
        if dt is not None:
            self.inv_dt.value = 1.0 / dt


def temperature_space(mesh, degree: int) -> fem.FunctionSpace:
    """The Lagrange space of the temperature (the displacement's degree)."""
    return fem.FunctionSpace(mesh, ("Lagrange", degree))
