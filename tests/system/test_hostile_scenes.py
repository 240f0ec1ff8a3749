"""A scene is data (issue 51): 200 hostile scenes, generated - every PETSc option family with file, viewer or
monitor values, Python types, names with paths, symbolic links out of the output folder, huge counts, a huge
file, deep nesting - each refused in one line naming why, exit status 2, no traceback, and nothing written
outside the output folder (a before/after listing of a sandbox the hostile values point into, and of the
folder the run starts in). The same options from the user's own command line are honoured."""
import copy
import hashlib
import itertools
import json
import os
from pathlib import Path

import pytest

from fem_forms.cli import main
from fem_forms.scene import set_key
from helpers import beam_scene, toml_dumps, with_

BASE = beam_scene(output={"probes": {"tip": [1.0, 0.05, 0.05]}, "picture": False, "fields": False})
DYNAMIC = with_(BASE, "analysis", "dynamic")
MODAL = with_(BASE, "analysis", "modal")

VIEWER_OPTIONS = ["snes_view", "ksp_view", "pc_view", "mat_view", "eps_view", "log_view", "snes_monitor",
                  "ksp_monitor", "snes_linesearch_monitor", "ksp_converged_reason", "snes_converged_reason",
                  "eps_view_values", "eps_error_relative", "ksp_view_mat", "snes_test_jacobian_view", "options_file",
                  "help", "malloc_dump", "info", "history", "mat_mumps_icntl_1", "mat_mumps_icntl_22",
                  "viewer_binary_filename", "ksp_plot_eigenvalues", "dll_append", "on_error_attach_debugger",
                  "objects_dump", "mg_levels_ksp_view", "st_ksp_monitor", "fieldsplit_0_ksp_view",
                  "pc_asm_print_subdomains", "pc_gasm_print_subdomains", "sub_pc_asm_print_subdomains",
                  "ksp_converged_rate", "ksp_compute_eigenvalues", "ksp_compute_singularvalues",
                  "ksp_compute_eigenvalues_explicitly", "st_mat_mumps_icntl_1", "sub_mat_mumps_icntl_22",
                  "mg_coarse_mat_mumps_icntl_3", "fieldsplit_u_mat_mumps_icntl_2", "mat_mumps_icntl_4"]
VIEWER_VALUES = ["ascii:{S}/a.txt", "binary", "{S}/c.txt", ".bashrc"]
CODE_OPTIONS = [("pc_type", "python"), ("ksp_type", "python"), ("snes_type", "python"),
                ("pc_python_type", "os.system"), ("ksp_python_type", "builtins.exec"), ("snes_type", "shell"),
                ("snes_linesearch_type", "shell"), ("pc_type", "shell"), ("snes_python_type", "x.Y"),
                ("pc_type", "lu -options_file {S}/o"), ("mat_type", "python"), ("dm_plex_filename", "{S}/m.h5"),
                ("pc_composite_pcs", "ilu,python"), ("snes_composite_sneses", "newtonls,python"),
                ("eps_nev", 100000), ("eps_ncv", 100000), ("ksp_gmres_restart", 10**8), ("pc_factor_levels", 10**6),
                ("mat_mumps_icntl_14", 10**7), ("snes_max_it", 10**9)]
NAMES = ["../x", "a/b", "/abs/path", "..", "x\\y", "\x1b[2J", "a\nb", "~/../../etc", "=HYPERLINK(1)", "a,b",
         "\x9b31m", "x" * 81]


