"""The scene key declarations, the reader and the JSON Schema agree: every key the reader accepts is in
the schema with its default, every demo and benchmark scene validates, bad scenes fail both ways."""
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import jsonschema
import pytest

from fem_forms.errors import InputError
from fem_forms.scene import Scene, registry
from fem_forms.scene.reader import Key, Section
from fem_forms.scene.schema import scene_schema, schema_json
from fem_forms.scene.selectors import SELECTOR_KEYS
from fem_forms.scene.spec import CORE_SECTIONS

ROOT = Path(__file__).resolve().parents[2]
SCENE_FILES = sorted([*ROOT.glob("demos/scenes/*.toml"), *ROOT.glob("benchmarks/scenes/*.toml")])
SCHEMA = scene_schema()
VALIDATOR = jsonschema.Draft7Validator(SCHEMA)


def all_sections() -> list[Section]:
    return list(CORE_SECTIONS) + [s for a in registry.ANALYSES.values() for s in a.sections]


def table_schema(section: Section) -> dict:
    s = SCHEMA["properties"][section.name]
    if section.name in registry.owned_sections() and registry.owned_sections()[section.name][1] is not section:
        # a narrower declaration of a table another analysis owns (thermal's [dynamic]): in its analysis's rule
        s = next(r["then"]["properties"][section.name] for r in SCHEMA["allOf"]
                 if section.name in r["then"].get("properties", {}))
    elif "anyOf" in s and "type" not in s:      # [sound]: the struck part's or the impact's; its owner's first
        s = s["anyOf"][0]
    if section.either:                           # [material]: a table, or an array of the same tables
        assert s["oneOf"][1]["items"] == s["oneOf"][0]
        return s["oneOf"][0]
    return s["items"] if section.array else s


def sample(k: Key, tmp: Path):
    """A valid value for a required key."""
    if k.kind == "points":                       # 0, e1, e2, ...: a valid outline or point list
        return [[float(i == j - 1) for i in range(k.length)] for j in range(k.min_items or 1)]
    if k.kind == "selector":
        return {"box": [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]} if k.choices == ("box",) else {"axis": "x", "at": 0.0}
    if k.kind == "table":
        return {s.name: sample(s, tmp) for s in k.keys if s.required}
    if k.kind == "file":
        return str(tmp / "any.msh")
    if k.kind == "string":
        return (k.choices or ("a",))[0]
    if k.kind == "names":
        return [f"n{i}" for i in range(k.length or 1)]
    if k.kind == "tables":
        return [{s.name: sample(s, tmp) for s in k.keys if s.required}]
    return {"number": 1.0, "integer": 1, "boolean": True, "vector": [1.0] * (k.length or 3)}[k.kind]


CROSS_KEY_NEEDS = {"material": {"E": 1e6, "nu": 0.3},       # what the rules after the declarations ask
                   "contact": {"self": True},                 # something to touch
                   "design": {"target": [{"probe": "p", "position": [0.0, 0.0, 0.0]}]}}   # a position or an angle
CASE_NEEDS = {("load", "inflation"): {"pressure": 1e3},       # one of pressure or volume (neither is required alone)
              ("load", "pressure"): {"pressure": 1e3}}        # pressure, or value (its first spelling)


def minimal_cases(section: Section, tmp: Path):
    """(data, keys read) for each case of the section, with only its required keys given."""
    cases = [(None, ())] if section.variants is None else list(section.variants.cases.items())
    for case, case_keys in cases:
        keys = list(section.keys) + list(case_keys)
        data = {k.name: sample(k, tmp) for k in keys if k.required} | CROSS_KEY_NEEDS.get(section.name, {})
        if case is not None:
            data[section.variants.key.name] = case
            data |= CASE_NEEDS.get((section.name, case), {})
        yield data, keys


def test_schema_is_valid_draft7_json(capsys):
    jsonschema.Draft7Validator.check_schema(SCHEMA)
    assert json.loads(schema_json()) == SCHEMA
    from fem_forms.cli import main
    assert main(["schema"]) == 0
    assert json.loads(capsys.readouterr().out) == SCHEMA


def test_schema_out_writes_a_file(tmp_path):
    from fem_forms.cli import main
    assert main(["schema", "--out", str(tmp_path / "scene.schema.json")]) == 0
    assert json.loads((tmp_path / "scene.schema.json").read_text()) == SCHEMA


