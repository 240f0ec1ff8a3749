"""The path every analysis shares: scene -> mesh -> spaces and state -> the terms the scene asks for ->
total potential energy, residual and tangent (UFL)."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

from dolfinx import fem, geometry
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.materials import Material
from fem_forms.meshes import LoadedMesh, load_mesh
from fem_forms.output.probes import ProbeSet
from fem_forms.physics.admissibility import SmallestValue
from fem_forms.physics.assemble import at_no_variation, equilibrium_forms, inverse_forms, scene_physics
from fem_forms.physics.parameters import Parameters
from fem_forms.physics.supports import LoadFactor
from fem_forms.physics.term_list import TermList
from fem_forms.physics.terms import Context, Load, Solid, SubProblem
from fem_forms.solvers.linear import rigid_body_modes
from fem_forms.solvers.snes import NonlinearProblem
from fem_forms.solvers.staggered import AlternateMinimization
from fem_forms.physics.thermoelastic import couple_temperature
from fem_forms.scene import Scene
from fem_forms.scene.material_sources import describe
from fem_forms.state import State


@dataclass
class Model:
    """A discretised scene: mesh, spaces, state, supports, the terms and the forms built from them.

    In the displacement formulation the solver's `unknown` is the displacement `u` itself; in the mixed
    formulation `unknown` holds (u, p) on a Taylor-Hood space and `u` is the displacement extracted
    from it by `sync_displacement()` for output. Every value a user can change is a Constant or a
    Function in the forms (`set_values` changes them without compiling anything)."""
    scene: Scene
    loaded: LoadedMesh
    V: fem.FunctionSpace           # displacement space
    u: fem.Function                # displacement (for output, probes, pictures); rest = "unknown": the rest offset
    material: Material             # parameters as Constants (bind_constants)
    dx: ufl.Measure
    load: LoadFactor
    bcs: list
    energy: ufl.Form | None        # total potential energy Pi(u) = int psi(F) - W_ext
    residual: ufl.Form             # dPi/du [v] (+ follower pressure virtual work)
    jacobian: ufl.Form             # d residual / du
    conservative: bool             # True when residual is the exact gradient of a minimised energy
    unknown: fem.Function          # what the solver solves for (u, or the mixed (u, p))
    u_form: object                 # displacement as it appears in forms (u, or split(unknown)[0])
    context: Context
    terms: TermList                # every term, declared once (find them by role: solid, loads)
    parameters: Parameters
    state: State
    warnings: list = field(default_factory=list)
    support_owners: list = field(default_factory=list)   # (fix index, component) of each of bcs
    temperature: fem.Function | None = None               # the coupled temperature ([thermal]), else None
    rest_offset: fem.Function | None = None               # rest shape minus mesh (a designed rest shape), else None

    def __post_init__(self):
        self._det_F: SmallestValue | None = None
        self._compiled: dict = {}
        self._probes: ProbeSet | None = None
        self._scalars: list | None = None
        self._sub_problems: list | None = None

    @property
    def probes(self) -> ProbeSet:
        """The scene's output probes located in the mesh once (a point outside it: InputError)."""
        if self._probes is None:
            self._probes = ProbeSet(self.mesh, self.scene.output.probes)
        return self._probes

    def compiled(self, which: str) -> fem.Form | None:
        """The compiled "residual", "jacobian" or "energy" (None if the model has none), compiled once and
        shared by the solver and the checks and outputs (each fem.form call re-hashes the UFL form: ~5 ms)."""
        if which not in self._compiled:
            expr = {"residual": self.residual, "jacobian": self.jacobian, "energy": self.energy}[which]
            self._compiled[which] = fem.form(expr) if expr is not None else None
        return self._compiled[which]

    @property
    def mesh(self):
        return self.loaded.mesh

    @property
    def solid(self) -> Solid:
        """The solid's stored-energy term (elastic or plastic)."""
        return self.terms.solid

    @property
    def loads(self) -> list[Load]:
        """The [[load]] terms, in scene order."""
        return self.terms.loads

    @property
    def physics(self) -> list[str]:
        """Names of the terms assembled into this model's forms (results.json "physics")."""
        names = [t.name for t in self.terms]
        if self.temperature is not None:
            names.append("thermal strain (heat solved first, staggered)")
        return names

    @property
    def dofs(self) -> int:
        space = self.unknown.function_space
        return space.dofmap.index_map.size_global * space.dofmap.index_map_bs

    def sync_displacement(self) -> None:
        """Copy the displacement out of a mixed state (no-op in the displacement formulation)."""
        if self.unknown is not self.u:
            self.u.interpolate(self.unknown.sub(0))

    def start_from_displacement(self) -> None:
        """Copy `u` into a mixed state's displacement part, a start guess (no-op in the displacement formulation)."""
        if self.unknown is not self.u:
            self.unknown.sub(0).interpolate(self.u)
            self.unknown.x.scatter_forward()

    def min_jacobian(self) -> float:
        """Smallest det F over the cells' quadrature points (all ranks): < 0 means inverted."""
        if self._det_F is None:                       # compiled once per model, on first use
            self._det_F = SmallestValue(ufl.det(self.context.F), self.mesh,
                                        self.dx.metadata()["quadrature_degree"])
        return self._det_F()

    def inadmissible(self) -> str | None:
        """Why the current state is not physical (inverted elements, a small-strain plastic state with
        large strains), or None."""
        if why := self.solid.outside_theory(self.context):
            return why
        if why := self.terms.inadmissible(self.unknown.vector):  # checked apart from a step filter (contact)
            return why
        if self.scene.small_strain and self.scene.analysis == "static":
            return None                                  # small-strain theory: J has no meaning
        jmin = self.min_jacobian()
        if not jmin > 0:
            return f"inverted elements (smallest det F = {jmin:.3g})"
        return None

    def problem(self, set_load=None, state: State | None = None) -> NonlinearProblem:
        """The model's equilibrium as the one SNES driver takes it: the compiled residual, tangent and (for a
        conservative model) energy, the supports, the admissibility check, the State, every array term and
        every global scalar."""
        return NonlinearProblem(self.unknown, self.compiled("residual"), self.compiled("jacobian"), self.bcs,
                                energy=self.compiled("energy") if self.conservative else None, set_load=set_load,
                                inadmissible=self.inadmissible, state=state or self.state,
                                array_terms=self.terms.arrays, scalars=self.global_scalars())

    def sub_problems(self) -> list[tuple[NonlinearProblem, SubProblem]]:
        """The problems the terms own in fields of their own (the damage), with the displacement frozen; built
        once per model: each the energy's derivative in its field, bounded by its committed values (if
        irreversible) and its upper bound."""
        if self._sub_problems is None:
            self._sub_problems = []
            for term in self.terms:
                sub = term.sub_problem(self.solid, self.context)
                if sub is None:
                    continue
                V, name = sub.field.function_space, sub.field.name
                R = ufl.derivative(sub.energy, sub.field, ufl.TestFunction(V))
                J = ufl.derivative(R, sub.field, ufl.TrialFunction(V))
                lower = self.state.old[name] if sub.irreversible else None
                problem = NonlinearProblem(sub.field, fem.form(R), fem.form(J), [], energy=fem.form(sub.energy),
                                           state=self.state, bounds=(lower, sub.upper))
                self._sub_problems.append((problem, sub))
        return self._sub_problems

    def staggered_driver(self, problem: NonlinearProblem, options: dict, linear_kind: str,
                         **kwargs) -> AlternateMinimization | None:
        """The displacement's driver whose steps alternate with the terms' sub-problems (None without any)."""
        subs = self.sub_problems()
        if not subs:
            return None
        return AlternateMinimization(problem, [p for p, _ in subs], min(s.tolerance for _, s in subs),
                                     max(s.max_iterations for _, s in subs), options, linear_kind=linear_kind,
                                     near_nullspace=lambda: rigid_body_modes(self.V),
                                     relaxation=[s.relaxation for _, s in subs], **kwargs)

    def global_scalars(self) -> list:
        """The scalar unknowns the terms add to the Newton solve (a volume-controlled cavity's pressure), made
        once per model: their forms compile once."""
        if self._scalars is None:
            scalars = [s for t in self.terms for s in t.global_scalars(self)]
            w = self.context.extra.get("virtual_displacement")
            if w is not None:                     # inverse elastostatics: its equations at w = 0 (inverse_forms);
                # its tangent is not an energy's: p is no Lagrange multiplier of the constraint there
                scalars = [replace(s, equation=at_no_variation(s.equation, w), multiplier=None,
                                   gradient=None if s.gradient is None else at_no_variation(s.gradient, w))
                           for s in scalars]
            self._scalars = scalars
        return self._scalars

    def only_ufl_terms(self, analysis: str) -> None:
        """InputError if a term computed as arrays (ArrayTerm) is in a model whose `analysis` assembles UFL
        forms alone (its energy would silently be left out)."""
        self.terms.only_ufl(analysis)

    def materials_report(self) -> list[dict]:
        """results.json "materials": name, cells, volume (m^3) and mass (kg) of each material, its model and
        parameters (and the library entry or the fit they came from)."""
        sizes = self.context.materials.summary(self.parameters.density, self.dx.metadata()["quadrature_degree"])
        return [{**size, **describe(spec)} for size, spec in zip(sizes, self.scene.materials)]

    def probe_materials(self) -> dict[str, str]:
        """The material each probe lies in (by name): on an interface, the first listed of those whose cells
        contain it (the same on any number of ranks)."""
        regions, names = self.context.materials, self.probes.names
        if not names:
            return {}
        tree = geometry.BoundingBoxTree(self.mesh, self.mesh.topology.dim)
        X = self.probes.X
        cells = geometry.compute_colliding_cells(self.mesh, geometry.compute_collisions(tree, X), X)
        first = np.array([min((int(regions.index[c]) for c in cells.links(i)), default=len(regions.materials))
                          for i in range(len(names))], dtype=np.int32)
        self.mesh.comm.Allreduce(MPI.IN_PLACE, first, op=MPI.MIN)
        return {n: regions.materials[int(i)].name for n, i in zip(names, first)}

    def set_values(self, scene: Scene) -> None:
        """Take the material constants, density, load and support values of `scene` (same mesh, same
        kinds of terms): only Constants and Functions change, no form is compiled."""
        self.terms.set_values(scene)
        self.parameters.set_density(self.context.materials.cell_values([m.rho for m in scene.materials]))
        for i, fix in enumerate(scene.fix):
            for c in fix.components:
                self.load.rescale((i, c), fix.value[c])
        self.scene = scene
        self._probes = None


