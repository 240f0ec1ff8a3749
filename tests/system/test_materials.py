"""Parts of several materials ([[material]] with `where`), against independent references:
- a two-layer cantilever (soft layer on a stiff one) deflects under a tip load as its transformed section
  says, delta = P L^3 / (3 EI) with EI about the stiffness-weighted neutral axis, whether both layers share
  a model (one psi with DG0 parameters) or not (each model over its own cells);
- its first bending frequency is Euler-Bernoulli's with that EI and the mass per length of both layers;
- a uniformly heated bimetal strip curls with Timoshenko's (1925) curvature;
- volumes and masses per material are the boxes', probes name the material they lie in, 2 ranks agree."""
import json
import math

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from fem_forms.analyses.modal import solve_modal
from helpers import mpirun, run_scene, toml_dumps, with_
from system.demo_runs import NUMBER, demo, grab, scene_dict  # noqa: F401 (demo: fixture)

L, B, H = 0.4, 0.04, 0.02           # length, width, height; the stiff layer is the lower half
E_SOFT, E_STIFF, RHO_SOFT, RHO_STIFF = 1.0e7, 1.0e8, 1000.0, 3000.0
P = 0.02                            # N, tip load (-z)


def layered(soft="linear", stiff="linear", cells=(16, 1, 4), analysis="static", **over) -> dict:
    d = {"title": "two layers", "analysis": analysis,
         "mesh": {"size": [L, B, H], "cells": list(cells), "cell": "hexahedron"},
         "material": [
             {"name": "soft", "model": soft, "E": E_SOFT, "nu": 0.0, "rho": RHO_SOFT},
             {"name": "stiff", "model": stiff, "E": E_STIFF, "nu": 0.0, "rho": RHO_STIFF,
              "where": {"box": [[0.0, 0.0, 0.0], [L, B, H / 2]]}}],
         "discretization": {"degree": 2},
         "fix": [{"name": "clamp", "where": {"axis": "x", "at": 0.0}}],
         "load": [{"type": "traction", "where": {"axis": "x", "at": L}, "value": [0.0, 0.0, -P / (B * H)]}],
         "output": {"picture": False, "fields": False,
                    "probes": {"tip": [L, B / 2, H / 2], "top": [L / 2, B / 2, 0.9 * H],
                               "bottom": [L / 2, B / 2, 0.1 * H]}}}
    d.update(over)
    return d


def transformed_section() -> tuple[float, float]:
    """EI about the neutral axis and the mass per length of the two layers."""
    layers = [(E_STIFF, RHO_STIFF, H / 4), (E_SOFT, RHO_SOFT, 3 * H / 4)]     # (E, rho, centre height)
    area = B * H / 2
    zn = sum(E * z for E, _, z in layers) / sum(E for E, _, _ in layers)
    EI = sum(E * (B * (H / 2) ** 3 / 12 + area * (z - zn) ** 2) for E, _, z in layers)
    return EI, sum(rho * area for _, rho, _ in layers)


@pytest.mark.parametrize("soft, stiff", [("linear", "linear"), ("neo-hookean", "stvk")])
def test_a_two_layer_cantilever_bends_as_its_transformed_section(soft, stiff):
    s = ff.solve_static(ff.Scene.from_dict(layered(soft, stiff))).summary()
    assert s["converged"]
    EI, _ = transformed_section()
    delta = P * L ** 3 / (3 * EI)
    assert delta / L < 2e-3                                   # small deflection: beam theory holds
    assert -s["probes"]["tip"]["displacement"][2] == pytest.approx(delta, rel=0.01)
    assert s["reactions"]["clamp"][2] == pytest.approx(P, rel=1e-6)
    assert [p["material"] for p in (s["probes"]["top"], s["probes"]["bottom"])] == ["soft", "stiff"]


def test_the_materials_are_reported_with_their_cells_volumes_and_masses():
    s = ff.solve_static(ff.Scene.from_dict(layered())).summary()
    half = L * B * H / 2
    got = {m["name"]: m for m in s["materials"]}
    assert got["soft"]["cells"] == got["stiff"]["cells"] == 32
    for name, rho in (("soft", RHO_SOFT), ("stiff", RHO_STIFF)):
        assert got[name]["volume"] == pytest.approx(half, rel=1e-10)
        assert got[name]["mass"] == pytest.approx(rho * half, rel=1e-10)


