"""Inflated closed cavities against the thick neo-Hookean sphere's closed form (Ogden, Non-linear Elastic
Deformations, 1984, section 5.2.6): incompressible, inner radius a, outer b = 2a, inner stretch l_a, outer
l_b^3 = 1 + (l_a^3 - 1)(a/b)^3,  p / mu = (2 / l_b + 1 / (2 l_b^4)) - (2 / l_a + 1 / (2 l_a^4)),
largest at l_a = 1.828: p_max = 0.8164 mu. One eighth of the shell, rollers on the symmetry planes (which
close the cavity through the origin). The stretch l_a is read from the cavity volume the run reports
(l_a^3 = V / V0), so the comparison is free of where a probe sits on the faceted inner surface."""
import importlib.util
import json

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from helpers import ROOT, mpirun, run_scene, toml_dumps

E, NU = 3.0, 0.499
MU = E / (2 * (1 + NU))
_geo = importlib.util.spec_from_file_location("thick_sphere", ROOT / "verification" / "geometry" / "thick_sphere.py")
thick_sphere = importlib.util.module_from_spec(_geo)
_geo.loader.exec_module(thick_sphere)


def ogden_pressure(stretch: float, ratio: float = 2.0) -> float:
    """p / mu of the incompressible neo-Hookean sphere at inner hoop stretch `stretch`."""
    outer = (1 + (stretch**3 - 1) / ratio**3) ** (1 / 3)
    f = lambda s: 2 / s + 1 / (2 * s**4)      # noqa: E731
    return f(outer) - f(stretch)


P_MAX = -minimize_scalar(lambda s: -ogden_pressure(s), bounds=(1, 4), method="bounded").fun   # 0.8164


@pytest.fixture(scope="module")
def sphere_mesh(tmp_path_factory):
    return thick_sphere.build(tmp_path_factory.mktemp("sphere") / "thick_sphere.msh", 1.0, 2.0, h=0.3)


def sphere_scene(mesh, steps=4, **cavity) -> dict:
    return {"title": "inflated sphere", "analysis": "static", "mesh": {"generator": "file", "file": str(mesh)},
            "material": {"model": "neo-hookean", "E": E, "nu": NU},
            "discretization": {"degree": 2, "formulation": "mixed"},
            "fix": [{"where": {"group": g}, "components": [g[0]]} for g in ("x0", "y0", "z0")],
            "load": [{"type": "inflation", "name": "inside", "where": {"group": "inner"}, **cavity}],
            "solver": {"steps": steps},
            "output": {"picture": False, "fields": False, "probes": {"inner": [1.0, 0.0, 0.0]}}}


def inner_stretch(cavity: dict) -> float:
    rest = cavity["volume"] - cavity["volume_change"]
    return (cavity["volume"] / rest) ** (1 / 3)


def test_pressure_control_follows_ogden_below_the_limit(sphere_mesh, tmp_path, capsys):
    code, res, err, _ = run_scene(tmp_path, sphere_scene(sphere_mesh, pressure=0.6 * MU), capsys)
    assert code == 0, err
    cav = res["cavities"]["inside"]
    assert cav["pressure"] == pytest.approx(0.6 * MU, rel=1e-12)
    assert ogden_pressure(inner_stretch(cav)) == pytest.approx(0.6, rel=0.01)
    assert res["physics"] == ["elastic (neo-hookean)", "inflation"]
    # the reactions on the three symmetry planes carry the pressure's resultant
    assert res["equilibrium_error"] < 1e-6


def test_pressure_past_the_maximum_stops_at_the_limit_point(sphere_mesh, tmp_path, capsys):
    code, res, err, _ = run_scene(tmp_path, sphere_scene(sphere_mesh, steps=5, pressure=1.0 * MU), capsys)
    assert code == 3, err
    assert res["converged"] is False
    assert res["message"].startswith("limit point")
    assert res["load_reached"] == pytest.approx(P_MAX, rel=0.02)


def test_volume_control_reaches_the_falling_branch(sphere_mesh, tmp_path, capsys):
    stretch = 2.3                                   # past the pressure maximum at 1.83
    code, res, err, _ = run_scene(tmp_path, sphere_scene(sphere_mesh, pressure=0.0), capsys)   # nothing to solve
    assert code == 0 and res["cavities"]["inside"]["volume_change"] == 0.0
    v0 = res["cavities"]["inside"]["volume"]
    added = (stretch**3 - 1) * v0
    code, res, err, _ = run_scene(tmp_path, sphere_scene(sphere_mesh, steps=8, volume=added), capsys)
    assert code == 0, err
    cav = res["cavities"]["inside"]
    assert cav["volume_change"] == pytest.approx(added, rel=1e-8)
    assert inner_stretch(cav) == pytest.approx(stretch, rel=1e-8)
    assert cav["pressure"] / MU == pytest.approx(ogden_pressure(stretch), rel=0.02)
    assert cav["pressure"] / MU < P_MAX - 0.02                # on the falling branch


