"""Changing a material, density, load or support value compiles no new form: every value a user can
change is a Constant or a Function in the forms. Counted by wrapping FFCx's compiler entry point, which
runs only on a JIT cache miss."""
import os
from pathlib import Path
import subprocess
import sys

import dolfinx.jit
import ffcx.codegeneration.jit as ffcx_jit
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.analyses.static.solve import solve_static
from fem_forms.model import build_model


def scene_dict(E=1e6, nu=0.3, rho=1000.0, g=-9.81, traction=-10.0, pressure=50.0, pull=0.001) -> dict:
    return {
        "title": "values as Constants",
        "mesh": {"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [6, 2, 2]},
        "material": {"model": "neo-hookean", "E": E, "nu": nu, "rho": rho},
        "discretization": {"degree": 1},
        "fix": [{"where": {"axis": "x", "at": 0.0}},
                {"where": {"axis": "x", "at": 1.0}, "components": ["y"], "value": [0.0, pull, 0.0]}],
        "load": [{"type": "gravity", "g": [0.0, 0.0, g]},
                 {"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [0.0, 0.0, traction]},
                 {"type": "pressure", "where": {"axis": "z", "at": 0.1}, "value": pressure}],
        "solver": {"steps": 2},
        "output": {"probes": {"tip": [1.0, 0.05, 0.05]}},
    }


@pytest.fixture
def compilations(monkeypatch, tmp_path):
    """A list that grows by one entry per FFCx compilation, with an empty JIT cache (a warm cache would
    hide a form that compiles under a second signature: it happened, see meshes.loader.settle_coordinate_element)."""
    monkeypatch.setitem(dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS, "cache_dir", (tmp_path / "jit", "test"))
    seen = []
    original = ffcx_jit._compile_objects

    def counting(*args, **kwargs):
        seen.append(args[2] if len(args) > 2 else kwargs.get("object_names"))
        return original(*args, **kwargs)

    monkeypatch.setattr(ffcx_jit, "_compile_objects", counting)
    return seen


NEW_VALUES = dict(E=2.5e6, nu=0.42, rho=1234.0, g=-3.0, traction=-25.0, pressure=80.0, pull=-0.002)


def test_new_values_in_a_new_model_compile_nothing(compilations):
    first = solve_static(ff.Scene.from_dict(scene_dict()))
    assert first.report.converged
    first.model.min_jacobian()
    before = len(compilations)
    assert before >= 4                                   # the cache was empty: the forms did compile
    second = solve_static(ff.Scene.from_dict(scene_dict(**NEW_VALUES)))
    second.model.min_jacobian()
    assert second.report.converged
    assert len(compilations) == before, f"new values compiled {len(compilations) - before} forms"
    # and the values did reach the forms: the answers differ
    assert not np.allclose(first.probes["tip"], second.probes["tip"])


def test_set_values_gives_the_fresh_model_answer_without_compiling(compilations):
    """Model.set_values (inside an optimisation loop, say) equals building the model anew."""
    scene_b = ff.Scene.from_dict(scene_dict(**NEW_VALUES))
    fresh = solve_static(scene_b)
    model = build_model(ff.Scene.from_dict(scene_dict()))
    solve_static(model.scene, model=model)
    before = len(compilations)
    model.set_values(scene_b)
    model.u.x.array[:] = 0.0
    changed = solve_static(scene_b, model=model)
    assert len(compilations) == before
    assert changed.report.converged
    a, b = np.array(changed.probes["tip"]), np.array(fresh.probes["tip"])
    assert np.linalg.norm(a - b) <= 1e-9 * np.linalg.norm(b)


def test_results_name_the_terms_assembled():
    scene = ff.Scene.from_dict(scene_dict())
    assert build_model(scene).physics == ["elastic (neo-hookean)", "gravity", "traction", "pressure"]
    d = scene_dict()
    d["load"] = d["load"][:1]
    assert build_model(ff.Scene.from_dict(d)).physics == ["elastic (neo-hookean)", "gravity"]


def test_density_is_a_cellwise_field():
    """A carved half (density 0) weighs half: the gravity term reads the density field cell by cell."""
    d = scene_dict()
    d["load"] = d["load"][:1]
    d["fix"] = d["fix"][:1]
    model = build_model(ff.Scene.from_dict(d))
    from dolfinx import fem
    from mpi4py import MPI
    import ufl
    mass = fem.form(model.context.volume(model.parameters.density))
    full = model.mesh.comm.allreduce(fem.assemble_scalar(mass), op=MPI.SUM)
    assert full == pytest.approx(1000.0 * 1.0 * 0.1 * 0.1, rel=1e-12)
    V0 = model.parameters.density.function_space
    x = V0.tabulate_dof_coordinates()
    rho = np.where(x[:, 0] < 0.5, 1000.0, 0.0)
    model.parameters.set_density(rho)
    half = model.mesh.comm.allreduce(fem.assemble_scalar(mass), op=MPI.SUM)
    assert half == pytest.approx(0.5 * full, rel=1e-12)
    del ufl


def test_every_load_type_the_scene_accepts_has_a_term():
    """A new [[load]] type is a Term class registered under its name plus its keys in LOAD_TYPES:
    neither can be forgotten without this failing."""
    from fem_forms.physics.terms import LOAD_TERMS
    from fem_forms.scene.spec import LOAD_TYPES
    assert set(LOAD_TERMS) == set(LOAD_TYPES)


ROOT = Path(__file__).resolve().parents[2]


def test_a_second_run_with_new_values_compiles_nothing(tmp_path):
    """Between runs (separate processes, as users run scenes): the FFCx compile log of `fem-forms run -v`
    shows compilations on the first run into an empty cache and none on a run with new values."""
    import json
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "cache"), PYTHONPATH=str(ROOT),
               OPENBLAS_NUM_THREADS="1")
    counts = []
    for i, values in enumerate(({}, NEW_VALUES)):
        scene = tmp_path / f"scene{i}.toml"
        scene.write_text(_toml(scene_dict(**values)))
        p = subprocess.run([sys.executable, "-m", "fem_forms", "run", str(scene), "--out", str(tmp_path / f"o{i}"),
                            "-v", "-q"], capture_output=True, text=True, env=env, cwd=ROOT)
        assert p.returncode == 0, p.stderr[-2000:]
        log = p.stdout + p.stderr
        counts.append(log.count("building 'libffcx_forms") + log.count("building 'libffcx_expressions"))
        assert json.loads((tmp_path / f"o{i}" / "results.json").read_text())["converged"]
    assert counts[0] >= 3 and counts[1] == 0, counts     # residual, tangent, energy (+ expressions)


