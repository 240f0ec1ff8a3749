"""Helpers shared by tests/unit and tests/system: scene builders, a TOML writer, the CLI and mpirun
runners. Test modules import them with `from helpers import ...` (tests/ is on sys.path through
tests/conftest.py and the `pythonpath` setting in pyproject.toml)."""
import base64
import copy
import json
import re
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from scipy.optimize import fsolve

import fem_forms as ff
from fem_forms.cli import main
from fem_forms.materials import lame_from_young_poisson

ROOT = Path(__file__).resolve().parent.parent


# --- scenes -----------------------------------------------------------------------------------
def beam_scene(**over) -> dict:
    """A small clamped beam scene as a dict (tests tweak it)."""
    d = {
        "title": "test beam",
        "mesh": {"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [10, 2, 2]},
        "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0},
        "discretization": {"degree": 1},
        "fix": [{"where": {"axis": "x", "at": 0.0}}],
        "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81]}],
        "output": {"probes": {"tip": [1.0, 0.05, 0.05]}},
    }
    for k, v in over.items():
        d[k] = v
    return d


def with_(d: dict, path: str, value):
    """Copy of scene d with d[a][b]... = value (value None deletes)."""
    d = copy.deepcopy(d)
    keys = path.split(".")
    node = d
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node[k]
    if value is None:
        del node[keys[-1]]
    else:
        node[keys[-1]] = value
    return d


# the block of the static system tests: E, nu and the Lame parameters of its neo-Hookean material
E, NU = 1.0e6, 0.3
MU, LMBDA = lame_from_young_poisson(E, NU)


def block_scene(cell, degree, loads, size=(1.0, 1.0, 1.0), cells=(2, 2, 2)):
    """A block with rollers on x=0, y=0, z=0 (symmetry planes) and the given loads."""
    return ff.Scene.from_dict({
        "mesh": {"generator": "box", "size": list(size), "cells": list(cells), "cell": cell},
        "material": {"model": "neo-hookean", "E": E, "nu": NU},
        "discretization": {"degree": degree},
        "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
        "load": loads,
        "output": {"probes": {"corner": list(size)}},
    })


def uniaxial_stretches(T):
    """Neo-Hookean uniaxial dead-load tension T (first Piola-Kirchhoff): stretches (l1, l2) with
    zero lateral stress, solved independently of the FE code."""
    def eqs(v):
        l1, l2 = v
        lnJ = np.log(l1 * l2**2)
        return [MU * (l1 - 1 / l1) + LMBDA * lnJ / l1 - T, MU * (l2 - 1 / l2) + LMBDA * lnJ / l2]
    return fsolve(eqs, [1.1, 0.95], xtol=1e-12)


def inverse_beam(E=1e7, method="direct", cells=(10, 2, 2), **inv) -> dict:
    d = beam_scene(mesh={"generator": "box", "size": [1.0, 0.1, 0.1], "cells": list(cells)},
                   material={"model": "neo-hookean", "E": E, "nu": 0.3, "rho": 1100.0})
    d["analysis"] = "inverse"
    d["inverse"] = {"method": method, **inv}
    d["solver"] = {"steps": 4}
    return d


# the slender square beam of the modal tests, nu = 0
MODAL_L, MODAL_T, MODAL_E, MODAL_RHO = 1.0, 0.025, 1.0e8, 1000.0


def modal_beam(count=4, cells=(20, 1, 1), fix=True, **over) -> dict:
    d = {"title": "modal beam", "analysis": "modal",
         "mesh": {"size": [MODAL_L, MODAL_T, MODAL_T], "cells": list(cells)},
         "material": {"model": "neo-hookean", "E": MODAL_E, "nu": 0.0, "rho": MODAL_RHO},
         "discretization": {"degree": 2},
         "fix": [{"where": {"axis": "x", "at": 0.0}}] if fix else [],
         "modal": {"count": count}}
    d.update(over)
    return d


def incompressible_beam(nu, formulation, degree, cells=(20, 2, 2)):
    L, h = 1.0, 0.05
    d = beam_scene(mesh={"generator": "box", "size": [L, h, h], "cells": list(cells)},
                   material={"model": "neo-hookean", "E": 1e9, "nu": nu, "rho": 1000.0},
                   discretization={"degree": degree, "formulation": formulation},
                   output={"probes": {"tip": [L, h / 2, h / 2]}})
    return ff.Scene.from_dict(d)


def rollered_block(model="linear", traction=300e6, history=None, E=200e9, yield_stress=250e6, hardening=20e9,
                   plasticity=None, rho=7800.0, **over) -> dict:
    """A 2 x 1 x 0.5 m block on rollers on three faces, pulled along x on the fourth (a uniform uniaxial
    stress): steel, von Mises with linear hardening unless `plasticity` says otherwise; `history` makes the
    traction follow one."""
    load = {"type": "traction", "where": {"axis": "x", "at": 2.0}, "value": [traction, 0, 0]}
    if history is not None:
        load["history"] = [list(p) for p in history]
    plasticity = plasticity or {"model": "von-mises", "yield_stress": yield_stress, "hardening": hardening}
    d = {"mesh": {"generator": "box", "size": [2.0, 1.0, 0.5], "cells": [2, 2, 2]},
         "material": {"model": model, "E": E, "nu": 0.3, "rho": rho, "plasticity": plasticity},
         "discretization": {"degree": 1},
         "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
         "load": [load]}
    d.update(over)
    return d


def tension_block(model="linear", history=((0, 0), (0.02, 1)), duration=0.03, output=None, **dynamic) -> dict:
    """The rollered block pulled by 300 MPa over a load history in a dynamic run (Rayleigh alpha 2000)."""
    return rollered_block(model, history=history, analysis="dynamic",
                          dynamic={"duration": duration, "dt": 5e-4, **dynamic},
                          damping={"rayleigh": {"alpha": 2000.0, "beta": 0.0}},
                          output=output or {"picture": False, "fields": []})


def mesh_volume(mesh) -> float:
    one = fem.Constant(mesh, 1.0)
    return mesh.comm.allreduce(fem.assemble_scalar(fem.form(one * ufl.dx(domain=mesh))), op=MPI.SUM)


# --- TOML writers -----------------------------------------------------------------------------
def toml_dumps(d: dict, prefix: str = "") -> str:
    """Minimal TOML writer for the test scenes (tables, arrays of tables, inline values; keys quoted where they
    are not bare)."""
    def key(k):
        return k if re.fullmatch(r"[A-Za-z0-9_-]+", str(k)) else json.dumps(str(k))

    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{key(k)} = {val(x)}" for k, x in v.items()) + " }"
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)
    lines, tables = [], []
    for k, v in d.items():
        if isinstance(v, dict) and not prefix.startswith("inline"):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v))
        else:
            lines.append(f"{key(k)} = {val(v)}")
    for k, v in tables:
        name = f"{prefix}{k}"
        if isinstance(v, list):
            for item in v:
                lines.append(f"[[{name}]]")
                lines.extend(f"{key(kk)} = {val(vv)}" for kk, vv in item.items())
        else:
            lines.append(f"[{name}]")
            lines.extend(f"{key(kk)} = {val(vv)}" for kk, vv in v.items())
    return "\n".join(lines) + "\n"


