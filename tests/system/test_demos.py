"""The main demo's scene solves and writes every output file (the first README command)."""
import json

from fem_forms import Scene, solve_static, write_static_outputs
from helpers import ROOT


def test_demo_scene_solves_and_writes_outputs(tmp_path):
    scene = Scene.from_file(ROOT / "demos" / "scenes" / "sagging_beam.toml")
    scene.mesh.cells = [10, 2, 2]          # coarser than the demo, same physics
    res = solve_static(scene)
    summary = write_static_outputs(res, tmp_path)
    assert summary["converged"]
    data = json.loads((tmp_path / "results.json").read_text())
    for key in ("analysis", "dofs", "converged", "newton_iterations", "load_steps", "energy",
                "max_displacement", "wall_time_s", "probes"):
        assert key in data
    assert data["probes"]["tip"]["displacement"][2] < -0.3     # a soft beam sags a lot
    for f in ("fields.xdmf", "fields.h5", "deformed.png", "newton_history.csv"):
        assert (tmp_path / f).stat().st_size > 0
