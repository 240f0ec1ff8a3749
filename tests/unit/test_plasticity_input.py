"""[material.plasticity]: each bad value or combination is refused in one line naming the key."""
import copy

import pytest

from fem_forms.errors import InputError
from fem_forms.materials.plasticity import OBrien, VonMises
from fem_forms.scene import Scene
from fem_forms.scene.schema import scene_schema

BASE = {"mesh": {"generator": "box", "cells": [2, 1, 1]}, "material": {"model": "linear", "E": 1e9, "nu": 0.3}}


def scene(plasticity, **over):
    d = copy.deepcopy(BASE)
    d["material"]["plasticity"] = plasticity
    for key, value in over.items():
        section, name = key.split("__")
        d.setdefault(section, {})[name] = value
    return Scene.from_dict(d)


def test_models_are_built_from_their_keys():
    assert scene({"model": "von-mises", "yield_stress": 2e8}).material.plasticity == VonMises(2e8, 0.0)
    assert scene({"model": "obrien", "elastic_limit": 0.01, "plastic_limit": 0.2}).material.plasticity == \
        OBrien(0.01, 0.2)
    assert Scene.from_dict(BASE).material.plasticity is None


@pytest.mark.parametrize("plasticity, over, words", [
    ({"yield_stress": 1e8}, {}, "material.plasticity.model: missing"),
    ({"model": "tresca", "yield_stress": 1e8}, {}, "material.plasticity.model = 'tresca'"),
    ({"model": "von-mises"}, {}, "yield_stress: missing"),
    ({"model": "von-mises", "yield_stress": 0.0}, {}, "yield_stress = 0.0: must be positive"),
    ({"model": "von-mises", "yield_stress": 1e8, "hardening": -1.0}, {}, "hardening = -1.0: must not be negative"),
    ({"model": "von-mises", "yield_stress": 1e8, "plastic_limit": 0.2}, {},
     "plastic_limit: only for model = 'obrien'"),
    ({"model": "obrien", "elastic_limit": 0.2, "plastic_limit": 0.1}, {}, "0 < elastic_limit < plastic_limit"),
    ({"model": "obrien", "elastic_limit": 0.01}, {}, "needs elastic_limit and plastic_limit"),
    ({"model": "obrien", "elastic_limit": 0.01, "plastic_limit": 0.1, "yield_stress": 1.0}, {},
     "yield_stress: only for model = 'von-mises'"),
    ({"model": "von-mises", "yield_stress": 1e8, "flow": 1}, {}, "material.plasticity.flow: unknown key"),
    ({"model": "von-mises", "yield_stress": 1e8}, {"material__model": "mooney-rivlin"},
     "finite-strain von-mises on 'mooney-rivlin' is not implemented"),
    ({"model": "obrien", "elastic_limit": 0.01, "plastic_limit": 0.1}, {"material__model": "neo-hookean"},
     "written for material.model = 'linear' or 'stvk' only"),
    ({"model": "von-mises", "yield_stress": 1e8}, {"discretization__formulation": "mixed"}, "mixed formulation"),
])
def test_bad_plasticity_is_refused_in_one_line(plasticity, over, words):
    with pytest.raises(InputError) as e:
        scene(plasticity, **over)
    assert words in str(e.value) and "\n" not in str(e.value)


def test_plasticity_is_refused_outside_static_and_dynamic():
    d = copy.deepcopy(BASE)
    d["material"]["plasticity"] = {"model": "von-mises", "yield_stress": 1e8}
    d["analysis"] = "modal"
    with pytest.raises(InputError, match="for analysis = 'static' or 'dynamic' only"):
        Scene.from_dict(d)


def test_schema_lists_the_plasticity_keys():
    keys = scene_schema()["properties"]["material"]["oneOf"][0]["properties"]["plasticity"]["properties"]
    assert set(keys) == {"model", "yield_stress", "hardening", "elastic_limit", "plastic_limit"}
