"""The plastic solid as a term (the model's solid in place of the elastic energy) and its history variables.

The history (plastic strain, equivalent plastic strain) lives on quadrature spaces of the dx degree; the
forms use its COMMITTED values, which change only in State.commit() (the return mapping evaluated at
the accepted displacement by fem.Expression) and go back in State.rollback().
- von Mises: stress from the radial return of the current strain and the committed history, a virtual
  work sigma : delta eps; its ufl.derivative is the algorithmic consistent tangent (quadratic Newton).
- O'Brien: with the committed plastic strain frozen, the stress comes from an energy psi(E - eps_p)
  (a conservative term, energy line search); the plastic strain is updated explicitly at commit.
The elastic law on the elastic strain e is the material's: mu e:e + lambda/2 (tr e)^2 (linear: small
strain; stvk: Green strain). A thermal strain in the Context is taken out of the total strain first; a temperature-dependent
modulus (ctx.extra["modulus_factor"] = E(T) / E) scales mu and lambda (and kappa) as it scales the elastic
term's psi, while the yield stress and hardening stay.
"""
from __future__ import annotations

from dolfinx import fem
import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.kinematics import green_strain, small_strain
from fem_forms.materials.constants import bind_constants, set_parameters
from fem_forms.materials.plasticity import OBrien, VonMises
from fem_forms.elements import MAX_DEGREE
from fem_forms.physics import quadrature
from fem_forms.physics.admissibility import SmallestValue, quadrature_points
from fem_forms.physics.terms import Context, Solid, register_solid
from fem_forms.state import State


def quadrature_rule(mesh, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The rule of `degree` the dx uses on the mesh's cell (physics/quadrature.py: positive Gauss-Jacobi
    where basix's default has a non-positive weight), refused if a weight is still not positive (a history
    variable stored at such a point would count negatively; cannot happen with the rules used now)."""
    points, weights = quadrature_points(mesh, degree)
    if np.any(weights <= 0):
        good = [q for q in range(1, MAX_DEGREE + 1)
                if np.all(quadrature.points(mesh.topology.cell_name(), q)[1] > 0)]
        raise InputError(f"discretization.quadrature_degree = {degree}: the rule of that degree on "
                         f"{mesh.topology.cell_name()} cells has a non-positive weight; plasticity stores history "
                         f"at the quadrature points: choose one of {good}")
    return points, weights


def quadrature_scheme(mesh, degree: int) -> str:
    """The Quadrature element's quad_scheme: it must name the dx rule, else FFCx reports "Mismatch of
    tabulation points"."""
    return quadrature.rule_name(mesh.topology.cell_name(), degree)


