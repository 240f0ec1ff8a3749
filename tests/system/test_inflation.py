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
from scipy.optimize import brentq, minimize_scalar

import fem_forms as ff
from fem_forms.analyses.static.solve import load_path
from fem_forms.model import build_model
from fem_forms.physics.cavities import cavity_report
from fem_forms.solvers import continuation
from fem_forms.solvers.snes import SNESDriver
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
    """control = "load": the pressure is stepped until the steps fail at the maximum, and the run stops there."""
    d = sphere_scene(sphere_mesh, steps=5, pressure=1.0 * MU)
    d["solver"].update(control="load", max_cutbacks=6)       # stops within 1 / 5 / 2^6 of the limit: 0.4 %
    code, res, err, _ = run_scene(tmp_path, d, capsys)
    assert code == 3, err
    assert res["converged"] is False
    assert res["message"].startswith("limit point")
    assert res["load_reached"] == pytest.approx(P_MAX, rel=0.02)
    assert "arc_length_from" not in res


def test_pressure_past_the_maximum_follows_the_falling_branch(sphere_mesh, tmp_path, capsys):
    """The default control (auto) steps the pressure up to the maximum; where a step fails there, arc length
    goes on along the falling branch: every accepted state lies on Ogden's curve, rising then falling, the cavity
    growing all the way (no turning back), until the pressure has dropped by 0.3 of its peak (solver.load_drop)."""
    d = sphere_scene(sphere_mesh, steps=5, pressure=1.0 * MU)
    d["solver"]["load_drop"] = 0.3
    code, res, err, out = run_scene(tmp_path, d, capsys)
    assert code == 3, err
    assert res["converged"] is False and res["message"].startswith("limit point"), res["message"]
    assert res["peak_load_factor"] == pytest.approx(P_MAX, rel=0.01)
    assert 0.9 * P_MAX < res["arc_length_from"] <= res["peak_load_factor"]
    assert 0.65 * res["peak_load_factor"] < res["load_reached"] < 0.7 * res["peak_load_factor"]
    rows = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    cav = res["cavities"]["inside"]
    stretch = (rows["inside_volume"] / (cav["volume"] - cav["volume_change"])) ** (1 / 3)
    assert np.all(np.diff(stretch) > 0)
    pressure = np.array([ogden_pressure(s) for s in stretch])
    np.testing.assert_allclose(rows["load_factor"], pressure, rtol=0.02)
    peak = int(np.argmax(rows["load_factor"]))
    assert stretch[peak] == pytest.approx(1.83, rel=0.05) and len(stretch) - peak > 5     # on, past the limit


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
    # the mixed formulation's energy is a saddle in (u, p): the stability check does not run, and the run says so,
    # in results.json and before it solves
    assert res["stability_checked"] is False and "mixed formulation" in res["stability_unchecked_why"]
    said = err.index("fem-forms: warning: volume control in the mixed formulation")
    assert said < err.index("load step 1")


@pytest.mark.parametrize("linear, checked", [("direct", True), ("iterative", False)])
def test_volume_control_says_whether_it_checked_stability(sphere_mesh, tmp_path, capsys, linear, checked):
    """Only MUMPS's LDL^T counts the tangent's inertia: with an iterative solver the states go unchecked, and
    results.json says so (the displacement formulation; the mixed one is never checked, tested above)."""
    d = sphere_scene(sphere_mesh, steps=1, volume=0.1)      # one small step: the flags are what is checked
    d["discretization"] = {"degree": 1}
    d["solver"]["linear"] = linear
    code, res, err, _ = run_scene(tmp_path, d, capsys)
    assert code == 0, err
    assert res["stability_checked"] is checked
    assert ("LDL^T only" in res.get("stability_unchecked_why", "")) is not checked


