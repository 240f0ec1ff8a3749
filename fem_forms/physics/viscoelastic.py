"""A viscoelastic solid: finite-strain generalized Maxwell (Simo 1987; Holzapfel, Nonlinear Solid Mechanics,
2000, sec. 6.10) on any hyperelastic model psi(F).

The second Piola-Kirchhoff stress is S = g_inf S0 + sum_i Q_i, with S0 = 2 dpsi/dC the elastic stress of the
instantaneous response (E), g_inf = 1 - sum g_i the long-term share, and each Prony term's non-equilibrium
stress Q_i relaxing with its time tau_i: dQ_i/dt + Q_i / tau_i = g_i dS0/dt. Over a step dt with S0 linear in
time (Simo's recursive update, exact for a piecewise linear S0):
    Q_i,n+1 = a_i Q_i,n + b_i (S0,n+1 - S0,n),   a_i = exp(-dt / tau_i),   b_i = g_i (1 - a_i) / (dt / tau_i).
So within a step S = (g_inf + sum b_i) S0(u) + H with H = sum_i (a_i Q_i,n - b_i S0,n) known: the step's
residual is the gradient of  int (g_inf + sum b_i) psi(F) + H : E(F) dX  (E the Green strain; the small strain
for a small-strain model, whose S0 is sigma): a conservative step energy (energy line search), the history
on quadrature spaces of the dx rule, updated on accepted steps and rolled back on rejected ones. Between
steps a = 1, b = g (dt = 0): the energy's stress is then the committed g_inf S0 + sum Q_i (stress output)."""
from __future__ import annotations

from dolfinx import fem
import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.kinematics import green_strain, small_strain
from fem_forms.materials.hyperelastic import is_small_strain
from fem_forms.physics.elastic import ElasticEnergy
from fem_forms.physics.plastic import quadrature_rule, quadrature_scheme, quadrature_update
from fem_forms.physics.terms import Context, register_solid
from fem_forms.state import State


