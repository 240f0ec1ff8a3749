"""Inverse rest-shape design against independent references: a forward solve from the designed rest
shape (and a static run of its file) must land on the target; methods agree; Taylor test of the adjoint
gradient; continuation for soft materials; MPI parity; unusable designs refused (bad settings: unit/test_inverse_input.py)."""

import numpy as np
import pytest
from mpi4py import MPI

import fem_forms as ff
from fem_forms.analyses import inverse
from fem_forms.design.adjoint import AdjointDesign
from fem_forms.design.forward_on_rest import ForwardOnRest
from helpers import inverse_beam, run_scene, serial_and_two_ranks

comm = MPI.COMM_WORLD


def test_direct_round_trip_on_a_soft_beam(tmp_path):
    """Soft silicone beam (E 1 MPa): the rest shape curls up by ~0.8 m; the forward solve from the
    written rest mesh reproduces the target to 1e-8 relative (exact discrete inverse for P1)."""
    code, data, _, out = run_scene(tmp_path, inverse_beam(E=1e6, cells=(20, 2, 2)))
    assert code == 0 and data["usable"]
    assert data["max_rest_offset"] > 0.6
    assert data["target_mismatch_max"] <= 1e-8 * data["max_rest_offset"]
    assert data["probes"]["tip"]["rest_position"][2] > 0.5           # the tip is cast high up
    for f in ("rest_shape.msh", "rest_shape.stl", "inverse.png", "fields.xdmf"):
        assert (out / f).stat().st_size > 0
    # what a user fabricates is the file: a static run of rest_shape.msh (generator = "file", loads ramped
    # from the rest shape) carries the tip's rest position onto the target's tip
    rest_tip = data["probes"]["tip"]["rest_position"]
    static = inverse_beam(E=1e6, cells=(20, 2, 2))
    del static["analysis"], static["inverse"]
    static["mesh"] = {"generator": "file", "file": str(out / "rest_shape.msh")}
    static["output"] = {"probes": {"tip": rest_tip}, "fields": [], "picture": False}
    (tmp_path / "static").mkdir()
    code, sdata, _, _ = run_scene(tmp_path / "static", static)
    assert code == 0 and sdata["mesh"]["cells"] == 20 * 2 * 2 * 6
    landed = np.add(rest_tip, sdata["probes"]["tip"]["displacement"])
    assert np.linalg.norm(landed - [1.0, 0.05, 0.05]) <= 1e-8 * data["max_rest_offset"]
    stl = (out / "rest_shape.stl").read_text()
    assert stl.count("facet normal") == 2 * 2 * (20 * 2 + 20 * 2 + 2 * 2) * 2 // 2


def test_direct_round_trip_on_a_gmsh_goblet(tmp_path):
    """A revolved goblet-like profile standing on its base under gravity (soft: E 0.5 MPa)."""
    d = inverse_beam(E=5e5)
    d["mesh"] = {"generator": "revolve", "h": 0.02,
                 "profile": [[0.0, 0.0], [0.06, 0.0], [0.06, 0.01], [0.02, 0.02], [0.02, 0.10],
                             [0.06, 0.16], [0.05, 0.16], [0.0, 0.12]]}
    d["fix"] = [{"where": {"group": "bottom"}}]
    d["output"] = {"probes": {"rim": [0.055, 0.0, 0.159]}}
    code, data, _, _ = run_scene(tmp_path, d)
    assert code == 0 and data["usable"], data
    assert data["target_mismatch_max"] <= 1e-8 * data["max_rest_offset"]
    assert data["max_rest_offset"] > 3e-4                           # a visible correction (0.6 mm)


def test_adjoint_matches_direct_and_fixed_point_agrees(tmp_path):
    """Where every point is matched, the adjoint optimum is the exact inverse: within 1e-4."""
    scene = ff.Scene.from_dict(inverse_beam(E=3e6))
    direct = inverse.design_rest_shape(scene)
    scene.inverse.method = "adjoint"
    adjoint = inverse.design_rest_shape(scene)
    scene.inverse.method, scene.inverse.optimizer = "adjoint", "lbfgs"
    scene.inverse.iterations = 400
    lbfgs = inverse.design_rest_shape(scene)
    scene.inverse.method = "fixed-point"
    fixed = inverse.design_rest_shape(scene)
    assert direct.converged and adjoint.converged and fixed.converged
    ref = np.abs(direct.v.x.array).max()
    assert ref > 0.05
    assert np.abs(adjoint.v.x.array - direct.v.x.array).max() <= 1e-4 * ref
    assert np.abs(fixed.v.x.array - direct.v.x.array).max() <= 1e-6 * ref
    # TAO's L-BFGS makes progress but stalls in its line search on this bending problem (see docs/analyses/inverse.md)
    assert lbfgs.history[-1]["J"] < 0.1 * lbfgs.history[0]["J"]


