"""Supports anywhere: point and line selectors, and gmsh physical groups of every dimension (volumes,
curves, points) checked against beam theory; the same answers on 2 MPI ranks; clear one-line errors."""
import json

import numpy as np
import pytest
from mpi4py import MPI

import fem_forms as ff
from fem_forms.errors import InputError
from helpers import beam_scene, mpirun, toml_dumps

E, RHO, L, H = 1e8, 1000.0, 1.0, 0.1
W, I, G = RHO * 9.81 * H * H, H**4 / 12, E / 2          # nu = 0


def timoshenko_simply_supported(span=L) -> float:
    """Midspan sag of a simply supported beam under its weight, bending plus shear (kappa 5/6)."""
    return 5 * W * span**4 / (384 * E * I) + W * span**2 / (8 * 5 / 6 * G * H * H)


def beam(fix, mesh=None, probes=None, degree=2) -> dict:
    return beam_scene(mesh=mesh or {"generator": "box", "size": [L, H, H], "cells": [20, 2, 2]},
                      material={"model": "neo-hookean", "E": E, "nu": 0.0, "rho": RHO},
                      discretization={"degree": degree}, fix=fix,
                      output={"probes": probes or {"mid": [L / 2, H / 2, H / 2]}})


LINE_SUPPORTS = [{"where": {"line": [[0, 0, 0], [0, H, 0]]}},
                 {"where": {"line": [[L, 0, 0], [L, H, 0]]}, "components": ["z"]}]
# three points: a pin (x, y, z), a second point on the same end (x, z) and a roller (z) at the far end
POINT_SUPPORTS = [{"where": {"point": [0.0, 0.0, 0.0]}},
                  {"where": {"point": [0.0, H, 0.001]}, "components": ["x", "z"]},
                  {"where": {"point": [L, 0.051, 0.0]}, "components": ["z"]}]


def test_line_supports_give_a_simply_supported_beam():
    res = ff.solve_static(ff.Scene.from_dict(beam(LINE_SUPPORTS)))
    assert res.report.converged
    assert -res.probes["mid"][2] == pytest.approx(timoshenko_simply_supported(), rel=0.03)


def test_point_supports_hold_the_nearest_nodes():
    res = ff.solve_static(ff.Scene.from_dict(beam(POINT_SUPPORTS, degree=1,
                                                  probes={"pin": [0, 0, 0], "roller": [L, 0.05, 0.0]})))
    assert res.report.converged
    np.testing.assert_allclose(res.probes["pin"], 0.0, atol=1e-12)
    assert abs(res.probes["roller"][2]) < 1e-12           # (1, 0.05, 0) is the node nearest (1, 0.051, 0)


def _gmsh_beam(path, anchor=0.1):
    """A beam of two volumes ('anchor' x < anchor, 'beam' beyond), physical curves 'pin' and 'roller'
    (bottom edges across the ends) and a physical point 'corner' at the origin."""
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    a = occ.addBox(0, 0, 0, anchor, H, H)
    b = occ.addBox(anchor, 0, 0, L - anchor, H, H)
    occ.fragment([(3, a)], [(3, b)])
    occ.synchronize()

    def find(dim, lo, hi):
        return [t for _, t in gmsh.model.getEntitiesInBoundingBox(*lo, *hi, dim)]
    eps = 1e-6
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, find(3, (-eps, -eps, -eps), (anchor + eps, H + eps, H + eps))), "anchor")
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, find(3, (anchor - eps, -eps, -eps), (L + eps, H + eps, H + eps))), "beam")
    gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, find(1, (-eps, -eps, -eps), (eps, H + eps, eps))), "pin")
    gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, find(1, (L - eps, -eps, -eps), (L + eps, H + eps, eps))), "roller")
    gmsh.model.setPhysicalName(0, gmsh.model.addPhysicalGroup(0, find(0, (-eps, -eps, -eps), (eps, eps, eps))), "corner")
    gmsh.option.setNumber("Mesh.CharacteristicLengthMax", 0.05)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(path))
    gmsh.finalize()


@pytest.fixture
def gmsh_beam(tmp_path):
    path = tmp_path / "beam.msh"
    if MPI.COMM_WORLD.rank == 0:
        _gmsh_beam(path)
    MPI.COMM_WORLD.barrier()
    return path


