"""The terms a scene asks for, and the forms built from them: total energy, residual and tangent.

Residual and tangent always come from ufl.derivative: of the energy for conservative terms, plus the
virtual work of the others. The inverse problem's residual is the same virtual work, taken with respect
to the displacement and then written with u = -v (the unknown rest offset)."""
from __future__ import annotations

from dataclasses import dataclass

from dolfinx import fem
import ufl

from fem_forms.errors import InputError
from fem_forms.materials import Material, as_material
from fem_forms.materials.constants import bind_constants
from fem_forms.meshes import LoadedMesh
import fem_forms.physics.elastic  # noqa: F401 (registers the elastic solid)
import fem_forms.physics.plastic  # noqa: F401 (registers the plastic solids)
import fem_forms.physics.viscoelastic  # noqa: F401 (registers the viscoelastic solid)
import fem_forms.physics.loads  # noqa: F401 (registers the load terms)
import fem_forms.physics.cavities  # noqa: F401 (registers the inflation load)
import fem_forms.physics.contact  # noqa: F401 (registers the [contact] terms)
import fem_forms.physics.fracture  # noqa: F401 (registers the [fracture] phase field)
import fem_forms.physics.foundation  # noqa: F401 (registers the foundation load type)
import fem_forms.physics.springs  # noqa: F401 (registers the [[spring]] terms)
from fem_forms.physics.material_fields import MaterialBinding, with_fibers
from fem_forms.physics.parameters import Parameters
from fem_forms.physics.regions import MaterialRegions
from fem_forms.physics import quadrature
from fem_forms.elements import check_degree
from fem_forms.physics.supports import LoadFactor, body_regions, load_regions, supports
from fem_forms.physics.term_list import TermList
from fem_forms.physics.terms import Context, LOAD_TERMS, SCENE_TERMS, SOLID_KINDS, Term
from fem_forms.scene import Scene


def build_material(scene: Scene, override=None) -> Material:
    """The scene's material model (validated and built once, when the scene was read), or the caller's own."""
    if override is not None:
        return as_material(override)
    return scene.material.material


@dataclass
class Physics:
    """What every model is built from: the Context, the declared terms, the load factor and the supports."""
    context: Context
    terms: TermList
    load: LoadFactor
    bcs: list
    support_owners: list                  # (fix index, component) of each of bcs


def scene_physics(scene: Scene, loaded: LoadedMesh, u, bc_space: fem.FunctionSpace, material=None,
                  rest_map=None, pressure=None, bc_sign: float = 1.0, rest_offset=None,
                  extra: dict | None = None) -> Physics:
    """The one recipe every model follows (forward, on a designed rest shape, inverse): the Context
    (measures, density field, load factor, kinematics of `u` and the rest map G = I + grad `rest_offset`), the
    scene's terms with the material's parameters as Constants, each prepared on the Context, and the supports
    on `bc_space` (sign -1: the inverse problem's unknown is rest minus deformed position)."""
    mesh = loaded.mesh
    regions = MaterialRegions(loaded, scene.materials)
    binding = MaterialBinding(scene.materials, regions) if material is None and regions.several else None
    mat = binding.material if binding is not None else bind_constants(build_material(scene, material), mesh)
    if material is None:
        mat = with_fibers(mat, scene.materials, regions, loaded)
    disc, cell = scene.discretization, mesh.topology.cell_name()
    if why := check_degree(cell, disc.degree, disc.quadrature_degree, disc.formulation):
        raise InputError(why)                          # a mesh file's cell, known only now
    dx = ufl.Measure("dx", domain=mesh, metadata=quadrature.metadata(cell, disc.quadrature))
    parameters = Parameters(mesh, regions.cell_values([m.rho for m in scene.materials]))
    load = LoadFactor(mesh)
    owners: list = []
    bcs = supports(bc_space, loaded, scene.fix, load, sign=bc_sign, owners=owners)
    ctx = make_context(loaded, scene, u, dx, parameters, load, rest_map, pressure)
    ctx.rest_offset, ctx.materials, ctx.loaded = rest_offset, regions, loaded
    ctx.extra.update(extra or {})
    name = scene.material.model if material is None else getattr(as_material(material), "name",
                                                                   type(material).__name__)
    if binding is not None:
        name = " + ".join(sorted({m.model for m in scene.materials}))
    terms = declare_terms(scene, mat, mesh, name, binding, regions if material is None else None)
    for t in terms:
        t.prepare(ctx)
    return Physics(ctx, terms, load, bcs, owners)


