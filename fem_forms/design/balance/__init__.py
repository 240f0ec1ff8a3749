"""Balance design's machinery, shared by balance scenes and inverse scenes with [balance]: the carvable body and
its mass properties (body.py), the linear programs of each goal (goals.py, lp.py, rows.py, sifting.py), the
binary design (design.py) and its check from the binary carving's own mass properties (evaluate.py). Here: the
design's setting from a scene and the stiffness a carving leaves each cell."""
from __future__ import annotations

import numpy as np

from fem_forms.design.balance.body import Body
from fem_forms.design.balance.design import Setting
from fem_forms.meshes import mesh_size
from fem_forms.physics.regions import MaterialRegions
from fem_forms.scene import Scene


def gravity(scene: Scene) -> np.ndarray:
    """[balance] gravity, else the scene's gravity load, else -z."""
    g = scene.balance.gravity or next((ld.g for ld in scene.load if ld.type == "gravity"), [0.0, 0.0, -9.81])
    return np.asarray(g, dtype=float)


def setting(scene: Scene, mesh, loaded=None) -> Setting:
    """The design's densities (one per owned cell of `loaded` with several materials), gravity and size."""
    rho = scene.material.rho
    if scene.several_materials:
        regions = MaterialRegions(loaded, scene.materials)
        rho = regions.cell_values([m.rho for m in scene.materials])[:regions.n_owned]
    return Setting(scene.balance, rho, gravity(scene), mesh_size(mesh))


def stiffness_factors(body: Body, solid: np.ndarray, fill_stiffness: float) -> np.ndarray:
    """Per owned cell: 1 for solid cells, `fill_stiffness` for carved ones."""
    f = np.ones(len(body.ids))
    f[body.carvable] = np.where(solid > 0.5, 1.0, fill_stiffness)
    return f