def _toml(d: dict) -> str:
    from helpers import toml_dumps
    return toml_dumps(d)


def thermal_scenes(k=35.0, alpha=1.2e-5, slope=-2e6, T0=100.0, h=50.0, amb=20.0, rho=1000.0, dt=0.5):
    """A coupled static scene and a transient heat scene carrying the same thermal values."""
    thermal = {"conductivity": k, "specific_heat": 400.0, "expansion": alpha, "modulus_slope": slope,
               "boundary": [{"where": {"axis": "x", "at": 0.0}, "temperature": T0},
                            {"where": {"axis": "x", "at": 1.0}, "convection": {"h": h, "ambient": amb}}]}
    base = {"mesh": {"size": [1.0, 0.1, 0.1], "cells": [6, 1, 1]}, "discretization": {"degree": 1},
            "material": {"model": "linear", "E": 1e9, "nu": 0.3, "rho": rho}, "thermal": thermal,
            "output": {"probes": {"tip": [1.0, 0.05, 0.05]}}}
    static = dict(base, fix=[{"where": {"axis": "x", "at": 0.0}}])
    heat = dict(base, analysis="thermal", dynamic={"duration": 2 * dt, "dt": dt})
    return ff.Scene.from_dict(static), ff.Scene.from_dict(heat)


def test_new_thermal_values_compile_nothing(compilations):
    from fem_forms.analyses.thermal import solve_thermal
    static, heat = thermal_scenes()
    a = solve_static(static)
    ha = solve_thermal(heat)
    before = len(compilations)
    assert before >= 4
    static, heat = thermal_scenes(k=20.0, alpha=2e-5, slope=-1e6, T0=150.0, h=80.0, amb=0.0, rho=500.0, dt=0.25)
    b = solve_static(static)
    hb = solve_thermal(heat)
    assert len(compilations) == before, f"new thermal values compiled {len(compilations) - before} forms"
    assert a.report.converged and b.report.converged, (a.report.message, b.report.message)
    assert not np.allclose(a.probes["tip"], b.probes["tip"])
    assert ha.probe_rows[-1][1] != hb.probe_rows[-1][1]