class ViscoelasticSolid(ElasticEnergy):
    """The elastic solid with Prony terms [g_i, tau_i], each material its own (DG0 fields of the term's index:
    a material with fewer terms, or none, has g_i = 0 there); every value changes without compiling."""

    def __init__(self, material, model_name: str, specs: list, regions, degree: int, binding=None):
        super().__init__(material, model_name, binding)
        self.regions = regions
        self.layout = [len(m.prony or []) for m in specs]
        n = max(self.layout)
        self.name = f"viscoelastic ({model_name}, {n} Prony term{'s' if n > 1 else ''})"
        self.g = [regions.field(v, f"prony_g_{i}") for i, v in enumerate(self._column(specs, 0, 0.0))]
        self.tau = [regions.field(v, f"prony_tau_{i}") for i, v in enumerate(self._column(specs, 1, 1.0))]
        self.a = [regions.field([1.0] * len(specs), f"prony_a_{i}") for i in range(n)]
        self.b = [regions.field([0.0] * len(specs), f"prony_b_{i}") for i in range(n)]
        mesh = regions.mesh
        self.points, _ = quadrature_rule(mesh, degree)
        Qt = fem.FunctionSpace(mesh, ufl.TensorElement("Quadrature", mesh.ufl_cell(), degree, shape=(3, 3),
                                                       quad_scheme=quadrature_scheme(mesh, degree)))
        self.Q = [fem.Function(Qt, name=f"prony_stress_{i}") for i in range(n)]
        self.S0 = fem.Function(Qt, name="elastic_stress_committed")
        self.t, self.t_committed = 0.0, 0.0

    @staticmethod
    def _column(specs: list, k: int, missing: float) -> list[list[float]]:
        """Per Prony term index, one value per material (g or tau; `missing` where a material has no such term)."""
        n = max(len(m.prony or []) for m in specs)
        return [[m.prony[i][k] if m.prony and i < len(m.prony) else missing for m in specs] for i in range(n)]

    @property
    def prony_terms(self) -> int:
        return len(self.g)

    @property
    def quadrature_history(self) -> bool:
        return self.prony_terms > 0

    @property
    def energy_caveat(self) -> str | None:
        return ("energy: not reported for a viscoelastic solid (its free energy holds the Prony branches' share, "
                "which the step energy the solver minimises is not)") if self.prony_terms else None

    def set_values(self, scene) -> None:
        layout = [len(m.prony or []) for m in scene.materials]
        if layout != self.layout:
            raise InputError(f"material.viscoelastic.prony: {layout} terms per material where the model has "
                             f"{self.layout} (a new number of Prony terms needs a new model)")
        super().set_values(scene)
        for i, (g, tau) in enumerate(zip(self._column(scene.materials, 0, 0.0),
                                          self._column(scene.materials, 1, 1.0))):
            self.regions.fill(self.g[i], g)
            self.regions.fill(self.tau[i], tau)
        self.update(self.t)

    def start(self, state: State) -> None:
        """Back to t = 0 at rest: no displacement, no Prony stress, no committed elastic stress (a new solve of
        this model)."""
        for f in (*self.Q, self.S0, state.fields["unknown"]):
            f.x.array[:] = 0.0
            f.x.scatter_forward()
        for name in (*(f.name for f in self.Q), self.S0.name, "unknown"):
            if name in state.old:
                state.old[name].x.array[:] = 0.0
        self.t = self.t_committed = 0.0
        self.update(0.0)

    def resume(self, t: float) -> None:
        """Continue from a checkpoint at time t (its Prony stresses and committed S0 restored with the State)."""
        self.t = self.t_committed = t
        self.update(t)

    def prepare(self, ctx: Context) -> None:
        self.residual_by_hand = False                  # the step energy has the history term: ufl.derivative

    def strain(self, F):
        return small_strain(F) if is_small_strain(self.material) else green_strain(F)

    def elastic_stress(self, ctx: Context, F):
        """S0: the instantaneous elastic second Piola-Kirchhoff stress (sigma for a small-strain model)."""
        F = ufl.variable(F)
        P = ufl.diff(super().density_at(ctx, F), F)
        return P if is_small_strain(self.material) else ufl.inv(F) * P

    def density_at(self, ctx: Context, F):
        """The step energy per rest volume: (g_inf + sum b_i) psi(F) + H : E(F)."""
        scale = 1 - sum(self.g) + sum(self.b)
        H = sum(a * Q - b * self.S0 for a, b, Q in zip(self.a, self.b, self.Q))
        return scale * super().density_at(ctx, F) + ufl.inner(H, self.strain(F))

    def energy(self, ctx: Context) -> ufl.Form:
        return ctx.volume(self.density(ctx))

    def elastic_law_energy(self, ctx: Context) -> ufl.Form:
        """int psi dX: the instantaneous elastic law (the stiffness at rest, for Rayleigh damping)."""
        return ctx.volume(super().density_at(ctx, ctx.F))

    def committed_energy(self, ctx: Context) -> ufl.Form:
        """int g_inf psi dX: the equilibrium branch's stored energy (the energy account's `elastic`; the Prony
        branches' share is booked as their work, `viscous_work`)."""
        return ctx.volume((1 - sum(self.g)) * super().density_at(ctx, ctx.F))

    def viscous_work(self, start: Context, end: Context) -> ufl.Form:
        """int sum_i (Q_i,n + Q_i,n+1) / 2 : (E_n+1 - E_n) dX: the work of the Prony branches' stresses over a
        step from start's u to end's (the trapezoidal rule of the energy account), Q_i,n the committed ones;
        stored in the branches or dissipated."""
        S0 = self.elastic_stress(end, end.F)
        dE = self.strain(end.F) - self.strain(start.F)
        mean = sum(Q + 0.5 * ((a - 1) * Q + b * (S0 - self.S0)) for a, b, Q in zip(self.a, self.b, self.Q))
        return end.volume(ufl.inner(mean, dE))

    def pk1(self, ctx: Context):
        F = ufl.variable(ctx.F)
        return ufl.diff(self.density_at(ctx, F), F)

    def attach(self, state: State, ctx: Context) -> None:
        """Each Prony stress and the committed S0 as history variables, updated at the accepted u."""
        S0 = self.elastic_stress(ctx, ctx.F)
        for i, (a, b, Q) in enumerate(zip(self.a, self.b, self.Q)):
            state.add_history(Q.name, Q, quadrature_update(Q, a * Q + b * (S0 - self.S0), self.points))
        stress = quadrature_update(self.S0, S0, self.points)

        def committed() -> np.ndarray:                 # the last update: the step is over (dt back to 0)
            values = stress()
            self.t_committed = self.t
            self.update(self.t)
            return values
        state.add_history(self.S0.name, self.S0, committed)

    def update(self, t: float) -> None:
        """The step's coefficients a_i = exp(-dt/tau_i), b_i = g_i (1 - a_i) / (dt/tau_i) on every cell, for
        dt = t - the last committed time (b_i = g_i at dt = 0)."""
        self.t = t
        dt = t - self.t_committed
        for g, tau, a, b in zip(self.g, self.tau, self.a, self.b):
            x = dt / tau.x.array
            a.x.array[:] = np.exp(-x)
            b.x.array[:] = g.x.array * (-np.expm1(-x) / x if dt > 0 else 1.0)


@register_solid(priority=10)
def viscoelastic_solid(scene, material, mesh, model_name: str, binding, regions) -> ViscoelasticSolid | None:
    """A solid with Prony terms where any of the scene's materials has them (the scene's own materials)."""
    if regions is None or not any(m.prony is not None for m in scene.materials):
        return None
    return ViscoelasticSolid(material, model_name, scene.materials, regions, scene.discretization.quadrature,
                             binding)
