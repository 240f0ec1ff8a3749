"""Support reactions and the equilibrium check in results.json against statics:
- a clamped cantilever under gravity and a tip traction: the clamp carries the whole load
  (rho g V + T A, exact integrals), to 1e-8 relative, also at large deflection (dead loads);
- a follower pressure: the reaction balances the pressure integrated on the deformed surface;
- a beam on two end supports (z held on the end faces, x held on a bottom pad whose forces have no
  lever arm about y, y held on a side face): the lever rule R_right = (W L/2 + P x_c) / L, exact in
  small-strain theory whatever the mesh (the discrete residual is orthogonal to rigid rotations);
- names: given ones kept, the others fix<i> in scene order, repeated names refused;
- two MPI ranks give the serial reactions."""
import json

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError
from helpers import beam_scene, mpirun, toml_dumps

L, H, RHO, G, T = 1.0, 0.1, 1000.0, 9.81, 100.0


def cantilever(E=1e7, loads=None, **over):
    return beam_scene(mesh={"generator": "box", "size": [L, H, H], "cells": [10, 2, 2]},
                      material={"model": "neo-hookean", "E": E, "nu": 0.3, "rho": RHO},
                      discretization={"degree": 2},
                      load=loads or [{"type": "gravity", "g": [0.0, 0.0, -G]},
                                     {"type": "traction", "where": {"axis": "x", "at": L},
                                      "value": [0.0, 30.0, -T]}], **over)


