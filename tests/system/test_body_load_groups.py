"""Gravity on a gmsh volume group: only that part weighs. The clamp's reaction must equal the group's
weight rho g V_group (statics: the only load), independently of the elastic solution."""
import gmsh
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.errors import InputError

L, H, SPLIT, RHO, G = 1.0, 0.1, 0.4, 1000.0, 9.81


def two_volume_beam(path):
    """A beam of two gmsh volumes: 'heavy' (x < SPLIT) and 'light' (beyond), one conforming mesh."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    a = occ.addBox(0, 0, 0, SPLIT, H, H)
    b = occ.addBox(SPLIT, 0, 0, L - SPLIT, H, H)
    occ.fragment([(3, a)], [(3, b)])
    occ.synchronize()
    eps = 1e-6
    heavy = [t for _, t in gmsh.model.getEntitiesInBoundingBox(-eps, -eps, -eps, SPLIT + eps, H + eps, H + eps, 3)]
    light = [t for _, t in gmsh.model.getEntitiesInBoundingBox(SPLIT - eps, -eps, -eps, L + eps, H + eps, H + eps, 3)]
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, heavy), "heavy")
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, light), "light")
    gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.05)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(path))
    gmsh.finalize()


def scene(mesh_file, gravity_where=None) -> dict:
    load = {"type": "gravity", "g": [0.0, 0.0, -G]}
    if gravity_where is not None:
        load["where"] = gravity_where
    return {"title": "weight of one part", "mesh": {"generator": "file", "file": str(mesh_file)},
            "material": {"model": "neo-hookean", "E": 1e8, "nu": 0.3, "rho": RHO},
            "discretization": {"degree": 1},
            "fix": [{"name": "clamp", "where": {"axis": "x", "at": 0.0}}], "load": [load],
            "output": {"picture": False}}


@pytest.fixture(scope="module")
def mesh_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("mesh") / "two_volumes.msh"
    two_volume_beam(path)
    return path


@pytest.mark.parametrize("group, volume", [("heavy", SPLIT * H * H), ("light", (L - SPLIT) * H * H),
                                           (None, L * H * H)])
def test_the_clamp_carries_the_weight_of_the_loaded_group(mesh_file, tmp_path, group, volume):
    where = None if group is None else {"group": group}
    result = ff.solve_static(ff.Scene.from_dict(scene(mesh_file, where)))
    assert result.report.converged
    summary = ff.write_static_outputs(result, tmp_path / "out")
    assert summary["reactions"]["clamp"][2] == pytest.approx(RHO * G * volume, rel=1e-8)
    assert np.allclose(summary["reactions"]["clamp"][:2], 0.0, atol=1e-8 * RHO * G * volume)


def test_gravity_on_a_missing_or_surface_group_is_one_clear_line(mesh_file):
    with pytest.raises(InputError, match="no such volume group"):
        ff.solve_static(ff.Scene.from_dict(scene(mesh_file, {"group": "nowhere"})))
    with pytest.raises(InputError):
        ff.Scene.from_dict(scene(mesh_file, {"axis": "x", "at": 0.0}))
