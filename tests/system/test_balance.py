"""Balance designs end to end: a leaning part that topples and stands after carving with the requested
margin; a lopsided top whose spin axis becomes principal with the CoM on it; a box that floats upright at
its waterline (mass = displaced water, GM against the box formula); no design -> exit 3 with the reason;
the same design on 2 MPI ranks."""
import math

import numpy as np
import pytest

import balance_shapes
from helpers import run_scene, serial_and_two_ranks


def run(path, d):
    path.mkdir(parents=True, exist_ok=True)
    return run_scene(path, d)


def scene(mesh, **balance):
    return {"title": "balance test", "analysis": "balance", "mesh": mesh,
            "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0}, "balance": balance}


@pytest.fixture(scope="module")
def leaning(tmp_path_factory):
    return balance_shapes.leaning_figure(tmp_path_factory.mktemp("mesh") / "lean.msh")


def test_leaning_part_topples_then_stands_with_margin(tmp_path, leaning):
    mesh = {"generator": "file", "file": str(leaning)}
    code, check, _, _ = run(tmp_path / "c", scene(mesh, goal="check"))
    assert code == 0 and not check["stands"] and check["toppling_angle_deg"] < 0
    code, d, _, out = run(tmp_path / "s", scene(mesh, goal="stand", margin_angle=2.0, shell=0.003))
    assert code == 0 and d["stands"] and d["meets_margin"]
    # the margin: CoM inside the polygon shrunk by h tan(2 deg), from the reported numbers
    h = d["center_of_mass"][2]
    assert d["stability_margin"] >= h * math.tan(math.radians(2.0))
    assert d["toppling_angle_deg"] == pytest.approx(math.degrees(math.atan2(d["stability_margin"], h)))
    assert 0 < d["carved_fraction"] < 1 and d["mass"] < check["mass"]
    # the carving mass checks out against the solid part: removed mass = rho x carved volume
    assert check["mass"] - d["mass"] == pytest.approx(check["mass"] * d["carved_fraction"], rel=1e-9)
    for f in ("void.stl", "outer.stl", "density.xdmf", "balance.png"):
        assert (out / f).stat().st_size > 0


def test_a_ballast_makes_the_leaning_part_stand_with_the_least_steel(tmp_path, leaning):
    """Stand with a steel ballast (fill_density 7800 > rho): it stands with the margin; the second stage moves the
    least mass, so the steel is a small part of the carvable volume (it filled all it could before: the stage
    maximised the mass, which for a ballast is the most steel); mass = solid + (7800 - rho) x ballast volume."""
    mesh = {"generator": "file", "file": str(leaning)}
    code, check, _, _ = run(tmp_path / "c", scene(mesh, goal="check"))
    code, d, err, _ = run(tmp_path / "b", scene(mesh, goal="stand", margin_angle=2.0, shell=0.003,
                                               fill_density=7800.0))
    assert code == 0 and d["stands"] and d["meets_margin"], err
    assert 0 < d["carved_fraction"] < 0.25
    assert d["mass"] - check["mass"] == pytest.approx(check["mass"] * d["carved_fraction"] * 6.8, rel=1e-9)


def test_stand_needs_an_area_and_a_reachable_margin(tmp_path, leaning):
    mesh = {"generator": "file", "file": str(leaning)}
    code, d, _, _ = run(tmp_path, scene(mesh, goal="stand", margin_angle=30.0))
    assert code == 3 and d is None


def test_top_axis_becomes_principal_with_com_on_it(tmp_path):
    top = balance_shapes.lopsided_top(tmp_path / "top.msh")
    code, d, _, _ = run(tmp_path, scene({"generator": "file", "file": str(top)}, goal="spin", kind="top",
                                              axis=[0.0, 0.0, 1.0], shell=0.003))
    assert code == 0
    c = np.array(d["center_of_mass"])
    assert abs(d["before"]["center_of_mass"][0]) > 1e-4          # off the axis before
    size = math.sqrt(0.08 ** 2 + 0.08 ** 2 + 0.07 ** 2)              # the top's bounding-box diagonal
    assert max(abs(c[0]), abs(c[1])) < 2e-4 * size * 1.02            # each off-axis component within its band
    I = np.array(d["inertia"])
    assert abs(I[0, 2]) < 3e-3 * I[2, 2] and abs(I[1, 2]) < 3e-3 * I[2, 2]     # about the CoM
    # about the tip (the origin), where the design bounds them by 1e-4 of the solid's spin moment
    tip = lambda r: np.array(r["inertia"]) + r["mass"] * (np.dot(r["center_of_mass"], r["center_of_mass"]) * np.eye(3)
                                                          - np.outer(r["center_of_mass"], r["center_of_mass"]))
    It, I0 = tip(d), tip(d["before"])
    assert abs(It[0, 2]) <= 1e-4 * I0[2, 2] * 1.001 and abs(It[1, 2]) <= 1e-4 * I0[2, 2] * 1.001
    assert d["spin_ratio"] == pytest.approx(I[2, 2] / max(np.linalg.eigvalsh(I[:2, :2])))


def test_box_floats_upright_at_its_waterline(tmp_path):
    L, B, H, T = 0.2, 0.1, 0.06, 0.03
    box = {"generator": "box", "size": [L, B, H], "cells": [20, 10, 6]}
    light = lambda **b: dict(scene(box, **b), material={"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 600.0})
    code, d, _, _ = run(tmp_path, light(goal="swim", waterline=T, shell=0.01))
    assert code == 0
    assert d["mass"] == pytest.approx(1000.0 * L * B * T, rel=1.1e-3)
    KG = d["center_of_mass"][2]
    assert d["metacentric_height"] == pytest.approx(T / 2 + B * B / (12 * T) - KG, rel=1e-9)
    assert d["metacentric_height"] > 0.01 * math.sqrt(L * L + B * B + H * H) * (1 - 1e-6)
    assert np.allclose(d["center_of_mass"][:2], [L / 2, B / 2], atol=3e-4 * 0.25)
    code, d, _, _ = run(tmp_path / "deep", light(goal="swim", waterline=0.055, shell=0.01))
    assert code == 3 and d is None                    # too light even solid
    code, d, _, _ = run(tmp_path / "shallow", light(goal="swim", waterline=0.01, shell=0.01))
    assert code == 3 and d is None                    # too heavy even carved


def test_a_steel_ballast_sinks_the_box_to_a_waterline_it_cannot_reach_solid(tmp_path):
    """The box above, asked to float at T = 55 mm (solid it is too light: exit 3 above): ballast (fill_density
    7800) adds the mass; it floats upright there (Archimedes: mass = rho_w L B T), the CoM on the vertical."""
    L, B, H, T = 0.2, 0.1, 0.06, 0.055
    box = {"generator": "box", "size": [L, B, H], "cells": [20, 10, 6]}
    d = dict(scene(box, goal="swim", waterline=T, shell=0.01, fill_density=7800.0),
             material={"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 600.0})
    code, r, err, _ = run(tmp_path, d)
    assert code == 0, err
    assert r["mass"] == pytest.approx(1000.0 * L * B * T, rel=1.1e-3)
    assert np.allclose(r["center_of_mass"][:2], [L / 2, B / 2], atol=3e-4 * 0.25)
    assert r["metacentric_height"] > 0


def test_results_report_the_lp_sifting(tmp_path):
    """A yoyo cube of 8000 hexahedra: 5832 carvable cells (more than sifting.MIN_CELLS = 4000), so every LP
    of the design is sifted, each in at least one round, none falls back to the whole LP; the small leaning
    figure (fewer cells) solves its LPs whole. The cube's equal moments become a spin ratio above 1."""
    cube = {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [20, 20, 20], "cell": "hexahedron"}
    code, d, _, _ = run(tmp_path, scene(cube, goal="spin", kind="yoyo", axis=[0.0, 0.0, 1.0]))
    assert code == 0 and d["carvable_cells"] == 18 ** 3 and d["spin_ratio"] > 1
    lp = d["lp"]
    assert lp["lps"] >= 1 and lp["sifted_lps"] == lp["lps"] and lp["sifting_fallbacks"] == 0
    assert lp["sifting_rounds"] >= lp["lps"]


def test_small_designs_solve_their_lps_whole(tmp_path, leaning):
    code, d, _, _ = run(tmp_path, scene({"generator": "file", "file": str(leaning)}, goal="stand",
                                        margin_angle=2.0, shell=0.003))
    assert code == 0 and d["carvable_cells"] < 4000
    assert d["lp"]["lps"] >= 1 and d["lp"]["sifted_lps"] == d["lp"]["sifting_rounds"] == 0


@pytest.mark.mpi
def test_two_ranks_same_design(tmp_path, leaning):
    d = scene({"generator": "file", "file": str(leaning)}, goal="stand", margin_angle=2.0, shell=0.003)
    r1, r2 = serial_and_two_ranks(tmp_path, d)
    assert r1["carved_fraction"] == pytest.approx(r2["carved_fraction"], rel=1e-12)
    assert np.allclose(r1["center_of_mass"], r2["center_of_mass"], rtol=1e-10)
