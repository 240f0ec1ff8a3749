"""Phase-field fracture ([fracture]) on a bar in uniaxial strain (nu = 0, rollers; E = Gc = 1, l = 0.1), against
the closed forms of the homogeneous solution (Pham, Amor, Marigo & Maurini 2011; Tanne et al. 2018):
- AT1: elastic (d = 0 exactly) until sigma_c = sqrt(3 Gc E / (8 l)), then d = 1 - 3 Gc / (8 l E eps^2);
- AT2: d = E eps^2 / (E eps^2 + Gc / l) from the first load, the peak stress (3/16) sqrt(3 Gc E / l);
- stress sigma = ((1 - k)(1 - d)^2 + k) E eps at every step; unloading keeps the damage (irreversibility) and
  follows the damaged secant;
- around a notch (d = 1 on a plane of nodes) the damage takes the optimal profile (1 - |x| / 2l)^2 (AT1),
  exp(-|x| / l) (AT2), and a bar cut through has the crack area A (1 + 3 h / (8 l)) (AT1: Bourdin's
  correction for the mesh size h);
- the volumetric-deviatoric split leaves a cube under hydrostatic compression intact (split none cracks it); the
  spectral split cracks a bar at the energy of its tensile principal strains (tension and compression);
- 2 ranks give the serial force-displacement curve; bad input refused in one line."""
import json
import math

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from helpers import report_data, run_scene, serial_and_two_ranks
from system.demo_runs import DEMOS, demo  # noqa: F401,F811 (demo: fixture)

E, GC, ELL, K, A = 1.0, 1.0, 0.1, 1.0e-6, 0.01
SIGMA_AT1 = math.sqrt(3 * GC * E / (8 * ELL))
SIGMA_AT2 = 3 / 16 * math.sqrt(3 * GC * E / ELL)


def bar(model="AT1", u_end=3.0, steps=30, cells=40, notch=False, history=None, **fracture) -> dict:
    """A 1 x 0.1 x 0.1 bar on rollers at x = 0 (and y = 0, z = 0), pulled at x = 1 by u_end."""
    pull = {"name": "pull", "where": {"axis": "x", "at": 1.0}, "components": ["x"], "value": [u_end, 0.0, 0.0]}
    if history is not None:
        pull["history"] = history
    d = {"title": "bar", "mesh": {"size": [1.0, 0.1, 0.1], "cells": [cells, 1, 1]},
         "material": {"model": "linear", "E": E, "nu": 0.0},
         "discretization": {"degree": 1},
         "fix": [{"name": "left", "where": {"axis": "x", "at": 0.0}, "components": ["x"]},
                 {"where": {"axis": "y", "at": 0.0}, "components": ["y"]},
                 {"where": {"axis": "z", "at": 0.0}, "components": ["z"]}, pull],
         "fracture": {"toughness": GC, "length": ELL, "model": model, **fracture},
         "solver": {"steps": steps, "max_step": 1.0 / steps},
         "output": {"picture": False, "fields": False}}
    if notch:
        d["fracture"]["notch"] = [{"where": {"box": [[0.5, 0.0, 0.0], [0.5, 0.1, 0.1]]}}]
    return d


def curve(out) -> np.ndarray:
    return np.genfromtxt(out / "force_displacement.csv", delimiter=",", names=True)


def homogeneous_damage(model: str, eps: np.ndarray) -> np.ndarray:
    """d minimizing (g(d) E eps^2 / 2 + Gc / c_w w(d) / l) with g(d) = (1 - K)(1 - d)^2 + K."""
    psi2 = (1 - K) * E * eps ** 2                             # 2 psi, of the degradable part
    if model == "AT1":
        return np.where(psi2 > 3 * GC / (8 * ELL), 1 - 3 * GC / (8 * ELL) / np.maximum(psi2, 1e-300), 0.0)
    return psi2 / (psi2 + GC / ELL)


def degraded(d):
    return (1 - K) * (1 - d) ** 2 + K


# the homogeneous solution is an equilibrium at every load, a saddle past the peak in a bar this long (10 l):
# stable_path = false keeps it, to check it against its closed form (the stable path: test_fracture_stability.py)
# with split = "spectral" too: in uniaxial strain (nu = 0) the strain's only principal value is the tensile one, so the
# split degrades all of the energy and the closed forms are those of split = "none" (issue 47 item 5's sweep: AT1 and AT2
# x none and spectral x static and dynamic, as an L4 with the struck bar below)
@pytest.mark.parametrize("model, peak, split", [("AT1", SIGMA_AT1, "none"), ("AT2", SIGMA_AT2, "none"),
                                                ("AT2", SIGMA_AT2, "spectral")])
