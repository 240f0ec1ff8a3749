"""The discretised dynamic problem: the static model's terms evaluated at the scheme's generalized
midpoint, the time-discrete inertia and the damping terms, the State (u, v, a with old values), the mass
(consistent form or HRZ-lumped diagonal) and each load's history."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc
import ufl

from fem_forms.model import Model, build_model
from fem_forms.physics.assemble import equilibrium_forms, virtual_work
from fem_forms.physics.damping import RayleighDamping, ViscousDamping
from fem_forms.physics.inertia import DiscreteInertia, Inertia
from fem_forms.physics.terms import Context, Term
from fem_forms.physics.time_discrete import BACKWARD_EULER, NEWMARK_AVERAGE, TimeDiscrete, chung_hulbert
from fem_forms.scene import Scene
from fem_forms.state import State


def scheme_params(scene: Scene) -> tuple:
    """(alpha_m, alpha_f, beta, gamma, w_a) of the scene's implicit scheme."""
    if scene.dynamic.scheme == "generalized-alpha":
        return chung_hulbert(scene.dynamic.rho_inf)
    if scene.dynamic.scheme == "backward-euler":
        return BACKWARD_EULER
    return NEWMARK_AVERAGE


def damping_terms(scene: Scene, model: Model, ctx: Context, velocity, with_mass: bool) -> list[Term]:
    """The scene's damping terms acting on `velocity` (UFL) in the state of `ctx`."""
    d, mesh, terms = scene.damping, model.mesh, []
    if d.alpha or d.beta:
        terms.append(RayleighDamping(mesh, d.alpha, d.beta, model.solid, model.V, velocity, with_mass))
    if d.shear or d.bulk:
        terms.append(ViscousDamping(mesh, d.shear, d.bulk, velocity, scene.small_strain))
    return terms


def mass_form(model: Model) -> fem.Form:
    """The consistent mass form int rho du . v dX, compiled once per dynamic system (lumping, the
    initial acceleration and the energy account share it)."""
    V = model.V
    return fem.form(Inertia().mass(model.context, ufl.TrialFunction(V), ufl.TestFunction(V)))


def hrz_lumped_mass(model: Model, mass: fem.Form) -> PETSc.Vec:
    """HRZ lumping: the consistent mass's diagonal scaled to keep the total mass (row sums for P1,
    positive for P2, where row sums are not)."""
    M = fpetsc.assemble_matrix(mass)
    M.assemble()
    diag = M.getDiagonal()
    one = fem.form(model.parameters.density * model.dx)
    total = model.mesh.comm.allreduce(fem.assemble_scalar(one), op=MPI.SUM)
    diag.scale(3.0 * total / diag.sum())
    M.destroy()
    return diag


@dataclass
class DynamicSystem:
    scene: Scene
    model: Model
    state: State
    td: TimeDiscrete
    v: fem.Function
    a: fem.Function
    residual: ufl.Form            # implicit step: inertia + f_int - f_ext (+ damping) at the midpoints
    jacobian: ufl.Form
    energy: ufl.Form | None       # effective energy (None when damping or follower loads remove it)
    explicit_residual: ufl.Form   # f_int(u) - f_ext(t) + C v_h (the explicit step's one assembly)
    v_h: fem.Function             # the velocity the explicit step's damping sees
    lumped: PETSc.Vec | None      # HRZ diagonal (lumped mass), zero nowhere
    constrained: np.ndarray       # owned local indices of supported dofs
    loads: list                   # the model's load terms (each with its factor Constant)
    mass: fem.Form                # the consistent mass form, compiled once
    start_warnings: list = field(default_factory=list)     # what the start found (printed before the march)
    _explicit_form: fem.Form | None = field(default=None, repr=False)
    _reaction_form: fem.Form | None = field(default=None, repr=False)

    @property
    def u(self) -> fem.Function:
        return self.model.u

    def explicit_form(self) -> fem.Form:
        """explicit_residual compiled once (the initial acceleration, the explicit step and the support forces)."""
        if self._explicit_form is None:
            self._explicit_form = fem.form(self.explicit_residual)
        return self._explicit_form

    def lumped_alpha(self) -> float:
        """Rayleigh's alpha where the implicit step applies it through the HRZ diagonal (lumped mass), else 0 (the
        explicit step applies alpha M v with the consistent M, in the explicit form)."""
        implicit = self.scene.dynamic.scheme != "central-difference"
        return float(self.scene.damping.alpha) if self.lumped is not None and implicit else 0.0

    def reaction_form(self) -> fem.Form:
        """f_int(u) - f_ext(t) + C v_h with the damping the implicit step applies: with the lumped mass Rayleigh's
        alpha part acts through the HRZ diagonal (the caller adds alpha D v_h), so it is left out here; without it
        the explicit form itself (compiled once, no second form)."""
        if not self.lumped_alpha():
            return self.explicit_form()
        if self._reaction_form is None:
            ctx, test = self.model.context, ufl.TestFunction(self.model.V)
            wd = virtual_work(damping_terms(self.scene, self.model, ctx, self.v_h, False), ctx, test)
            self._reaction_form = fem.form(self.model.residual + wd if wd is not None else self.model.residual)
        return self._reaction_form

    def set_load_time(self, t_new: float, t_old: float, released: set) -> None:
        """Each load's factor at the force midpoint: (1 - alpha_f) h(t_new) + alpha_f h(t_old);
        loads held only for the initial state are released (0)."""
        af = float(self.td.alpha_f.value)
        for term in self.loads:
            f = 0.0 if term.index in released else (1 - af) * term.factor_at(t_new) + af * term.factor_at(t_old)
            term.factor.value = f


def build_system(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD) -> DynamicSystem:
    model = build_model(scene, comm=comm, more_fields=lambda V: {
        "velocity": fem.Function(V, name="velocity"), "acceleration": fem.Function(V, name="acceleration")})
    V, u, state = model.V, model.u, model.state      # one State: u, v, a, T, the terms' fields and history
    v, a = state.fields["velocity"], state.fields["acceleration"]
    old = state.old
    td = TimeDiscrete(model.mesh, old["unknown"], old["velocity"], old["acceleration"],
                      scheme_params(scene), scene.dynamic.dt)
    lumped = scene.dynamic.mass == "lumped"
    ctx_f = replace(model.context, u=td.mid_f(u, old["unknown"]))
    velocity_f = td.mid_f(td.velocity(u), old["velocity"])
    damping = damping_terms(scene, model, ctx_f, velocity_f, with_mass=not lumped)
    test = ufl.TestFunction(V)
    # the model's recipe with its terms at the generalized mid-point u_f, the inertia and the damping added
    inertia = None if lumped else DiscreteInertia(td, u).energy(model.context)
    forms = equilibrium_forms(model.terms, ctx_f, u, test, scale=1 / (1 - td.alpha_f), inertia=inertia,
                              damping=tuple(damping))
    v_h = fem.Function(V, name="velocity_h")
    explicit = model.residual
    wd = virtual_work(damping_terms(scene, model, model.context, v_h, True), model.context, test)
    if wd is not None:
        explicit = explicit + wd
    mass = mass_form(model)
    nown = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    constrained = np.unique(np.concatenate([bc.dof_indices()[0][: bc.dof_indices()[1]] for bc in model.bcs])) \
        if model.bcs else np.empty(0, dtype=np.int32)
    constrained = constrained[constrained < nown]
    return DynamicSystem(scene, model, state, td, v, a, forms.residual, forms.jacobian,
                         forms.energy if forms.conservative else None, explicit, v_h,
                         hrz_lumped_mass(model, mass) if lumped else None, constrained, model.loads, mass)
