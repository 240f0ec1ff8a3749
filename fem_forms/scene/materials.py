"""The [material] section: one table, or an array of tables [[material]] each claiming its cells (`where`),
with its energy density, density and thermal constants. Read into scene.materials (a list, one entry for a
single table); scene.material is the first, for what a whole part shares (the model's name in messages)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fem_forms.errors import InputError
from fem_forms.materials import MODELS, Material, make_material
from fem_forms.materials.anisotropic import FIBER_MODELS, ORTHOTROPIC_CONSTANTS
from fem_forms.materials.hyperelastic import PARAMETER_KEYS, SMALL_STRAIN_MODELS
from fem_forms.materials.fitting import RESIDUALS
from fem_forms.materials.isochoric import ISOCHORIC_MODELS
from fem_forms.materials.library import LIBRARY
from fem_forms.materials.plasticity import make_plasticity
from fem_forms.scene.material_sources import from_fit, from_library
from fem_forms.scene.plasticity import PLASTICITY, material_plasticity_rules
from fem_forms.scene.reader import Key, Section, Table
from fem_forms.scene.selectors import Selector, where

REGION_KINDS = ("box", "group")
RUBBER_PARAMETERS = ("C20", "C30", "alpha", "Jm", "lambda_m", "bulk")     # the isochoric models' own keys
ORTHOTROPIC_DOCS = {"E": "Young's modulus", "G": "shear modulus", "n": "Poisson's ratio"}
THERMAL_CONSTANTS = ("conductivity", "specific_heat", "expansion")   # per material, else [thermal]'s
MATERIAL_KEYS = (
    Key("name", "string", "the material's name in results and messages", default="material"),
    where("the cells of this material: a gmsh volume group { group = ... } or the cells whose centroid "
          "lies in { box = [[x0, y0, z0], [x1, y1, z1]] }; absent: every cell no other material claims",
          required=False, kinds=REGION_KINDS),
    Key("model", "string", "hyperelastic energy density", default="neo-hookean", choices=tuple(MODELS),
        note=f"unknown model (choose from {', '.join(MODELS)})"),
    *PARAMETER_KEYS,
    Key("library", "string", "a named material of the library (its model, parameters, density and source; the "
        "manual's rubber page lists them)", choices=tuple(LIBRARY), note=f"unknown material (the library has "
        f"{', '.join(LIBRARY)})"),
    Key("fit", "table", "fit the model (ogden, yeoh, gent, arruda-boyce) to lab tests before the analysis: CSV "
        "files with the columns stretch, nominal_stress (Pa)", keys=(
            Key("uniaxial", "file", "uniaxial tension test (a dog-bone)", attr="fit_uniaxial"),
            Key("biaxial", "file", "equibiaxial tension test (a bulge or biaxial rig)", attr="fit_biaxial"),
            Key("shear", "file", "pure shear test (a wide strip)", attr="fit_shear"),
            Key("terms", "integer", "terms of ogden (default 2) or yeoh (default 3)", minimum=1, maximum=3,
                attr="fit_terms"),
            Key("residual", "string", "fit relative or absolute errors", default="relative", choices=RESIDUALS,
                attr="fit_residual"))),
    Key("rho", "number", "mass density (gravity and modal analysis need it)", default=0.0, unit="kg/m^3",
        minimum=0),
    Key("conductivity", "number", "thermal conductivity k of this material (default: thermal.conductivity)",
        unit="W/(m K)", exclusive_minimum=0),
    Key("specific_heat", "number", "specific heat c of this material (default: thermal.specific_heat)",
        unit="J/(kg K)", exclusive_minimum=0),
    Key("expansion", "number", "linear thermal expansion coefficient of this material (default: "
        "thermal.expansion)", unit="1/K"),
    *(Key(n, "number", f"orthotropic: {ORTHOTROPIC_DOCS[n[0]]} {n[1:]}", unit="" if n[0] == "n" else "Pa")
      for n in ORTHOTROPIC_CONSTANTS),
    Key("axis1", "vector", "orthotropic: material axis 1 (global frame)", length=3),
    Key("axis2", "vector", "orthotropic: material axis 2, perpendicular to axis1 (axis3 = axis1 x axis2)",
        length=3),
    Key("fibers", "table", "fibre reinforcement of a finite-strain model, active in tension only", keys=(
        Key("direction", "vector", "fibre direction in the rest shape", length=3, attr="fiber_direction"),
        Key("group_field", "string", "instead of direction: the name of a cell field of the mesh file (a vector "
            "per cell: VTU or XDMF cell data) giving each cell's fibre direction", attr="fiber_field"),
        Key("E", "number", "fibre stiffness: Young's modulus added along the fibres (small strain)",
            unit="Pa", exclusive_minimum=0, attr="fiber_E"),
        Key("model", "string", "holzapfel: k1/(2 k2) (exp(k2 (I4-1)^2) - 1), k1 = E/4; quadratic: E/8 (I4-1)^2",
            default="holzapfel", choices=FIBER_MODELS, attr="fiber_model"),
        Key("k2", "number", "holzapfel: exponential stiffening (dimensionless)", default=1.0,
            exclusive_minimum=0, attr="fiber_k2"))),
    Key("viscoelastic", "table", "finite-strain generalized Maxwell (Simo 1987): the stress relaxes from its "
        "instantaneous value (E) to g_inf = 1 - sum g_i of it; dynamic (implicit schemes) and static, with a "
        "load or support history (its pseudo-time is then time)", keys=(
            Key("prony", "points", "[g_i, tau_i] pairs: relative modulus and relaxation time", unit="-, s",
                length=2, min_items=1, attr="prony", note="must list [g, tau] pairs"),)),
    PLASTICITY,
    Key("strength", "table", "what the material can bear, for the safety factor of every run with stresses", keys=(
        Key("tensile", "number", "largest principal (Cauchy) stress allowed: brittle failure", unit="Pa",
            exclusive_minimum=0, attr="strength_tensile"),
        Key("yield", "number", "von Mises stress allowed: ductile failure (default: plasticity.yield_stress)",
            unit="Pa", exclusive_minimum=0, attr="strength_yield"))),
)
_MAT = {k.name: k for k in MATERIAL_KEYS}
_PLASTIC = {k.name: k for k in PLASTICITY.keys}


@dataclass
class MaterialSpec:
    name: str = _MAT["name"].field()
    where: Selector | None = None
    model: str = _MAT["model"].field()
    E: float | None = None
    nu: float | None = None
    mu: float | None = None
    lmbda: float | None = None
    C10: float | None = None
    C01: float | None = None
    C20: float | None = None
    C30: float | None = None
    alpha: list | None = None
    Jm: float | None = None
    lambda_m: float | None = None
    bulk: float | None = None
    library: str | None = None
    fit_uniaxial: Path | None = None
    fit_biaxial: Path | None = None
    fit_shear: Path | None = None
    fit_terms: int | None = None
    fit_residual: str = "relative"
    fitted: Any = None                         # the Fit (materials.fitting) the parameters came from
    rho: float = _MAT["rho"].field()
    conductivity: float | None = None
    specific_heat: float | None = None
    expansion: float | None = None
    E1: float | None = None
    E2: float | None = None
    E3: float | None = None
    G12: float | None = None
    G13: float | None = None
    G23: float | None = None
    nu12: float | None = None
    nu13: float | None = None
    nu23: float | None = None
    axis1: list | None = None
    axis2: list | None = None
    fiber_direction: list | None = None
    fiber_field: str | None = None
    fiber_E: float | None = None
    fiber_model: str = "holzapfel"
    fiber_k2: float = 1.0
    prony: list | None = None
    plasticity_model: str | None = None
    yield_stress: float | None = None
    hardening: float = _PLASTIC["hardening"].field()
    elastic_limit: float | None = None
    plastic_limit: float | None = None
    strength_tensile: float | None = None
    strength_yield: float | None = None
    key: str = "material"                      # the scene key, for messages: material or material[i]
    _built: tuple | None = field(default=None, repr=False, compare=False)   # (values, Material)

    @property
    def material(self) -> Material:
        """The validated model, built once when the scene is read (again only if a value was changed
        since, so a changed E can never be silently ignored)."""
        ortho = {n: getattr(self, n) for n in ORTHOTROPIC_CONSTANTS}
        rubber = {n: getattr(self, n) for n in RUBBER_PARAMETERS}
        values = (self.model, self.E, self.nu, self.mu, self.lmbda, self.C10, self.C01, tuple(ortho.values()),
                  self.axis1, self.axis2, tuple(rubber.values()))
        if self._built is None or self._built[0] != values:
            try:
                built = make_material(self.model, E=self.E, nu=self.nu, mu=self.mu, lmbda=self.lmbda,
                                      C10=self.C10, C01=self.C01, orthotropic=ortho, axis1=self.axis1,
                                      axis2=self.axis2, **rubber)
            except InputError as e:                    # the models name "material."; say which one
                raise InputError(str(e).replace("material", self.key, 1)) from None
            self._built = (values, built)
        return self._built[1]

    @property
    def poisson(self) -> float | None:
        """Poisson's ratio at small strain: nu as given, or a rubber model's from its bulk and shear moduli."""
        if self.nu is not None or self.bulk is None:
            return self.nu
        mu0 = float(np.min(self.material.shear_modulus(np.asarray)))
        return (3 * self.bulk - 2 * mu0) / (2 * (3 * self.bulk + mu0))

    @property
    def plasticity(self):
        """The plastic model of [material.plasticity] (VonMises or OBrien), or None."""
        return make_plasticity(self.plasticity_model, self.yield_stress, self.hardening, self.elastic_limit,
                               self.plastic_limit)


def _material_rules(s: MaterialSpec, t: Table) -> None:
    s.key = t.path
    from_library(s, t)
    from_fit(s, t)
    if s.model not in ISOCHORIC_MODELS and (s.E is not None or s.nu is not None) and (s.mu is not None
                                                                                      or s.lmbda is not None):
        raise InputError(f"{t.path}: give either E and nu or mu and lambda, not both")
    s.material                                           # builds and validates the model once, now
    _fiber_rules(s, t)
    _prony_rules(s, t)
    if t.path != "material" and t.has("plasticity"):
        raise InputError(f"{t.key('plasticity')}: plasticity is for a single [material] table only "
                         "(not implemented for several materials)")
    material_plasticity_rules(s, t.data.get("plasticity"))
    if t.has("strength"):
        if s.strength_yield is None and s.yield_stress is not None:
            s.strength_yield = s.yield_stress              # the plastic yield stress, as the users expect
        if s.strength_tensile is None and s.strength_yield is None:
            raise InputError(f"{t.key('strength')}: give tensile (largest principal stress, Pa) and/or yield "
                             "(von Mises stress, Pa)")


def _fiber_rules(s: MaterialSpec, t: Table) -> None:
    """[material] fibers: a direction and a stiffness, on a finite-strain model."""
    if not t.has("fibers"):
        return
    key = t.key("fibers")
    if (s.fiber_direction is None) == (s.fiber_field is None):
        raise InputError(f"{key}: give the fibres' direction = [x, y, z] or group_field = \"name\" (a cell field "
                         "of the mesh file), one of the two")
    if s.fiber_E is None:
        raise InputError(f"{key}.E: missing (fibres need a stiffness E)")
    if s.model in SMALL_STRAIN_MODELS:
        raise InputError(f"{key}: for a finite-strain model (neo-hookean, mooney-rivlin, stvk, corotated); "
                         f"{t.key('model')} is {s.model!r} (use model = 'orthotropic' for small-strain anisotropy)")
    if s.fiber_direction is not None and not any(s.fiber_direction):
        raise InputError(f"{key}.direction: must not be the zero vector")
    if t.has("plasticity"):
        raise InputError(f"{key}: not with [material.plasticity] (not implemented together)")
    if t.data["fibers"].get("k2") is not None and s.fiber_model != "holzapfel":
        raise InputError(f"{key}.k2: only for model = 'holzapfel'")


def _prony_rules(s: MaterialSpec, t: Table) -> None:
    """[material.viscoelastic]: relative moduli in (0, 1) summing below 1, positive relaxation times."""
    if not t.has("viscoelastic"):
        return
    key = f"{t.key('viscoelastic')}.prony"
    if s.prony is None:
        raise InputError(f"{key}: missing (give [[g_i, tau_i], ...])")
    for i, (g, tau) in enumerate(s.prony):
        if not 0 < g < 1:
            raise InputError(f"{key}[{i}] = {[g, tau]}: the relative modulus g must lie in (0, 1)")
        if tau <= 0:
            raise InputError(f"{key}[{i}] = {[g, tau]}: the relaxation time tau must be positive")
    if sum(g for g, _ in s.prony) >= 1:
        raise InputError(f"{key}: the relative moduli sum to {sum(g for g, _ in s.prony):.6g}; they must sum "
                         "below 1 (g_inf = 1 - sum g_i is the long-term modulus, positive)")


def kinematics_rules(scene) -> None:
    """Small-strain laws beside finite-strain materials take their Green-strain form: not in the mixed
    formulation, whose pressure splits off a volumetric part that form does not have."""
    small = [m for m in scene.materials if m.model in SMALL_STRAIN_MODELS]
    if small and not scene.small_strain and scene.discretization.formulation != "displacement":
        raise InputError(f"{small[0].key}.model = {small[0].model!r}: a small-strain law beside finite-strain "
                         "materials is not implemented with formulation = 'mixed'; use 'displacement'")


def viscoelastic_rules(scene) -> None:
    """What [material.viscoelastic] needs from the rest of the scene, refused when the scene is read."""
    visco = next((m for m in scene.materials if m.prony is not None), None)
    if visco is None:
        return
    key = f"{visco.key}.viscoelastic"
    if scene.analysis not in ("static", "dynamic"):
        raise InputError(f"{key}: for analysis = 'static' or 'dynamic' only (this scene's is {scene.analysis!r})")
    if scene.analysis == "dynamic" and scene.dynamic.scheme == "central-difference":
        raise InputError(f"{key}: not with the explicit central-difference scheme (its steps solve nothing: no "
                         "step energy); use newmark, generalized-alpha or backward-euler")
    if visco.plasticity_model is not None:
        raise InputError(f"{key}: not with [material.plasticity] (not implemented together)")
    if scene.discretization.formulation != "displacement":
        raise InputError(f"{key}: the mixed formulation is not implemented with viscoelasticity; use "
                         "formulation = 'displacement'")
    if scene.solver.control == "arc-length":
        raise InputError(f"{key}: not with solver.control = {scene.solver.control!r} (its path parameter is no "
                         "time); use control = 'load'")
    if scene.analysis == "static" and not (any(ld.history for ld in scene.load)
                                           or any(f.history for f in scene.fix)):
        raise InputError(f"{key}: a static scene needs time: give a [[load]] or [[fix]] history ([time, factor] "
                         "pairs; the load steps' pseudo-time is then time in seconds)")


def _materials_rules(materials: list[MaterialSpec]) -> None:
    """Across the materials: distinct names."""
    names = [m.name for m in materials]
    for i, m in enumerate(materials):
        if m.name in names[:i]:
            raise InputError(f"{m.key}.name = {m.name!r}: another material has this name")


def open_ended_rule(scene) -> None:
    """At most one material without `where` (it takes the rest), the material a design places aside (its
    `where`, if any, is where it may go)."""
    materials = scene.materials
    placed = scene.design.materials[1] if scene.analysis == "design" and scene.design is not None else None
    open_ended = [m for m in materials if m.where is None and m.name != placed]
    if len(materials) > 1 and len(open_ended) > 1:
        raise InputError(f"{open_ended[1].key}.where: missing (only one material may leave out `where`: "
                         f"it takes every cell no other material claims; {open_ended[0].key} already does)")


class MaterialSection(Section):
    """[material] as one table or as an array of tables [[material]]: always read into a list."""

    def parse(self, data: Any, base_dir: Path = Path(".")) -> list[MaterialSpec]:
        if isinstance(data, list):
            if not data:
                raise InputError("material: an empty array of tables (give at least one [[material]])")
            specs = [self._one(Table(d, f"material[{i}]", base_dir)) for i, d in enumerate(data)]
        else:
            specs = [self._one(Table(data, "material", base_dir))]
        _materials_rules(specs)
        return specs


MATERIAL = MaterialSection(
    "material", "the material(s): one [material] table, or [[material]] tables each claiming its cells with "
    "`where` (E and nu, or mu and lambda; density; thermal constants)", MaterialSpec, keys=MATERIAL_KEYS,
    rules=_material_rules, required=True, attr="materials", either=True)
