"""The rest-shape design: what an inverse method returns, and the target it aims at."""
from __future__ import annotations

from dataclasses import dataclass, field

from dolfinx import fem

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


def target_scene(scene: Scene) -> MeshSpec:
    """The target shape's mesh: [inverse] target if given, else the scene's mesh."""
    if scene.inverse.target is not None:
        return MeshSpec(generator="file", file=scene.inverse.target)
    return scene.mesh

