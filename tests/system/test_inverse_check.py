"""The inverse design's forward check (analyses/inverse/forward.py, stability.py) against independent
references: a right design is an equilibrium at the target (the P1 inverse is the exact discrete inverse
of the forward problem), a perturbed one is not; the path check agrees; the tangent's inertia counts the
negative eigenvalues a dense eigensolver finds, and a compressed column designed beyond Euler's load is
refused as unstable (clamped-free column: modes at 1 and 9 x pi^2 E I / (4 L^2), the conforming P1
discretisation only stiffer)."""
import json

import numpy as np
import pytest
from dolfinx.fem import form
from dolfinx.fem.petsc import assemble_matrix
from mpi4py import MPI

import fem_forms as ff
from fem_forms.analyses import inverse
from fem_forms.analyses.inverse.check import check_rest_shape
from fem_forms.analyses.inverse.forward import EQUILIBRIUM_NEWTON_STEPS
from helpers import inverse_beam, mpirun, run_scene, toml_dumps

comm = MPI.COMM_WORLD
E, A, L = 1e6, 0.1, 1.0
EULER_STRESS = np.pi ** 2 * E * A ** 2 / (48 * L ** 2)   # P_cr / area, clamped-free square column


def column(multiple: float) -> dict:
    """A square column clamped at x = 0, its end face pushed along -x by `multiple` x Euler's load (a dead
    traction; the box selector holds the end face of the target and of the longer rest shape)."""
    return {"title": "column", "analysis": "inverse",
            "mesh": {"generator": "box", "size": [L, A, A], "cells": [20, 2, 2]},
            "material": {"model": "neo-hookean", "E": E, "nu": 0.3, "rho": 1000.0},
            "discretization": {"degree": 1},
            "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "load": [{"type": "traction", "where": {"box": [[0.99 * L, -A, -A], [1.5 * L, 2 * A, 2 * A]]},
                      "value": [-multiple * EULER_STRESS, 0.0, 0.0]}],
            "solver": {"steps": 2}}


def designed_and_checked(d: dict, tmp_path, perturb: float = 1.0):
    scene = ff.Scene.from_dict(d)
    res = inverse.design_rest_shape(scene)
    assert res.converged
    res.v.x.array[:] *= perturb
    tmp_path.mkdir(exist_ok=True)
    return scene, check_rest_shape(scene, res, tmp_path)


def test_right_design_is_an_equilibrium_and_a_perturbed_one_is_not(tmp_path):
    """Soft beam (E 1 MPa, rest offset ~0.8 m): the target's residual is the design's own tolerance
    (measured 2.4e-8 of the rest shape's residual), one or two Newton steps bring it to 1e-9 and move the
    shape by less than 1e-8 of the offset; the rest offset scaled by 0.9 leaves a residual 180x the load's
    there, which two Newton steps cannot remove: refused. The path check refuses it too (another shape)."""
    d = inverse_beam(E=1e6, cells=(20, 2, 2))
    _, right = designed_and_checked(d, tmp_path / "right")
    s = right.solve.summary()
    assert right.problems == [] and s["kind"] == "equilibrium"
    assert s["start_residual_relative"] < 1e-6 and s["newton_iterations"] <= EQUILIBRIUM_NEWTON_STEPS
    assert right.mismatch_max <= 1e-8 * 0.6
    assert s["tangent"] == {"negative_pivots": 0, "null_pivots": 0, "stable": True}
    _, wrong = designed_and_checked(d, tmp_path / "wrong", perturb=0.9)
    assert wrong.solve.start_residual > 1e-3
    assert any("the target is not an equilibrium of the rest shape" in p for p in wrong.problems), wrong.problems
    d["inverse"]["check"] = "path"
    _, path = designed_and_checked(d, tmp_path / "path", perturb=0.9)
    assert path.solve.kind == "path" and path.mismatch_max > 0.01
    assert any("lands" in p and "from the target" in p for p in path.problems), path.problems


