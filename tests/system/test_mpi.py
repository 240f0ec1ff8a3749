"""The same answer on 1 and 2 MPI ranks: the CLI under `mpirun -n 2` against a serial solve."""
import json

import numpy as np
import pytest

import fem_forms as ff
from helpers import MPIRUN, beam_scene, mpirun, toml_dumps

SCENES = {
    "soft P2 beam, gravity + traction": beam_scene(
        mesh={"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [12, 2, 2]},
        discretization={"degree": 2},
        load=[{"type": "gravity", "g": [0.0, 0.0, -9.81]},
              {"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [0.0, 0.0, -100.0]}]),
    "gmsh cylinder, group selectors, pressure": beam_scene(
        mesh={"generator": "cylinder", "radius": 0.05, "height": 0.4, "h": 0.02},
        discretization={"degree": 1},
        fix=[{"where": {"group": "bottom"}}],
        load=[{"type": "pressure", "where": {"group": "side"}, "value": 2e4}],
        output={"probes": {"top": [0.0, 0.0, 0.4], "mid": [0.0, 0.04, 0.2]}}),
    # CG + GAMG kept across Newton steps: every rank must take the same rebuild decisions
    "very soft P2 beam, iterative solver": beam_scene(
        mesh={"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [20, 2, 2]},
        material={"model": "neo-hookean", "E": 3e5, "nu": 0.3, "rho": 1000.0},
        discretization={"degree": 2}, solver={"linear": "iterative"}),
}


@pytest.mark.mpi          # the precondition of every mpi case: deselected with them by -m "not mpi"
def test_mpirun_is_available():
    assert MPIRUN is not None, "openmpi-bin (mpirun) is part of the stack setup.sh installs"


@pytest.mark.mpi
@pytest.mark.parametrize("name", list(SCENES))
def test_two_ranks_give_the_serial_answer(tmp_path, name):
    scene_dict = SCENES[name]
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene_dict))
    serial = ff.solve_static(ff.Scene.from_file(path)).summary()
    assert serial["converged"]
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr
    par = json.loads((tmp_path / "out" / "results.json").read_text())
    assert par["mpi_ranks"] == 2 and par["dofs"] == serial["dofs"]
    assert par["linear_solver"] == serial["linear_solver"]
    for probe in serial["probes"]:
        np.testing.assert_allclose(par["probes"][probe]["displacement"],
                                   serial["probes"][probe]["displacement"], rtol=1e-8, atol=1e-12)
    assert par["energy"] == pytest.approx(serial["energy"], rel=1e-9)
    assert par["max_displacement"] == pytest.approx(serial["max_displacement"], rel=1e-9)
    assert (tmp_path / "out" / "deformed.png").stat().st_size > 0


@pytest.mark.mpi
def test_bad_input_under_mpi_is_one_line_and_status_2(tmp_path):
    d = beam_scene()
    d["fix"] = [{"where": {"axis": "x", "at": 7.0}}]
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 2
    lines = [ln for ln in p.stderr.splitlines() if "fem-forms: error" in ln]
    assert len(lines) == 1 and lines[0].startswith(
        "fem-forms: error: fix[0].where: matches no boundary facet (mesh spans [0.0, 0.0, 0.0] to [1.0, 0.1, 0.1])"
        " (help: fem-forms help fix.where"), p.stderr                                           # one line, its key
    assert "Traceback" not in p.stderr
