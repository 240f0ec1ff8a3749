"""Scene: what to simulate, read from TOML (or a dict) and validated with one-line messages.

Every key is declared once (reader.Key) and checked against its declaration before any mesh is
built or file written; unknown keys are refused. The core sections are in spec.py; the sections an
analysis owns come from the registry (registry.py), so this reader knows no analysis by name.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from fem_forms.errors import InputError
from fem_forms.materials.hyperelastic import SMALL_STRAIN_MODELS
from fem_forms.scene import registry
from fem_forms.scene.analyses.balance import BalanceSpec
from fem_forms.scene.analyses.contact_section import ContactSpec
from fem_forms.scene.analyses.design import DesignSpec
from fem_forms.scene.analyses.fracture_section import FractureSpec, fracture_scene_rules
from fem_forms.scene.analyses.dynamic import DampingSpec, DynamicSpec
from fem_forms.scene.analyses.impact_section import ImpactSoundSpec
from fem_forms.scene.analyses.inverse import InverseSpec
from fem_forms.scene.analyses.modal import ModalSpec, SoundSpec
from fem_forms.scene.analyses.thermal_section import ThermalSpec
from fem_forms.scene.cavities import cavity_rules
from fem_forms.scene.materials import MaterialSpec, kinematics_rules, open_ended_rule, viscoelastic_rules
from fem_forms.scene.files import parse_assignment, read_toml, set_key
from fem_forms.scene.limits import LIMITS, NO_LIMITS, Limits, check_scene
from fem_forms.scene.reader import AXES, Key, Section, Table, Variants, check_number, check_vector
from fem_forms.scene.registry import ANALYSIS_KEY
from fem_forms.scene.spec import (CELL_TYPES, CORE_SECTIONS, GENERATORS, LOAD_TYPES, TITLE, Discretization,
                                  Fix, Load, MeshSpec, OutputSpec, Selector, SolverSpec, fix_names,
                                  prism_rules, quadrature_rules)
from fem_forms.scene.plasticity import plasticity_rules

__all__ = ["AXES", "CELL_TYPES", "GENERATORS", "LIMITS", "LOAD_TYPES", "NO_LIMITS", "Discretization", "Fix",
           "InverseSpec", "Key", "Limits", "Load", "MaterialSpec", "MeshSpec", "ModalSpec", "OutputSpec", "Scene",
           "Section", "Selector", "SolverSpec", "SoundSpec", "Table", "Variants", "check_number", "check_vector",
           "parse_assignment", "set_key"]


@dataclass
class Scene:
    """A validated scene: one attribute per section (analysis-owned ones hold defaults when absent)."""
    title: str = TITLE.field()
    analysis: str = ANALYSIS_KEY.field()
    mesh: MeshSpec = field(default_factory=MeshSpec)
    materials: list = field(default_factory=lambda: [MaterialSpec()])   # [material] or [[material]]
    discretization: Discretization = field(default_factory=Discretization)
    fix: list = field(default_factory=list)
    load: list = field(default_factory=list)
    solver: SolverSpec = field(default_factory=SolverSpec)
    output: OutputSpec = field(default_factory=OutputSpec)
    modal: ModalSpec = field(default_factory=ModalSpec)
    sound: SoundSpec | ImpactSoundSpec | None = None     # None: no sound; a dynamic scene's: [sound.impact]
    inverse: InverseSpec = field(default_factory=InverseSpec)
    balance: BalanceSpec | None = field(default_factory=BalanceSpec)   # inverse scenes: None without [balance]
    dynamic: DynamicSpec = field(default_factory=DynamicSpec)
    damping: DampingSpec = field(default_factory=DampingSpec)
    thermal: ThermalSpec | None = None     # None: no temperature field
    design: DesignSpec | None = None       # [design] of analysis = "design"
    contact: ContactSpec | None = None     # None: no contact
    fracture: FractureSpec | None = None   # None: no damage field
    source: Path | None = None
    limits: Limits = LIMITS                # what the scene may ask for (NO_LIMITS: --no-limits)

    @property
    def material(self) -> MaterialSpec:
        """The first material (the only one of a single [material] table)."""
        return self.materials[0]

    @property
    def several_materials(self) -> bool:
        return len(self.materials) > 1

    @property
    def small_strain(self) -> bool:
        """Is every material a small-strain law (the part's kinematics then infinitesimal)? With finite-strain
        materials beside them, the small-strain laws take their Green-strain (St Venant-Kirchhoff) form."""
        return all(m.model in SMALL_STRAIN_MODELS for m in self.materials)

    @classmethod
    def from_file(cls, path: str | Path, overrides: dict | None = None, limits: Limits = LIMITS) -> "Scene":
        """Read and validate a TOML scene; `overrides` {"mesh.cells": [8, 1, 1], ...} replace keys first."""
        path = Path(path)
        return cls.from_dict(read_toml(path, overrides, limits), base_dir=path.parent, source=path, limits=limits)

    @classmethod
    def from_dict(cls, data: dict, base_dir: str | Path = ".", source: Path | None = None,
                  limits: Limits = LIMITS) -> "Scene":
        """Validate a scene given as a dict (file paths in it are relative to base_dir) against `limits`."""
        return _parse_scene(data, Path(base_dir), source, limits)


# the corotated model's mixed tangent did not finish compiling within 6 minutes (materials/hyperelastic.py);
# the sweep (tests/system/test_option_sweep.py) found a mixed corotated scene running past its time limit
MIXED_TOO_SLOW = ("corotated",)


def _section(t: Table, section: Section, base_dir: Path):
    return section.parse(t.raw(section.name), base_dir) if t.has(section.name) else section.missing()


def _parse_scene(data: dict, base_dir: Path, source: Path | None, limits: Limits) -> Scene:
    t = Table(data, "", base_dir)
    sc = Scene(source=source, limits=limits)
    sc.title = t.read(TITLE)
    sc.analysis = t.read(ANALYSIS_KEY)
    analysis = registry.get(sc.analysis)
    for section in CORE_SECTIONS:
        setattr(sc, section.attr or section.name, _section(t, section, base_dir))

    formulation = sc.discretization.formulation
    if formulation not in analysis.formulations:
        able = " or ".join(repr(a.name) for a in registry.ANALYSES.values() if formulation in a.formulations)
        raise InputError(f"discretization.formulation = {formulation!r}: available for analysis = {able} only")
    slow = next((m for m in sc.materials if m.model in MIXED_TOO_SLOW), None)
    if formulation == "mixed" and slow is not None:
        raise InputError(f"discretization.formulation = 'mixed': not with {slow.key}.model = "
                         f"{slow.model!r} (its Taylor-Hood tangent takes minutes to compile with FFCx 0.5); "
                         "use neo-hookean, mooney-rivlin, stvk or linear for mixed, or formulation = 'displacement'")
    fix_names(sc.fix)                                  # repeated support names are refused here
    timed = next((i for i, f in enumerate(sc.fix) if f.history is not None), None)
    if timed is not None and sc.analysis != "static":
        raise InputError(f"fix[{timed}].history: for analysis = 'static' only (this scene's is {sc.analysis!r})")
    cavity_rules(sc.load, sc.analysis, sc.solver.control)
    prism_rules(sc.mesh, sc.discretization, sc.load, sc.analysis)
    quadrature_rules(sc.mesh, sc.discretization)
    plasticity_rules(sc)
    if any(ld.type == "gravity" for ld in sc.load) and max(m.rho for m in sc.materials) <= 0:
        raise InputError("material.rho: gravity needs a positive density")

    for name, (owners, first) in registry.owned_sections().items():
        mine = registry.section_of(analysis, name)
        if t.has(name) and mine is None:
            raise InputError(f"{name}: only for analysis = {' or '.join(repr(o.name) for o in owners)} "
                             f"(this scene's analysis is {sc.analysis!r})")
        setattr(sc, name, _section(t, mine or first, base_dir))
    if "contact_pressure" in (sc.output.fields or []) and getattr(sc, "contact", None) is None:
        raise InputError("output.fields: 'contact_pressure' needs a [contact] section (nothing touches without)")
    if "utilization" in (sc.output.fields or []) and not any(
            m.strength_tensile is not None or m.strength_yield is not None for m in sc.materials):
        raise InputError("output.fields: 'utilization' needs a [material.strength] (stress over strength)")
    viscoelastic_rules(sc)                             # after the analysis's own sections: it reads [dynamic]
    kinematics_rules(sc)
    fracture_scene_rules(sc)
    if analysis.check is not None:
        analysis.check(sc)
    open_ended_rule(sc)                                # after [design]'s check: the material it places needs no `where`
    t.done()
    check_scene(sc, limits)
    return sc