class PlasticSolid(Solid):
    """Shared part: the material (Constants), the plastic model (Constants) and the history spaces."""
    is_plastic = True

    def __init__(self, material, plastic, model_name: str, mesh, degree: int, green: bool):
        self.material = material
        self.plastic = bind_constants(plastic, mesh)
        self.green = green                     # strain measure: Green (stvk) or small strain (linear)
        self.name = f"plastic ({model_name}, {plastic.name})"
        self.points, _ = quadrature_rule(mesh, degree)
        cell = mesh.ufl_cell()
        scheme = quadrature_scheme(mesh, degree)
        Qt = fem.FunctionSpace(mesh, ufl.TensorElement("Quadrature", cell, degree, quad_scheme=scheme,
                                                       shape=(3, 3)))
        Qs = fem.FunctionSpace(mesh, ufl.FiniteElement("Quadrature", cell, degree, quad_scheme=scheme))
        self.degree = degree
        self._small = None
        self.eps_p = fem.Function(Qt, name="plastic_strain")          # committed plastic strain
        self.alpha = fem.Function(Qs, name="equivalent_plastic_strain")   # committed equivalent strain

    def set_values(self, scene) -> None:
        set_parameters(self.material, scene.material.material)
        set_parameters(self.plastic, scene.material.plasticity)

    def counts_plastic_work(self, thermal: bool) -> bool:
        """Booked by the energy account; with a temperature only where the thermal work of the stresses is
        written (small-strain von Mises overrides this)."""
        return not thermal

    def strain(self, ctx: Context):
        """Total strain minus the thermal strain (small strain, or Green strain of F / (1 + eps_th))."""
        F = ctx.F
        if self.green:
            if ctx.thermal_strain is not None:
                F = F / (1 + ctx.thermal_strain)
            return green_strain(F)
        eps = small_strain(F)
        return eps if ctx.thermal_strain is None else eps - ctx.thermal_strain * ufl.Identity(3)

    def strain_variation(self, ctx: Context, v):
        """delta E[v]: sym(F^T grad v) for the Green strain, sym(grad v) for the small strain."""
        return ufl.sym(ctx.F.T * ufl.grad(v)) if self.green else ufl.sym(ufl.grad(v))

    def moduli(self, ctx: Context) -> tuple:
        """(mu, lambda) at the context's temperature: E(T) / E scales both (nu fixed)."""
        k = ctx.extra.get("modulus_factor")
        mu, lmbda = self.material.mu, self.material.lmbda
        return (mu, lmbda) if k is None else (k * mu, k * lmbda)

    def elastic_energy(self, ctx: Context, e):
        mu, lmbda = self.moduli(ctx)
        return mu * ufl.inner(e, e) + 0.5 * lmbda * ufl.tr(e) ** 2

    def elastic_stress(self, ctx: Context, e):
        mu, lmbda = self.moduli(ctx)
        return 2 * mu * e + lmbda * ufl.tr(e) * ufl.Identity(3)

    def elastic_law_energy(self, ctx: Context) -> ufl.Form:
        """int psi(total strain) dX: the elastic law alone (the stiffness at rest, for Rayleigh damping)."""
        return ctx.volume(self.elastic_energy(ctx, self.strain(ctx)))

    def new_history(self, ctx: Context) -> tuple:
        """(plastic strain, equivalent plastic strain) after the step, as UFL expressions of ctx's u."""
        raise NotImplementedError

    def attach(self, state: State, ctx: Context) -> None:
        """Register the history with the State: commit() evaluates the new history at the accepted u."""
        eps_p, alpha = self.new_history(ctx)
        for f, expr in ((self.eps_p, eps_p), (self.alpha, alpha)):
            state.add_history(f.name, f, quadrature_update(f, expr, self.points))

    def outside_theory(self, ctx: Context) -> str | None:
        """Small strain only: a displacement gradient above 1 somewhere is no small-strain answer (past the
        collapse load Newton runs off to huge displacements that the bounded plastic stresses cannot
        resist, where the round-off floor of the residual check would grow with |u| and pass them)."""
        if self.green:
            return None
        if self._small is None:                       # compiled once, on first use
            g = ufl.grad(ctx.u)
            self._small = SmallestValue(1 - ufl.sqrt(ufl.inner(g, g)), ctx.mesh, self.degree)
        return self._small.positive_or("displacement gradient above 1 (1 - |grad u| = {value:.3g}): "
                                       "outside small strain, no equilibrium found near this load")

    @property
    def plastic_strain(self):
        """The plastic strain tensor written as a field."""
        return self.eps_p

    @property
    def equivalent(self):
        """The scalar reported as max_plastic_strain: alpha (von Mises), |eps_p| (O'Brien)."""
        return self.alpha


class VonMisesSolid(PlasticSolid):
    """Small-strain J2 plasticity: sigma(eps, committed history) by radial return; non-conservative."""

    def _map(self, ctx: Context) -> tuple:
        """(elastic strain, plastic strain, equivalent plastic strain) after the radial return."""
        return self.plastic.return_map(self.moduli(ctx)[0], self.strain(ctx), self.eps_p, self.alpha)

    def stress(self, ctx: Context):
        return self.elastic_stress(ctx, self._map(ctx)[0])

    def virtual_work(self, ctx: Context, v) -> ufl.Form:
        return ctx.volume(ufl.inner(self.stress(ctx), self.strain_variation(ctx, v)))

    def pk1(self, ctx: Context):
        """The stress for output (small strain: every stress measure is sigma)."""
        return self.stress(ctx)

    def stored_energy(self, ctx: Context) -> ufl.Form:
        """int psi(elastic strain) dX after the return mapping (energy accounting; not a potential of the
        residual: the plastic work is dissipated)."""
        return ctx.volume(self.elastic_energy(ctx, self._map(ctx)[0]))

    def new_history(self, ctx: Context) -> tuple:
        _, eps_p, alpha = self._map(ctx)
        return eps_p, alpha

    def plastic_dissipation(self, start: Context, end: Context) -> ufl.Form:
        """int (sigma_n + sigma_n+1) / 2 : (eps_p,n+1 - eps_p,n) dX: the plastic work of a step from start's u
        to end's u, from the committed history of its start (the trapezoidal rule of the energy account)."""
        e1, eps_p1, _ = self._map(end)
        mean = 0.5 * (self.stress(start) + self.elastic_stress(end, e1))
        return end.volume(ufl.inner(mean, eps_p1 - self.eps_p))

    def counts_plastic_work(self, thermal: bool) -> bool:
        return True

    def thermal_work(self, start: Context, end: Context) -> ufl.Form:
        """-int (sigma_n + sigma_n+1) / 2 : (eps_th,n+1 - eps_th,n) I dX: the work of the thermal expansion in
        a step (start's context at the old temperature)."""
        mean = 0.5 * (self.stress(start) + self.stress(end))
        return end.volume(-ufl.tr(mean) * (end.thermal_strain - start.thermal_strain))