def test_the_homogeneous_bar_follows_the_closed_form_and_peaks_at_the_critical_stress(tmp_path, model, peak, split):
    code, s, err, out = run_scene(tmp_path, bar(model, steps=60, split=split, stable_path=False))
    assert code == 0, err
    rows = curve(out)
    eps = rows["pull_ux"]
    d = homogeneous_damage(model, eps)
    assert rows["damage_max"] == pytest.approx(d, abs=1e-6)
    assert rows["pull_Fx"] / A == pytest.approx(degraded(d) * E * eps, rel=1e-5, abs=1e-9)
    k = int(np.argmax(rows["pull_Fx"]))
    assert s["peak_load_factor"] == pytest.approx(rows["load_factor"][k])
    assert s["peak_force"]["pull"] / A == pytest.approx(peak, rel=0.01 if model == "AT2" else 0.03)
    if model == "AT1":                                        # no damage at all below the elastic limit
        below = E * eps < SIGMA_AT1 * (1 - 1e-6)
        assert below.sum() >= 30 and np.all(rows["damage_max"][below] == 0.0)
        assert rows["pull_Fx"][k] / A <= SIGMA_AT1 <= E * eps[k + 1]


def test_unloading_keeps_the_damage_and_follows_the_damaged_secant(tmp_path):
    """AT2, pulled to eps 1.5, back to 0.5, then to 2: the damage of the first peak stays while unloading and
    reloading below it (the force on the secant E (1 - d1)^2), then grows again."""
    history = [[0.0, 0.0], [1.0, 0.75], [2.0, 0.25], [3.0, 1.0]]
    code, s, err, out = run_scene(tmp_path, bar("AT2", u_end=2.0, steps=60, history=history, stable_path=False))
    assert code == 0, err
    rows = curve(out)
    t, eps = rows["time"], rows["pull_ux"]
    assert np.all(np.diff(rows["damage_max"]) >= 0.0)        # irreversible
    d1 = homogeneous_damage("AT2", np.array([1.5]))[0]
    back = (t > 1.0) & (t < 2.6)                              # unloading and reloading below eps 1.5
    assert back.sum() >= 10
    assert rows["damage_max"][back] == pytest.approx(d1, abs=1e-6)
    assert rows["pull_Fx"][back] / A == pytest.approx(degraded(d1) * E * eps[back], rel=1e-5)
    assert rows["damage_max"][-1] == pytest.approx(homogeneous_damage("AT2", np.array([2.0]))[0], abs=1e-6)


@pytest.mark.parametrize("model, profile", [("AT1", lambda r: np.clip(1 - r / (2 * ELL), 0, None) ** 2),
                                            ("AT2", lambda r: np.exp(-r / ELL))])
def test_a_notch_takes_the_optimal_damage_profile(model, profile):
    """At a small load the damage around a notch is the 1D optimal profile (h = l/10: within 0.03)."""
    scene = ff.Scene.from_dict(bar(model, u_end=1e-3, steps=1, cells=200, notch=True))
    result = ff.solve_static(scene)
    assert result.report.converged
    d = result.histories[0].term.d
    x = d.function_space.tabulate_dof_coordinates()[:, 0]
    r = np.abs(x - 0.5)
    assert np.abs(d.x.array - profile(r)).max() < 0.03
    assert d.x.array[r < 1e-9] == pytest.approx(1.0)


def test_a_bar_cut_through_has_the_crack_area_of_its_section(tmp_path):
    code, s, err, out = run_scene(tmp_path, bar("AT1", notch=True))
    assert code == 0, err
    h = 1.0 / 40
    assert s["damage_max"] == pytest.approx(1.0)
    assert s["crack_area"] == pytest.approx(A * (1 + 3 * h / (8 * ELL)), rel=0.01)
    rows = curve(out)
    assert rows["pull_Fx"][-1] < 0.1 * rows["pull_Fx"].max()        # cut: the force has fallen
    assert s["files"]["force_displacement"] == "force_displacement.csv"