def test_curve_groups_support_and_a_volume_group_clamps(gmsh_beam):
    mesh = {"generator": "file", "file": str(gmsh_beam)}
    curves = ff.solve_static(ff.Scene.from_dict(beam(
        [{"where": {"group": "pin"}}, {"where": {"group": "roller"}, "components": ["z"]}], mesh=mesh)))
    assert curves.report.converged
    assert -curves.probes["mid"][2] == pytest.approx(timoshenko_simply_supported(), rel=0.03)
    # the whole 'anchor' volume held: a cantilever of length L - 0.1 clamped at x = 0.1
    clamped = ff.solve_static(ff.Scene.from_dict(beam([{"where": {"group": "anchor"}}], mesh=mesh,
                                                      probes={"tip": [L, H / 2, H / 2], "in": [0.05, 0.05, 0.05]})))
    span = L - 0.1
    cantilever = W * span**4 / (8 * E * I) + W * span**2 / (2 * 5 / 6 * G * H * H)
    assert -clamped.probes["tip"][2] == pytest.approx(cantilever, rel=0.04)
    np.testing.assert_allclose(clamped.probes["in"], 0.0, atol=1e-14)
    # the point group holds its node
    held = ff.solve_static(ff.Scene.from_dict(beam(
        [{"where": {"group": "corner"}}, {"where": {"group": "pin"}, "components": ["z"]},
         {"where": {"group": "roller"}, "components": ["y", "z"]}], mesh=mesh,
        probes={"corner": [0.0, 0.0, 0.0]})))
    assert held.report.converged
    np.testing.assert_allclose(held.probes["corner"], 0.0, atol=1e-14)


@pytest.mark.parametrize("where, fragment", [
    ({"line": [[0, 0, 0.03], [0.0, 0.1, 0.03]]}, "fix[0].where: the line from [0.0, 0.0, 0.03] to [0.0, 0.1, 0.03] "
                                                  "passes through no mesh node"),
    ({"point": [2.0, 0.0, 0.0]}, "fix[0].where.point = [2.0, 0.0, 0.0]: lies outside the mesh"),
    ({"group": "nowhere"}, "fix[0].where.group = 'nowhere': no such group (the mesh has: none)"),
])
def test_a_selector_that_selects_nothing_is_one_clear_line(where, fragment):
    d = beam([{"where": where}], mesh={"generator": "box", "size": [L, H, H], "cells": [4, 2, 2]}, degree=1)
    with pytest.raises(InputError) as e:
        ff.solve_static(ff.Scene.from_dict(d))
    assert fragment in str(e.value)


def test_loads_refuse_points_lines_and_volume_groups(gmsh_beam):
    d = beam(LINE_SUPPORTS)
    d["load"] = [{"type": "traction", "where": {"line": [[L, 0, 0], [L, H, 0]]}, "value": [0, 0, 1.0]}]
    with pytest.raises(InputError, match=r"load\[0\]\.where: a line has no area to carry a traction"):
        ff.Scene.from_dict(d)
    d = beam([{"where": {"group": "pin"}}, {"where": {"group": "roller"}, "components": ["z"]}],
             mesh={"generator": "file", "file": str(gmsh_beam)})
    d["load"] = [{"type": "pressure", "where": {"group": "beam"}, "value": 10.0}]
    with pytest.raises(InputError, match=r"load\[0\]\.where\.group = 'beam': a volume group; a traction or "
                                         "pressure needs a surface group"):
        ff.solve_static(ff.Scene.from_dict(d))


@pytest.mark.mpi
@pytest.mark.parametrize("fix", [LINE_SUPPORTS, POINT_SUPPORTS], ids=["lines", "points"])
def test_two_ranks_hold_the_same_nodes(tmp_path, fix):
    d = beam(fix, mesh={"generator": "box", "size": [L, H, H], "cells": [12, 2, 2]}, degree=1)
    d["output"]["picture"] = False
    d["output"]["fields"] = False
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    serial = ff.solve_static(ff.Scene.from_file(path))
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "out")])
    assert p.returncode == 0, p.stderr
    par = json.loads((tmp_path / "out" / "results.json").read_text())
    np.testing.assert_allclose(par["probes"]["mid"]["displacement"], serial.probes["mid"], rtol=1e-8)