def test_a_design_is_accepted_where_it_stopped_and_no_looser(tmp_path):
    """One load step, P1: the design's Newton stops at snes_rtol of its residual scale or at its round-off
    floor; the check accepts the target there without a Newton step (mismatch round-off). The same rest
    shape scaled by 1 - 1e-6 is off by far more than that tolerance: Newton steps are taken."""
    d = inverse_beam(E=1e7, cells=(20, 2, 2))
    d["solver"] = {"steps": 1}
    _, right = designed_and_checked(d, tmp_path / "right")
    assert right.problems == [] and right.solve.static.report.newton_iterations == 0
    assert right.mismatch_max <= 1e-14 and right.solve.start_residual < 1e-8      # the target, to round-off
    _, near = designed_and_checked(d, tmp_path / "near", perturb=1 - 1e-6)
    assert near.problems == [] and near.solve.static.report.newton_iterations >= 1
    assert near.solve.start_residual > 100 * right.solve.start_residual


def test_path_check_lands_on_the_target(tmp_path):
    """check = "path": the forward solve ramped from the rest shape reproduces the target to 1e-8 relative,
    as the equilibrium check (default) says it must; results.json names the check that ran."""
    d = inverse_beam(E=1e6, cells=(20, 2, 2), check="path")
    code, data, _, _ = run_scene(tmp_path, d)
    assert code == 0 and data["usable"]
    assert data["forward_check"]["kind"] == "path" and data["forward_check"]["newton_iterations"] > 2
    assert data["target_mismatch_max"] <= 1e-8 * data["max_rest_offset"]
    assert data["forward_check"]["tangent"]["stable"]


def test_degree_two_checks_agree(tmp_path):
    """P2 design (E 10 MPa beam): the written straight-edged rest mesh loses the mid-edge rest positions,
    so the target is only near an equilibrium (1e-4 m, within the 1e-3 x size tolerance); Newton from
    the target (a few steps) and the load path (4 load steps, many more) find the same equilibrium."""
    found = {}
    for kind in ("equilibrium", "path"):
        d = inverse_beam(E=1e7, check=kind)
        d["discretization"] = {"degree": 2}
        _, chk = designed_and_checked(d, tmp_path / kind)
        assert chk.problems == [] and chk.solve.inertia.stable
        found[kind] = chk
    eq, path = found["equilibrium"], found["path"]
    assert 1e-6 < eq.mismatch_max < 1e-3 * 1.0
    assert eq.mismatch_max == pytest.approx(path.mismatch_max, rel=1e-6)
    assert eq.static.report.newton_iterations < path.static.report.newton_iterations
    assert np.allclose(eq.static.u.x.array, path.static.u.x.array, rtol=0, atol=1e-9)


@pytest.mark.parametrize("multiple, negative", [(0.5, 0), (5.0, 2)])
def test_inertia_counts_the_columns_buckling_modes(tmp_path, multiple, negative):
    """Below Euler's load the straight column is stable; at 5x it is an equilibrium (residual at round-off)
    but an unstable one with two negative eigenvalues (the first mode in each bending plane; the second
    mode needs 9x): refused. MUMPS's negative pivots equal the negative eigenvalues of the dense tangent."""
    _, chk = designed_and_checked(column(multiple), tmp_path)
    inertia = chk.solve.inertia
    assert chk.solve.start_residual < 1e-9
    assert inertia.negative == negative and inertia.null == 0
    model = chk.static.model
    K = assemble_matrix(form(model.jacobian), bcs=model.bcs)
    K.assemble()
    dense = comm.allgather(K.getValues(range(*K.getOwnershipRange()), range(K.getSize()[1])))
    eig = np.linalg.eigvalsh(np.vstack(dense))
    assert int(np.sum(eig < 0)) == negative
    assert (chk.problems == []) == (negative == 0)
    if negative:
        assert any("not positive definite (2 negative" in p and "unstable equilibrium" in p for p in chk.problems)


@pytest.mark.mpi
def test_two_ranks_refuse_the_unstable_column(tmp_path):
    """Under mpirun -n 2 the same two negative pivots (global inertia), exit status 3, usable false."""
    path = tmp_path / "column.toml"
    path.write_text(toml_dumps(column(5.0)))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "par")])
    assert p.returncode == 3, p.stderr
    data = json.loads((tmp_path / "par" / "results.json").read_text())
    assert data["usable"] is False and data["mpi_ranks"] == 2
    assert data["forward_check"]["tangent"] == {"negative_pivots": 2, "null_pivots": 0, "stable": False}