def test_the_material_field_marks_each_cell_for_paraview(tmp_path):
    """output.fields = ["material"]: a cell-centred field in fields.xdmf (the material index of each cell; its
    values: the regions' DG0 field, checked by the masses above). No reader of the .h5 in the venv: the XDMF's
    declaration is checked."""
    import xml.etree.ElementTree as ET
    d = layered()
    d["output"]["fields"] = ["displacement", "material"]
    code, s, err, out = run_scene(tmp_path, d)
    assert code == 0, err
    attrs = {a.get("Name"): a.get("Center") for a in ET.parse(out / "fields.xdmf").getroot().iter("Attribute")}
    assert attrs.get("material") == "Cell" and attrs.get("displacement") == "Node"


def test_the_first_bending_frequency_is_euler_bernoullis_of_the_layered_section():
    d = layered(analysis="modal", cells=(24, 2, 4), load=[], modal={"count": 3})
    d["output"]["probes"] = {}
    r = solve_modal(ff.Scene.from_dict(d))
    EI, mass = transformed_section()
    f1 = 1.875104 ** 2 / (2 * math.pi * L ** 2) * math.sqrt(EI / mass)
    assert r.frequencies_hz[0] == pytest.approx(f1, rel=0.01)


@pytest.mark.mpi
def test_two_ranks_give_the_serial_answer(tmp_path):
    d = layered(soft="neo-hookean", stiff="neo-hookean")
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_dumps(d))
    serial = ff.solve_static(ff.Scene.from_dict(d)).summary()
    run = mpirun(["-m", "fem_forms", "run", str(scene), "--out", str(tmp_path / "out")])
    assert run.returncode == 0, run.stderr[-2000:]
    par = json.loads(next((tmp_path / "out").rglob("results.json")).read_text())
    assert np.allclose(par["probes"]["tip"]["displacement"], serial["probes"]["tip"]["displacement"], rtol=1e-8)
    assert [m["mass"] for m in par["materials"]] == pytest.approx([m["mass"] for m in serial["materials"]])


def test_the_mixed_formulation_with_two_materials_bends_as_the_transformed_section():
    """Taylor-Hood P2-P1 (its lambda a DG0 field), nu 0.3, P2 tetrahedra: the transformed section within 1 %
    (measured +0.26 %; the P2 displacement formulation on these coarse tetrahedra: -1.6 %)."""
    d = layered("neo-hookean", "neo-hookean", discretization={"degree": 2, "formulation": "mixed"})
    d["mesh"]["cell"] = "tetrahedron"
    for m in d["material"]:
        m["nu"] = 0.3
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert s["converged"]
    EI, _ = transformed_section()
    assert -s["probes"]["tip"]["displacement"][2] == pytest.approx(P * L ** 3 / (3 * EI), rel=0.01)


# --- a bimetal strip: two layers expanding differently, heated uniformly ---------------------
ALPHA_LOW, ALPHA_HIGH, DT = 1.0e-5, 2.0e-5, 50.0


def timoshenko_curvature(h1, h2, E1, E2, a1, a2, dT) -> float:
    """Timoshenko (1925): curvature of a free bimetal strip, layer 1 below layer 2."""
    m, n, h = h1 / h2, E1 / E2, h1 + h2
    return 6 * (a2 - a1) * dT * (1 + m) ** 2 / (h * (3 * (1 + m) ** 2 + (1 + m * n) * (m ** 2 + 1 / (m * n))))


def test_a_heated_bimetal_strip_curls_with_timoshenkos_curvature():
    d = layered(load=[])
    d["material"][0]["expansion"] = ALPHA_HIGH                 # the soft upper layer expands more
    d["material"][1]["expansion"] = ALPHA_LOW
    d["thermal"] = {"conductivity": 1.0, "boundary": [{"where": {"axis": "x", "at": 0.0}, "temperature": DT}]}
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert s["converged"]
    kappa = timoshenko_curvature(H / 2, H / 2, E_STIFF, E_SOFT, ALPHA_LOW, ALPHA_HIGH, DT)
    # a clamped strip of curvature kappa: tip deflection -kappa L^2 / 2 (curling down: the top grows)
    assert -s["probes"]["tip"]["displacement"][2] == pytest.approx(kappa * L ** 2 / 2, rel=0.01)


