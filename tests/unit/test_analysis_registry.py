"""The one registry of analyses: each has a runner, owns its sections, and a scene dispatches through it."""
import inspect

import pytest

from fem_forms.errors import InputError
from fem_forms.scene import Scene, registry
from fem_forms.scene.reader import Key

BASE = {"mesh": {"cells": [4, 1, 1]}, "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0}}
# tables an analysis cannot run without, and keys a table needs beyond its required ones (cross-key rules)
HEATED_END = {"boundary": [{"where": {"axis": "x", "at": 0.0}, "temperature": 1.0}]}
TWO = {"material": [{"name": "soft", "E": 1e6, "nu": 0.3, "rho": 1000.0},
                    {"name": "stiff", "E": 1e7, "nu": 0.3, "rho": 1000.0}], "output": {"probes": {"tip": [1.0, 0.05, 0.05]}}}
DESIGNED = {"materials": ["soft", "stiff"], "target": [{"probe": "tip", "position": [1.0, 0.05, 0.0]}]}
NEEDS = {"thermal": {"thermal": {"conductivity": 1.0, "specific_heat": 1.0, **HEATED_END}},
         "design": {**TWO, "design": DESIGNED}}
COMPLETE = {"thermal": {**HEATED_END, "conductivity": 1.0, "specific_heat": 1.0}, "contact": {"self": True},
            "design": DESIGNED}
# tables of other sections a section needs in one analysis (balance reads [contact] with elastic = true only)
ALONG = {("balance", "contact"): {"balance": {"elastic": True}},
         ("inverse", "contact"): {"inverse": {"method": "adjoint"}},      # a part standing on a table
         ("dynamic", "sound"): {"contact": {"obstacle": [{"name": "a", "shape": "plane", "point": [0.0, 0.0, -1.0],
                                                          "normal": [0.0, 0.0, 1.0]}]}}}   # [sound.impact] names it
# a section's table in one analysis where COMPLETE's is refused there (an inverse design stands on obstacles, not on
# itself)
IN_ANALYSIS = {("inverse", "contact"): {"self": False, "obstacle": [{"shape": "plane", "point": [0.0, 0.0, -1.0], "friction": 0.5,
                                                                      "normal": [0.0, 0.0, 1.0]}]}}
REQUIRED = {"vector": [0.0, 0.0, 1.0], "number": 1.0, "integer": 1, "string": "a", "names": ["a", "b"], "tables": []}


def required_only(keys) -> dict:
    """The smallest table of these keys: only the required ones, sub-tables included."""
    return {k.name: required_only(k.keys) if k.kind == "table" else REQUIRED[k.kind]
            for k in keys if k.required}


@pytest.mark.parametrize("name", registry.names())
def test_every_analysis_has_a_runner(name):
    analysis = registry.get(name)
    run = analysis.run_function()
    assert callable(run)
    assert list(inspect.signature(run).parameters)[:3] == ["scene", "out", "echo"]
    assert analysis.outputs and "results.json" in analysis.outputs


@pytest.mark.parametrize("name", registry.names())
def test_every_section_of_an_analysis_parses(name):
    analysis = registry.get(name)
    base = BASE | NEEDS.get(name, {})
    scene = Scene.from_dict(base | {"analysis": name})
    for section in analysis.sections:
        if section.name not in NEEDS.get(name, {}):
            assert getattr(scene, section.name) == section.missing()    # absent: its default
        data = required_only(section.keys) | COMPLETE.get(section.name, {}) | IN_ANALYSIS.get((name, section.name), {})
        along = ALONG.get((name, section.name), {})
        parsed = getattr(Scene.from_dict(base | along | {"analysis": name, section.name: data}), section.name)
        assert isinstance(parsed, section.spec)


def test_a_section_of_another_analysis_is_refused():
    owned = registry.owned_sections()
    for name in registry.names():
        for section, (owners, _) in owned.items():
            if name not in [o.name for o in owners]:
                allowed = " or ".join(f"'{o.name}'" for o in owners)
                with pytest.raises(InputError, match=f"^{section}: only for analysis = {allowed} "
                                                     f"\\(this scene's analysis is '{name}'\\)$"):
                    Scene.from_dict(BASE | {"analysis": name, section: {}})


def test_analysis_key_lists_the_registry():
    assert registry.ANALYSIS_KEY.choices == registry.names() == tuple(registry.ANALYSES)
    with pytest.raises(InputError, match="analysis = 'dance'"):
        registry.get("dance")
    assert isinstance(registry.ANALYSIS_KEY, Key)
