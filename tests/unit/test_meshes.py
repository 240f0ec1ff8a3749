"""Meshes: gmsh generators against exact volumes (files and groups through whole solves are in
system/test_mesh_files.py)."""
import math

import pytest

from fem_forms.meshes import load_mesh
from fem_forms.scene import MeshSpec
from helpers import mesh_volume as volume


@pytest.mark.parametrize("spec, exact, rel", [
    (MeshSpec(generator="cylinder", radius=0.1, height=0.3, h=0.03), math.pi * 0.01 * 0.3, 0.02),
    (MeshSpec(generator="sphere", radius=0.2, h=0.05), 4 / 3 * math.pi * 0.008, 0.03),
    # a revolved annular step: a cylinder r<=0.1 of height 0.1 under a ring 0.05<=r<=0.1 of height 0.2
    (MeshSpec(generator="revolve", h=0.03, profile=[[0.0, 0.0], [0.1, 0.0], [0.1, 0.3], [0.05, 0.3],
                                                    [0.05, 0.1], [0.0, 0.1]]),
     math.pi * 0.01 * 0.1 + math.pi * (0.01 - 0.0025) * 0.2, 0.03),
])
def test_gmsh_generators_fill_the_exact_volume(spec, exact, rel):
    loaded = load_mesh(spec)
    assert volume(loaded.mesh) == pytest.approx(exact, rel=rel)   # faceted curved surfaces lose a little
