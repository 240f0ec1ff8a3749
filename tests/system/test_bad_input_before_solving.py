"""Bad input caught before Newton or before allocation: loads on a body its supports leave free,
meshes larger than the machine, PETSc option values, absurd sizes; and a scene with nothing to
solve answers u = 0 at once. Each refusal is one line and exit status 2."""
import json

import pytest

from fem_forms.cli import main
from helpers import MPIRUN, beam_scene, mpirun, toml_dumps, with_

BASE = beam_scene(output={"probes": {"tip": [1.0, 0.05, 0.05]}, "picture": False, "fields": False})


def run(tmp_path, scene, capsys, *extra):
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), "-q", *extra])
    err = capsys.readouterr().err
    data = json.loads((out / "results.json").read_text()) if (out / "results.json").exists() else None
    return code, err, data


REFUSED = [
    ("free body under gravity", with_(BASE, "fix", []),
     "fix: the supports leave the body free (translation z) and the loads push it that way"),
    ("roller leaves z free", with_(BASE, "fix", [{"where": {"axis": "x", "at": 0.0}, "components": ["x", "y"]}]),
     "no static equilibrium exists"),
    ("free but not pushed", with_(BASE, "fix", [{"where": {"axis": "x", "at": 0.0}, "components": ["x", "z"]}]),
     "fix: the supports leave the body free (translation y); the loads do not push it that way"),
    ("box larger than the machine", with_(BASE, "mesh.cells", [4000, 4000, 4000]),
     "mesh.cells = [4000, 4000, 4000]: 384,000,000,000 cells, more than a scene may ask for (2,000,000); "
     "--no-limits lifts it"),
    ("non-numeric snes_rtol", with_(BASE, "solver", {"petsc": {"snes_rtol": "abc"}}),
     "solver.petsc.snes_rtol = 'abc': must be a finite number"),
    ("bad line search", with_(BASE, "solver", {"petsc": {"snes_linesearch_type": "cubic"}}),
     "solver.petsc.snes_linesearch_type = 'cubic': must be one of"),
    ("box of size 1e30", with_(BASE, "mesh.size", [1e30, 0.1, 0.1]), "mesh.size[0] = 1e+30"),
    ("elongated cells", with_(BASE, "mesh.size", [1e5, 0.1, 0.1]), "too elongated"),
]


@pytest.mark.parametrize("name, scene, fragment", REFUSED, ids=[r[0] for r in REFUSED])
def test_refused_in_one_line_with_status_2(tmp_path, capsys, name, scene, fragment):
    code, err, data = run(tmp_path, scene, capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and fragment in lines[0], err
    assert len(lines[0]) < 320 and data is None


def test_memory_refusal_names_the_estimate_and_the_machine(tmp_path, capsys):
    code, err, _ = run(tmp_path, with_(BASE, "mesh.cells", [4000, 4000, 4000]), capsys, "--no-limits")
    assert code == 2 and "3.84e+11 cells" in err and "GiB, more than this machine's" in err and "use fewer cells" in err


def test_a_surface_meshed_too_finely_is_refused_before_gmsh_runs(tmp_path, capsys):
    import meshio
    import numpy as np
    from system.test_surface_meshes import box_surface
    p, t = box_surface(1.0, 1.0, 1.0)
    meshio.write(tmp_path / "cube.stl", meshio.Mesh(p, [("triangle", t)]))
    scene = with_(BASE, "mesh", {"generator": "file", "file": str(tmp_path / "cube.stl"), "h": 1e-4})
    scene["output"]["probes"] = {}
    code, err, _ = run(tmp_path, scene, capsys)
    assert code == 2 and "mesh.file = " in err and "at h = 0.0001: about" in err and "--no-limits lifts it" in err
    code, err, _ = run(tmp_path, scene, capsys, "--no-limits")
    assert code == 2 and "mesh.file = " in err and "at h = 0.0001" in err and "GiB" in err


def test_petsc_option_on_the_command_line_is_checked(tmp_path, capsys):
    code, err, _ = run(tmp_path, BASE, capsys, "-snes_rtol", "abc")
    assert code == 2 and "command line: -snes_rtol = 'abc': must be a finite number" in err


def test_no_loads_is_u_zero_at_once(tmp_path, capsys):
    code, err, data = run(tmp_path, with_(BASE, "load", []), capsys)
    assert code == 0, err
    assert data["converged"] and data["newton_iterations"] == 0 and data["max_displacement"] == 0.0
    assert "nothing to solve" in data["message"]


def test_no_loads_but_a_prescribed_displacement_is_solved(tmp_path, capsys):
    scene = with_(BASE, "load", [])
    scene["fix"] = [{"where": {"axis": "x", "at": 0.0}}, {"where": {"axis": "x", "at": 1.0}, "value": [0.1, 0.0, 0.0]}]
    code, err, data = run(tmp_path, scene, capsys)
    assert code == 0 and data["converged"] and data["newton_iterations"] < 15
    assert data["probes"]["tip"]["displacement"][0] == pytest.approx(0.1)


@pytest.mark.mpi
def test_a_free_body_is_refused_on_two_ranks(tmp_path):
    assert MPIRUN is not None
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(with_(BASE, "fix", [{"where": {"point": [0.0, 0.0, 0.0]}}])))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out"), "-q"])
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if "fem-forms: error" in ln]
    assert len(lines) == 1 and "rotation about x, rotation about y" in lines[0], p.stderr