def to_toml(d: dict) -> str:
    """Just enough TOML for these scenes: scalars, lists, inline tables, tables, arrays of tables."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return "{" + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + "}"
    lines = [f"{k} = {val(v)}" for k, v in d.items() if not isinstance(v, (dict, list)) or
             (isinstance(v, list) and not (v and isinstance(v[0], dict)))]
    for k, v in d.items():
        if isinstance(v, dict):
            lines += [f"[{k}]"] + [f"{kk} = {val(x)}" for kk, x in v.items()]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                lines += [f"[[{k}]]"] + [f"{kk} = {val(x)}" for kk, x in item.items()]
    return "\n".join(lines) + "\n"


# --- running the CLI and mpirun ---------------------------------------------------------------
def run_scene(tmp_path, d, capsys=None):
    """`fem-forms run` on scene dict d in this process: (status, results.json or None, stderr, out)."""
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out)])
    err = capsys.readouterr().err if capsys else ""
    data = json.loads((out / "results.json").read_text()) if (out / "results.json").exists() else None
    return code, data, err, out


def serial_and_two_ranks(tmp_path, d) -> tuple[dict, dict]:
    """results.json of scene dict d run in this process (out/) and under `mpirun -n 2` (two/, same scene file):
    the 2-rank check without a 1-rank mpirun (this process sums as one does: one BLAS thread, tests/conftest.py)."""
    code, one, _, _ = run_scene(tmp_path, d)
    assert code == 0, f"the in-process run exited {code}"
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "two"), "-q"])
    assert p.returncode == 0, p.stderr[-2000:]
    two = json.loads((tmp_path / "two" / "results.json").read_text())
    assert (one["mpi_ranks"], two["mpi_ranks"]) == (1, 2)
    return one, two


MPIRUN = shutil.which("mpirun")

# The suite runs one pytest worker per core: an mpirun's two ranks beside the other worker's test are three busy
# processes on two cores, and a rank waiting for the other polls (Open MPI's default) while the one with work waits
# for a core. Measured with one busy process beside it: the 2-rank PneuNet of test_pneunet 14.4 and 15.7 s, at this
# nice value 7.6 and 8.2 s (7.3 s with nothing beside it); with OMPI_MCA_mpi_yield_when_idle=1 instead a small
# 2-rank check took 13-16 s against 7-8 s. mpirun is given the value as soon as it runs, before it starts its ranks
# (they inherit it); where the user may not lower it (not root, or no CAP_SYS_NICE) the ranks run as before.
MPI_NICE = -10


def ahead_of_the_other_worker(pid: int) -> None:
    """Process `pid` (a just started mpirun) at MPI_NICE, where the user may (else unchanged)."""
    try:
        os.setpriority(os.PRIO_PROCESS, pid, MPI_NICE)
    except OSError:
        pass


def run_ahead(cmd: list, timeout: float, **kwargs) -> subprocess.CompletedProcess:
    """subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, **kwargs) for an mpirun, ahead of the
    other worker (no code runs in the child between fork and exec: the workers hold MPI's threads)."""
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs) as p:
        ahead_of_the_other_worker(p.pid)
        try:
            out, err = p.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.communicate()
            raise
    return subprocess.CompletedProcess(cmd, p.returncode, out, err)


def mpirun(args, n=2):
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OPENBLAS_NUM_THREADS="1")
    cmd = [MPIRUN, "-n", str(n), "--bind-to", "none", "--oversubscribe", sys.executable, *args]
    return run_ahead(cmd, 600, cwd=ROOT, env=env)


# --- report.html -----------------------------------------------------------------------------------
def report_data(page) -> tuple[np.ndarray, np.ndarray, dict]:
    """The page's surface (rest points, triangles) and colour fields {name: (unit, [values per frame])}, decoded
    from its embedded data."""
    text = page.read_text()
    data = json.loads(text.split('<script id="report-data" type="application/json">')[1].split("</script>")[0])
    decode = lambda b, t: np.frombuffer(base64.b64decode(b), t)              # noqa: E731
    return (decode(data["surface"]["rest"], "<f4").reshape(-1, 3), decode(data["surface"]["triangles"], "<u4")
            .reshape(-1, 3), {name: (f["unit"], [decode(v, "<f4") for v in f["frames"]])
                              for name, f in data["fields"].items()})
