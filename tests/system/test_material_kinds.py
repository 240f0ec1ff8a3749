"""Materials of different kinds in one part, against independent references:
- a small-strain law (orthotropic, linear) beside finite-strain materials takes its Green-strain form: a
  layered cantilever bends as its transformed section says (small deflection), and at a large deflection an
  orthotropic layer with isotropic constants bends exactly as St Venant-Kirchhoff does;
- viscoelastic materials among elastic ones: a bar of two halves side by side (one with Prony terms, one
  without) under a held stretch carries the sum of its halves' forces, E1 eps R(t) A/2 + E2 eps A/2, R the
  Prony relaxation (exact: both halves stay in uniaxial stress), on 1 and 2 ranks;
- the issue's scene: a body from a gmsh volume group, a fibre-reinforced layer from a box and an orthotropic
  viscoelastic print taking the rest, pulled in series: its force starts at the series compliance of the
  instantaneous moduli and relaxes to that of the long-term ones."""
import copy
import json
import math

import gmsh
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from helpers import mpirun, run_scene, toml_dumps
from system.test_materials import E_STIFF, L, P, layered, transformed_section

PRONY = [[0.3, 0.01], [0.2, 0.1]]
G_INF = 1 - sum(g for g, _ in PRONY)


def orthotropic(E1: float, E2: float, G: float, nu: float = 0.0) -> dict:
    return {"model": "orthotropic", "E1": E1, "E2": E2, "E3": E2, "G12": G, "G13": G, "G23": G,
            "nu12": nu, "nu13": nu, "nu23": nu, "axis1": [1.0, 0.0, 0.0], "axis2": [0.0, 1.0, 0.0]}


def with_stiff_layer(d: dict, law: dict) -> dict:
    d = copy.deepcopy(d)
    stiff = {k: v for k, v in d["material"][1].items() if k not in ("model", "E", "nu")}
    d["material"][1] = stiff | law
    return d


@pytest.mark.parametrize("law", [orthotropic(E_STIFF, E_STIFF / 3, E_STIFF / 5),
                                 {"model": "linear", "E": E_STIFF, "nu": 0.0}], ids=["orthotropic", "linear"])
def test_a_small_strain_layer_beside_a_neo_hookean_one_bends_as_the_transformed_section(law):
    s = ff.solve_static(ff.Scene.from_dict(with_stiff_layer(layered("neo-hookean", "stvk"), law))).summary()
    EI, _ = transformed_section()
    assert s["converged"]
    assert -s["probes"]["tip"]["displacement"][2] == pytest.approx(P * L ** 3 / (3 * EI), rel=0.01)


def test_at_a_large_deflection_the_orthotropic_layer_is_st_venant_kirchhoff():
    """With isotropic constants the orthotropic law's Green-strain form is St Venant-Kirchhoff's psi: the same
    tip displacement at a deflection of 85 % of the length (a linear strain would give spurious stresses)."""
    E, nu = E_STIFF, 0.3
    tips = []
    for law in (orthotropic(E, E, E / (2 * (1 + nu)), nu), {"model": "stvk", "E": E, "nu": nu}):
        d = with_stiff_layer(layered("neo-hookean", "stvk", solver={"steps": 5}), law)
        d["load"][0]["value"] = [0.0, 0.0, -3000 * P / (0.04 * 0.02)]
        s = ff.solve_static(ff.Scene.from_dict(d)).summary()
        assert s["converged"]
        tips.append(s["probes"]["tip"]["displacement"])
    assert -tips[1][2] > 0.8 * L
    assert tips[0] == pytest.approx(tips[1], rel=1e-9, abs=1e-12)


def test_a_small_strain_law_beside_finite_ones_is_refused_in_the_mixed_formulation():
    d = with_stiff_layer(layered("neo-hookean", "stvk", discretization={"degree": 2, "formulation": "mixed"}),
                         {"model": "linear", "E": E_STIFF, "nu": 0.3})
    with pytest.raises(InputError, match="small-strain law beside finite-strain materials"):
        ff.Scene.from_dict(d)


# --- viscoelastic materials among others ----------------------------------------------------------
E1, E2, EPS, T_R, T_END = 1.0e6, 3.0e6, 1e-4, 1e-3, 0.3


def relaxation(t: float) -> float:
    """Force over E eps A of a strain ramped over T_R, then held (the Prony series)."""
    if t <= T_R:
        return (G_INF * t + sum(g * tau * -math.expm1(-t / tau) for g, tau in PRONY)) / T_R
    return (G_INF * T_R + sum(g * tau * (math.exp(-(t - T_R) / tau) - math.exp(-t / tau)) for g, tau in PRONY)) / T_R


