"""Facets chosen by geometry, for a part with no groups (an STL, a STEP): facing a direction (`normal`), on a plane
of any orientation (`plane`), the walls of a cavity (`cavity`). Checked against what they must be: the face of a
tilted block (its area, the same facets as the plane through it), the side of a cylinder within a cone (the arc's
area), a block's two cavities against gmsh's own named surfaces (the same facets; the pocket's exact volume, the
sphere's to its faceting), the same inflation on 1 and 2 ranks; one-line errors."""
import json
import math
import re

from dolfinx import fem
from mpi4py import MPI
import numpy as np
import pytest
import ufl

import fem_forms as ff
from fem_forms.cli import main
from fem_forms.errors import InputError
from fem_forms.meshes import load_mesh
from fem_forms.meshes.facet_geometry import cavities, outward_geometry
from fem_forms.physics.supports import locate_facets
from fem_forms.scene import Selector
from helpers import mpirun, toml_dumps

TILT = math.radians(30.0)
POCKET, BALL = 0.02, 0.01          # the cubic pocket's edge, the spherical cavity's radius


def _gmsh_part(path, build, h):
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("part")
    build(gmsh)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(path))
    gmsh.finalize()
    return path


def _tilted(gmsh):
    box = gmsh.model.occ.addBox(0, 0, 0, 0.1, 0.04, 0.02)
    gmsh.model.occ.rotate([(3, box)], 0, 0, 0, 0, 1, 0, TILT)
    gmsh.model.occ.synchronize()


def _half_with_a_cavity(gmsh):
    """The symmetric half (y >= 0) of a block with a ball-shaped cavity at the origin: the cavity's wall meets the
    symmetry plane y = 0, which closes it (as an inflation of a half model)."""
    occ = gmsh.model.occ
    box = occ.addBox(-0.05, 0, -0.02, 0.1, 0.02, 0.04)
    ball = occ.addSphere(0, 0, 0, BALL)
    occ.cut([(3, box)], [(3, ball)])
    occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 16)


def _two_cavities(gmsh):
    occ = gmsh.model.occ
    box = occ.addBox(0, 0, 0, 0.1, 0.04, 0.04)
    ball = occ.addSphere(0.03, 0.02, 0.02, BALL)
    pocket = occ.addBox(0.06, 0.01, 0.01, POCKET, POCKET, POCKET)
    (vol,), _ = occ.cut([(3, box)], [(3, ball), (3, pocket)])
    occ.synchronize()
    names = {"ball": [], "pocket": []}
    for _, tag in gmsh.model.getEntities(2):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, tag)
        if min(y0, z0) > 0.005 and max(y1, z1) < 0.035:
            names["ball" if x1 < 0.05 else "pocket"].append(tag)
    for name, tags in names.items():
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags), name)
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [vol[1]]), "body")
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 16)      # the ball's wall: 16 elements around


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    folder = tmp_path_factory.mktemp("parts")
    return {"tilted": _gmsh_part(folder / "tilted.msh", _tilted, 0.01),
            "half": _gmsh_part(folder / "half.msh", _half_with_a_cavity, 0.008),
            "cavities": _gmsh_part(folder / "cavities.msh", _two_cavities, 0.008)}


def _loaded(mesh: dict):
    return load_mesh(ff.Scene.from_dict({"mesh": mesh, "material": {"E": 1e6, "nu": 0.3}}).mesh)


def _facets(loaded, where: dict) -> np.ndarray:
    return locate_facets(loaded, Selector.parse(where, "where"))


def _area(loaded, facets) -> float:
    owned = facets[facets < loaded.mesh.topology.index_map(2).size_local]
    return loaded.mesh.comm.allreduce(float(outward_geometry(loaded.mesh, owned)[1].sum()), op=MPI.SUM)


def _key_set(loaded, facets) -> set:
    top = loaded.mesh.topology
    top.create_connectivity(2, 0)
    imap, f2v = top.index_map(0), top.connectivity(2, 0)
    return {tuple(sorted(imap.local_to_global(f2v.links(f)).tolist())) for f in facets}


def test_a_tilted_blocks_face_by_its_normal_and_by_its_plane(parts):
    loaded = _loaded({"generator": "file", "file": str(parts["tilted"])})
    down = [-math.sin(TILT), 0.0, -math.cos(TILT)]           # the bottom face's outward normal, tilted
    by_normal = _facets(loaded, {"normal": down})
    by_plane = _facets(loaded, {"plane": [[0, 0, 0], down]})
    assert _area(loaded, by_normal) == pytest.approx(0.1 * 0.04, rel=1e-12)
    assert _key_set(loaded, by_normal) == _key_set(loaded, by_plane)
    with pytest.raises(InputError, match="where: matches no boundary facet"):
        _facets(loaded, {"normal": [0, 0, -1]})                 # 30 degrees off: outside the 5-degree cone
    assert _key_set(loaded, _facets(loaded, {"normal": [0, 0, -1], "within_deg": 31})) == _key_set(loaded, by_normal)