def test_adjoint_designs_the_soft_beam():
    """E 1 MPa (the rest shape curls up): damped Gauss-Newton lands on the exact inverse (the direct
    design) within 1e-4, in a few dozen forward solves (the undamped line-search version needed 165)."""
    scene = ff.Scene.from_dict(inverse_beam(E=1e6, cells=(20, 2, 2)))
    direct = inverse.design_rest_shape(scene)
    scene.inverse.method = "adjoint"
    adjoint = inverse.design_rest_shape(scene)
    assert direct.converged and adjoint.converged, adjoint.message
    ref = comm.allreduce(np.abs(direct.v.x.array).max(), op=MPI.MAX)
    assert ref > 0.3
    assert comm.allreduce(np.abs(adjoint.v.x.array - direct.v.x.array).max(), op=MPI.MAX) <= 1e-4 * ref
    assert adjoint.forward_solves <= 40


def region_design(cells=(20, 2, 2)) -> dict:
    """Soft beam whose outer fifth alone must keep its target place, with a smooth rest shape."""
    return inverse_beam(E=1e6, method="adjoint", cells=cells, smoothness=1e-2,
                        match_region={"box": [[0.8, 0.0, 0.0], [1.0, 0.1, 0.1]]})


def test_region_matching_design_lands_where_it_predicted(tmp_path):
    """Only the region is matched: the forward solve from the written rest shape lands on the shape
    the design predicted, the region within a small fraction of the uncorrected sag of the target,
    while the unmatched rest of the body may stay off the target."""
    from fem_forms.analyses.static.solve import solve_static
    d = region_design()
    code, data, _, _ = run_scene(tmp_path, d)
    assert code == 0, data["problems"]
    static = ff.Scene.from_dict({k: v for k, v in d.items() if k != "inverse"} | {"analysis": "static"})
    sag = abs(solve_static(static).probes["tip"][2])           # the target itself, uncorrected
    assert sag > 0.3
    assert data["design_gap_max"] < 1e-6
    assert data["matched_mismatch_max"] < 0.01 * sag
    assert data["target_mismatch_max"] > 10 * data["matched_mismatch_max"]


