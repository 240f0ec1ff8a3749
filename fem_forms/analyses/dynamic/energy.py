"""Energy accounting every step: kinetic 1/2 v.Mv (the scheme's own mass), stored elastic energy,
work of the external loads and energy dissipated by damping, the last two integrated by the trapezoidal
rule over each step (the rule Newmark average acceleration satisfies exactly for a linear problem:
there E_kin + E_el - W_ext + D stays constant to solver tolerance).

With [thermal] the temperature changes from T_n to T_n+1 in the staggered heat step, and the thermal
expansion does work on the motion: `thermal_work` adds psi(u_m, T_n+1) - psi(u_m, T_n) per step at the
midpoint u_m = (u_n + u_n+1) / 2. Not psi at u_n: Newmark's step sees the thermal force as the
trapezoidal mean of its values at T_n (through a_n) and T_n+1, and with that mean the identity
E_kin + E_el - W_ext - W_th + D = constant is exact for a linear material (checked to 1e-12; psi at u_n
left 7 % of a sudden heating's energy unaccounted).

A small-strain von Mises solid dissipates `plastic_work` int (sigma_n + sigma_n+1) / 2 : (eps_p,n+1 - eps_p,n) dX
per step (the term's `plastic_dissipation`; the same trapezoidal rule, which makes the identity
E_kin + E_el - W_ext + D + W_p = constant exact for Newmark); with a temperature its thermal work is
-int (sigma_n + sigma_n+1) / 2 : (eps_th,n+1 - eps_th,n) I dX (psi after a return mapping is no potential).
The finite-strain von Mises solid dissipates int sigma_y da + H/2 d(a^2) dX per step (tau : d_p on the yield
surface, a its equivalent plastic strain), and stores psi at Simo's return-mapped bbar_e taken at unit
determinant (the closed-form return keeps tr bbar_e, so mu/2 (tr bbar_e - 3) would not see the energy the
flow releases). O'Brien's plastic strain jumps at commit, at fixed total strain: it dissipates the stored
energy that jump releases. Neither is fitted to close the balance: what remains is the scheme's own energy
error (for O'Brien mostly its one-step-late update). With a temperature neither is accounted (the run
warns)."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl
from ufl.algorithms import expand_derivatives

from fem_forms.analyses.dynamic.system import DynamicSystem, damping_terms
from fem_forms.physics.assemble import total_energy, virtual_work
from fem_forms.errors import InputError
from fem_forms.meshes import bounding_box
from fem_forms.physics.terms import Context
from fem_forms.physics.thermoelastic import young_modulus


@dataclass
class Energies:
    kinetic: float = 0.0
    elastic: float = 0.0
    external_work: float = 0.0
    dissipated: float = 0.0
    thermal_work: float = 0.0
    plastic_work: float = 0.0
    contact: float = 0.0              # the contact barrier's stored energy
    viscous_work: float = 0.0         # the work on a viscoelastic solid's Prony branches (stored there or lost)
    fracture: float = 0.0             # the crack's surface energy beyond the notches' (what cracking dissipated)
    support: float = 0.0              # the energy stored in elastic supports (springs, foundations)

    def value(self, name: str) -> float:
        """The energy of column `name`."""
        return dict(zip(COLUMNS, self.row()))[name]

    def row(self) -> list:
        """The values in the order of COLUMNS."""
        return [self.kinetic, self.elastic, self.external_work, self.dissipated, self.thermal_work,
                self.plastic_work, self.contact, self.viscous_work, self.fracture, self.support]

    def balance(self) -> float:
        """E_kin + E_el + E_contact + E_support - W_ext - W_th + D + W_p + W_v + E_crack (constant in an exact
        account)."""
        return (self.kinetic + self.elastic + self.contact + self.support - self.external_work - self.thermal_work
                + self.dissipated + self.plastic_work + self.viscous_work + self.fracture)


# energies below that of the whole part strained this much are round-off: a balance relative to them would be
# a ratio of two noises (strains of 1e-8 are sqrt(machine epsilon), far below any motion a run is asked for)
ENERGY_FLOOR_STRAIN = 1e-8
COLUMNS = ("kinetic", "elastic", "external_work", "dissipated", "thermal_work", "plastic_work", "contact",
           "viscous_work", "fracture", "support")


def at_temperature(ctx: Context, T: fem.Function, T_then: fem.Function) -> Context:
    """ctx with its thermal strain and modulus factor written with T_then in place of T."""
    extra = dict(ctx.extra, temperature=T_then)
    if "modulus_factor" in extra:
        extra["modulus_factor"] = ufl.replace(extra["modulus_factor"], {T: T_then})
    return replace(ctx, thermal_strain=ufl.replace(ctx.thermal_strain, {T: T_then}), extra=extra)


@dataclass
class EnergyAccount:
    """Forms on their own Functions (state ue, velocity vm, increment w), so the step's forms and
    Constants are untouched; `history` holds (t, Energies) for every step."""
    system: DynamicSystem
    released: set
    history: list = field(default_factory=list)

    def __post_init__(self):
        s = self.system
        m, V = s.model, s.model.V
        self.comm = m.mesh.comm
        self.ue, self.vm, self.w = (fem.Function(V) for _ in range(3))
        self.thermal = m.temperature is not None       # the temperature changes between motion steps
        ctx = replace(m.context, u=self.ue)
        term = m.solid
        # a plastic solid's work in the account; with a temperature only where the thermal work of its
        # stresses is written (small-strain von Mises)
        plastic = term.counts_plastic_work(self.thermal)
        # a counted plastic solid stores psi with the history its state leads to; uncounted, the committed
        stored = term.stored_energy if plastic else term.committed_energy
        self.elastic = fem.form(stored(ctx))
        loads = total_energy(s.loads, ctx)
        power = -ufl.derivative(loads, self.ue, self.w) if loads is not None else None
        vw = virtual_work(s.loads, ctx, self.w)
        if vw is not None:
            power = -vw if power is None else power - vw
        dead = power is not None and vw is None and self.ue not in expand_derivatives(power).coefficients()
        self.dead = self._dead_load_vectors(ctx) if dead else None
        self.power = fem.form(power) if power is not None and not dead else None
        # the damping the scheme applies: with the lumped mass, Rayleigh's alpha part acts through the HRZ
        # diagonal (counted with the consistent M it left 3.9e-2 of the balance of a test beam, measured)
        dterms = damping_terms(s.scene, m, ctx, self.vm, s.lumped is None)
        self.dissipation = fem.form(virtual_work(dterms, ctx, self.w)) if dterms else None
        self.lumped_alpha = s.scene.damping.alpha if s.lumped is not None else 0.0
        self.u0 = fem.Function(V) if plastic else None            # the step's start for the plastic work
        start = replace(m.context, u=self.u0)
        if plastic and self.thermal:
            start = at_temperature(start, m.temperature, s.state.old["temperature"])
        self.plastic = fem.form(term.plastic_dissipation(start, ctx)) if plastic else None
        self.plastic_thermal = fem.form(term.thermal_work(start, ctx)) if plastic and self.thermal else None
        u0 = self.u0 if self.u0 is not None else fem.Function(V)
        viscous = term.viscous_work(replace(m.context, u=u0), ctx)     # None: no viscous history
        if viscous is not None:
            self.u0 = u0
        self.viscous = fem.form(viscous) if viscous is not None else None
        if s.lumped is None:
            self.M = fpetsc.assemble_matrix(s.mass)
            self.M.assemble()
        self.now = Energies()

    def _scalar(self, form) -> float:
        return self.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM)

    def _set(self, f: fem.Function, values) -> None:
        f.x.array[:] = values
        f.x.scatter_forward()

    def kinetic(self) -> float:
        v = self.system.v.vector
        if self.system.lumped is not None:
            y = v.copy()
            y.pointwiseMult(y, self.system.lumped)
            e = 0.5 * y.dot(v)
        else:
            y = self.M.createVecLeft()
            self.M.mult(v, y)
            e = 0.5 * y.dot(v)
        y.destroy()
        return e

    def _dead_load_vectors(self, ctx) -> list:
        """Dead loads (power independent of the state): each load's force vector at factor 1, assembled
        once, so a step's external work is dot products instead of two assemblies (half the cost of the
        accounting of an explicit step, measured)."""
        test = ufl.TestFunction(self.system.model.V)
        vectors = []
        for term in self.system.loads:
            saved = term.factor.value.copy()
            term.factor.value = 1.0
            f = fpetsc.assemble_vector(fem.form(-ufl.derivative(term.energy(ctx), self.ue, test)))
            f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            term.factor.value = saved
            vectors.append((term, f))
        return vectors

    def _factor(self, term, t: float) -> float:
        return 0.0 if term.index in self.released else term.factor_at(t)

    def _power(self, state, t: float) -> float:
        """External power at `state` with the loads' factors at t, in the direction w."""
        if self.power is None:
            return 0.0
        saved = [term.factor.value.copy() for term in self.system.loads]
        for term in self.system.loads:
            term.factor.value = self._factor(term, t)
        self._set(self.ue, state)
        p = self._scalar(self.power)
        for term, f in zip(self.system.loads, saved):
            term.factor.value = f
        return p

    def _thermal_work(self, mid) -> float:
        """psi(mid, T_n+1) - psi(mid, T_n): the stored energy's change by the step's new temperature
        (T_n is the State's committed value; T is put back after)."""
        T, T_old = self.system.model.temperature, self.system.state.old["temperature"]
        self._set(self.ue, mid)
        after = self._scalar(self.elastic)
        new = T.x.array.copy()
        T.x.array[:] = T_old.x.array
        before = self._scalar(self.elastic)
        T.x.array[:] = new
        return after - before

    @property
    def plastic_accounted(self) -> bool:
        return self.plastic is not None

    def start(self, t: float) -> Energies:
        self._set(self.ue, self.system.u.x.array)
        self.now = Energies(self.kinetic(), self._scalar(self.elastic), **self._stored())
        self.history.append((t, self.now))
        return self.now

    def advance(self, t_old: float, t_new: float) -> Energies:
        """After a step (old values in the State's old, new in its fields, not yet committed)."""
        s = self.system
        u0, u1 = s.state.old["unknown"].x.array, s.u.x.array
        prev = self.now
        self._set(self.w, u1 - u0)
        if self.dead is not None:
            work = 0.5 * sum((self._factor(term, t_old) + self._factor(term, t_new)) * f.dot(self.w.vector)
                             for term, f in self.dead)
        else:
            work = 0.5 * (self._power(u0, t_old) + self._power(u1, t_new))
        dis = 0.0
        if self.dissipation is not None or self.lumped_alpha:
            self._set(self.ue, 0.5 * (u0 + u1))
            self._set(self.vm, 0.5 * (s.state.old["velocity"].x.array + s.v.x.array))
            dis = self._scalar(self.dissipation) if self.dissipation is not None else 0.0
            if self.lumped_alpha:
                y = s.lumped.copy()
                y.pointwiseMult(y, self.vm.vector)
                dis += self.lumped_alpha * y.dot(self.w.vector)
                y.destroy()
        dis += s.model.terms.step_dissipation(s.u.vector)      # the terms' own (lagged friction)
        thermal = plastic = 0.0
        if self.thermal and self.plastic_thermal is None:
            thermal = self._thermal_work(0.5 * (u0 + u1))
        self._set(self.ue, u1)
        if self.plastic is not None:                 # before commit: the history is the step's start
            self._set(self.u0, u0)
            plastic = self._scalar(self.plastic)
            if self.plastic_thermal is not None:
                thermal = self._scalar(self.plastic_thermal)
        viscous = 0.0
        if self.viscous is not None:                 # before commit: the Prony stresses are the step's start
            self._set(self.u0, u0)
            viscous = self._scalar(self.viscous)
        self.now = Energies(self.kinetic(), self._scalar(self.elastic), prev.external_work + work,
                            prev.dissipated + dis, prev.thermal_work + thermal, prev.plastic_work + plastic,
                            viscous_work=prev.viscous_work + viscous, **self._stored())
        self.history.append((t_new, self.now))
        return self.now

    def _stored(self) -> dict[str, float]:
        """The energies the terms store at the current state, by column (a contact barrier's; the crack's
        surface energy beyond the notches')."""
        return self.system.model.terms.stored_energies(self.system.u.vector)

    def columns(self) -> tuple:
        """The energies this run records (thermal_work with a temperature field, plastic_work with an
        accounted plastic solid, contact with [contact])."""
        recorded = set(COLUMNS[:4]) | self.system.model.terms.energy_columns | \
            ({"thermal_work"} if self.thermal else set()) | ({"plastic_work"} if self.plastic_accounted else set()) | \
            ({"viscous_work"} if self.viscous is not None else set())
        return tuple(c for c in COLUMNS if c in recorded)

    def imbalance(self) -> float:
        """max over time of |E_kin + E_el - W_ext - W_th + D + W_p - (its start value)| in J."""
        start = self.history[0][1].balance()
        return max(abs(e.balance() - start) for _, e in self.history)

    def balance_error(self, floor: float = 0.0) -> float | None:
        """imbalance() over the largest energy of the run; None when that largest energy is at most `floor`
        (J): a run in which (almost) nothing moved has a ratio of two round-off numbers, no error."""
        scale = max(abs(x) for _, e in self.history for x in e.row())
        if scale <= floor:
            return None if scale > 0 or floor > 0 else 0.0
        return self.imbalance() / scale

    def round_off_floor(self) -> float:
        """ENERGY_FLOOR_STRAIN^2 x E x the part's bounding-box volume: about the elastic energy of the whole
        part at a strain round-off cannot tell from zero (0 for a user psi(F), which has no E)."""
        m = self.system.model
        try:
            E = young_modulus(m.material)
        except InputError:
            return 0.0
        lo, hi = bounding_box(m.mesh)
        return ENERGY_FLOOR_STRAIN**2 * E * float(np.prod(hi - lo))