def test_a_cone_of_normals_takes_the_arc_of_a_cylinder():
    loaded = _loaded({"generator": "cylinder", "radius": 0.05, "height": 0.1, "h": 0.006})
    arc = _area(loaded, _facets(loaded, {"normal": [1, 0, 0], "within_deg": 30}))
    assert arc == pytest.approx(0.05 * math.pi / 3 * 0.1, rel=0.05)      # R x 60 degrees x H, faceted


def test_cavities_are_the_closed_surfaces_inside_ordered_by_volume(parts):
    loaded = _loaded({"generator": "file", "file": str(parts["cavities"])})
    found = cavities(loaded.mesh)
    assert len(found) == 2
    assert found[0][0] == pytest.approx(POCKET**3, rel=1e-10)           # flat walls: exact
    material = loaded.mesh.comm.allreduce(fem.assemble_scalar(fem.form(1.0 * ufl.dx(loaded.mesh))), op=MPI.SUM)
    assert found[1][0] == pytest.approx(0.1 * 0.04 * 0.04 - material - POCKET**3, rel=1e-9)   # the faceted ball
    assert found[1][0] == pytest.approx(4 / 3 * math.pi * BALL**3, rel=0.1)
    first, second = _facets(loaded, {"cavity": 1}), _facets(loaded, {"cavity": 2})
    assert _key_set(loaded, first) == _key_set(loaded, _facets(loaded, {"group": "pocket"}))
    assert _key_set(loaded, second) == _key_set(loaded, _facets(loaded, {"group": "ball"}))
    assert _key_set(loaded, _facets(loaded, {"cavity": "all"})) == _key_set(loaded, first) | _key_set(loaded, second)
    with pytest.raises(InputError, match=r"where.cavity = 3: the mesh has 2 cavities \(enclosing 8e-06, "):
        _facets(loaded, {"cavity": 3})
    box = _loaded({"generator": "box", "size": [1, 1, 1], "cells": [2, 2, 2]})
    with pytest.raises(InputError, match="where.cavity: the mesh has no cavity"):
        _facets(box, {"cavity": 1})


def test_a_cavity_cut_by_a_symmetry_plane(parts):
    loaded = _loaded({"generator": "file", "file": str(parts["half"])})
    found = cavities(loaded.mesh)
    material = loaded.mesh.comm.allreduce(fem.assemble_scalar(fem.form(1.0 * ufl.dx(loaded.mesh))), op=MPI.SUM)
    assert len(found) == 1 and found[0][0] == pytest.approx(0.1 * 0.02 * 0.04 - material, rel=1e-9)
    assert found[0][0] == pytest.approx(2 / 3 * math.pi * BALL**3, rel=0.1)          # the faceted half ball


def test_the_facet_counts_are_said_when_solving_starts_or_a_solve_ends():
    import io
    from fem_forms.output.progress_line import ProgressLine
    for ending in ("load_step", "solve_done", "march_done"):
        log = io.StringIO()
        line = ProgressLine(stream=log, tty=False)
        line("selected", key="fix[0].where", facets=12)
        line("selected", key="fix[0].where", facets=12)                # a rebuild selects again: said once
        assert log.getvalue() == ""                                     # bad input found now stays one line
        line(ending, time=0.0, steps=0)
        assert log.getvalue().startswith("fem-forms: fix[0].where: 12 boundary facets\n"), (ending, log.getvalue())
        assert log.getvalue().count("boundary facets") == 1


def test_cavities_inflated_with_no_groups_the_same_on_two_ranks(parts, tmp_path, capsys):
    scene = {"title": "two cavities", "mesh": {"generator": "file", "file": str(parts["cavities"])},
             "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3},
             "fix": [{"where": {"normal": [0, 0, -1]}}],
             "load": [{"type": "inflation", "where": {"cavity": 1}, "pressure": 2e4},
                      {"type": "inflation", "where": {"cavity": 2}, "pressure": 1e4}],
             "output": {"picture": False, "fields": False}}
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "one")]) == 0
    err = capsys.readouterr().err
    counts = dict(re.findall(r"fem-forms: (\S+\.where): (\d+) boundary facets", err))
    assert set(counts) == {"fix[0].where", "load[0].where", "load[1].where"}, err
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "two")], n=2)
    assert p.returncode == 0, p.stderr
    assert dict(re.findall(r"fem-forms: (\S+\.where): (\d+) boundary facets", p.stderr)) == counts
    results = [json.loads((tmp_path / out / "results.json").read_text())["cavities"] for out in ("one", "two")]
    one, two = results
    assert one["cavity0"]["volume"] - one["cavity0"]["volume_change"] == pytest.approx(POCKET**3, rel=1e-10)
    assert one["cavity0"]["volume_change"] > 0 and one["cavity1"]["volume_change"] > 0
    for name in one:
        assert two[name]["volume"] == pytest.approx(one[name]["volume"], rel=1e-9)


