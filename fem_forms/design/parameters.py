"""The rest-shape design: what an inverse method returns, and the target it aims at."""
from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace

from dolfinx import fem
import ufl

from fem_forms.meshes import LoadedMesh
from fem_forms.scene import MeshSpec, Scene


@dataclass
class InverseResult:
    method: str
    v: fem.Function                 # rest minus target position, on the target mesh
    loaded: LoadedMesh
    converged: bool
    iterations: int
    message: str = ""
    history: list = field(default_factory=list)
    solve_time: float = 0.0
    forward_solves: int = 0
    # deformed minus target position at the design's own equilibrium (None: exactly the target, as
    # for the direct method); the adjoint method's partial or regularised goals leave a mismatch
    deformed_offset: fem.Function | None = None
    physics: list = field(default_factory=list)     # names of the terms in the design's forms
    # direct method: the inverse residual at the target under the full load (rest = target); its Newton
    # stopped at snes_rtol of it, which is what the forward check's equilibrium test holds it to
    residual_scale: float = 0.0
    carving: object = None          # [balance] in an inverse scene: the carving designed on the target
    cavities: dict = field(default_factory=dict)   # direct method: each inflated cavity's designed numbers
    free_direction: object = None   # standing on obstacles: the table's normal, along which the part rests where
                                    # the barrier holds it (the mismatch's mean along it is not the design's)


def target_scene(scene: Scene) -> MeshSpec:
    """The target shape's mesh: [inverse] target if given, else the scene's mesh."""
    if scene.inverse.target is not None:
        return MeshSpec(generator="file", file=scene.inverse.target)
    return scene.mesh



def one_point_scene(scene: Scene, mesh) -> Scene | None:
    """The scene with one quadrature point per cell, where that is exact for the inverse forms: P1 on
    straight-sided tetrahedra (F, det G and the stresses cellwise constant, the test functions linear),
    unless the scene sets its own quadrature degree. None where it would not be exact. Measured on the
    Chen-size arm: the design 1.6 -> 1.4 s CPU, the rest shape the same to 2e-16 relative."""
    disc = scene.discretization
    if (disc.quadrature_degree is not None or disc.degree != 1 or mesh.topology.cell_name() != "tetrahedron"
            or mesh.ufl_domain().ufl_coordinate_element().degree() != 1):
        return None
    one = copy.copy(scene)
    one.discretization = replace(disc, quadrature_degree=1)
    return one


def cellwise_exact(form: ufl.Form, unknown: fem.Function) -> bool:
    """Whether every coefficient of `form` other than the P1 unknown is cellwise constant (DG0), so that
    its integrand is a polynomial of degree <= 1 in each straight-sided cell (a one-point rule is exact)."""
    return all(c is unknown or c.ufl_element().degree() == 0 for c in form.coefficients())