def _check_key(k: Key, s: dict, where: str) -> None:
    props = s["properties"]
    assert k.name in props, f"{where}.{k.name} missing from the schema"
    ks = props[k.name]
    if "anyOf" in ks:                    # one name, a different type per case (load value)
        return
    assert ks.get("default") == k.default, f"{where}.{k.name}: schema default differs"
    assert k.doc in ks["description"] and k.unit in ks["description"]
    if k.kind == "table":
        for sub in k.keys:
            _check_key(sub, ks, f"{where}.{k.name}")
        assert set(ks["properties"]) == {sub.name for sub in k.keys}
    if k.kind == "selector":
        shapes = ks.get("oneOf", [ks])
        kinds = [kind for kind in SELECTOR_KEYS if k.choices is None or kind in k.choices]
        assert [set(sh["properties"]) for sh in shapes] == [{x.name for x in SELECTOR_KEYS[kd]} for kd in kinds]


def test_every_declared_key_is_in_the_schema_and_nothing_else():
    top = SCHEMA["properties"]
    assert set(top) == {"title", "analysis"} | {s.name for s in all_sections()}
    assert SCHEMA["additionalProperties"] is False
    for section in all_sections():
        s = table_schema(section)
        assert s["additionalProperties"] is False
        for k in section.all_keys():
            _check_key(k, s, section.name)
        assert set(s["properties"]) == {k.name for k in section.all_keys()}


def test_schema_defaults_equal_the_parsed_defaults(tmp_path):
    (tmp_path / "any.msh").write_text("")
    for section in all_sections():
        for data, keys in minimal_cases(section, tmp_path):
            spec = section.parse([data] if section.array else data, tmp_path)
            spec = spec[0] if section.array or section.either else spec
            flat = [sub for k in keys for sub in (k.keys if k.kind == "table" else (k,))]
            for k in flat:
                if not k.required and k.default is not None and k.name not in data:
                    assert getattr(spec, k.target) == k.value_default(), f"{section.name}.{k.name}"
    scene = Scene.from_dict({"mesh": {}, "material": {"E": 1e6, "nu": 0.3}})
    assert scene.title == SCHEMA["properties"]["title"]["default"]
    assert scene.analysis == SCHEMA["properties"]["analysis"]["default"]
    assert scene.discretization.degree == table_schema(CORE_SECTIONS[2])["properties"]["degree"]["default"]
    assert scene.mesh.size == SCHEMA["properties"]["mesh"]["properties"]["size"]["default"]
    assert scene.material.model == table_schema(CORE_SECTIONS[1])["properties"]["model"]["default"]


@pytest.mark.parametrize("path", SCENE_FILES, ids=[p.name for p in SCENE_FILES])
def test_demo_and_benchmark_scenes_validate(path):
    assert list(VALIDATOR.iter_errors(tomllib.loads(path.read_text()))) == []
    Scene.from_file(path)


BASE = {"title": "beam", "mesh": {"size": [1.0, 0.1, 0.1], "cells": [4, 1, 1]},
        "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0},
        "fix": [{"where": {"axis": "x", "at": 0.0}}], "load": [{"type": "gravity"}]}


def changed(path: str, value) -> dict:
    d = json.loads(json.dumps(BASE))
    *head, last = path.split(".")
    node = d
    for k in head:
        node = node[int(k)] if isinstance(node, list) else node.setdefault(k, {})
    node[last] = value
    return d


GOOD = [BASE, changed("mesh", {"generator": "cylinder", "radius": 0.1, "height": 1.0, "h": 0.05}),
        changed("load", [{"type": "traction", "where": {"box": [[1, 0, 0], [1, 1, 1]]}, "value": [0, 0, -1.0]},
                         {"type": "pressure", "where": {"axis": "z", "at": 0.1}, "value": 10}]),
        changed("analysis", "modal") | {"modal": {"count": 4}, "sound": {"strike": {"point": [1, 0, 0],
                                                                           "direction": [0, 0, 1]}}},
        changed("analysis", "inverse") | {"inverse": {"method": "adjoint", "smoothness": 1e-3,
                                                      "match_region": {"box": [[0, 0, 0], [1, 1, 1]]}}}]