def test_normals_of_hexahedra_and_a_plane_across_a_box():
    loaded = _loaded({"generator": "box", "size": [0.3, 0.2, 0.1], "cells": [3, 2, 2], "cell": "hexahedron"})
    assert _area(loaded, _facets(loaded, {"normal": [0, 0, -1]})) == pytest.approx(0.3 * 0.2, rel=1e-12)
    assert _area(loaded, _facets(loaded, {"normal": [1, 0, 0], "within_deg": 90})) == pytest.approx(
        0.2 * 0.1 + 2 * (0.3 * 0.2 + 0.3 * 0.1), rel=1e-12)      # the +x face and the four it is square to
    side = _facets(loaded, {"plane": [[0.3, 0.0, 0.0], [2, 0, 0]], "tolerance": 1e-9})
    assert _key_set(loaded, side) == _key_set(loaded, _facets(loaded, {"axis": "x", "at": 0.3}))


def resting_block(where: dict | None = None, degree: int = 1, **contact) -> dict:
    """A soft block resting by its weight on a frictional floor (no [[fix]]); contact `where` when given."""
    floor = {"name": "floor", "shape": "plane", "point": [0, 0, -5e-5], "normal": [0, 0, 1], "friction": 0.5}
    return {"title": "block on a floor", "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [3, 3, 3]},
            "material": {"E": 1e5, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": degree},
            "load": [{"type": "gravity"}],
            "contact": {"obstacle": [floor], **({"where": where} if where else {}), **contact},
            "output": {"picture": False, "fields": False, "probes": {"top": [0.05, 0.05, 0.1]}}}


@pytest.mark.parametrize("degree", [1, 2])
def test_contact_where_leaves_the_obstacles_the_selected_facets_only(tmp_path, capsys, degree):
    """The floor touches the block's sole only: selected by its normal, the answer is the whole surface's to
    round-off (P2: the sole's edge nodes touch too) and the floor carries the weight; offered the top face only,
    nothing holds the block (one line, exit 2); self-contact takes the whole surface, so `where` beside it is
    refused when the scene is read."""
    from helpers import run_scene
    answers = []
    for name, where in (("all", None), ("sole", {"normal": [0, 0, -1]})):
        (tmp_path / name).mkdir()
        code, res, err, _ = run_scene(tmp_path / name, resting_block(where, degree), capsys)
        assert code == 0, err
        assert res["contact"]["floor"]["force"][2] == pytest.approx(1000.0 * 0.1 ** 3 * 9.81, rel=1e-8)
        answers.append((res["probes"]["top"]["displacement"], res["contact"]["floor"]["active_points"]))
    assert answers[1][0] == pytest.approx(answers[0][0], rel=1e-10, abs=1e-16)
    assert answers[1][1] == answers[0][1] == (3 * degree + 1) ** 2          # the sole's nodes: 3 x 3 cells
    if degree == 2:
        return                                  # the refusals below do not depend on the degree
    (tmp_path / "top").mkdir()
    code, res, err, _ = run_scene(tmp_path / "top", resting_block({"normal": [0, 0, 1]}), capsys)
    assert code == 2 and "supports leave the body free (translation z)" in err and "Traceback" not in err
    (tmp_path / "self").mkdir()
    code, _, err, _ = run_scene(tmp_path / "self", resting_block({"normal": [0, 0, -1]}, self=True), capsys)
    assert code == 2 and "contact.where: only with plane, sphere, box and cylinder obstacles" in err


@pytest.mark.mpi
def test_contact_where_on_two_ranks(tmp_path):
    from helpers import serial_and_two_ranks
    one, two = serial_and_two_ranks(tmp_path, resting_block({"normal": [0, 0, -1]}))
    assert two["probes"]["top"]["displacement"] == pytest.approx(one["probes"]["top"]["displacement"], rel=1e-8)
    assert two["contact"]["floor"]["active_points"] == one["contact"]["floor"]["active_points"] == 16
