"""An inflated closed cavity ([[load]] type = "inflation"): its pressure p does work p dV on the walls, so the
load has an energy, -p (V(u) - V0), with the cavity volume V = -1/3 int x . n da over the walls (n the
solid's outward normal, pointing into the cavity; on a symmetry plane through the origin x . n = 0, so the
walls alone give V when the planes close the cavity). Its derivative is the follower pressure's virtual
work, so Newton keeps the energy line search. Pressure control ramps p with the load factor; volume
control prescribes the added volume and solves p with the displacement (a GlobalScalar: bordered Newton),
passing the pressure's limit points (a balloon's snap-through)."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.errors import InputError
from fem_forms.meshes.enclosure import enclosure_problem
from fem_forms.physics.scalars import GlobalScalar, derivative_wrt_constant
from fem_forms.physics.terms import Context, Load as LoadTerm, register_load
from fem_forms.physics.thermoelastic import young_modulus
from fem_forms.scene import Load


@register_load("inflation")
class Inflation(LoadTerm):
    """A closed cavity under pressure (pressure control) or with a prescribed added volume (volume control)."""
    name = "inflation"
    # the walls' energy misses the symmetry planes' share of dV when a plane's normal displacement varies: only
    # the supports hold it at 0. The residual is the exact virtual work p int v . J F^-T N dA (the same on the
    # free dofs), so that the reactions on the symmetry planes carry the pressure's true resultant
    residual_by_hand = True

    def declare(self, spec: Load, mesh: dmesh.Mesh) -> None:
        self.cavity = spec.name
        self.volume_control = spec.volume is not None
        # pressure control: the prescribed pressure (scaled by the load factor and history);
        # volume control: the unknown pressure itself (a Lagrange multiplier, 0 at rest)
        self.pressure = fem.Constant(mesh, PETSc.ScalarType(0.0 if self.volume_control else spec.pressure))
        self.added_volume = fem.Constant(mesh, PETSc.ScalarType(spec.volume or 0.0))
        self.rest_volume = fem.Constant(mesh, PETSc.ScalarType(0.0))      # V0, set by prepare
        self.wall_area = fem.Constant(mesh, PETSc.ScalarType(1.0))        # mesh area of the walls
        self.where = spec.where
        self._ctx: Context | None = None
        self._volume_form = self._rest_volume_form = None

    def set_spec(self, spec: Load) -> None:
        if (spec.volume is not None) != self.volume_control:
            raise InputError(f"load[{self.index}]: a model cannot switch between pressure and volume control")
        if self.volume_control:
            self.added_volume.value = spec.volume
        else:
            self.pressure.value = spec.pressure

    # -- geometry ------------------------------------------------------------------------------------
    def _walls(self, ctx: Context):
        """The boundary measure of the cavity's walls (the ds ids of its facets, summed)."""
        ids = ctx.regions[self.index]
        measure = ctx.ds(ids[0])
        for k in ids[1:]:
            measure = measure + ctx.ds(k)
        return measure

    def volume_integrand(self, ctx: Context):
        """-1/3 x . J F^-T N (per mesh facet area): its integral over the walls is the cavity volume."""
        area_vector = ufl.det(ctx.F) * ufl.inv(ctx.F).T * ctx.rest_area_vector()
        return -ufl.dot(ctx.position, area_vector) / 3.0

    @staticmethod
    def rest_shape_integrand(ctx: Context):
        """-1/3 X . N dA (per mesh facet area): its integral over the walls is the cavity's rest volume."""
        return -ufl.dot(ctx.rest_position, ctx.rest_area_vector()) / 3.0

    def rest_volume_integrand(self, ctx: Context):
        """The rest volume's integrand in the volume-control equation: the rest shape's, which an inverse design's
        unknown rest shape moves; V0 / the walls' area (the same integral) where the mesh is the rest shape."""
        if ctx.rest_offset is None:
            return self.rest_volume / self.wall_area
        return self.rest_shape_integrand(ctx)

    def prepare(self, ctx: Context) -> None:
        """Refuse walls that enclose no volume; the rest volume V0 and the walls' area as Constants."""
        label = f"{self.where.key} (cavity {self.cavity!r})"
        tags = ctx.ds.subdomain_data()
        facets = np.unique(np.concatenate([tags.find(k) for k in ctx.regions[self.index]] or [np.zeros(0, np.int32)]))
        if why := enclosure_problem(ctx.mesh, facets):
            raise InputError(f"{label}: the walls enclose no volume: {why}; select the whole cavity wall, or use "
                             "type = \"pressure\" for a pressure on an open surface")
        walls = self._walls(ctx)
        comm = ctx.mesh.comm
        rest = self.rest_shape_integrand(ctx) * walls
        v0 = comm.allreduce(fem.assemble_scalar(fem.form(rest)), op=MPI.SUM)
        if not v0 > 0:
            raise InputError(f"{label}: the walls enclose a volume of {v0:.4g} m^3 on the solid's outer side: a "
                             "cavity's walls face into it (is this the body's outer surface? use type = \"pressure\")")
        self.rest_volume.value = v0
        self.wall_area.value = comm.allreduce(fem.assemble_scalar(fem.form(1.0 * walls)), op=MPI.SUM)
        self._ctx = ctx

    def applied_pressure(self, ctx: Context):
        """The pressure acting: the prescribed one times the load factor and history, or the unknown one."""
        if self.volume_control:
            return self.pressure
        return ctx.load.constant * self.factor * self.pressure

    def energy(self, ctx: Context) -> ufl.Form:
        """-p (V(u) - V0) = p/3 int (x . J F^-T N - X . N) dA."""
        return -self.applied_pressure(ctx) * (self.volume_integrand(ctx) - self.rest_shape_integrand(ctx)) \
            * self._walls(ctx)

    def first_variation(self, ctx: Context, v) -> ufl.Form:
        """-p dV[v] = p int v . J F^-T N dA: the follower pressure's virtual work (exact for a closed surface,
        and with v . n = 0 on the symmetry planes that close it)."""
        area_vector = ufl.det(ctx.F) * ufl.inv(ctx.F).T * ctx.rest_area_vector()
        return self.applied_pressure(ctx) * ufl.dot(v, area_vector) * self._walls(ctx)

    # -- volume control ----------------------------------------------------------------------------
    def added(self, ctx: Context):
        """lambda f dV: the prescribed added volume, ramped by the load factor and history (UFL scalar)."""
        return ctx.load.constant * self.factor * self.added_volume

    def global_scalars(self, model) -> list:
        """Under volume control, the cavity pressure with its equation s (V(u) - V_rest - lambda dV) = 0 (V_rest: V0,
        or the designed rest shape's cavity), scaled by s = E / V0^(1/3) so that it reads as a force beside the
        field residual."""
        if not self.volume_control:
            return []
        ctx = model.context
        try:
            modulus = young_modulus(model.material)
        except InputError:                                # a user's psi(F): no modulus to scale with
            modulus = 1.0
        scale = modulus / float(self.rest_volume.value) ** (1.0 / 3.0)
        walls = self._walls(ctx)
        equation = scale * (self.volume_integrand(ctx) - self.rest_volume_integrand(ctx)
                            - self.added(ctx) / self.wall_area) * walls
        v = model.residual.arguments()[0]
        return [GlobalScalar(f"{self.cavity} pressure", self.pressure, equation,
                             coupling=derivative_wrt_constant(model.residual, self.pressure),
                             gradient=ufl.derivative(equation, model.unknown, v), slope=0.0,
                             multiplier=-1.0 / scale)]      # -p (V - V0): dR/dp = -dV/du = -(dc/du) / s

    # -- reporting ---------------------------------------------------------------------------------
    def volume(self) -> float:
        """The cavity's volume at the current state (m^3, every rank)."""
        if self._volume_form is None:
            self._volume_form = fem.form(self.volume_integrand(self._ctx) * self._walls(self._ctx))
        return self._ctx.mesh.comm.allreduce(fem.assemble_scalar(self._volume_form), op=MPI.SUM)

    def pressure_now(self) -> float:
        """The pressure acting at the current load factor (Pa)."""
        if self.volume_control:
            return float(self.pressure.value)
        return float(self._ctx.load.constant.value) * float(self.factor.value) * float(self.pressure.value)

    def report(self, x=None) -> dict:
        """results.json `cavities`: this cavity's numbers (merged with the other cavities')."""
        return {"cavities": {self.cavity: self.numbers()}}

    def numbers(self) -> dict:
        """Pressure, volume and volume_change at the current state (from the rest volume, which an inverse
        design's rest shape sets: then also `rest_volume`)."""
        volume, rest = self.volume(), self.rest_volume_now()
        designed = {} if self._ctx.rest_offset is None else {"rest_volume": rest}
        return {"pressure": self.pressure_now(), "volume": volume, "volume_change": volume - rest, **designed}

    def rest_volume_now(self) -> float:
        """The cavity's rest volume (m^3, every rank): V0, or where the rest shape is designed, at its design."""
        if self._ctx.rest_offset is None:
            return float(self.rest_volume.value)
        if self._rest_volume_form is None:
            self._rest_volume_form = fem.form(self.rest_volume_integrand(self._ctx) * self._walls(self._ctx))
        return self._ctx.mesh.comm.allreduce(fem.assemble_scalar(self._rest_volume_form), op=MPI.SUM)

    def record(self) -> dict:
        r = self.numbers()
        return {f"{self.cavity}_pressure": r["pressure"], f"{self.cavity}_volume": r["volume"]}


def cavity_report(terms) -> dict:
    """results.json `cavities`: {name: {pressure, volume, volume_change}} of every inflated cavity (and its
    `rest_volume` where the rest shape is designed)."""
    return {t.cavity: t.numbers() for t in terms if isinstance(t, Inflation)}