def side_by_side() -> dict:
    """A 1 x 0.1 x 0.1 m bar on rollers, its y < 0.05 half viscoelastic, the other half not."""
    fix = [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"]
    fix.append({"name": "pull", "where": {"axis": "x", "at": 1.0}, "components": ["x"], "value": [EPS, 0.0, 0.0],
                "history": [[0.0, 0.0], [T_R, 1.0], [T_END, 1.0]]})
    return {"mesh": {"size": [1.0, 0.1, 0.1], "cells": [2, 2, 1]},
            "material": [{"name": "damper", "model": "linear", "E": E1, "nu": 0.3, "viscoelastic": {"prony": PRONY},
                          "where": {"box": [[0.0, 0.0, 0.0], [1.0, 0.05, 0.1]]}},
                         {"name": "spring", "model": "linear", "E": E2, "nu": 0.3}],
            "discretization": {"degree": 1}, "fix": fix, "solver": {"steps": 20},
            "output": {"picture": False, "fields": False, "probes": {"end": [1.0, 0.1, 0.1]}}}


def expected_force(t: float) -> float:
    return EPS * 0.005 * (E1 * relaxation(t) + E2)


def test_side_by_side_halves_relax_as_the_sum_of_their_forces(tmp_path):
    code, s, err, out = run_scene(tmp_path, side_by_side())
    assert code == 0, err
    rows = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    assert rows["time"][-1] == pytest.approx(T_END) and len(rows) >= 5
    assert rows["pull_Fx"] == pytest.approx([expected_force(t) for t in rows["time"]], rel=1e-8, abs=1e-12)
    assert [m["name"] for m in s["materials"]] == ["damper", "spring"]


@pytest.mark.mpi
def test_two_ranks_relax_side_by_side_as_one(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_dumps(side_by_side()))
    r = mpirun(["-m", "fem_forms", "run", str(scene), "--out", str(tmp_path / "out")])
    assert r.returncode == 0, r.stderr[-2000:]
    s = json.loads((tmp_path / "out" / "results.json").read_text())
    assert s["reactions"]["pull"][0] == pytest.approx(expected_force(T_END), rel=1e-8)


# --- the issue's scene: group, box and the rest; fibres; orthotropic viscoelastic --------------------
H, CUTS = 0.1, (0.4, 0.7)


def three_part_bar(path) -> None:
    """A 1 x 0.1 x 0.1 bar meshed conforming at x = 0.4 and 0.7; volume groups 'body' (x < 0.4) and 'rest'."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    edges = (0.0, *CUTS, 1.0)
    boxes = [occ.addBox(a, 0, 0, b - a, H, H) for a, b in zip(edges, edges[1:])]
    occ.fragment([(3, boxes[0])], [(3, b) for b in boxes[1:]])
    occ.synchronize()
    e = 1e-6
    body = [t for _, t in gmsh.model.getEntitiesInBoundingBox(-e, -e, -e, CUTS[0] + e, H + e, H + e, 3)]
    rest = [t for _, t in gmsh.model.getEntities(3) if t not in body]
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, body), "body")
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, rest), "rest")
    gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.05)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(path))
    gmsh.finalize()


def test_the_issues_three_material_scene_relaxes_from_its_instantaneous_to_its_long_term_series_force(tmp_path):
    mesh = tmp_path / "bar.msh"
    three_part_bar(mesh)
    u = 1e-4
    fix = [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"]
    fix.append({"name": "pull", "where": {"axis": "x", "at": 1.0}, "components": ["x"], "value": [u, 0.0, 0.0],
                "history": [[0.0, 0.0], [1e-6, 1.0], [2.0, 1.0]]})
    d = {"mesh": {"generator": "file", "file": str(mesh)},
         "material": [
             {"name": "body", "where": {"group": "body"}, "model": "neo-hookean", "E": 1.0e6, "nu": 0.0, "rho": 1070.0},
             {"name": "layer", "where": {"box": [[CUTS[0], 0.0, 0.0], [CUTS[1], H, H]]}, "model": "neo-hookean",
              "E": 1.0e6, "nu": 0.0, "rho": 900.0,
              "fibers": {"direction": [1.0, 0.0, 0.0], "E": 1.0e6, "model": "holzapfel"}},
             {"name": "print", **orthotropic(3.0e6, 1.0e6, 0.5e6), "viscoelastic": {"prony": PRONY}}],
         "discretization": {"degree": 1}, "fix": fix, "solver": {"steps": 20},
         "output": {"picture": False, "fields": False, "probes": {"end": [1.0, H, H]}}}
    code, s, err, out = run_scene(tmp_path, d)
    assert code == 0, err
    rows = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    lengths, area = (0.4, 0.3, 0.3), H * H

    def series(E_print: float) -> float:
        return u * area / sum(Li / Ei for Li, Ei in zip(lengths, (1.0e6, 2.0e6, E_print)))
    first = int(np.argmin(abs(rows["time"] - 1e-6)))
    assert rows["pull_Fx"][first] == pytest.approx(series(3.0e6), rel=1e-3)
    assert rows["pull_Fx"][-1] == pytest.approx(series(G_INF * 3.0e6), rel=1e-3)
    assert [(m["name"], round(m["volume"] / area, 9)) for m in s["materials"]] == [
        ("body", 0.4), ("layer", 0.3), ("print", 0.3)]