class OBrienSolid(PlasticSolid):
    """O'Brien-Bargteil-Hodgins: energy of the elastic strain E - eps_p (committed); explicit update."""

    def stored_energy(self, ctx: Context) -> ufl.Form:
        """int psi(E - eps_p) dX with the plastic strain the commit sets (the update releases energy)."""
        E = self.strain(ctx)
        return ctx.volume(self.elastic_energy(ctx, self.plastic.elastic_strain(E, self.plastic.update(E, self.eps_p))))

    def committed_energy(self, ctx: Context) -> ufl.Form:
        """int psi(E - eps_p) dX at the committed plastic strain: the energy the step's forces derive from."""
        return self.energy(ctx)

    def plastic_dissipation(self, start: Context, end: Context) -> ufl.Form:
        """int psi(E - eps_p,n) - psi(E - eps_p,n+1) dX at the step's end strain E: the stored energy the
        plastic update releases (it happens at commit, at fixed total strain)."""
        return self.committed_energy(end) - self.stored_energy(end)

    def energy(self, ctx: Context) -> ufl.Form:
        return ctx.volume(self.elastic_energy(ctx, self.plastic.elastic_strain(self.strain(ctx), self.eps_p)))

    def pk1(self, ctx: Context):
        """First Piola-Kirchhoff stress F S of S = dpsi/dE at the elastic strain (S itself for small strain)."""
        S = self.elastic_stress(ctx, self.plastic.elastic_strain(self.strain(ctx), self.eps_p))
        return ctx.F * S if self.green else S

    def new_history(self, ctx: Context) -> tuple:
        eps_p = self.plastic.update(self.strain(ctx), self.eps_p)
        return eps_p, ufl.sqrt(ufl.inner(eps_p, eps_p))

    @property
    def equivalent(self):
        return ufl.sqrt(ufl.inner(self.eps_p, self.eps_p))


