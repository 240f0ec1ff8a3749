"""goal = "swing" (Make it swing) against closed forms: a solid hemisphere resting on its dome rocks about
the dome's centre (the flat face's centre), its CoM 3R/8 below it: stable as it is. A roly-poly (the
hemisphere under a cylinder) whose solid CoM lies above that centre is carved until the CoM is R sin(margin
angle) below it, on its vertical; one too tall for any carving exits 3."""
import math

import numpy as np
import pytest

import balance_shapes
import helpers

R, MARGIN = 0.05, 5.0
CHORD = 0.015            # straight-sided tetrahedra inscribed in the sphere (h = 6 mm): CoM within 1.5 %


def run(tmp_path, mesh, fill_density=0.0):
    d = {"title": "roly-poly", "analysis": "balance", "mesh": {"generator": "file", "file": str(mesh)},
         "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0},
         "balance": {"goal": "swing", "shell": 0.003, "contact_tolerance": 0.01, "margin_angle": MARGIN,
                     "fill_density": fill_density}}
    tmp_path.mkdir(parents=True, exist_ok=True)
    return helpers.run_scene(tmp_path, d)


def com_height(H):
    """CoM height above the dome's centre: hemisphere (-3R/8) and cylinder of radius R, height H (H/2)."""
    vh, vc = 2 / 3 * math.pi * R**3, math.pi * R * R * H
    return (vh * -3 * R / 8 + vc * H / 2) / (vh + vc)


def test_hemisphere_rocks_about_its_centre(tmp_path):
    code, d, _, _ = run(tmp_path, balance_shapes.roly_poly(tmp_path / "hemi.msh", R=R, h=0.006))
    assert code == 0
    b = d["before"]                                   # the solid hemisphere
    assert np.allclose(b["curvature_center"], [0, 0, 0], atol=1e-9)      # surface nodes lie on the sphere
    assert b["curvature_radius"] == pytest.approx(R, rel=1e-9)
    assert b["com_depth_below_center"] == pytest.approx(3 * R / 8, rel=CHORD)
    assert d["com_depth_below_center"] >= R * math.sin(math.radians(MARGIN))


def test_roly_poly_carved_to_swing_back(tmp_path):
    H = 0.04
    code, d, _, _ = run(tmp_path, balance_shapes.roly_poly(tmp_path / "rp.msh", R=R, H=H, h=0.006))
    assert code == 0
    assert com_height(H) > 0                                       # the solid toy falls over
    # a small difference of two moments: compared within 0.2 % of R (the chords move each part's volume ~0.5 %)
    assert d["before"]["center_of_mass"][2] == pytest.approx(com_height(H), abs=2e-3 * R)
    c = np.array(d["center_of_mass"])                              # the design against the closed-form centre
    assert -c[2] >= R * math.sin(math.radians(MARGIN)) * (1 - 1e-6)
    size = math.sqrt(2 * (2 * R) ** 2 + (R + H) ** 2)
    assert np.hypot(c[0], c[1]) <= math.sqrt(2) * 1.02 * 2e-4 * size
    assert 0 < d["carved_fraction"] < 1


def test_too_tall_to_swing_exits_3(tmp_path):
    code, d, _, _ = run(tmp_path, balance_shapes.roly_poly(tmp_path / "tall.msh", R=R, H=0.1, h=0.008))
    assert code == 3 and d is None


def test_a_steel_ballast_rights_a_roly_poly_that_hollowing_cannot(tmp_path):
    """H = 5 cm: no hollowing brings the CoM low enough (exit 3); carving the bottom and filling the cavity
    with steel (fill_density 7800 > rho) does, and the mass is the shell's plus the ballast's."""
    H, STEEL = 0.05, 7800.0
    mesh = balance_shapes.roly_poly(tmp_path / "rp.msh", R=R, H=H, h=0.008)
    code, d, _, _ = run(tmp_path / "hollow", mesh)
    assert code == 3 and d is None
    code, d, _, _ = run(tmp_path / "ballast", mesh, fill_density=STEEL)
    assert code == 0
    c = np.array(d["center_of_mass"])
    assert -c[2] >= R * math.sin(math.radians(MARGIN)) * (1 - 1e-6)
    volume = 2 / 3 * math.pi * R**3 + math.pi * R * R * H
    f = d["carved_fraction"]
    assert 0 < f < 1
    assert d["mass"] == pytest.approx(volume * (1000.0 * (1 - f) + STEEL * f), rel=CHORD)


def test_a_heavy_dome_of_a_second_material_rights_the_tall_toy(tmp_path):
    """Several materials in balance design: the H = 5 cm toy whose dome (z < 0) is a material three times
    denser than its head is carved (hollowed) until it swings back, which one material cannot. Its mass lies
    between the 3 mm shell's and the solid toy's of those densities (closed forms, within the chords' 1.5 %)."""
    H, HEAVY, LIGHT = 0.05, 3000.0, 1000.0
    mesh = balance_shapes.roly_poly(tmp_path / "rp.msh", R=R, H=H, h=0.008)
    d = {"title": "two-material roly-poly", "analysis": "balance", "mesh": {"generator": "file", "file": str(mesh)},
         "material": [{"name": "head", "E": 1e6, "nu": 0.3, "rho": LIGHT},
                      {"name": "dome", "E": 1e6, "nu": 0.3, "rho": HEAVY,
                       "where": {"box": [[-R, -R, -R], [R, R, 0.0]]}}],
         "balance": {"goal": "swing", "shell": 0.003, "contact_tolerance": 0.01, "margin_angle": MARGIN}}
    code, r, err, _ = helpers.run_scene(tmp_path, d)
    assert code == 0, err
    vh, vc = 2 / 3 * math.pi * R**3, math.pi * R * R * H
    solid = HEAVY * vh + LIGHT * vc
    assert r["before"]["mass"] == pytest.approx(solid, rel=CHORD)
    height = (HEAVY * vh * -3 * R / 8 + LIGHT * vc * H / 2) / solid            # the solid toy's CoM
    assert r["before"]["center_of_mass"][2] == pytest.approx(height, abs=4e-3 * R)     # measured 2.3e-3 R
    assert -r["center_of_mass"][2] >= R * math.sin(math.radians(MARGIN)) * (1 - 1e-6)
    assert r["mass"] < solid