def declare_terms(scene: Scene, material: Material, mesh, model_name: str | None = None,
                  binding=None, regions=None) -> TermList:
    """The one place a model's terms are declared: the solid (the first registered kind, by priority, that the
    scene asks for: plastic, viscoelastic, else elastic), one term per [[load]] in scene order, then those of
    each registered scene section (SCENE_TERMS) the scene asks for."""
    name = model_name or scene.material.model
    solid = next(s for s in (build(scene, material, mesh, name, binding, regions) for _, build in SOLID_KINDS)
                 if s is not None)
    terms: list[Term] = [solid]
    for i, spec in enumerate(scene.load):
        terms.append(LOAD_TERMS[spec.type](spec, i, mesh))
    for build in SCENE_TERMS.values():
        terms.extend(build(scene, mesh))
    return TermList(terms)


def make_context(loaded: LoadedMesh, scene: Scene, u, dx: ufl.Measure, parameters: Parameters,
                 load: LoadFactor, rest_map=None, pressure=None) -> Context:
    """A Context on the loaded mesh with one tagged boundary measure for all of the scene's surface loads."""
    tags, regions = load_regions(loaded, scene.load)
    ds = ufl.Measure("ds", domain=loaded.mesh, subdomain_data=tags, metadata=dx.metadata())
    ctx = Context(loaded.mesh, u, dx, ds, regions, parameters, load, rest_map, pressure)
    if any(spec.type == "gravity" and spec.where is not None for spec in scene.load):
        cell_tags, ctx.body_regions = body_regions(loaded, scene.load)
        ctx.dx_regions = ufl.Measure("dx", domain=loaded.mesh, subdomain_data=cell_tags,
                                     metadata=dx.metadata())
    return ctx


def total_energy(terms: list[Term], ctx: Context) -> ufl.Form | None:
    """Sum of the conservative terms' energies (None if no term has one)."""
    parts = [e for e in (t.energy(ctx) for t in terms) if e is not None]
    return sum(parts[1:], parts[0]) if parts else None


def virtual_work(terms: list[Term], ctx: Context, v) -> ufl.Form | None:
    """Sum of the non-conservative terms' virtual works (None if there are none)."""
    parts = [w for w in (t.virtual_work(ctx, v) for t in terms) if w is not None]
    return sum(parts[1:], parts[0]) if parts else None


@dataclass
class EquilibriumForms:
    """Total potential energy (None without one), residual and tangent of one unknown."""
    energy: ufl.Form | None
    residual: ufl.Form
    jacobian: ufl.Form
    conservative: bool          # the residual is the exact gradient of `energy`


def equilibrium_forms(terms: list[Term], ctx: Context, unknown: fem.Function, v, scale=None, inertia=None,
                      damping: tuple = ()) -> EquilibriumForms:
    """Residual dPi/du[test] + non-conservative virtual work at v (v: the displacement part of the
    test function), tangent by ufl.derivative: the one recipe of a static model and of an implicit time step.
    A time step gives the terms' Context at its generalized mid-point with `scale` 1 / (1 - alpha_f) (see
    energy_variation), the time-discrete `inertia` energy (on the step's end; None: a lumped mass, added as
    arrays) and the `damping` terms of the step."""
    test, trial = ufl.TestFunction(unknown.function_space), ufl.TrialFunction(unknown.function_space)
    stored = total_energy(terms, ctx)
    energy = stored if scale is None or stored is None else scale * stored
    extra = virtual_work(list(terms) + list(damping), ctx, v)
    parts = [energy_variation(terms, ctx, unknown, test, v) if scale is None else
             energy_variation(terms, ctx, unknown, test, v, scale=scale)]
    if inertia is not None:
        energy = inertia if energy is None else energy + inertia
        parts.append(ufl.derivative(inertia, unknown, test))
    parts = [p for p in parts + [extra] if p is not None]
    residual = sum(parts[1:], parts[0])
    jacobian = ufl.derivative(residual, unknown, trial)
    return EquilibriumForms(energy, residual, jacobian, extra is None)


