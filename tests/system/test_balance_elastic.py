"""Balance on the shape sagging under gravity (`elastic = true`): a cantilever's deformed centre of mass
against Euler-Bernoulli-Timoshenko (mass kept as it deforms), and a soft leaning figure that stands rigid,
topples after sagging, and stands once designed on its sagged shape within 4 static solves; the carved
part as built (solid.vtu, carved cells removed instead of made soft) checked again by an independent run;
one too soft for any carving exits 3; 1 and 2 MPI ranks give the same elastic design."""
import math

import numpy as np
import pytest

import balance_shapes
import helpers

G = 9.81


def run_scene(path, d):
    path.mkdir(parents=True, exist_ok=True)
    return helpers.run_scene(path, d)


def cantilever(**balance):
    return {"title": "sagging cantilever", "analysis": "balance",
            "mesh": {"generator": "box", "size": [1.0, 0.05, 0.05], "cells": [20, 2, 2]},
            "material": {"model": "neo-hookean", "E": 1e9, "nu": 0.0, "rho": 1000.0},
            "discretization": {"degree": 2}, "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "balance": {"goal": "check", "elastic": True, **balance}}


def test_cantilever_deformed_center_of_mass(tmp_path):
    """The CoM sinks by the mean deflection: int w dx / L with w(x) = q x^2 (6L^2 - 4Lx + x^2) / (24 EI)
    (Euler-Bernoulli) + q (Lx - x^2/2) / (kappa G A) (shear, kappa 5/6), i.e. q L^4 / (20 EI) + q L^2 / (3 kGA)."""
    L, h, E, rho = 1.0, 0.05, 1e9, 1000.0
    q, EI, kGA = rho * G * h * h, E * h**4 / 12, 5 / 6 * (E / 2) * h * h
    code, d, _, _ = run_scene(tmp_path, cantilever())
    assert code == 0 and d["static_solves"] == 1
    rigid, bent = np.array(d["center_of_mass"]), np.array(d["deformed"]["center_of_mass"])
    assert np.allclose(rigid, [L / 2, h / 2, h / 2], atol=1e-12)
    assert d["deformed"]["mass"] == pytest.approx(d["mass"], rel=1e-12)      # rho dv = rho_0 dV
    sink = q * L**4 / (20 * EI) + q * L**2 / (3 * kGA)
    assert rigid[2] - bent[2] == pytest.approx(sink, rel=0.01)
    assert abs(bent[1] - rigid[1]) < 1e-3 * sink and abs(bent[0] - rigid[0]) < 0.01 * sink
    assert d["deformed"]["max_displacement"] == pytest.approx(q * L**4 / (8 * EI) + q * L**2 / (2 * kGA), rel=0.01)


def test_two_material_cantilever_sinks_as_its_transformed_section(tmp_path):
    """A heavy stiff lower half and a light soft upper one: the CoM (the density-weighted one) sinks by
    q L^4 / (20 EI) with EI of the transformed section and q the weight of both layers per length (shear
    adds about 0.3 %, within the tolerance)."""
    L, h, g = 1.0, 0.05, 9.81
    (E_b, rho_b), (E_t, rho_t) = (3e9, 3000.0), (1e9, 1000.0)
    d = cantilever()
    d["material"] = [{"name": "top", "model": "neo-hookean", "E": E_t, "nu": 0.0, "rho": rho_t},
                     {"name": "bottom", "model": "neo-hookean", "E": E_b, "nu": 0.0, "rho": rho_b,
                      "where": {"box": [[0.0, 0.0, 0.0], [L, h, h / 2]]}}]
    code, r, err, _ = run_scene(tmp_path, d)
    assert code == 0, err
    area = h * h / 2
    zn = (E_b * h / 4 + E_t * 3 * h / 4) / (E_b + E_t)
    EI = sum(E * (h * (h / 2) ** 3 / 12 + area * (z - zn) ** 2) for E, z in ((E_b, h / 4), (E_t, 3 * h / 4)))
    q = g * (rho_b + rho_t) * area
    rigid, bent = np.array(r["center_of_mass"]), np.array(r["deformed"]["center_of_mass"])
    assert rigid[2] == pytest.approx((rho_b * h / 4 + rho_t * 3 * h / 4) / (rho_b + rho_t), rel=1e-12)
    assert rigid[2] - bent[2] == pytest.approx(q * L ** 4 / (20 * EI), rel=0.01)
    assert r["deformed"]["max_displacement"] == pytest.approx(q * L ** 4 / (8 * EI), rel=0.01)


@pytest.mark.mpi
def test_cantilever_two_ranks(tmp_path):
    one, two = helpers.serial_and_two_ranks(tmp_path, cantilever())
    assert np.allclose(one["deformed"]["center_of_mass"], two["deformed"]["center_of_mass"], rtol=1e-9)


# --- the soft figure ----------------------------------------------------------------------------
LEAN, E_SOFT, MARGIN = 0.06, 1.5e5, 2.0


def soft(mesh, **balance):
    return {"title": "soft figure", "analysis": "balance", "mesh": {"generator": "file", "file": str(mesh)},
            "material": {"model": "neo-hookean", "E": E_SOFT, "nu": 0.4, "rho": 1100.0},
            "discretization": {"degree": 2}, "fix": [{"where": {"axis": "z", "at": 0.0}}],
            "balance": {"margin_angle": MARGIN, "shell": 0.003, "elastic": True, **balance}}


def foot_margin(c):
    """Distance of the CoM's ground projection to the edges of the foot's sole [-0.03, 0.06] x [0, 0.04]
    (clamped: it does not move as the figure sags)."""
    return min(0.06 - c[0], c[0] + 0.03, c[1], 0.04 - c[1])


@pytest.fixture(scope="module")
def figure(tmp_path_factory):
    return balance_shapes.leaning_figure(tmp_path_factory.mktemp("soft") / "fig.msh", h=0.008, lean=LEAN)


def test_soft_figure_stands_rigid_topples_sagged_stands_designed(tmp_path, figure):
    # rigid: the closed form of the two boxes (the column sheared by LEAN keeps its volume)
    vf, vc = 0.09 * 0.04 * 0.03, 0.04 * 0.04 * 0.14
    x = (vf * 0.015 + vc * (0.04 + LEAN / 2)) / (vf + vc)
    z = (vf * 0.015 + vc * 0.10) / (vf + vc)
    code, chk, _, _ = run_scene(tmp_path / "check", soft(figure, goal="check"))
    assert code == 0 and chk["static_solves"] == 1
    assert chk["stands"] and chk["toppling_angle_deg"] == pytest.approx(math.degrees(math.atan2(0.06 - x, z)), abs=1e-6)
    dfm = chk["deformed"]
    assert not dfm["stands"] and dfm["toppling_angle_deg"] < 0
    assert dfm["stability_margin"] == pytest.approx(-(dfm["center_of_mass"][0] - 0.06), rel=1e-6)

    code, d, _, out = run_scene(tmp_path / "stand", soft(figure, goal="stand"))
    assert code == 0
    assert 1 <= d["static_solves"] <= 4 and len(d["elastic_iterations"]) == d["static_solves"]
    dd = d["deformed"]
    assert dd["stands"] and dd["toppling_angle_deg"] >= MARGIN
    assert dd["stability_margin"] == pytest.approx(foot_margin(dd["center_of_mass"]), rel=1e-6)
    h = dd["center_of_mass"][2]
    assert dd["toppling_angle_deg"] == pytest.approx(math.degrees(math.atan2(foot_margin(dd["center_of_mass"]), h)))
    assert 0 < d["carved_fraction"] < 1 and d["mass"] < chk["mass"]

    # the part as built: carved cells removed (not an ersatz material), checked again on its own sag
    code, again, _, _ = run_scene(tmp_path / "again", soft(out / "solid.vtu", goal="check"))
    assert code == 0
    assert again["mass"] == pytest.approx(d["mass"], rel=1e-9)
    assert again["deformed"]["stands"] and again["deformed"]["toppling_angle_deg"] >= MARGIN
    assert again["deformed"]["toppling_angle_deg"] == pytest.approx(dd["toppling_angle_deg"], abs=1e-3)   # measured 8e-7


def test_too_soft_to_stand_exits_3(tmp_path, figure):
    """E 0.05 MPa (P1): sagged 11 cm, no carving brings the CoM back over the sole; the loop stops at its
    fixed point and the run exits 3 without a results file."""
    d = soft(figure, goal="stand")
    d["material"]["E"], d["discretization"]["degree"] = 5e4, 1
    code, res, _, _ = run_scene(tmp_path, d)
    assert code == 3 and res is None


@pytest.mark.mpi
def test_soft_figure_two_ranks_same_design(tmp_path, figure):
    """The elastic stand design (P1, E 0.1 MPa: the rigid design misses the margin once sagged, the
    redesign meets it) on 1 and 2 ranks: the same carving and sagged numbers."""
    d = soft(figure, goal="stand")
    d["material"]["E"], d["discretization"]["degree"] = 1e5, 1
    one, two = helpers.serial_and_two_ranks(tmp_path, d)
    assert one["static_solves"] == two["static_solves"]
    assert one["elastic_iterations"][0]["toppling_angle_deg"] < MARGIN <= one["deformed"]["toppling_angle_deg"]
    assert one["carved_fraction"] == pytest.approx(two["carved_fraction"], rel=1e-12)
    assert np.allclose(one["deformed"]["center_of_mass"], two["deformed"]["center_of_mass"], rtol=1e-9)


def test_soft_figure_resting_on_a_floor_sags_as_when_clamped(tmp_path, capsys):
    """elastic = true with no [[fix]]: a figure leaning 3 cm rests on a frictional floor ([contact]) and sags
    under its weight. Its sole cannot slide (mu 1) and its heel stays down, so it stands as the clamped one
    does: the same toppling angle within 0.2 deg, the deformed CoM within 0.3 mm; the floor carries m g. A
    [contact] floor without elastic = true is refused (the rigid balance meets its ground by tolerance)."""
    figure = balance_shapes.leaning_figure(tmp_path / "fig.msh", h=0.008, lean=0.03)
    code, clamped, _, _ = run_scene(tmp_path / "clamped", soft(figure, goal="check"))
    floor = dict(soft(figure, goal="check"), fix=[])
    floor["contact"] = {"distance": 1e-4, "obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -5e-5],
                                                       "normal": [0, 0, 1], "friction": 1.0}]}
    code2, rests, _, _ = run_scene(tmp_path / "floor", floor)
    assert code == 0 and code2 == 0
    a, b = clamped["deformed"], rests["deformed"]
    assert a["stands"] and b["stands"] and b["toppling_angle_deg"] == pytest.approx(a["toppling_angle_deg"], abs=0.2)
    assert np.allclose(b["center_of_mass"], a["center_of_mass"], atol=3e-4)        # measured 0.06 deg, 0.11 mm
    assert b["contact"]["floor"]["force"][2] == pytest.approx(rests["mass"] * G, rel=1e-6)
    assert b["intersection_free"] and 0 < b["min_distance"] < 1e-4
    rigid = dict(floor, balance=dict(floor["balance"], elastic=False))
    code, _, err, _ = helpers.run_scene(tmp_path, rigid, capsys)
    assert code == 2 and "contact: for balance only with elastic = true" in err