NEARLY_INCOMPRESSIBLE_NU = 0.49


REST_SHAPES = (None, "designed", "unknown")


def build_model(scene: Scene, material=None, comm: MPI.Comm = MPI.COMM_WORLD,
                loaded: LoadedMesh | None = None, extra: dict | None = None,
                more_fields: Callable[[fem.FunctionSpace], dict] | None = None, rest: str | None = None) -> Model:
    """Mesh (the scene's, or `loaded`), spaces, supports and the forms of the scene's terms
    (displacement or mixed u-p); `extra` enters the Context (a cellwise `stiffness_factor`, say);
    `more_fields(V)` adds fields on the displacement space to the State (dynamics: velocity, acceleration).
    `rest`: where the rest shape is not the mesh (inverse design, on the target mesh): "designed", the rest shape is
    mesh + `rest_offset` d (a Function the design sets) and the unknown the displacement; "unknown", the unknown is
    the rest offset v itself (in the mixed formulation: (v, p), `u` then v's copy) and equilibrium is written on the
    mesh (inverse elastostatics, u = -v); "designed" in the displacement formulation only."""
    if rest not in REST_SHAPES:
        raise ValueError(f"rest = {rest!r}: one of {REST_SHAPES}")
    loaded = loaded or load_mesh(scene.mesh, comm, degree=scene.discretization.degree)
    mesh = loaded.mesh
    disc = scene.discretization
    warnings = []
    if disc.formulation == "mixed":
        cell = mesh.ufl_cell()
        Wspace = fem.FunctionSpace(mesh, ufl.MixedElement([ufl.VectorElement("Lagrange", cell, 2),
                                                            ufl.FiniteElement("Lagrange", cell, 1)]))
        unknown = fem.Function(Wspace, name="state")
        u_form, pressure = ufl.split(unknown)
        V, _ = Wspace.sub(0).collapse()
        u = fem.Function(V, name="displacement")
        bc_space = Wspace.sub(0)
        v = ufl.split(ufl.TestFunction(Wspace))[0]
    else:
        V = fem.VectorFunctionSpace(mesh, ("Lagrange", disc.degree))
        u = unknown = u_form = fem.Function(V, name="displacement")
        pressure, bc_space = None, V
        v = ufl.TestFunction(V)
        soft = max(scene.materials, key=lambda m: m.poisson if m.poisson is not None else -1.0)
        nu = soft.poisson
        if material is None and nu is not None and nu >= NEARLY_INCOMPRESSIBLE_NU:
            said = f"nu = {nu}" if soft.nu is not None else f"bulk = {soft.bulk:g} (nu = {nu:.4g})"
            warnings.append(f"{soft.key}.{said}: nearly incompressible in the displacement formulation "
                            "locks (too stiff); set [discretization] formulation = \"mixed\"")
    rest_offset = offset = rest_map = variation = None
    if rest is not None:
        rest_offset = offset = fem.Function(V, name="rest_minus_target")
        if rest == "unknown" and pressure is not None:         # mixed: v is the state's first part (u: its copy)
            offset = u_form
        rest_map = ufl.Identity(3) + ufl.grad(offset)           # G = dX/dx: the mesh mapped to the rest shape
    if rest == "unknown":
        variation = fem.Function(V)                              # d/dw, then w = 0: u = -v (inverse_forms)
        u = rest_offset
        unknown = unknown if pressure is not None else rest_offset
        u_form = variation - offset
    physics = scene_physics(scene, loaded, u_form, bc_space, material, pressure=pressure, extra=extra,
                            rest_map=rest_map, rest_offset=offset, bc_sign=-1.0 if rest == "unknown" else 1.0)
    context, terms = physics.context, physics.terms
    fields = {"unknown": unknown}
    if scene.thermal is not None:
        fields["temperature"] = couple_temperature(scene, context, terms.solid.material, disc.degree)
    fields.update(terms.state_fields())                 # a term's own fields (the damage), committed with u
    fields.update(more_fields(V) if more_fields is not None else {})
    warnings += [w for t in terms for w in t.warnings()]
    if rest == "unknown":
        context.deformation = ufl.inv(rest_map) + ufl.grad(variation) * ufl.inv(rest_map)
        context.extra["virtual_displacement"] = variation
        forms = inverse_forms(terms, context, unknown, variation)
    else:
        forms = equilibrium_forms(terms, context, unknown, v)
    # the mixed energy is a saddle in (u, p): no line-search objective there
    conservative = forms.conservative and disc.formulation != "mixed"
    state = State(fields)
    terms.solid.attach(state, context)               # history variables (plasticity)
    terms.start(state)                               # every term's start values, committed (the notches' damage)
    return Model(scene, loaded, V, u, terms.solid.material, context.dx, physics.load, physics.bcs, forms.energy,
                 forms.residual, forms.jacobian, conservative, unknown, u_form, context, terms,
                 context.parameters, state, warnings, physics.support_owners, fields.get("temperature"), rest_offset)