def test_over_relaxed_sweeps_cut_the_bar_to_the_same_crack_in_fewer_sweeps():
    """[fracture] over_relaxation = 1.3 (Farrell & Maurini 2017): the bar cut through has Bourdin's crack area and
    the plain alternate minimization's to the staggered tolerance, in fewer sweeps; the damage never falls below
    its committed value (the over-relaxed step is projected onto the bounds)."""
    results = {}
    for omega in (1.0, 1.3):
        scene = ff.Scene.from_dict(bar("AT1", notch=True, over_relaxation=omega))
        result = ff.solve_static(scene)
        assert result.report.converged
        results[omega] = result.summary()
    h = 1.0 / 40
    plain, relaxed = results[1.0], results[1.3]
    assert relaxed["crack_area"] == pytest.approx(A * (1 + 3 * h / (8 * ELL)), rel=0.01)
    assert relaxed["crack_area"] == pytest.approx(plain["crack_area"], rel=1e-4)
    assert relaxed["staggered_sweeps"] < plain["staggered_sweeps"]
    assert relaxed["damage_max"] == pytest.approx(1.0)


@pytest.mark.parametrize("split, cracks", [("volumetric-deviatoric", False), ("none", True)])
def test_hydrostatic_compression_cracks_nothing_with_the_volumetric_split(split, cracks):
    fix = [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"]
    fix += [{"where": {"axis": a, "at": 1.0}, "components": [a], "value": [-0.3 if b == a else 0.0 for b in "xyz"]}
            for a in "xyz"]
    d = {"mesh": {"size": [1.0, 1.0, 1.0], "cells": [2, 2, 2]}, "material": {"model": "linear", "E": E, "nu": 0.2},
         "discretization": {"degree": 1}, "fix": fix, "solver": {"steps": 3},
         "fracture": {"toughness": 0.1 * GC, "length": ELL, "model": "AT2", "split": split},
         "output": {"picture": False, "fields": False}}
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert s["converged"]
    assert (s["damage_max"] > 0.1) == cracks
    if not cracks:
        assert s["damage_max"] < 1e-12


@pytest.mark.parametrize("pull", [2.5, -6.0])
def test_the_spectral_split_damages_at_the_tensile_principal_strains_energy(tmp_path, pull):
    """A bar in uniaxial stress (nu = 0.3, sides free), AT1 with the spectral split: intact and linear
    (F/A = E eps) until 2 psi+ = 3 Gc / (8 l) with psi+ = lambda/2 <tr eps>+^2 + mu sum <eps_i>+^2 of the
    strains (eps, -nu eps, -nu eps): in tension (lambda (1 - 2 nu)^2 + 2 mu) eps^2 (the volumetric-deviatoric
    split would crack at E eps^2: earlier); in compression only the lateral extension's 4 mu nu^2 eps^2."""
    nu = 0.3
    lmbda, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    d = bar("AT1", u_end=pull, steps=50, split="spectral")
    d["material"]["nu"] = nu
    code, s, err, out = run_scene(tmp_path, d)
    assert code == 0, err
    rows = curve(out)
    eps = rows["pull_ux"]
    stiffness = lmbda * (1 - 2 * nu) ** 2 + 2 * mu if pull > 0 else 4 * mu * nu ** 2
    eps_c = math.sqrt(3 * GC / (8 * ELL) / ((1 - K) * stiffness))
    below, above = np.abs(eps) < eps_c * (1 - 1e-6), np.abs(eps) > eps_c * 1.03
    assert below.sum() >= 30 and above.sum() >= 2
    assert np.all(rows["damage_max"][below] == 0.0)
    assert rows["pull_Fx"][below] / A == pytest.approx(E * eps[below], rel=1e-6)
    assert np.all(rows["damage_max"][above] > 1e-3)


@pytest.mark.mpi
def test_two_ranks_give_the_serial_curve(tmp_path):
    serial_and_two_ranks(tmp_path, bar("AT1", notch=True, steps=10))
    curves = [curve(tmp_path / folder) for folder in ("out", "two")]
    assert curves[1]["pull_Fx"] == pytest.approx(curves[0]["pull_Fx"], rel=1e-6)
    assert curves[1]["crack_area"] == pytest.approx(curves[0]["crack_area"], rel=1e-6)


@pytest.mark.parametrize("change, message", [
    (("material", "model", "neo-hookean"), None),
    (("fracture", "toughness", -1.0), "fracture.toughness"),
    (("fracture", "over_relaxation", 2.0), "fracture.over_relaxation"),
    (("fracture", "notch", [{"where": {"box": [[0.51, 0.0, 0.0], [0.52, 0.1, 0.1]]}}]), "holds no mesh node"),
    (("solver", "control", "arc-length"), "not with solver.control = 'arc-length'"),
    (("analysis", None, "modal"), "fracture: only for analysis = 'static'"),
])
def test_bad_fracture_input_is_refused_in_one_line(change, message):
    d = bar()
    if message is None:                           # the spectral split is isotropic linear elasticity's
        d["fracture"]["split"], message = "spectral", "'spectral': for model = 'linear' only"
    section, key, value = change
    if key is None:
        d[section] = value
    else:
        d[section][key] = value
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        ff.solve_static(ff.Scene.from_dict(d))


@pytest.mark.parametrize("model, split, traction", [("AT2", "none", 0.5), ("AT1", "spectral", 1.2)])
def test_a_struck_bar_damages_with_the_energy_account_closed_by_the_crack(tmp_path, model, split, traction):
    """Dynamics (Newmark): a step traction swings the bar (AT2: half its peak stress; AT1 with the spectral split:
    0.62 of its elastic limit, which the swing's overshoot passes); the damage grows with the first stretch and then
    holds (irreversible), and kinetic + elastic + crack energy equals the load's work (the crack's surface energy,
    10 % of it for AT2, is what the account needs to close)."""
    from fem_forms.analyses.dynamic import solve_dynamic
    d = bar(model, split=split)
    d["analysis"] = "dynamic"
    del d["solver"]
    d["fix"] = d["fix"][:3]
    d["material"]["rho"] = 1.0
    d["load"] = [{"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [traction, 0.0, 0.0]}]
    d["dynamic"] = {"duration": 2.0, "dt": 0.02}
    result = solve_dynamic(ff.Scene.from_dict(d))
    s = result.summary()
    assert s["converged"]
    final = s["energy_final"]
    assert final["fracture"] > 0.05 * final["external_work"]
    assert s["energy_balance_error"] < 2e-3
    crack = [e.fracture for _, e in result.energy.history]
    assert np.all(np.diff(crack) >= -1e-12 * max(crack))            # the crack never heals


def test_a_mesh_too_coarse_for_the_length_is_warned_about():
    d = bar(cells=4, steps=1, u_end=0.1, length=0.05)          # shortest edges 0.1 > l = 0.05
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert any("not resolved" in w for w in s["warnings"])
    s = ff.solve_static(ff.Scene.from_dict(bar(steps=1, u_end=0.1))).summary()     # h = 0.025
    assert not any("not resolved" in w for w in s["warnings"])


def test_printed_hook_demo(demo):
    """The PLA hook pulled until it cracks (demos/printed_hook.py), against an elastic solve of its mesh (the same
    scene without [fracture]): AT1 leaves the first step purely elastic (the same force); the crack starts where
    the elastic stress is largest (the inner side where shank and bend meet: within 4 mm), not before that
    stress reaches the strength sqrt(3 Gc E / (8 l)) (the stress gradient over l delays it: at most 2x); it cuts
    through the shank (its area at least the section) and the force falls to nothing."""
    import tomllib
    text, out = demo("printed_hook")
    res = json.loads((out / "results.json").read_text())
    rows = curve(out)
    d = tomllib.loads((DEMOS / "scenes" / "printed_hook.toml").read_text())
    fr, mat = d["fracture"], d["material"]
    del d["fracture"]
    d["mesh"]["file"] = str(out / "printed_hook.msh")
    d["solver"] = {"steps": 1}
    d["fix"][1]["value"] = [0.0, float(rows["load_uy"][0]), 0.0]
    d["output"] = {"fields": False, "picture": False}
    elastic = ff.solve_static(ff.Scene.from_dict(d)).summary()
    force = -rows["load_Fy"]
    assert force[0] == pytest.approx(-elastic["reactions"]["load"][1], rel=1e-5)
    stress_per_newton = mat["strength"]["tensile"] / elastic["strength"]["safety_factor"] / force[0]
    sigma_c = math.sqrt(3 * fr["toughness"] * mat["E"] / (8 * fr["length"]))
    assert 1.0 <= stress_per_newton * force.max() / sigma_c <= 2.0
    assert np.linalg.norm(np.subtract(res["crack_center"], elastic["strength"]["where"])[:2]) < 4e-3
    assert res["crack_area"] >= 6e-3 * 5e-3 and force[-1] < 0.01 * force.max()
    assert res["peak_force"]["load"] == pytest.approx(force.max()) and (out / "crack.png").stat().st_size > 0
    assert "peak force" in text


def test_torn_silicone_strip_demo(demo):
    """The notched neo-Hookean strip of demos/torn_silicone_strip.py against Rivlin & Thomas's pure-shear tear
    criterion W(lambda) h0 = Gc (1 + 3 h / (8 l)), W the plane-stress pure-shear energy of the compressible
    neo-Hookean computed here: the crack runs between the step before it and the one after (2 % slack); it runs
    along the notch's line through the whole strip (its area the strip's section with the mesh correction,
    within 3 %) and the force falls to nothing. On the stable path (the default) with no saddle left behind: the
    residual stiffness's own modes on the crack's line (the notch's mouth, the last ligament) are no instability
    of the strip (they made it warn and report stable_path false before stable_path.CRACK_LINE)."""
    from scipy.optimize import brentq, minimize_scalar
    import tomllib
    text, out = demo("torn_silicone_strip")
    res = json.loads((out / "results.json").read_text())
    d = tomllib.loads((DEMOS / "scenes" / "torn_silicone_strip.toml").read_text())
    m, fr = d["material"], d["fracture"]
    width, h0, thick = d["mesh"]["size"]
    h = width / d["mesh"]["cells"][0]
    mu, lmbda = m["E"] / (2 * (1 + m["nu"])), m["E"] * m["nu"] / ((1 + m["nu"]) * (1 - 2 * m["nu"]))

    def pure_shear(lam):
        f = lambda t: (mu / 2 * (lam**2 + t**2 - 2) - mu * math.log(lam * t)       # noqa: E731
                       + lmbda / 2 * math.log(lam * t) ** 2)
        return minimize_scalar(f, bounds=(0.2, 1.5), method="bounded").fun
    gc = fr["toughness"] * (1 + 3 * h / (8 * fr["length"]))
    critical = brentq(lambda lam: pure_shear(lam) * h0 - gc, 1.0 + 1e-9, 3.0)
    rows = curve(out)
    force, stretch = rows["top_Fy"], 1 + rows["top_uy"] / h0
    k = int(np.argmax(force))
    assert stretch[k] <= critical * 1.02 and stretch[k + 1] >= critical * 0.98
    assert force[-1] < 0.01 * force[k] and res["damage_max"] == pytest.approx(1.0)
    assert res["crack_area"] == pytest.approx(width * thick * (1 + 3 * h / (8 * fr["length"])), rel=0.03)
    assert abs(res["crack_center"][1] - h0 / 2) <= h
    assert res["stable_path"] is True and not res["warnings"]
    assert "Rivlin-Thomas" in text and (out / "crack.png").stat().st_size > 0
    # report.html colours the torn strip by its damage: broken (1) along the crack, intact beyond AT1's band
    # (damage only within 2 l of the crack; one cell's interpolation more: measured 0.007 there)
    rest, _, fields = report_data(out / "report.html")
    damage = next(values[-1] for name, (_, values) in fields.items() if name.startswith("damage"))
    assert damage.max() == pytest.approx(1.0, abs=1e-6)
    assert damage[np.abs(rest[:, 1] - res["crack_center"][1]) > 2 * fr["length"] + h].max() < 0.02


def test_a_notch_on_a_surface_group_damages_that_surface(tmp_path):
    """A notch given as a gmsh surface group puts d = 1 on exactly that surface's nodes (the end face x = 1)."""
    import gmsh
    path = tmp_path / "bar.msh"
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.occ.addBox(0, 0, 0, 1.0, 0.1, 0.1)
    gmsh.model.occ.synchronize()
    e = 1e-6
    end = [t for _, t in gmsh.model.getEntitiesInBoundingBox(1 - e, -e, -e, 1 + e, 0.1 + e, 0.1 + e, 2)]
    gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, end), "end")
    gmsh.model.addPhysicalGroup(3, [1], 1)
    gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.05)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(path))
    gmsh.finalize()
    d = bar(steps=1, u_end=1e-3)
    d["mesh"] = {"generator": "file", "file": str(path)}
    d["fix"][3]["where"] = {"axis": "x", "at": 0.5}
    d["fix"] = d["fix"][:3]
    d["fracture"]["notch"] = [{"where": {"group": "end"}}]
    from fem_forms.model import build_model
    model = build_model(ff.Scene.from_dict(d))
    term = next(iter(model.terms.with_role("fracture")))
    x = term.d.function_space.tabulate_dof_coordinates()[:, 0]
    assert np.all(term.d.x.array[np.isclose(x, 1.0)] == 1.0)
    assert np.all(term.d.x.array[~np.isclose(x, 1.0)] == 0.0) and np.isclose(x, 1.0).any()
