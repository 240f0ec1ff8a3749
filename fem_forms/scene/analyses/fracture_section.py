"""The [fracture] section: damage as a second field of a static or dynamic analysis, by the variational phase field
(Francfort-Marigo, Bourdin): toughness Gc, regularization length l, the AT1 or AT2 crack density, which part of
the energy damage degrades (the split), and initial cracks ([[fracture.notch]])."""
from __future__ import annotations

from dataclasses import dataclass, field

from fem_forms.errors import InputError
from fem_forms.materials.hyperelastic import SMALL_STRAIN_MODELS
from fem_forms.scene.reader import Key, Section, Table
from fem_forms.scene.selectors import where

MODELS = ("AT1", "AT2")
SPLITS = ("volumetric-deviatoric", "none", "spectral")
NOTCH_KEYS = (
    where("damage = 1 (a crack from the start) on the mesh nodes inside { box = [[x0, y0, z0], [x1, y1, z1]] } "
          "(a thin box: a crack face) or on the nodes of a gmsh group { group = ... } (volume or surface)",
          kinds=("box", "group")),
)
FRACTURE_KEYS = (
    Key("toughness", "number", "critical energy release rate Gc", unit="J/m^2", required=True, exclusive_minimum=0),
    Key("length", "number", "regularization length l: the crack's half-width (mesh size about l/3 or finer); "
        "with E and Gc it sets the strength: sqrt(3 Gc E / (8 l)) (AT1), (3/16) sqrt(3 Gc E / l) (AT2)",
        unit="m", required=True, exclusive_minimum=0),
    Key("model", "string", "AT1: w(d) = d, an elastic phase before damage starts; AT2: w(d) = d^2, damage from "
        "the first load", default="AT1", choices=MODELS),
    Key("split", "string", "what damage degrades: volumetric-deviatoric (Amor et al. 2009: compression does not "
        "crack), none (all of psi), spectral (Miehe et al. 2010: tensile principal strains; linear model only)",
        default="volumetric-deviatoric", choices=SPLITS),
    Key("residual_stiffness", "number", "what a fully damaged point keeps of its stiffness (k in g(d) = "
        "(1 - k)(1 - d)^2 + k)",
        default=1.0e-6, minimum=0, exclusive_maximum=1),
    Key("tolerance", "number", "the alternate minimization stops when a sweep changes the damage (and the "
        "displacement, relative to its largest value) by less than this", default=1.0e-4, exclusive_minimum=0,
        exclusive_maximum=1),
    Key("max_iterations", "integer", "sweeps of the alternate minimization per load step before the step is "
        "cut back", default=500, minimum=1),
    Key("over_relaxation", "number", "the alternate minimization's over-relaxation omega: each sweep moves the "
        "damage omega times its step, within its bounds (Farrell & Maurini 2017; 1: plain alternate minimization; "
        "the fixed point is the same)", default=1.0, minimum=1, exclusive_maximum=2),
    Key("stable_path", "boolean", "static runs with a direct linear solver: accept only stable states (after each "
        "converged step, the energy's Hessian on the damaging set, the crack's own line left out, is checked with "
        "SLEPc and a saddle is pushed along its unstable mode: a homogeneous bar cracks in one band, a symmetric "
        "part on one side); false keeps what the alternate minimization converged to (a homogeneous bar stays "
        "homogeneous past its peak: a saddle)", default=True),
    Key("notch", "tables", "initial cracks [[fracture.notch]]: where", default=[], keys=NOTCH_KEYS),
)


@dataclass
class FractureSpec:
    """[fracture]: the phase field's constants and initial cracks."""
    toughness: float = 0.0
    length: float = 0.0
    model: str = "AT1"
    split: str = "volumetric-deviatoric"
    residual_stiffness: float = 1.0e-6
    tolerance: float = 1.0e-4
    max_iterations: int = 500
    over_relaxation: float = 1.0
    stable_path: bool = True
    notch: list = field(default_factory=list)       # [{"where": Selector}, ...]


def _fracture_rules(spec: FractureSpec, t: Table) -> None:
    spec.notch = [n["where"] for n in spec.notch]


def fracture_scene_rules(scene) -> None:
    """What [fracture] needs from the rest of the scene, refused in one line each when the scene is read."""
    fr = getattr(scene, "fracture", None)
    if fr is None:
        return
    if scene.analysis == "dynamic" and scene.dynamic.scheme == "central-difference":
        raise InputError("fracture: not with the explicit central-difference scheme (its steps solve nothing: no "
                         "step for the damage to minimize with); use newmark, generalized-alpha or backward-euler")
    if scene.solver.control == "arc-length":
        raise InputError("fracture: not with solver.control = 'arc-length' (the staggered damage solve steps the "
                         "load factor); use control = 'load' with a prescribed displacement")
    if scene.discretization.formulation != "displacement":
        raise InputError("fracture: the mixed formulation is not implemented with a phase field; use "
                         "formulation = 'displacement'")
    for m in scene.materials:
        if m.plasticity_model is not None or m.prony is not None:
            raise InputError(f"fracture: not with {m.key}.{'plasticity' if m.plasticity_model else 'viscoelastic'} "
                             "(not implemented together)")
        anisotropic = m.model == "orthotropic" or m.fiber_direction is not None or m.fiber_field is not None
        if anisotropic and fr.split != "none":
            raise InputError(f"fracture.split = {fr.split!r}: splits an isotropic energy; {m.key} is anisotropic "
                             "(use split = 'none')")
        if fr.split == "spectral" and m.model != "linear":
            raise InputError(f"fracture.split = 'spectral': for model = 'linear' only ({m.key}.model is {m.model!r}); "
                             "use 'volumetric-deviatoric' for finite strain")
    if fr.split == "spectral" and not all(m.model in SMALL_STRAIN_MODELS for m in scene.materials):
        raise InputError("fracture.split = 'spectral': small strain only")


FRACTURE = Section("fracture", "phase-field fracture: damage as a second field (toughness, length, model, split, "
                   "notches)", FractureSpec, keys=FRACTURE_KEYS, rules=_fracture_rules, absent=lambda: None)