@pytest.mark.parametrize("E", [1e9, 2e6])          # small and large (tip sag ~ 0.1 L) deflection
def test_clamp_carries_gravity_and_tip_traction(E):
    s = ff.solve_static(ff.Scene.from_dict(cantilever(E))).summary()
    assert s["converged"]
    total = np.array([0.0, 30.0 * H * H, -RHO * G * L * H * H - T * H * H])
    np.testing.assert_allclose(s["applied_load"], total, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(s["reactions"]["fix0"], -total, rtol=1e-8, atol=1e-8 * np.linalg.norm(total))
    assert s["equilibrium_error"] < 1e-8


def test_follower_pressure_is_balanced_on_the_deformed_surface():
    d = cantilever(2e6, loads=[{"type": "pressure", "where": {"axis": "z", "at": H}, "value": 200.0}])
    s = ff.solve_static(ff.Scene.from_dict(d)).summary()
    assert s["converged"]
    load = np.array(s["applied_load"])
    # the top face turned as the beam bent: the pressure force is no longer straight down
    assert load[2] < 0 and abs(load[0]) > 1e-3 * abs(load[2])
    assert abs(load[2]) == pytest.approx(200.0 * L * H, rel=0.05)
    np.testing.assert_allclose(s["reactions"]["fix0"], -load, rtol=1e-8, atol=1e-8 * np.linalg.norm(load))
    assert s["equilibrium_error"] < 1e-8


def two_supports(cells=(20, 2, 4), degree=2):
    return {"mesh": {"generator": "box", "size": [L, H, H], "cells": list(cells)},
            "material": {"model": "linear", "E": 1e9, "nu": 0.0, "rho": RHO},
            "discretization": {"degree": degree},
            "fix": [{"name": "left", "where": {"axis": "x", "at": 0.0}, "components": ["z"]},
                    {"name": "right", "where": {"axis": "x", "at": L}, "components": ["z"]},
                    {"where": {"axis": "y", "at": 0.0}, "components": ["y"]},
                    {"where": {"box": [[0.45, 0.0, 0.0], [0.55, H, 0.0]]}, "components": ["x"]}],
            "load": [{"type": "gravity", "g": [0.0, 0.0, -G]},
                     {"type": "traction", "where": {"box": [[0.6, 0.0, H], [0.8, H, H]]},
                      "value": [0.0, 0.0, -5000.0]}],
            "output": {"fields": False, "picture": False}}


@pytest.mark.parametrize("cells, degree", [((20, 2, 4), 2), ((20, 2, 2), 1)])
def test_beam_on_two_supports_splits_the_load_by_the_lever_rule(cells, degree):
    s = ff.solve_static(ff.Scene.from_dict(two_supports(cells, degree))).summary()
    W, P, xc = RHO * G * L * H * H, 5000.0 * 0.2 * H, 0.7
    right = (W * L / 2 + P * xc) / L
    assert list(s["reactions"]) == ["left", "right", "fix2", "fix3"]
    np.testing.assert_allclose(s["reactions"]["right"], [0.0, 0.0, right], atol=1e-8 * (W + P))
    np.testing.assert_allclose(s["reactions"]["left"], [0.0, 0.0, W + P - right], atol=1e-8 * (W + P))
    for free in ("fix2", "fix3"):                                  # no horizontal load
        np.testing.assert_allclose(s["reactions"][free], 0.0, atol=1e-8 * (W + P))
    assert s["equilibrium_error"] < 1e-8


def test_support_names():
    d = two_supports()
    d["fix"][2]["name"] = "side"
    sc = ff.Scene.from_dict(d)
    from fem_forms.scene.spec import fix_names
    assert fix_names(sc.fix) == ["left", "right", "side", "fix3"]
    d["fix"][2]["name"] = "fix3"                     # the default name of the next, unnamed support
    with pytest.raises(InputError, match=r"fix\[3\]\.name: 'fix3' already names fix\[2\]"):
        ff.Scene.from_dict(d)
    d["fix"][2]["name"] = 3
    with pytest.raises(InputError, match=r"fix\[2\]\.name = 3: must be a string"):
        ff.Scene.from_dict(d)


@pytest.mark.mpi
def test_two_ranks_give_the_serial_reactions(tmp_path):
    d = two_supports(cells=(20, 2, 2))
    d["load"].append({"type": "traction", "where": {"axis": "x", "at": L}, "value": [0.0, 0.0, -T]})
    d["output"]["probes"] = {"top": [0.5, 0.0, H]}
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    serial = ff.solve_static(ff.Scene.from_file(path)).summary()
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr
    par = json.loads((tmp_path / "out" / "results.json").read_text())
    assert par["mpi_ranks"] == 2
    scale = np.linalg.norm(serial["applied_load"])
    for name, force in serial["reactions"].items():
        np.testing.assert_allclose(par["reactions"][name], force, rtol=1e-8, atol=1e-9 * scale)
    np.testing.assert_allclose(par["probes"]["top"]["stress"], serial["probes"]["top"]["stress"],
                               rtol=1e-7, atol=1e-7 * abs(serial["probes"]["top"]["stress"][0][0]))
    assert par["probes"]["top"]["von_mises"] == pytest.approx(serial["probes"]["top"]["von_mises"], rel=1e-7)


def test_equilibrium_error_is_relative_only_above_round_off():
    """A ratio of two round-off numbers is no error: below 1e3 x the accepted residual the relative error is
    None and the absolute imbalance stands alone; above it the ratio is the imbalance over the larger side."""
    from fem_forms.output.reactions import equilibrium_error, equilibrium_imbalance
    tiny_r, tiny_f = np.array([[1e-13, 0.0, 0.0]]), np.array([-0.16e-13, 0.0, 0.0])
    assert equilibrium_error(tiny_r, tiny_f, noise=1e-12) is None
    assert equilibrium_imbalance(tiny_r, tiny_f) == pytest.approx(0.84e-13)
    real_r, real_f = np.array([[10.0, 0.0, 0.0], [0.0, 5.0, 0.0]]), np.array([-10.0, -5.0 + 1e-9, 0.0])
    assert equilibrium_error(real_r, real_f, noise=1e-12) == pytest.approx(1e-9 / 15.0)
    assert equilibrium_error(np.zeros((1, 3)), np.zeros(3)) is None