BAD = [changed("material.E", "stiff"), changed("colour", "red"), changed("material.Young", 1.0),
       changed("mesh.radius", 0.1), changed("mesh.cells", [4, 1.5, 1]), changed("discretization.degree", 3),
       changed("load.0.type", "wind"), changed("load.0.value", [1, 0, 0]), changed("fix.0.where", {}),
       changed("fix.0.components", ["x", "x"]), changed("output.probes", {"tip": [1, 2]}),
       changed("solver.steps", 0), changed("modal", {"count": 3}),
       changed("analysis", "inverse") | {"inverse": {"method": "direct", "smoothness": 1.0}},
       changed("analysis", "modal") | {"sound": {"strike": {"point": [1, 0, 0]}}}]


@pytest.mark.parametrize("data", GOOD, ids=range(len(GOOD)))
def test_valid_scenes_pass_both(data):
    assert list(VALIDATOR.iter_errors(data)) == []
    Scene.from_dict(data)


@pytest.mark.parametrize("data", BAD, ids=range(len(BAD)))
def test_bad_scenes_fail_both(data):
    assert list(VALIDATOR.iter_errors(data)) != []
    with pytest.raises(InputError) as e:
        Scene.from_dict(data)
    assert "\n" not in str(e.value)


BLOCK_DOLFINX = """
import importlib.abc, sys, types, tomllib
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in ("dolfinx", "petsc4py", "slepc4py", "mpi4py", "basix", "ffcx"):
            raise ImportError(f"{name} is blocked")
sys.meta_path.insert(0, Block())
pkg = types.ModuleType("fem_forms")          # the package without its __init__ (which loads analyses)
pkg.__path__ = [sys.argv[1] + "/fem_forms"]
sys.modules["fem_forms"] = pkg
from fem_forms.scene import Scene
from fem_forms.scene.schema import schema_json
for f in sys.argv[2:]:
    Scene.from_file(f)
print(len(schema_json()) > 1000)
"""


def test_scene_reading_needs_no_dolfinx():
    p = subprocess.run([sys.executable, "-c", BLOCK_DOLFINX, str(ROOT), *map(str, SCENE_FILES)],
                       capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout.strip() == "True", p.stderr


def test_the_material_is_built_once_when_the_scene_is_read():
    from fem_forms.materials import make_material
    scene = Scene.from_dict(BASE)
    assert scene.material.material == make_material("neo-hookean", E=1e6, nu=0.3)
    mr = Scene.from_dict(changed("material", {"model": "mooney-rivlin", "C10": 1e5, "C01": 2e4, "lambda": 1e6,
                                              "rho": 1.0}))
    assert mr.material.material == make_material("mooney-rivlin", C10=1e5, C01=2e4, lmbda=1e6)


def test_a_pressure_load_reads_pressure_as_its_python_attribute_and_value_as_before():
    """`pressure = ...` (the key named like Load.pressure and like an inflation load's) and `value = ...`
    (its first spelling) give the same load; both or neither: one line naming the key."""
    def load(**keys):
        return changed("load", [{"type": "pressure", "where": {"axis": "z", "at": 0.1}, **keys}])
    assert Scene.from_dict(load(pressure=2e4)).load[0].pressure == 2e4
    old = Scene.from_dict(load(value=2e4)).load[0]
    assert old.pressure == 2e4 and old.value is None
    for keys in ({"pressure": 1.0, "value": 1.0}, {}):
        with pytest.raises(InputError, match=r"^load\[0\]\.pressure: a pressure load gives its pressure"):
            Scene.from_dict(load(**keys))


def test_an_override_of_one_spelling_of_a_pressure_replaces_the_other(tmp_path):
    """--set load.0.pressure=... on a scene that spells it value = ... (and the other way round)."""
    path = tmp_path / "scene.toml"
    path.write_text('[mesh]\nsize = [1.0, 0.1, 0.1]\n[material]\nE = 1e6\nnu = 0.3\n[[fix]]\nwhere = { axis = "x", at = 0.0 }\n'
                    '[[load]]\ntype = "pressure"\nwhere = { axis = "z", at = 0.1 }\nvalue = 1.0\n')
    assert Scene.from_file(path, {"load.0.pressure": 3.0}).load[0].pressure == 3.0
    assert Scene.from_file(path, {"load.0.value": 4.0}).load[0].pressure == 4.0