@pytest.mark.parametrize("stretch, lost", [(1.5, 0), (2.3, 1)])
def test_volume_control_accepts_the_stable_states_of_both_branches(sphere_mesh, stretch, lost):
    """The solver accepts only stable states under volume control (solvers/constrained_stability.py): the tangent's
    negative eigenvalues beyond the starting state's plus the positive ones of q = c_u.K^-1 c_u must number
    one. On the rising branch K is positive definite and q > 0; past the maximum the pressure falls as the
    volume grows (Ogden: from l_a = 1.83), so K has lost one eigenvalue and q, of the sign of dV/dp, is
    negative: the constraint holds it. The inertia (MUMPS's LDL^T pivots) is checked against the path's own
    slope dp/dV over the last accepted step. Displacement formulation: the check needs the LDL^T of an energy's
    tangent."""
    added = (stretch**3 - 1) * np.pi / 6               # the eighth sphere's inner volume is about pi/6
    d = sphere_scene(sphere_mesh, volume=added)
    d["discretization"]["formulation"], d["material"]["nu"] = "displacement", 0.45
    model = build_model(ff.Scene.from_dict(d))
    set_load, _ = load_path(model)
    problem = model.problem(set_load)
    drv = SNESDriver(problem, {}, "direct", "stable_test_", None, False)
    path = []
    record = lambda lam: path.append([cavity_report(model.terms)["inside"][k] for k in ("volume", "pressure")])  # noqa
    assert continuation.solve(problem, {}, steps=8, driver=drv, on_step=record).converged
    (v0, p0), (v1, p1) = path[-2:]
    check = drv.bordered.stability
    assert check.reference == 0 and check.negative == lost
    assert (p1 - p0) / (v1 - v0) < 0 if lost else (p1 - p0) / (v1 - v0) > 0
    assert (check.q[0, 0] > 0) == (lost == 0)
    assert check.instability() is None


def two_balloons(folder, stretch: float = 2.3) -> dict:
    """Two thick spheres (b = 2a), their inner walls one cavity: air injected to inflate both to `stretch`."""
    mesh = thick_sphere.build_pair(folder / "pair.msh", 1.0, 2.0, h=0.3)
    d = sphere_scene(mesh, steps=8, volume=2 * (stretch**3 - 1) * np.pi / 6)
    d["discretization"]["formulation"], d["material"]["nu"] = "displacement", 0.45
    d["output"]["probes"] = {"a": [1.0, 0.0, 0.0], "b": [-1.0, 0.0, 0.0]}
    return d


@pytest.fixture(scope="module")
def balloons_run(tmp_path_factory):
    """The two-balloon scene and its serial results (one run for the tests below)."""
    folder = tmp_path_factory.mktemp("balloons")
    d = two_balloons(folder)
    code, res, err, _ = run_scene(folder, d)
    assert code == 0, err
    return folder, d, res


def test_two_joined_balloons_share_the_air_as_ogden_says(balloons_run):
    """The two-balloon experiment: past the pressure maximum, both balloons inflated alike is a saddle (the
    tangent lost two eigenvalues, the one volume holds one); the solver rejects it, leaves it along its unstable
    mode (no Newton step leaves it on this mirror-symmetric mesh) and ends where one balloon took the air. Each
    balloon is then Ogden's sphere at the one pressure: p(l_a) = p(l_b) with l_a^3 + l_b^3 = 2 x 2.3^3 gives
    l_a = 2.793, l_b = 1.365, p = 0.6715 mu (incompressible; measured 0.1-0.3 % off at nu = 0.45)."""
    _, d, res = balloons_run
    mu = E / (2 * (1 + d["material"]["nu"]))
    total = 2 * 2.3**3
    big = brentq(lambda s: ogden_pressure(s) - ogden_pressure((total - s**3) ** (1 / 3)), 2.6, 2.89)
    small = (total - big**3) ** (1 / 3)
    assert len(res["unstable_rejected"]) >= 1                 # the evenly inflated pair: a saddle
    assert res["stability_checked"] is True                   # volume control, displacement formulation
    stretches = sorted(1 + abs(res["probes"][k]["displacement"][0]) for k in ("a", "b"))
    assert stretches == pytest.approx([small, big], rel=0.01)
    assert res["cavities"]["inside"]["pressure"] / mu == pytest.approx(ogden_pressure(big), rel=0.01)


@pytest.mark.mpi
def test_two_balloons_on_two_ranks_give_the_serial_answer(balloons_run):
    """The escape from the saddle starts inverse iteration from a vector of the dof coordinates: every partition
    finds the same mode with the same sign, so the same balloon takes the air."""
    folder, d, serial = balloons_run
    path = folder / "two.toml"
    path.write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(folder / "two"), "-q"])
    assert p.returncode == 0, p.stderr
    two = json.loads((folder / "two" / "results.json").read_text())
    assert two["mpi_ranks"] == 2
    assert two["unstable_rejected"] == serial["unstable_rejected"] and two["load_steps"] == serial["load_steps"]
    for k in ("a", "b"):
        assert two["probes"][k]["displacement"] == pytest.approx(serial["probes"][k]["displacement"], rel=1e-6)
    assert two["cavities"]["inside"]["pressure"] == pytest.approx(serial["cavities"]["inside"]["pressure"], rel=1e-6)


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
