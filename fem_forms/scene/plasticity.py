"""[material.plasticity]: the keys of the plastic models and the rules that involve other sections."""
from __future__ import annotations

from fem_forms.errors import InputError
from fem_forms.materials.plasticity import MODELS as PLASTIC_MODELS
from fem_forms.scene.reader import Key

PLASTICITY = Key("plasticity", "table", "plastic flow: von Mises (small strain with model = 'linear', "
                 "finite strain with 'neo-hookean') or O'Brien (linear or stvk)", keys=(
    Key("model", "string", "plastic model", choices=PLASTIC_MODELS, attr="plasticity_model"),
    Key("yield_stress", "number", "von Mises yield stress", unit="Pa", exclusive_minimum=0),
    Key("hardening", "number", "linear isotropic hardening modulus (0: perfectly plastic; von Mises)",
        default=0.0, unit="Pa", minimum=0),
    Key("elastic_limit", "number", "O'Brien gamma1: deviatoric strain norm where flow starts",
        exclusive_minimum=0),
    Key("plastic_limit", "number", "O'Brien gamma2: largest norm of the plastic strain",
        exclusive_minimum=0)))

# the hyperelastic models each plastic model is written for (others are refused when the scene is read)
PLASTIC_MATERIALS = {"von-mises": ("linear", "neo-hookean"), "obrien": ("linear", "stvk")}


def material_plasticity_rules(s, given: dict | None) -> None:
    """[material.plasticity]: its model named, only its own keys, a hyperelastic model it is written for."""
    if given is None:
        return
    key = "material.plasticity"
    if s.plasticity_model is None:
        raise InputError(f"{key}.model: missing (choose from {', '.join(PLASTIC_MODELS)})")
    own = {"von-mises": ("yield_stress", "hardening"), "obrien": ("elastic_limit", "plastic_limit")}
    for name in given:
        if name != "model" and name not in own[s.plasticity_model]:
            raise InputError(f"{key}.{name}: only for model = "
                             f"{next(m for m, names in own.items() if name in names)!r}")
    if s.model not in PLASTIC_MATERIALS[s.plasticity_model]:
        raise InputError(f"{key}.model = {s.plasticity_model!r}: written for material.model = "
                         f"{' or '.join(map(repr, PLASTIC_MATERIALS[s.plasticity_model]))} only "
                         f"(finite-strain {s.plasticity_model} on {s.model!r} is not implemented)")
    s.plasticity                                         # validates the values (limits, yield stress)


def plasticity_rules(scene) -> None:
    """What plasticity does not run with, refused when the scene is read."""
    if scene.material.plasticity_model is None:
        return
    if scene.analysis not in ("static", "dynamic"):
        raise InputError(f"material.plasticity: for analysis = 'static' or 'dynamic' only "
                         f"(this scene's is {scene.analysis!r})")
    if scene.discretization.formulation != "displacement":
        raise InputError("material.plasticity: the mixed formulation is not implemented with plasticity; "
                         "use formulation = 'displacement'")
    if scene.mesh.cell == "prism":
        raise InputError("material.plasticity: not on prism meshes")