def adjoint_taylor(pressed: bool = False) -> tuple[np.ndarray, float, float]:
    """(Taylor rates of |J(d + h p) - J(d) - h g.p| at h = 0.4 ... 0.05, g.p, J) of a region-matching, regularised
    objective on a curled rest shape; `pressed`: the beam loaded by a follower pressure on its top face instead of
    its weight (a tangent that is not symmetric)."""
    d = inverse_beam(E=1e6, method="adjoint", match_region={"box": [[0.5, 0.0, 0.0], [1.0, 0.1, 0.1]]},
                     smoothness=1e-4, stay_close=1e-2)
    if pressed:
        d["load"] = [{"type": "pressure", "where": {"axis": "z", "at": 0.1}, "value": 100.0}]
    scene = ff.Scene.from_dict(d)
    from fem_forms.meshes import load_mesh
    loaded = load_mesh(scene.mesh)
    fwd = ForwardOnRest(scene, None, loaded)
    V = fwd.V
    design = AdjointDesign(fwd)
    rng = np.random.default_rng(3)
    X = V.tabulate_dof_coordinates()[: design.n // 3]
    d0 = np.zeros((len(X), 3))
    d0[:, 2] = 0.2 * X[:, 0] ** 2                           # a curled rest shape
    d0 = d0.ravel()
    d0[design.fixed] = 0.0
    p = rng.uniform(-0.01, 0.01, design.n)
    p[design.fixed] = 0.0
    J0, g = design.evaluate(d0)
    dJ = comm.allreduce(float(g @ p), op=MPI.SUM)
    errs = []
    for h in [0.4, 0.2, 0.1, 0.05]:
        J = design.evaluate(d0 + h * p, gradient=False)[0]
        errs.append(abs(J - J0 - h * dJ))
    return np.log2(np.array(errs[:-1]) / np.array(errs[1:])), dJ, J0


def test_adjoint_gradient_passes_the_taylor_test():
    """|J(d + h p) - J(d) - h g.p| = O(h^2) for a region-matching, regularised objective."""
    rates, dJ, J0 = adjoint_taylor()
    assert np.all(rates > 1.8), rates
    # and the gradient is not trivially small
    assert abs(dJ) > 1e-3 * abs(J0)


def test_adjoint_gradient_under_a_follower_pressure_passes_the_taylor_test():
    """The same under a follower pressure on the top face: K is not symmetric, the adjoint solves with K^T
    (measured: rates 2.015, 2.005, 2.002; with K instead the gradient along p is 0.9 % off and the rates climb,
    2.11, 2.22, 2.58, as the remainder's linear error takes over)."""
    rates, dJ, J0 = adjoint_taylor(pressed=True)
    assert np.all(np.abs(rates - 2.0) < 0.1), rates
    assert abs(dJ) > 1e-3 * abs(J0)


def test_soft_case_needs_continuation(tmp_path):
    """E 1 MPa beam: one full-load Newton solve without cut-backs fails; continuation solves it."""
    d = inverse_beam(E=1e6, cells=(40, 4, 4))
    d["solver"] = {"steps": 1, "max_cutbacks": 0}
    scene = ff.Scene.from_dict(d)
    assert not inverse.design_rest_shape(scene).converged
    scene.solver.max_cutbacks, scene.solver.steps = 12, 1
    res = inverse.design_rest_shape(scene)
    assert res.converged
    assert sum(1 for h in res.history if h["accepted"]) > 1          # it took several load steps


def test_unusable_rest_shape_is_refused(tmp_path, capsys):
    """E 0.3 MPa: the exact discrete rest shape curls back through the clamped wall; the design is
    refused with status 3 and a reason, never handed out."""
    code, data, err, out = run_scene(tmp_path, inverse_beam(E=3e5, cells=(20, 2, 2)), capsys)
    assert code == 3
    assert data["usable"] is False
    assert any("support plane x = 0.0" in p or "forward solve" in p or "did not reach" in p
               for p in data["problems"]), data["problems"]
    assert "no usable rest shape" in err


@pytest.mark.mpi
def test_two_ranks_design_the_same_rest_shape(tmp_path):
    serial, par = serial_and_two_ranks(tmp_path, inverse_beam(E=1e6, cells=(12, 2, 2)))
    np.testing.assert_allclose(par["probes"]["tip"]["rest_position"], serial["probes"]["tip"]["rest_position"],
                               rtol=1e-8, atol=1e-10)
    assert par["max_rest_offset"] == pytest.approx(serial["max_rest_offset"], rel=1e-9)
    assert par["target_mismatch_max"] < 1e-8


@pytest.mark.mpi
def test_two_ranks_give_the_same_adjoint_design(tmp_path):
    """The adjoint stops once J cannot fall by more than its precision (1e-8 relative), which pins the
    design to about 1e-4 of its size: serial and 2 ranks agree to that."""
    serial, par = serial_and_two_ranks(tmp_path, region_design(cells=(12, 2, 2)))
    np.testing.assert_allclose(par["probes"]["tip"]["rest_position"], serial["probes"]["tip"]["rest_position"],
                               rtol=0, atol=1e-4 * serial["max_rest_offset"])   # measured: 2e-5
    assert par["matched_mismatch_max"] == pytest.approx(serial["matched_mismatch_max"], rel=1e-4)


@pytest.mark.parametrize("E", [3e6, 1e6])
def test_chord_steps_land_on_newtons_rest_shape(monkeypatch, E):
    """The direct design's chord iterations (one LU per load step as the operator) give the rest shape of
    Newton with the fresh tangent; where the chord stalls (E 1 MPa: the rest shape curls up) the step is
    retried with Newton at the same size, not halved."""
    from fem_forms.design import direct
    scene = ff.Scene.from_dict(inverse_beam(E=E, cells=(20, 2, 2)))
    results = {}
    for mode in ("chord", True):
        real = direct.continuation.solve
        monkeypatch.setattr(direct.continuation, "solve", lambda *a, mode=mode, real=real, **k: real(
            *a, **{**k, "reuse_factor": mode}))
        results[mode] = direct.solve_direct(scene)
        monkeypatch.setattr(direct.continuation, "solve", real)
    chord, newton = results["chord"], results[True]
    assert chord.converged and newton.converged
    v_c, v_n = chord.v.x.array, newton.v.x.array
    assert np.abs(v_c - v_n).max() <= 1e-10 * np.abs(v_n).max()
    loads = [h["load"] for h in chord.history]
    for k, h in enumerate(chord.history):
        if not h["accepted"]:                           # a stalled chord: the same load again, with Newton
            assert "DIVERGED_MAX_IT" in h["reason"] and loads[k + 1] == loads[k]
    if E == 1e6:
        assert any(not h["accepted"] for h in chord.history)
