"""Fuzz the scene reader: 1,000 seeded mutations of the demo scenes, parse only (Scene.from_dict).
Whatever a mutation does, the reader either accepts the scene or raises the one-line InputError
(one line, under 300 characters); no other exception escapes."""
import copy
import random
import tomllib

import pytest

from fem_forms.errors import InputError
from fem_forms.scene import Scene
from helpers import ROOT

SCENES = sorted((ROOT / "demos" / "scenes").glob("*.toml"))
HUGE = "x" * 100_000

VALUES = [HUGE, "abc", "", "a\nb", 10**30, -10**30, 10**400, -1, 0, 1, 2**31, 1e30, -1e30, 1e-300,
          float("nan"), float("inf"), True, False, None, [], [[1, 2, 3]], [["x"]], [1, [2]],
          {"a": 1}, {}, [0.0, 0.0], [1e30, 1e30, 1e30], ["x", ["y"]], [HUGE], {"\n": 1},
          {"group": HUGE}, {"point": [0, 0]}, {"line": [[0, 0, 0]]}, {"box": [[1, 1, 1], [0, 0, 0]]}]
KEYS = ["colour", "evil\nkey", HUGE, "", "x" * 500, 7]


def _paths(node, prefix=()):
    """Every (path, value) in a scene tree."""
    yield prefix, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


def _mutate(scene: dict, rng: random.Random) -> dict:
    d = copy.deepcopy(scene)
    for _ in range(rng.randint(1, 3)):
        paths = [p for p, _ in _paths(d) if p]
        path = rng.choice(paths)
        parent = d
        for k in path[:-1]:
            parent = parent[k]
        last = path[-1]
        action = rng.random()
        if action < 0.6:
            parent[last] = copy.deepcopy(rng.choice(VALUES))
        elif action < 0.75 and isinstance(parent, dict):
            del parent[last]
        elif action < 0.9 and isinstance(parent, dict):
            parent[rng.choice(KEYS)] = copy.deepcopy(rng.choice(VALUES))
        elif isinstance(parent[last], list) and parent[last]:
            parent[last] = [copy.deepcopy(rng.choice(VALUES))] + parent[last][1:]
        else:
            parent[last] = str(parent[last]) * 3
    return d


def test_a_thousand_mutations_raise_nothing_but_one_line_input_errors():
    bases = [tomllib.loads(p.read_text()) for p in SCENES]
    assert bases
    rng = random.Random(13)
    accepted = refused = 0
    for i in range(1000):
        scene = _mutate(rng.choice(bases), rng)
        try:
            Scene.from_dict(scene, base_dir=ROOT / "demos" / "scenes")
            accepted += 1
        except InputError as e:
            msg = str(e)
            assert "\n" not in msg and len(msg) < 300, f"mutation {i}: {msg[:400]!r}"
            refused += 1
        except Exception as e:                                   # noqa: BLE001 - the point of the test
            pytest.fail(f"mutation {i}: {type(e).__name__}: {str(e)[:300]} for {str(scene)[:300]}")
    assert refused > 500 and accepted > 20


@pytest.mark.parametrize("path, value, fragment", [
    (("material", "E"), HUGE, "material.E = 'xxxx"),
    (("fix", 0, "components"), ["x", ["y"]], "fix[0].components"),
    (("solver", "petsc"), {"snes_rtol": "abc"}, "solver.petsc.snes_rtol = 'abc': must be a finite number"),
    (("solver", "petsc"), {"snes_max_it": 2.5}, "must be a whole number"),
    (("solver", "petsc"), {"snes_type": "newtonish"}, "solver.petsc.snes_type = 'newtonish': must be one of"),
    (("mesh", "cells"), [10**30, 2, 2], "mesh.cells[0]"),
    (("mesh", "size"), [1e30, 1.0, 1.0], "mesh.size[0]"),
])
def test_values_found_by_fuzzing_give_short_one_line_errors(path, value, fragment):
    d = tomllib.loads((ROOT / "demos" / "scenes" / "sagging_beam.toml").read_text())
    node = d
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    with pytest.raises(InputError) as e:
        Scene.from_dict(d)
    assert fragment in str(e.value) and "\n" not in str(e.value) and len(str(e.value)) < 300


def test_an_unknown_key_with_a_newline_is_quoted_on_one_line():
    d = tomllib.loads((ROOT / "demos" / "scenes" / "sagging_beam.toml").read_text())
    d["material"]["evil\nkey" + "y" * 1000] = 1
    with pytest.raises(InputError) as e:
        Scene.from_dict(d)
    msg = str(e.value)
    assert msg.startswith("material.'evil\\nkey") and "unknown key" in msg and len(msg) < 300