def energy_variation(terms: list[Term], ctx: Context, unknown, test, v, scale=1.0) -> ufl.Form | None:
    """d/d unknown of scale x the terms' energies at ctx, in the direction `test` (v: its displacement
    part): ufl.derivative of the energies, and a term's own `first_variation` where it gives its residual by
    hand (a cavity closed by symmetry planes; a material with its own pk1). A by-hand variation is taken
    with respect to ctx.u, so `scale` must make d/d unknown of scale x energy(ctx.u) equal it (dynamics:
    1 / (1 - alpha_f) on the energy at the generalized mid-point u_f = (1 - alpha_f) u + alpha_f u_old).
    None if no term has an energy (a plastic solid)."""
    by_hand = [t.first_variation(ctx, v) for t in terms if t.residual_by_hand and t.energy(ctx) is not None]
    derived = total_energy([t for t in terms if not t.residual_by_hand], ctx)
    parts = ([] if derived is None else [ufl.derivative(scale * derived, unknown, test)]) + by_hand
    return sum(parts[1:], parts[0]) if parts else None


def inverse_forms(terms: list[Term], ctx: Context, unknown: fem.Function,
                  variation: fem.Function) -> EquilibriumForms:
    """Equilibrium on the deformed (mesh) shape with the rest offset v as unknown: the virtual work of
    every term, its derivative with respect to the displacement. The Context has u = w - v and
    F = G^-1 + grad w G^-1 with G = I + grad v and w a placeholder `variation`: d/dw gives the virtual
    work (a term's `first_variation` where it has one: P : Grad eta with P by ufl.diff), then w = 0
    leaves the inverse problem's u = -v and F = G^-1 exactly. Measured on the 27,675-dof arm: the
    tangent assembles in 0.147 s CPU, as fast as the former hand-written P : grad(eta) F j form
    (0.142-0.148 s); a Gateaux derivative with u = -v substituted took 0.166 s. `unknown`: v, or in the mixed
    formulation (v, p), whose pressure equation is the energy's derivative in p alone (the direction (0, q))."""
    W = unknown.function_space
    test, trial = ufl.TestFunction(W), ufl.TrialFunction(W)
    eta = test if ctx.pressure is None else ufl.split(test)[0]
    parts = []
    for t in terms:
        if t.energy(ctx) is not None:
            by_hand = t.first_variation(ctx, eta)
            parts.append(by_hand if by_hand is not None else ufl.derivative(t.energy(ctx), variation, eta))
    work = sum(parts[1:], parts[0])
    extra = virtual_work(terms, ctx, eta)
    if extra is not None:
        work = work + extra
    if ctx.pressure is not None:
        energy = sum(e for e in (t.energy(ctx) for t in terms) if e is not None)
        q = ufl.split(test)[1]
        work = work + ufl.derivative(energy, unknown, ufl.as_vector([0.0] * len(variation) + [q]))
    residual = at_no_variation(work, variation)
    return EquilibriumForms(None, residual, ufl.derivative(residual, unknown, trial), False)


def at_no_variation(form, variation: fem.Function):
    """`form` with the inverse problem's placeholder virtual displacement w set to 0 (inverse_forms: u = -v)."""
    return ufl.replace(form, {variation: ufl.as_vector([0.0] * len(variation))})
