"""The two-material layout design's gradient (issue 52 item 3, its first part): J(rho), the probes' mismatch at the
equilibrium of a beam whose cells mix a soft and a stiff neo-Hookean solid by the SIMP weight of the filtered
density, and dJ/drho by one adjoint solve. Checked against finite differences (the Taylor remainder
|J(rho + h d) - J(rho) - h g.d| falls as h^2 only if g is the true gradient) and on 2 ranks (the same J and the
same gradient in the design's own cell order)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from tests.helpers import mpirun  # noqa: E402


def measure() -> dict:
    """J, the gradient along a random direction and the Taylor remainders at h = 0.1, 0.05, 0.025 (a random
    layout between 0.3 and 0.7, a filter of 1.5 cells)."""
    from dolfinx import fem
    from mpi4py import MPI
    import fem_forms as ff
    from fem_forms.analyses.static.solve import solve_static
    from fem_forms.design.layout import CellVector, LayoutGradient, LayoutMaterial, TargetPoints, part_length
    from fem_forms.materials.constants import bind_constants
    from fem_forms.materials.hyperelastic import NeoHookean
    from fem_forms.meshes import load_mesh
    from fem_forms.model import build_model
    scene = ff.Scene.from_dict({
        "title": "layout", "mesh": {"size": [0.1, 0.02, 0.02], "cells": [10, 2, 2]},
        "material": {"model": "neo-hookean", "E": 1e5, "nu": 0.3, "rho": 1000.0},
        "fix": [{"where": {"axis": "x", "at": 0.0}}], "load": [{"type": "gravity", "g": [0, 0, -9.81]}],
        "solver": {"steps": 1}, "output": {"picture": False, "fields": False}})
    loaded = load_mesh(scene.mesh, MPI.COMM_WORLD, degree=1)
    weight = fem.Function(fem.FunctionSpace(loaded.mesh, ("DG", 0)))
    soft = scene.material.material
    stiff = NeoHookean(mu=10 * soft.mu, lmbda=10 * soft.lmbda)
    model = build_model(scene, LayoutMaterial(bind_constants(soft, loaded.mesh), bind_constants(stiff, loaded.mesh),
                                              weight), loaded=loaded)
    cells = CellVector(weight.function_space)
    tip = np.array([[0.1, 0.01, 0.01]])
    targets = TargetPoints(model.V, tip, tip + [0.0, 0.0, -0.006], part_length(model))
    design = LayoutGradient(model, weight, cells, targets, radius=0.015, penalty=3.0,
                            solve=lambda m: solve_static(scene, model=m).report)
    rng = np.random.default_rng(1)
    rho = 0.3 + 0.4 * rng.random(cells.size)
    direction = rng.standard_normal(cells.size)
    J0 = design.value(rho)
    g = design.gradient(rho)
    remainders = [abs(design.value(rho + h * direction) - J0 - h * g @ direction) for h in (0.1, 0.05, 0.025)]
    return {"J": J0, "g_dot_d": float(g @ direction), "g_norm": float(np.linalg.norm(g)), "remainders": remainders,
            "cells": cells.size}


def test_layout_gradient_passes_the_taylor_test_on_one_and_two_ranks():
    serial = measure()
    rates = np.log2(np.array(serial["remainders"][:-1]) / serial["remainders"][1:])
    assert np.all(np.abs(rates - 2.0) < 0.1), rates                  # measured 1.99, 2.00
    assert serial["remainders"][-1] < 0.05 * abs(0.025 * serial["g_dot_d"])   # the linear term dominates (1.3 %)
    p = mpirun([__file__])
    assert p.returncode == 0, p.stderr
    two = json.loads(p.stdout.strip().splitlines()[-1])
    assert two["cells"] == serial["cells"]
    assert abs(two["J"] - serial["J"]) < 1e-10 * serial["J"]
    assert abs(two["g_dot_d"] - serial["g_dot_d"]) < 1e-8 * abs(serial["g_dot_d"])
    assert abs(two["g_norm"] - serial["g_norm"]) < 1e-8 * serial["g_norm"]


if __name__ == "__main__":
    from mpi4py import MPI
    out = measure()
    if MPI.COMM_WORLD.rank == 0:
        print(json.dumps(out))