# --- refusals ---------------------------------------------------------------------------------
@pytest.mark.parametrize("change, message", [
    (("material.1.where", {"box": [[0.0, 0.0, 0.0], [L, B, 0.0001]]}), "claims no cell"),
    (("material.1.name", "soft"), "another material has this name"),
    (("material.0.where", {"box": [[0.0, 0.0, 0.0], [L, B, H]]}), "regions must not overlap"),
    (("material.1.where", None), "only one material may leave out `where`"),
    (("material.1.where", {"group": "layer"}), "no such volume group"),
    (("material.0.expansion", 1e-5), "needs a [thermal] section"),
])
def test_bad_materials_are_refused_in_one_line(change, message):
    d = with_(layered(), *change)
    with pytest.raises(InputError, match=message.replace("[", r"\[").replace("`", ".")):
        ff.solve_static(ff.Scene.from_dict(d))


def test_cells_no_material_claims_are_refused():
    d = layered()
    d["material"][0]["where"] = {"box": [[0.0, 0.0, H / 2], [L / 2, B, H]]}
    with pytest.raises(InputError, match="16 cells belong to no material"):
        ff.solve_static(ff.Scene.from_dict(d))


def test_balance_and_plasticity_with_several_materials_are_refused(tmp_path, capsys):
    d = with_(layered(), "material.1.plasticity", {"model": "von-mises", "yield_stress": 1e6})
    code, _, err, _ = run_scene(tmp_path, d, capsys)
    assert code == 2 and "material[1].plasticity: plasticity is for a single [material] table only" in err


def test_a_step_load_swings_the_layered_cantilever_at_its_transformed_section_frequency():
    """Undamped, a tip load applied at t = 0 swings the tip between 0 and about 2 delta and back to 0 after
    one period of the first bending mode (Euler-Bernoulli with the layered EI and mass per length)."""
    from fem_forms.analyses.dynamic import solve_dynamic
    EI, mass = transformed_section()
    period = 1.0 / (1.875104 ** 2 / (2 * math.pi * L ** 2) * math.sqrt(EI / mass))
    d = layered(analysis="dynamic", dynamic={"duration": 1.2 * period, "dt": period / 60})
    d["output"]["probes"] = {"tip": [L, B / 2, H / 2]}
    r = solve_dynamic(ff.Scene.from_dict(d))
    assert r.failure is None
    assert r.system.model.probe_materials() == {"tip": "soft"}           # on the joint: the first listed
    rows = np.array(r.probe_rows)
    t, uz = rows[:, 0], -rows[:, 3]
    back = np.flatnonzero(t > period / 2)[np.argmin(uz[t > period / 2])]
    assert t[back] == pytest.approx(period, rel=0.03) and abs(uz[back]) < 0.02 * uz.max()
    assert uz.max() == pytest.approx(2 * P * L ** 3 / (3 * EI), rel=0.05)


def test_the_rest_shape_of_a_two_material_part_keeps_its_materials(tmp_path):
    """Inverse design of a sagging two-layer beam: the forward check on the written rest mesh (its cells
    in the volume groups of their materials) lands on the target; so do the groups' sizes."""
    import meshio
    d = layered(analysis="inverse", load=[{"type": "gravity", "g": [0.0, 0.0, -9.81]}],
                inverse={"method": "direct"}, solver={"steps": 2})
    for m in d["material"]:
        m["model"], m["nu"] = "neo-hookean", 0.3
    d["output"]["probes"] = {}
    code, s, err, out = run_scene(tmp_path, d)
    assert code == 0, err
    assert s["usable"] and s["target_mismatch_max"] < 1e-3 * s["max_rest_offset"]
    rest = meshio.read(out / "rest_shape.msh")
    tags = np.asarray(rest.cell_data_dict["gmsh:physical"]["hexahedron"])
    assert {n: int((tags == rest.field_data[n][0]).sum()) for n in ("soft", "stiff")} == {"soft": 32, "stiff": 32}


