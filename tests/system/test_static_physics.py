"""System tests of static equilibrium against independent references: patch test, uniaxial tension and
hydrostatic pressure (closed-form neo-Hookean solutions), Euler-Bernoulli cantilever, the StVK limit load (Taylor tests of the forms: unit/test_form_derivatives.py)."""
import numpy as np
import pytest
from dolfinx import fem, mesh as dmesh
from scipy.optimize import brentq

import fem_forms as ff
from fem_forms.solvers import continuation, snes
from fem_forms.model import build_model
from helpers import E, LMBDA, MU, beam_scene, block_scene, uniaxial_stretches


@pytest.mark.parametrize("cell, degree", [("tetrahedron", 1), ("tetrahedron", 2), ("hexahedron", 1),
                                          ("hexahedron", 2)])
def test_patch_test_reproduces_homogeneous_deformation(cell, degree):
    """Affine displacement on the whole boundary of a distorted mesh: the solution is affine, exactly."""
    scene = block_scene(cell, degree, [], cells=(3, 3, 3))
    scene.fix = []
    model = build_model(scene)
    x = model.mesh.geometry.x
    interior = np.all((x > 1e-9) & (x < 1 - 1e-9), axis=1)
    rng = np.random.default_rng(0)
    x[interior] += rng.uniform(-0.08, 0.08, size=(interior.sum(), 3))     # distort interior nodes
    A = np.array([[0.15, 0.05, -0.02], [0.03, -0.10, 0.04], [0.00, 0.06, 0.08]])  # F = I + A
    g = fem.Function(model.V)
    g.interpolate(lambda X: A @ X)
    tdim = model.mesh.topology.dim
    model.mesh.topology.create_connectivity(tdim - 1, tdim)
    facets = dmesh.exterior_facet_indices(model.mesh.topology)
    bcs = [fem.dirichletbc(g, fem.locate_dofs_topological(model.V, tdim - 1, facets))]
    problem = snes.NonlinearProblem(model.u, model.residual, model.jacobian, bcs, energy=model.energy)
    report = continuation.solve(problem, {"snes_rtol": 1e-12})
    assert report.converged
    err = np.abs(model.u.x.array - g.x.array).max()
    assert err < 1e-10


@pytest.mark.parametrize("cell, degree", [("tetrahedron", 1), ("hexahedron", 2)])
def test_uniaxial_tension_matches_analytic_neo_hookean(cell, degree):
    T = 0.4 * E                               # large: stretch about 1.35
    size = (2.0, 1.0, 0.5)
    scene = block_scene(cell, degree, [{"type": "traction", "where": {"axis": "x", "at": 2.0},
                                        "value": [T, 0.0, 0.0]}], size=size)
    scene.solver.steps = 2
    res = ff.solve_static(scene)
    assert res.report.converged
    l1, l2 = uniaxial_stretches(T)
    assert l1 > 1.3
    expect = [(l1 - 1) * size[0], (l2 - 1) * size[1], (l2 - 1) * size[2]]
    np.testing.assert_allclose(res.probes["corner"], expect, rtol=1e-8)


def test_follower_pressure_gives_analytic_hydrostatic_compression():
    """Pressure p on the deformed faces x=1, y=1, z=1 of a unit cube on rollers: F = l I with
    Cauchy stress -p I, i.e. (mu (l^2 - 1) + 3 lambda ln l) / l^3 = -p. A dead load would differ."""
    p = 0.5 * E
    loads = [{"type": "pressure", "where": {"axis": a, "at": 1.0}, "value": p} for a in "xyz"]
    scene = block_scene("tetrahedron", 1, loads)
    scene.solver.steps = 2
    res = ff.solve_static(scene)
    assert res.report.converged
    lam = brentq(lambda s: (MU * (s**2 - 1) + 3 * LMBDA * np.log(s)) / s**3 + p, 0.3, 1.0, xtol=1e-15)
    np.testing.assert_allclose(res.probes["corner"], [lam - 1] * 3, rtol=1e-8)
    dead_lam = brentq(lambda s: (MU * (s**2 - 1) + 3 * LMBDA * np.log(s)) / s**3 + p / s**2, 0.3, 1.0)
    assert abs(dead_lam - lam) > 1e-2          # the test can tell follower from dead load


def test_cantilever_under_gravity_matches_euler_bernoulli_with_p2():
    """Small load, slender beam (1 x 0.05 x 0.05, nu = 0): tip sag w L^4 / (8 E I), with the
    Timoshenko shear correction (0.2 % here) added to the reference."""
    L, h, Eb, rho, g = 1.0, 0.05, 1.0e9, 1000.0, 9.81
    scene = ff.Scene.from_dict(beam_scene(
        mesh={"generator": "box", "size": [L, h, h], "cells": [20, 2, 2]},
        material={"model": "neo-hookean", "E": Eb, "nu": 0.0, "rho": rho},
        discretization={"degree": 2},
        output={"probes": {"tip": [L, h / 2, h / 2]}}))
    res = ff.solve_static(scene)
    assert res.report.converged
    A, I = h * h, h**4 / 12
    w = rho * g * A
    eb = w * L**4 / (8 * Eb * I)
    timoshenko = eb + w * L**2 / (2 * (5 / 6) * (Eb / 2) * A)
    sag = -res.probes["tip"][2]
    assert sag == pytest.approx(timoshenko, rel=0.01)
    assert sag == pytest.approx(eb, rel=0.01)


def test_crushing_a_stvk_block_past_its_limit_load_is_reported_at_its_last_accepted_state():
    """StVK in uniaxial compression (nu = 0) carries at most |P| = E / (3 sqrt 3) (at stretch 1/sqrt 3).
    Asking for twice E under load control must fail (inverted elements seen, not converged), having reached the
    limit load; the numbers reported are those of the last accepted state, on StVK's uniaxial curve
    P = E/2 l (1 - l^2)."""
    scene = block_scene("tetrahedron", 1, [{"type": "traction", "where": {"axis": "x", "at": 1.0},
                                            "value": [-2 * E, 0.0, 0.0]}])
    scene.material.model, scene.material.nu = "stvk", 0.0
    scene.solver.max_cutbacks, scene.solver.control = 8, "load"
    res = ff.solve_static(scene)
    assert not res.report.converged
    assert "inverted elements" in res.report.message
    limit = E / (3 * np.sqrt(3))
    reached = res.report.load_reached * 2 * E
    assert 0.97 * limit < reached <= limit * (1 + 1e-5)      # equilibrium accepted at 1e-6 residual
    stretch = 1.0 - res.max_displacement                     # the unit block's end moved by 1 - l
    assert E / 2 * stretch * (1 - stretch**2) == pytest.approx(reached, rel=1e-4)