class FiniteVonMisesSolid(PlasticSolid):
    """Finite-strain J2 (Simo): the history `eps_p` holds C_p^-1 (identity at rest); non-conservative."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        bs = self.eps_p.function_space.dofmap.index_map_bs
        self.eps_p.x.array[:] = np.tile(np.eye(3).ravel(), self.eps_p.x.array.size // bs)

    def mechanical_F(self, ctx: Context):
        """F with the thermal stretch taken out multiplicatively: F (1 + eps_th)^-1."""
        return ctx.F if ctx.thermal_strain is None else ctx.F / (1 + ctx.thermal_strain)

    def _map(self, ctx: Context):
        mu, lmbda = self.moduli(ctx)
        return self.plastic.return_map_finite(mu, lmbda + 2 * mu / 3, self.mechanical_F(ctx), self.eps_p,
                                              self.alpha)

    def pk1(self, ctx: Context):
        """P = tau F^-T (times F_th^-T with a thermal stretch)."""
        tau, _, _ = self._map(ctx)
        P = tau * ufl.inv(self.mechanical_F(ctx)).T
        return P if ctx.thermal_strain is None else P / (1 + ctx.thermal_strain)

    def virtual_work(self, ctx: Context, v) -> ufl.Form:
        return ctx.volume(ufl.inner(self.pk1(ctx), ufl.grad(v)))

    def new_history(self, ctx: Context) -> tuple:
        _, Cp_inv, alpha = self._map(ctx)
        return Cp_inv, alpha

    def _psi(self, ctx: Context, F, Cp_inv):
        mu, lmbda = self.moduli(ctx)
        J = ufl.det(F)
        bbar = J ** (-2.0 / 3.0) * F * Cp_inv * F.T
        return 0.5 * (lmbda + 2 * mu / 3) * ufl.ln(J) ** 2 + 0.5 * mu * (ufl.tr(bbar) - 3)

    def stored_energy(self, ctx: Context) -> ufl.Form:
        """int psi dX at the C_p^-1 the return mapping leads to (energy accounting), its isochoric bbar_e taken
        at unit determinant: the closed-form return keeps tr bbar_e (so psi's mu/2 (tr bbar_e - 3) would not
        see the energy the flow releases) and lets det bbar_e drift from 1 (Simo & Hughes, Box 9.1, correct
        it with a cubic)."""
        mu, lmbda = self.moduli(ctx)
        F = self.mechanical_F(ctx)
        J = ufl.det(F)
        bbar = J ** (-2.0 / 3.0) * F * self._map(ctx)[1] * F.T
        iso = ufl.tr(bbar) * ufl.det(bbar) ** (-1.0 / 3.0)
        return ctx.volume(0.5 * (lmbda + 2 * mu / 3) * ufl.ln(J) ** 2 + 0.5 * mu * (iso - 3))

    def elastic_law_energy(self, ctx: Context) -> ufl.Form:
        return ctx.volume(self._psi(ctx, self.mechanical_F(ctx), ufl.Identity(3)))

    def plastic_dissipation(self, start: Context, end: Context) -> ufl.Form:
        """int sigma_y (a_n+1 - a_n) + H/2 (a_n+1^2 - a_n^2) dX: on the yield surface, where Simo's return
        lands, tau : d_p = (sigma_y + H a) da, integrated exactly over the step (a_n committed, a_n+1 the
        return mapping's at end's state)."""
        a0, a1 = self.alpha, self._map(end)[2]
        return end.volume(self.plastic.yield_stress * (a1 - a0) + 0.5 * self.plastic.hardening * (a1**2 - a0**2))

    def committed_energy(self, ctx: Context) -> ufl.Form:
        """int psi at the committed C_p^-1 (the energy account of a run that cannot count the plastic work)."""
        return ctx.volume(self._psi(ctx, self.mechanical_F(ctx), self.eps_p))

    @property
    def plastic_strain(self):
        """Plastic Green strain (C_p - I) / 2 for output."""
        return 0.5 * (ufl.inv(self.eps_p) - ufl.Identity(3))


@register_solid(priority=20)
def plastic_solid(scene, material, mesh, model_name: str, binding, regions) -> PlasticSolid | None:
    """The scene's material with [material.plasticity] (a single material; the scene's own model only)."""
    plastic = scene.material.plasticity if model_name == scene.material.model else None
    if plastic is None:
        return None
    return plastic_term(material, plastic, scene.material.model, mesh, scene.discretization.quadrature)


def plastic_term(material, plastic, model_name: str, mesh, degree: int) -> PlasticSolid:
    """The term for a plastic model on a bound material: von Mises small strain ('linear') or finite strain
    ('neo-hookean'); O'Brien on the small strain ('linear') or the Green strain ('stvk')."""
    assert isinstance(plastic, (VonMises, OBrien))
    if isinstance(plastic, OBrien):
        cls = OBrienSolid
    else:
        cls = FiniteVonMisesSolid if model_name == "neo-hookean" else VonMisesSolid
    return cls(material, plastic, model_name, mesh, degree, green=model_name in ("stvk", "neo-hookean"))


def quadrature_update(f: fem.Function, expr, points: np.ndarray):
    """update() for State.add_history: expr at the quadrature points of every local cell, laid out in
    f's array through its dofmap (cell by cell, point by point, components innermost)."""
    V = f.function_space
    mesh = V.mesh
    tdim = mesh.topology.dim
    imap = mesh.topology.index_map(tdim)
    cells = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
    compiled = fem.Expression(expr, points)
    bs = V.dofmap.index_map_bs
    dofs = V.dofmap.list.array.reshape(len(cells), -1)          # (cells, points) blocked dofs
    index = (dofs[:, :, None] * bs + np.arange(bs)[None, None, :]).reshape(len(cells), -1)

    def update() -> np.ndarray:
        values = compiled.eval(cells).reshape(len(cells), -1)
        out = f.x.array.copy()
        out[index] = values
        return out
    return update