def test_walls_that_enclose_nothing_are_refused(sphere_mesh, tmp_path, capsys):
    d = sphere_scene(sphere_mesh, pressure=0.1)
    d["load"][0]["where"] = {"group": "outer"}      # closed by the symmetry planes, but facing outward
    code, res, err, _ = run_scene(tmp_path, d, capsys)
    assert code == 2 and res is None
    assert "load[0].where (cavity 'inside')" in err and "outer side" in err and "type = \"pressure\"" in err
    box = {"title": "open", "analysis": "static", "mesh": {"size": [1.0, 0.2, 0.2], "cells": [4, 1, 1]},
           "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3},
           "fix": [{"where": {"axis": "x", "at": 0.0}}],
           "load": [{"type": "inflation", "where": {"axis": "x", "at": 1.0}, "pressure": 1e3}]}
    code, res, err, _ = run_scene(tmp_path, box, capsys)
    assert code == 2 and res is None
    assert "cavity 'cavity0'" in err and "edges are open" in err and err.count("\n") == 1


def test_inflation_keys_are_checked(tmp_path, capsys):
    box = {"title": "keys", "analysis": "static", "mesh": {"size": [1.0, 0.2, 0.2], "cells": [4, 1, 1]},
           "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3},
           "fix": [{"where": {"axis": "x", "at": 0.0}}],
           "load": [{"type": "inflation", "where": {"axis": "x", "at": 1.0}, "pressure": 1e3, "volume": 1e-3}]}
    code, _, err, _ = run_scene(tmp_path, box, capsys)
    assert code == 2 and "load[0].pressure" in err and "not both" in err
    box["analysis"] = "dynamic"
    del box["load"][0]["pressure"]
    code, _, err, _ = run_scene(tmp_path, box, capsys)
    assert code == 2 and "load[0].volume: volume control is for analysis = 'static'" in err


@pytest.mark.mpi
def test_volume_control_on_two_ranks_gives_the_serial_answer(sphere_mesh, tmp_path, capsys):
    d = sphere_scene(sphere_mesh, steps=2, volume=0.5)
    code, serial, err, _ = run_scene(tmp_path, d, capsys)
    assert code == 0, err
    path = tmp_path / "two.toml"
    path.write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "two"), "-q"])
    assert p.returncode == 0, p.stderr
    two = json.loads((tmp_path / "two" / "results.json").read_text())
    for key in ("pressure", "volume", "volume_change"):
        assert two["cavities"]["inside"][key] == pytest.approx(serial["cavities"]["inside"][key], rel=1e-8)
    assert np.allclose(two["probes"]["inner"]["displacement"], serial["probes"]["inner"]["displacement"],
                       rtol=1e-8, atol=1e-12)


def test_arc_length_passes_the_stvk_compression_limit(tmp_path, capsys):
    """A St. Venant-Kirchhoff block (nu = 0) crushed by a dead traction of 2E carries at most |P| = E / (3 sqrt 3)
    (P = E (l^3 - l) / 2 is extremal at stretch l = 1/sqrt 3): arc length climbs to that load factor, 1 / (6 sqrt 3),
    passes it with the load falling and the block compressed past l = 1/sqrt 3, and stops: a limit point."""
    E = 1.0e6
    d = {"title": "StVK limit", "analysis": "static", "mesh": {"size": [1.0, 1.0, 1.0], "cells": [2, 2, 2]},
         "material": {"model": "stvk", "E": E, "nu": 0.0}, "discretization": {"degree": 1},
         "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
         "load": [{"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [-2 * E, 0.0, 0.0]}],
         "solver": {"steps": 20, "max_cutbacks": 8, "control": "arc-length"},
         "output": {"picture": False, "fields": False, "probes": {"corner": [1.0, 1.0, 1.0]}}}
    code, res, err, out = run_scene(tmp_path, d, capsys)
    assert code == 3 and res["converged"] is False, err
    assert res["message"].startswith("limit point")
    assert res["peak_load_factor"] == pytest.approx(1 / (6 * np.sqrt(3)), rel=0.005)
    accepted = [ln.split(",") for ln in (out / "newton_history.csv").read_text().splitlines()[1:]]
    loads = [float(row[1]) for row in accepted if row[2] == "1"]
    peak_at = int(np.argmax(loads))
    assert peak_at < len(loads) - 1 and min(loads[peak_at:]) < 0.5 * max(loads)      # on, past the limit
    assert res["load_reached"] < 0.5 * res["peak_load_factor"]