def test_a_run_waits_for_a_form_another_process_is_compiling(tmp_path):
    """Two processes sharing a cold JIT cache: the second waits for the first's compile instead of failing after
    dolfinx's timeout (10 s; the largest forms here took 25-35 s with gcc). Each process makes that default 2 s
    before fem_forms sets its own; the first process holds the first cache entry it takes (the element's) for
    6 s, and the second, started on the same forms once that entry is taken, waits longer than that default."""
    import subprocess
    import sys
    import textwrap
    import dolfinx.jit
    assert dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS["timeout"][0] >= 600
    script = textwrap.dedent(f"""
        import pathlib, sys, time
        sys.path.insert(0, {str(ROOT)!r})
        import dolfinx.jit
        dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS["timeout"] = (2, "")      # shorter than the hold below
        import fem_forms, ffcx.codegeneration.jit as fj
        from dolfinx import fem, mesh
        from mpi4py import MPI
        import ufl
        dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS["cache_dir"] = ({str(tmp_path / 'jit')!r}, "")
        slow = sys.argv[1] == "slow"
        original = fj._compile_objects
        holding = pathlib.Path({str(tmp_path / 'holding')!r})
        def compile_slowly(*a, **k):
            if slow and not holding.exists():     # the first entry (the element's) is taken: say so, hold it
                holding.touch()
                time.sleep(6)
            return original(*a, **k)
        fj._compile_objects = compile_slowly
        while not slow and not holding.exists():
            time.sleep(0.05)
        start = time.perf_counter()         # the element's compile and the form's wait for the first process
        m = mesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1)
        V = fem.FunctionSpace(m, ("Lagrange", 1))
        u = fem.Function(V)
        fem.form(u * u * ufl.dx)
        print("ok", time.perf_counter() - start)
    """)
    path = tmp_path / "jit_twice.py"
    path.write_text(script)
    procs = [subprocess.Popen([sys.executable, str(path), kind], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for kind in ("slow", "fast")]
    waited = []
    for p in procs:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0 and out.startswith("ok "), err[-2000:]
        waited.append(float(out.split()[1]))
    assert waited[1] > 2.0, waited               # the second process did wait, past the 2 s default


def test_an_interrupted_compile_leaves_no_lock_for_the_next_run(tmp_path):
    """Ctrl-C while FFCx compiles a new form (a real SIGINT, delivered while the C compiler would run): the cache
    entry is marked failed, not left as a lock, so the next run compiles the form at once instead of waiting the
    JIT timeout out and failing with TimeoutError (here shortened to 5 s so that a leftover lock shows)."""
    import subprocess
    import sys
    import textwrap
    script = textwrap.dedent(f"""
        import os, signal, sys, time
        sys.path.insert(0, {str(ROOT)!r})
        import fem_forms, dolfinx.jit, cffi
        from dolfinx import fem, mesh
        from mpi4py import MPI
        import ufl
        dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS["cache_dir"] = ({str(tmp_path / 'jit')!r}, "")
        dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS["timeout"] = (5, "")
        m = mesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1)
        V = fem.FunctionSpace(m, ("Lagrange", 1))
        u = fem.Function(V)
        if sys.argv[1] == "interrupted":          # the form's compile, not the element's
            signal.signal(signal.SIGINT, signal.default_int_handler)    # ignored in a background job's child
            def compile_until_interrupted(self, *a, **k):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(30)
            cffi.FFI.compile = compile_until_interrupted
        try:
            fem.form(u * u * u * ufl.dx)
        except KeyboardInterrupt:
            print("interrupted")
        else:
            print("ok")
    """)
    path = tmp_path / "jit_interrupted.py"
    path.write_text(script)
    runs = {}
    for kind in ("interrupted", "again"):
        p = subprocess.run([sys.executable, str(path), kind], capture_output=True, text=True, timeout=300)
        runs[kind] = p
        assert p.returncode == 0, p.stderr[-2000:]
    assert runs["interrupted"].stdout.strip() == "interrupted", runs["interrupted"].stderr[-2000:]
    assert runs["again"].stdout.strip() == "ok", runs["again"].stderr[-2000:]
    entries = list((tmp_path / "jit").glob("libffcx_forms_*.c"))
    assert entries and all(c.with_suffix(".c.cached").exists() for c in entries), entries
