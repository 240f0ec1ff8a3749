"""Bad input: one clear line naming the key, exit status 2, no traceback, nothing written.
A solve that cannot converge: exit status 3 and no answer."""
import json
import subprocess
import sys

import pytest
import tomllib

from fem_forms.cli import main
from helpers import ROOT, beam_scene, toml_dumps, with_


def run_cli(tmp_path, scene: dict, capsys, *extra):
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    assert tomllib.loads(path.read_text()) == scene          # the writer is faithful
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), *extra])
    err = capsys.readouterr().err
    return code, err, out


BASE = beam_scene()

CASES = [
    ("unknown top-level key", with_(BASE, "colour", "red"), "colour: unknown key"),
    ("unknown material key", with_(BASE, "material.Young", 1.0), "material.Young: unknown key"),
    ("wrong type", with_(BASE, "material.E", "stiff"), "material.E = 'stiff': must be a number"),
    ("nu at 0.5", with_(BASE, "material.nu", 0.5), "material.nu = 0.5"),
    ("nu above 0.5", with_(BASE, "material.nu", 0.7), "material.nu = 0.7"),
    ("E zero", with_(BASE, "material.E", 0.0), "material.E = 0.0"),
    ("E negative", with_(BASE, "material.E", -5.0), "material.E = -5.0"),
    ("unknown model", with_(BASE, "material.model", "rubber"), "material.model = 'rubber'"),
    ("missing mesh file", with_(BASE, "mesh", {"generator": "file", "file": "nowhere.msh"}),
     "mesh.file = 'nowhere.msh': file not found"),
    ("selector matches nothing", with_(BASE, "fix.0.where", {"axis": "x", "at": 5.0}),
     "fix[0].where: matches no boundary facet"),
    ("unknown group", with_(BASE, "fix.0.where", {"group": "base"}), "fix[0].where.group = 'base'"),
    ("unsupported element degree", with_(BASE, "discretization.degree", 4),
     "discretization.degree = 4: unsupported element"),
    ("unsupported cell", with_(BASE, "mesh.cell", "pyramid"), "mesh.cell = 'pyramid'"),
    ("bad component", with_(BASE, "fix.0.components", ["x", "w"]), "fix[0].components"),
    ("bad vector length", with_(BASE, "load.0.g", [0.0, -9.81]), "load[0].g"),
    ("gravity without density", with_(BASE, "material.rho", 0.0), "material.rho: gravity needs"),
    ("probe outside", with_(BASE, "output.probes", {"far": [3.0, 0.0, 0.0]}),
     "output.probes.far = [3.0, 0.0, 0.0]: point lies outside the mesh"),
    ("unknown analysis", with_(BASE, "analysis", "dance"), "analysis = 'dance'"),
    ("negative cells", with_(BASE, "mesh.cells", [10, -2, 2]), "mesh.cells[1] = -2"),
]


@pytest.mark.parametrize("name, scene, fragment", CASES, ids=[c[0] for c in CASES])
def test_bad_input_gives_one_line_and_status_2(tmp_path, capsys, name, scene, fragment):
    code, err, out = run_cli(tmp_path, scene, capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], err
    assert "Traceback" not in err
    assert not out.exists()                      # nothing half written


def test_bad_toml_and_missing_scene(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("title = \n")
    assert main(["run", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "not valid TOML" in capsys.readouterr().err
    assert main(["run", str(tmp_path / "none.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "not found" in capsys.readouterr().err


def test_inverted_and_degenerate_cells_in_a_mesh_file_are_rejected(tmp_path, capsys):
    import meshio
    import numpy as np
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, 1, 0]], dtype=float)
    good = [[0, 1, 2, 3], [1, 2, 3, 4]]
    # one cell reversed against the others: inverted
    meshio.write(tmp_path / "inv.vtu", meshio.Mesh(pts, [("tetra", np.array(good + [[1, 3, 2, 4]]))]))
    # four coplanar points: degenerate
    meshio.write(tmp_path / "flat.vtu", meshio.Mesh(pts, [("tetra", np.array(good + [[0, 1, 5, 2]]))]))
    for name, expect in (("inv.vtu", "inverted cells"), ("flat.vtu", "degenerate")):
        scene = with_(BASE, "mesh", {"generator": "file", "file": str(tmp_path / name)})
        code, err, out = run_cli(tmp_path, scene, capsys)
        assert code == 2 and expect in err and len(err.strip().splitlines()) == 1, err


def test_mesh_without_volume_cells_is_rejected(tmp_path, capsys):
    import meshio
    import numpy as np
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    meshio.write(tmp_path / "tri.vtu", meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))
    scene = with_(BASE, "mesh", {"generator": "file", "file": str(tmp_path / "tri.vtu")})
    code, err, _ = run_cli(tmp_path, scene, capsys)
    assert code == 2 and "found: triangle" in err


def test_bad_petsc_option_on_command_line(tmp_path, capsys):
    code, err, out = run_cli(tmp_path, BASE, capsys, "snes_rtol")
    assert code == 2 and "is not an option" in err


def test_nonconvergence_exits_3_without_an_answer(tmp_path, capsys):
    """One Newton iteration allowed and no cut-backs: the soft beam cannot converge."""
    scene = with_(BASE, "solver", {"steps": 1, "max_cutbacks": 0, "petsc": {"snes_max_it": 1}})
    code, err, out = run_cli(tmp_path, scene, capsys)
    assert code == 3 and "did not converge" in err
    data = json.loads((out / "results.json").read_text())
    assert data["converged"] is False
    assert data["max_displacement"] is None and data["probes"] == {}


def test_cli_process_prints_no_traceback(tmp_path):
    """The installed entry point, as a user runs it: one line, status 2."""
    path = tmp_path / "s.toml"
    path.write_text(toml_dumps(with_(BASE, "material.nu", 0.5)))
    p = subprocess.run([sys.executable, "-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "material.nu" in p.stderr and p.stdout == ""
