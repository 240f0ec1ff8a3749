"""Extremes of material, load, mesh and tolerance: each converges to the right answer or fails with a
clear report; none gives NaN or a silent wrong answer."""
import math

import numpy as np
import pytest
from dolfinx import fem, mesh as dmesh

import fem_forms as ff
from fem_forms.solvers import continuation, snes
from fem_forms.model import build_model
from helpers import beam_scene, uniaxial_stretches, block_scene, E as E_BLOCK


def sag_scene(E):
    return ff.Scene.from_dict(beam_scene(
        mesh={"generator": "box", "size": [1.0, 0.05, 0.05], "cells": [16, 2, 2]},
        material={"model": "neo-hookean", "E": E, "nu": 0.3, "rho": 1000.0},
        discretization={"degree": 2}, solver={"steps": 1, "max_cutbacks": 10},
        output={"probes": {"tip": [1.0, 0.025, 0.025]}}))


def hanging_bar_drop(E, nu=0.3, rho=1000.0, g=9.81, L=1.0) -> float:
    """Tip drop of a neo-Hookean bar hanging from its end under its own weight (1D uniaxial theory,
    lateral faces free): int_0^L stretch(P = rho g (L - X)) dX. Independent of the FE code."""
    from scipy.integrate import quad
    from scipy.optimize import brentq
    from fem_forms.materials import lame_from_young_poisson
    mu, lm = lame_from_young_poisson(E, nu)

    def lateral(l1):
        return brentq(lambda s: mu * (s - 1 / s) + lm * np.log(l1 * s * s) / s, 1e-8, 1.0 + 1e-12)

    def axial_stress(l1):
        l2 = lateral(l1)
        return mu * (l1 - 1 / l1) + lm * np.log(l1 * l2 * l2) / l1

    def stretch(P):
        return 1.0 if P <= 0 else brentq(lambda l1: axial_stress(l1) - P, 1.0, 1e5)
    return quad(lambda X: stretch(rho * g * (L - X)), 0, L, limit=200)[0]


@pytest.mark.parametrize("E", [1e11, 1e8, 1e6, 1e4, 1e2])
def test_young_modulus_from_1e2_to_1e11_pa(E):
    """Same beam and gravity over nine decades of stiffness. Stiff: Euler-Bernoulli. Soft: the beam
    hangs from its clamp like a rope and stretches (to 128 m at 100 Pa, in neo-Hookean theory with the
    weight per reference volume): 1D hanging-bar theory. Nothing is NaN; a failure must be reported."""
    I, w = 0.05**4 / 12, 1000 * 9.81 * 0.05**2
    scene = sag_scene(E)
    if E <= 1e2:
        scene.mesh.cells = [8, 1, 1]            # 1,000+ Newton steps up to stretch 250: keep it small
    res = ff.solve_static(scene)
    assert res.report.converged, res.report.message
    tip = np.array(res.probes["tip"])
    assert np.all(np.isfinite(tip))
    if E >= 1e8:
        assert -tip[2] == pytest.approx(w / (8 * E * I), rel=0.02)
    elif E <= 1e4:
        assert -tip[2] == pytest.approx(hanging_bar_drop(E), rel=0.01)
        assert tip[0] == pytest.approx(-1.0, abs=0.03)                 # it hangs straight down
    else:
        assert 0.2 < -tip[2] < 1.0                                      # large sag, still a cantilever


def test_bar_stretched_to_twice_its_length():
    """Uniaxial dead load giving stretch 2 (analytic neo-Hookean) is reached through continuation."""
    from fem_forms.materials import lame_from_young_poisson
    mu, lmbda = lame_from_young_poisson(E_BLOCK, 0.3)
    l1 = 2.0
    from scipy.optimize import brentq
    l2 = brentq(lambda s: mu * (s - 1 / s) + lmbda * np.log(l1 * s * s) / s, 0.3, 1.0)
    T = mu * (l1 - 1 / l1) + lmbda * np.log(l1 * l2 * l2) / l1
    scene = block_scene("hexahedron", 1, [{"type": "traction", "where": {"axis": "x", "at": 1.0},
                                           "value": [T, 0.0, 0.0]}])
    scene.solver.steps = 1
    res = ff.solve_static(scene)
    assert res.report.converged
    assert uniaxial_stretches(T)[0] == pytest.approx(2.0, rel=1e-9)
    np.testing.assert_allclose(res.probes["corner"], [l1 - 1, l2 - 1, l2 - 1], rtol=1e-8)


