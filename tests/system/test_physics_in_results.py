"""results.json says which terms were assembled, for every analysis."""
import json
from pathlib import Path

import pytest

from fem_forms.cli import main


def write_scene(tmp_path: Path, analysis: str, loads: str) -> Path:
    text = f'''
title = "physics list"
analysis = "{analysis}"
[mesh]
generator = "box"
size = [1.0, 0.1, 0.1]
cells = [6, 1, 1]
[material]
model = "stvk"
E = 1.0e7
nu = 0.3
rho = 1000.0
[discretization]
degree = 1
[[fix]]
where = {{ axis = "x", at = 0.0 }}
{loads}
[output]
picture = false
'''
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


GRAVITY = '[[load]]\ntype = "gravity"\n'
TRACTION = '[[load]]\ntype = "traction"\nwhere = { axis = "x", at = 1.0 }\nvalue = [0.0, 0.0, -10.0]\n'


@pytest.mark.parametrize("analysis, loads, physics", [
    ("static", GRAVITY + TRACTION, ["elastic (stvk)", "gravity", "traction"]),
    ("static", TRACTION, ["elastic (stvk)", "traction"]),
    ("inverse", GRAVITY, ["elastic (stvk)", "gravity"]),
    ("modal", GRAVITY, ["elastic (stvk)", "gravity", "inertia"]),
])
def test_results_list_the_assembled_terms(tmp_path, analysis, loads, physics):
    out = tmp_path / "out"
    assert main(["run", str(write_scene(tmp_path, analysis, loads)), "--out", str(out)]) == 0
    assert json.loads((out / "results.json").read_text())["physics"] == physics