def test_bimetal_strip_demo(demo):
    """The steel-brass blade heated by 200 K (demos/bimetal_strip.py) curls into Timoshenko's arc: its tip
    drops s (1 - cos(kappa L)) / kappa, s the interface's stretch (small-strain theory: the O(strain)
    difference of the finite-strain solve, measured -0.3 %, is inside 0.5 %); the masses per material are
    the layers' volumes times their densities."""
    text, out = demo("bimetal_strip")
    d = scene_dict("bimetal_strip")
    brass, steel = d["material"]
    L, b, h = d["mesh"]["size"]
    dT = d["thermal"]["boundary"][0]["temperature"] - d["thermal"]["reference_temperature"]
    kappa = timoshenko_curvature(h / 2, h / 2, steel["E"], brass["E"], steel["expansion"], brass["expansion"], dT)
    force = 2 * kappa * (steel["E"] + brass["E"]) * (h / 2) ** 3 / 12 / h
    stretch = 1 + steel["expansion"] * dT + force / (steel["E"] * h / 2) + kappa * h / 4
    drop, back = grab(rf"tip drop ({NUMBER}) mm, arc {NUMBER} mm; tip moves back ({NUMBER}) mm", text)
    assert drop / 1000 == pytest.approx(stretch * (1 - math.cos(kappa * L)) / kappa, rel=0.005)
    assert back / 1000 == pytest.approx(L - stretch * math.sin(kappa * L) / kappa, rel=0.02)
    res = json.loads((out / "results.json").read_text())
    assert [m["mass"] for m in res["materials"]] == pytest.approx(
        [brass["rho"] * L * b * h / 2, steel["rho"] * L * b * h / 2], rel=1e-9)
    assert (out / "deformed.png").stat().st_size > 0


def test_heat_flows_through_two_materials_in_series_as_their_resistances_say():
    """Steady conduction (analysis = "thermal") through a bar whose halves conduct differently (each
    material's own conductivity, no [thermal] conductivity at all): the joint's temperature divides the drop
    as the series resistances L/2k do."""
    from fem_forms.analyses.thermal import solve_thermal
    k1, k2, T0, T1 = 1.0, 4.0, 100.0, 0.0
    d = {"analysis": "thermal", "mesh": {"size": [1.0, 0.1, 0.1], "cells": [20, 1, 1]},
         "material": [{"name": "left", "E": 1e9, "nu": 0.3, "rho": 1000.0, "conductivity": k1},
                      {"name": "right", "E": 1e9, "nu": 0.3, "rho": 1000.0, "conductivity": k2,
                       "where": {"box": [[0.5, 0.0, 0.0], [1.0, 0.1, 0.1]]}}],
         "thermal": {"boundary": [{"where": {"axis": "x", "at": 0.0}, "temperature": T0},
                                  {"where": {"axis": "x", "at": 1.0}, "temperature": T1}]},
         "output": {"probes": {"joint": [0.5, 0.05, 0.05]}}}
    s = solve_thermal(ff.Scene.from_dict(d)).summary()
    r1, r2 = 0.5 / k1, 0.5 / k2
    assert s["probes"]["joint"]["temperature"] == pytest.approx(T1 + (T0 - T1) * r2 / (r1 + r2), rel=1e-9)


def test_two_models_with_gravity_on_one_volume_group():
    """Materials of two kinds (each psi over its own cells) with gravity on one gmsh volume group (cell tags of
    its own): one form could hold only one of the two cell taggings, and the run stopped; now the clamp
    carries the group's weight rho g V, V = 100 x 20 x 2 mm (the PneuNet's bottom layer)."""
    from helpers import ROOT
    d = {"mesh": {"generator": "file", "file": str(ROOT / "demos" / "scenes" / "pneunet.msh")},
         "material": [{"name": "silicone", "model": "neo-hookean", "E": 1e5, "nu": 0.45, "rho": 1070.0},
                      {"name": "layer", "model": "stvk", "E": 1e6, "nu": 0.45, "rho": 1100.0,
                       "where": {"group": "layer"}}],
         "discretization": {"degree": 1}, "fix": [{"name": "clamp", "where": {"group": "clamp"}}],
         "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81], "where": {"group": "layer"}}],
         "output": {"picture": False, "fields": False}}
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert s["converged"]
    assert s["reactions"]["clamp"][2] == pytest.approx(1100.0 * 9.81 * 0.1 * 0.02 * 0.002, rel=1e-8)