def test_mesh_with_sliver_cells_still_passes_the_patch_test(tmp_path):
    """Delaunay of a jittered grid is full of slivers (near-flat tetrahedra); the solver must still
    reproduce a homogeneous deformation exactly."""
    import meshio
    from scipy.spatial import Delaunay
    g = np.linspace(0, 1, 4)
    pts = np.array([[x, y, z] for x in g for y in g for z in g])
    rng = np.random.default_rng(2)
    pts += rng.uniform(-1e-3, 1e-3, pts.shape)       # general position: no exactly flat cells
    tets = Delaunay(pts).simplices
    p = pts[tets]
    signed = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
    tets[signed < 0] = tets[signed < 0][:, [0, 2, 1, 3]]          # one orientation for all cells
    p = pts[tets]
    vol = np.abs(np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))) / 6
    edge = np.max([np.linalg.norm(p[:, i] - p[:, j], axis=1) for i in range(4) for j in range(i)], axis=0)
    quality = vol / (edge**3 / (6 * np.sqrt(2)))                  # 1 for a regular tetrahedron
    assert quality.min() < 0.01                                   # there are slivers
    meshio.write(tmp_path / "slivers.vtu", meshio.Mesh(pts, [("tetra", tets)]))
    scene = ff.Scene.from_dict(beam_scene(mesh={"generator": "file", "file": str(tmp_path / "slivers.vtu")},
                                          load=[], fix=[], output={"probes": {}}))
    model = build_model(scene)
    A = np.array([[0.2, 0.05, 0.0], [0.0, -0.1, 0.03], [0.02, 0.0, 0.1]])
    g_ = fem.Function(model.V)
    g_.interpolate(lambda X: A @ X)
    model.mesh.topology.create_connectivity(2, 3)
    facets = dmesh.exterior_facet_indices(model.mesh.topology)
    bcs = [fem.dirichletbc(g_, fem.locate_dofs_topological(model.V, 2, facets))]
    report = continuation.solve(snes.NonlinearProblem(model.u, model.residual, model.jacobian, bcs,
                                                  energy=model.energy))
    assert report.converged
    assert np.abs(model.u.x.array - g_.x.array).max() < 1e-9


def test_tolerance_1e_14_converges_on_step_size_with_the_same_answer():
    loose = ff.solve_static(sag_scene(1e6))
    tight_scene = sag_scene(1e6)
    tight_scene.solver.petsc = {"snes_rtol": 1e-14, "snes_atol": 0.0}
    tight = ff.solve_static(tight_scene)
    assert loose.report.converged and tight.report.converged
    np.testing.assert_allclose(tight.probes["tip"], loose.probes["tip"], rtol=1e-7)
    assert tight.report.residual_norm <= loose.report.residual_norm * 1.01


def test_tolerance_1e_14_without_a_step_test_fails_clearly():
    """With the step-size test switched off, a residual below round-off cannot be reached: the solve
    must report failure (or stop at the floor), never loop forever or invent an answer."""
    scene = sag_scene(1e6)
    scene.solver.petsc = {"snes_rtol": 1e-16, "snes_stol": 0.0, "snes_max_it": 30}
    scene.solver.max_cutbacks = 1
    res = ff.solve_static(scene)
    if res.report.converged:
        ref = ff.solve_static(sag_scene(1e6))
        np.testing.assert_allclose(res.probes["tip"], ref.probes["tip"], rtol=1e-7)
    else:
        assert "no convergence" in res.report.message and math.isnan(res.max_displacement)