def _cases(sandbox: Path) -> list:
    """(name, scene dict or None, file text or None, extra argv, setup, expected fragment): exactly 200 scenes."""
    s = str(sandbox)
    cases = []
    pairs = [(n, VIEWER_VALUES[(i + k) % len(VIEWER_VALUES)]) for i, n in enumerate(VIEWER_OPTIONS) for k in (0, 1)]
    for name, value in pairs:
        cases.append((f"{name}={value}", with_(BASE, "solver", {"petsc": {name: value.format(S=s)}}), None, [],
                      None, f"solver.petsc.{name}"))
    for name, value in CODE_OPTIONS:
        v = value.format(S=s) if isinstance(value, str) else value
        cases.append((f"{name}={value}", with_(BASE, "solver", {"petsc": {name: v}}), None, [], None,
                      f"solver.petsc.{name}"))
        cases.append((f"--set {name}={value}", BASE, None, ["--set", f"solver.petsc.{name}={json.dumps(v)}"], None,
                      f"solver.petsc.{name}"))
    for name in NAMES:
        cases.append((f"probe {name!r}", with_(BASE, "output.probes", {name: [1.0, 0.05, 0.05]}), None, [], None,
                      "output.probes"))
        cases.append((f"fix {name!r}", with_(BASE, "fix.0.name", name), None, [], None, "fix[0].name"))
        cases.append((f"material {name!r}", with_(BASE, "material.name", name), None, [], None, "material.name"))
    for target in ("results.json", "probes.csv", "newton_history.csv", "sub", "loop"):
        cases.append((f"link {target}", BASE, None, [], ("link", target), "symbolic link out of it"))
    cases.append(("default out/ a link", BASE, None, ["--default-out"], ("out link", None), "a symbolic link"))
    cases.append(("default out/stem a link", BASE, None, ["--default-out"], ("stem link", None), "a symbolic link"))
    struck = with_(with_(MODAL, "modal", {"count": 6}), "sound",
                   {"strike": {"point": [1.0, 0.05, 0.1], "direction": [0, 0, -1]}})
    huge = [(BASE, "mesh.cells", [3000, 3000, 3000], "mesh.cells = [3000, 3000, 3000]"),
            (BASE, "solver.steps", 10**7, "solver.steps"),
            (BASE, "solver.max_step", 1e-9, "solver.max_step"),
            (BASE, "solver.max_cutbacks", 10**6, "solver.max_cutbacks"),
            (BASE, "output.probes", {f"p{i}": [1.0, 0.05, 0.05] for i in range(1500)}, "output.probes"),
            (with_(DYNAMIC, "dynamic", {"duration": 1e4}), "dynamic.dt", 1e-6, "dynamic.duration / dynamic.dt"),
            (MODAL, "modal.count", 10**5, "modal.count"),
            (struck, "sound.duration", 1e5, "sound.duration x sound.sample_rate")]
    for base, key, value, fragment in huge:
        cases.append((f"{key} = {str(value)[:20]}", _set(base, key, value), None, [], None, f"{fragment}: "))
        cases.append((f"--set {key}", base, None, ["--set", f"{key}={_toml(value)}"], None, f"{fragment}: "))
    cases.append(("9 MB string", None, 'title = "' + "x" * 9_000_000 + '"\n', [], None, "more than a scene may ask"))
    cases.append(("nesting 40", None, "a = " + "[" * 40 + "]" * 40 + "\n", [], None, "levels of tables and arrays"))
    cases.append(("nesting 100000", None, "a = " + "[" * 100_000 + "]" * 100_000 + "\n", [], None,
                  "nested too deeply"))
    cases.append(("nested inline tables", None, "a = " + "{b = " * 60 + "1" + "}" * 60 + "\n", [], None,
                  "levels of tables and arrays"))
    cases.append(("title with an escape", with_(BASE, "title", "\x1b]0;owned\x07"), None, [], None, "title"))
    assert len(cases) <= 200, len(cases)
    fill = itertools.product(["snes_view", "ksp_monitor", "log_view", "options_file", "pc_asm_print_subdomains"],
                             ["ascii:{S}/e.txt", "{S}/../f.txt", "stdout", "binary"])
    for name, value in itertools.islice(fill, 200 - len(cases)):
        argv = ["--set", f"solver.petsc.{name}={json.dumps(value.format(S=s))}"]
        cases.append((f"--set {name}={value}", BASE, None, argv, None, f"solver.petsc.{name}"))
    return cases


def _set(scene: dict, key: str, value) -> dict:
    """A copy of scene with the dotted key set (tables made as needed)."""
    scene = copy.deepcopy(scene)
    set_key(scene, key, value)
    return scene


def _toml(value) -> str:
    """A value as --set takes it (TOML)."""
    return toml_dumps({"v": value}).split("=", 1)[1].strip() if not isinstance(value, dict) else \
        "{" + ", ".join(f'{k} = {v}' for k, v in value.items()) + "}"


def _listing(folder: Path) -> dict:
    """Every entry under folder (links not followed) with its content's hash."""
    out = {}
    for root, dirs, files in os.walk(folder, followlinks=False):
        for n in dirs + files:
            p = Path(root) / n
            out[str(p)] = ("link" if p.is_symlink() else "dir" if p.is_dir()
                           else hashlib.sha256(p.read_bytes()).hexdigest())
    return out


def _setup(kind, out: Path, sandbox: Path, cwd: Path) -> None:
    if kind is None:
        return
    what, target = kind
    if what == "link" and target == "loop":
        out.mkdir(parents=True, exist_ok=True)
        os.symlink(out / "b", out / "a")
        os.symlink(out / "a", out / "b")
    elif what == "link":
        out.mkdir(parents=True, exist_ok=True)
        os.symlink(sandbox / "victim" if target != "sub" else sandbox, out / target)
    elif what == "out link":
        os.symlink(sandbox, cwd / "out")
    else:
        (cwd / "out").mkdir()
        os.symlink(sandbox, cwd / "out" / "scene")


@pytest.fixture(scope="module")
def sandbox(tmp_path_factory):
    box = tmp_path_factory.mktemp("sandbox")
    (box / "victim").write_text("a user's own file\n")
    (box / "notes.txt").write_text("keep me\n")
    return box


def test_two_hundred_hostile_scenes_are_refused_in_one_line_and_write_nothing(tmp_path, sandbox, capsys,
                                                                              monkeypatch):
    cases = _cases(sandbox)
    assert len(cases) == 200 and len({c[0] for c in cases}) == 200
    before = _listing(sandbox)
    for i, (name, scene, text, extra, setup, fragment) in enumerate(cases):
        cwd = tmp_path / f"case{i}"
        cwd.mkdir()
        monkeypatch.chdir(cwd)
        path = cwd / "scene.toml"
        path.write_text(text if text is not None else toml_dumps(scene))
        out = cwd / "given_out"
        _setup(setup, out, sandbox, cwd)
        argv = [a for a in extra if a != "--default-out"]
        outs = [] if "--default-out" in extra else ["--out", str(out)]
        code = main(["run", str(path), *outs, "-q", *argv])
        err = capsys.readouterr().err
        lines = err.strip().splitlines()
        assert code == 2, (name, err)
        assert len(lines) == 1 and "Traceback" not in err and fragment in lines[0], (name, err)
        inside = {str(p) for p in cwd.rglob("*")} - {str(path)}
        assert not [p for p in inside if not p.startswith((str(out), str(cwd / "out")))], (name, inside)
        assert not (out / "results.json").exists() or (out / "results.json").is_symlink(), name
    assert _listing(sandbox) == before


def test_the_users_own_command_line_may_view_and_log(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(BASE))
    log = tmp_path / "log.txt"
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "-q", "--petsc", f"-log_view ascii:{log}",
                 "-snes_converged_reason"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "PETSc Performance Summary" in log.read_text()
    assert code == 0 and json.loads((tmp_path / "out" / "results.json").read_text())["converged"]


def test_no_limits_lifts_a_cap(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(with_(BASE, "output.probes", {f"p{i}": [1.0, 0.05, 0.05] for i in range(1001)})))
    assert main(["run", str(path), "--out", str(tmp_path / "capped"), "-q"]) == 2
    assert "output.probes: 1,001 probes, more than a scene may ask for (1,000); --no-limits lifts it" in \
        capsys.readouterr().err
    assert main(["run", str(path), "--out", str(tmp_path / "lifted"), "-q", "--no-limits"]) == 0
    assert len(json.loads((tmp_path / "lifted" / "results.json").read_text())["probes"]) == 1001


def test_an_obstacle_file_over_the_cap_is_refused(tmp_path):
    import meshio
    from fem_forms.errors import InputError
    from fem_forms.physics.contact.mesh_obstacle import FileObstacle
    from fem_forms.scene.analyses.contact_section import Obstacle
    from system.test_surface_meshes import box_surface
    p, t = box_surface(1.0, 1.0, 1.0)
    meshio.write(tmp_path / "cube.stl", meshio.Mesh(p, [("triangle", t)]))
    spec = Obstacle(name="table", shape="file", file=tmp_path / "cube.stl")
    assert len(FileObstacle(spec, "contact.obstacle[0]", len(t)).triangles) == len(t)
    with pytest.raises(InputError, match=rf"{len(t)} triangles, more than a scene may ask for \({len(t) - 1}\); "
                                         "--no-limits lifts it"):
        FileObstacle(spec, "contact.obstacle[0]", len(t) - 1)
    ob = FileObstacle(spec, "contact.obstacle[0]", 4 * len(t))
    with pytest.raises(InputError, match="refined to the part's surface edge"):
        ob.refine(0.4, "contact.obstacle[0]")          # 3 x 3 pieces each: 9 times the triangles
    FileObstacle(spec, "contact.obstacle[0]", None).refine(0.4, "contact.obstacle[0]")


def test_a_shared_folders_petscrc_and_modules_are_not_read(tmp_path, sandbox, monkeypatch):
    """PETSc reads .petscrc from the current folder when it starts, Python imports modules from it, dolfinx and
    FFCx their JIT settings (a form cache elsewhere, compiler flags): a folder shared with a scene could hold any.
    A run (a process of its own) and a study's runs read none of them."""
    import subprocess
    import sys
    from fem_forms.study import study
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scene.toml").write_text(toml_dumps(BASE))
    (tmp_path / ".petscrc").write_text(f"-log_view ascii:{sandbox}/petscrc.txt\n")
    (tmp_path / "petscrc").write_text(f"-options_file {sandbox}/other\n")
    (tmp_path / "json.py").write_text(f"open({str(sandbox / 'json_imported.txt')!r}, 'w').write('x')\n"
                                      "raise SystemExit(7)\n")
    (tmp_path / "dolfinx_jit_parameters.json").write_text(json.dumps({"cache_dir": str(sandbox / "forms")}))
    (tmp_path / "ffcx_parameters.json").write_text(json.dumps({"scalar_type": "float"}))
    before = _listing(sandbox)
    script = Path(sys.executable).parent / "fem-forms"          # the command users run (its folder on sys.path)
    p = subprocess.run([str(script), "run", "scene.toml", "-q"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    study(Path("scene.toml"), tmp_path / "study", [1], 1, echo=False)
    assert json.loads((tmp_path / "study" / "P1_level0" / "results.json").read_text())["converged"]
    assert _listing(sandbox) == before
