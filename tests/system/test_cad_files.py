"""CAD files in (issue 50): a STEP, IGES or BREP solid meshed by gmsh at h (h_min, h_max, finer near points), its
faces numbered (`fem-forms faces`, `where = { face = N }`), its named solid a volume group, its unit honoured. A
cantilever exported from CAD in millimetres sags as Timoshenko's beam under its weight; bad CAD input is one line."""
import json
import math

import numpy as np
import pytest

import fem_forms as ff
from fem_forms.cli import main
from fem_forms.meshes import load_mesh
from fem_forms.meshes.cad import cad_faces
from helpers import toml_dumps

L, B = 100.0, 10.0                  # the beam's length and square side in the CAD file (mm)
E, RHO, G_ACC = 1e8, 1000.0, 9.81


def _write_cad(folder, name="finger"):
    """A 100 x 10 x 10 mm beam as STEP (its product named `name`; also as .stp) and BREP, a bare surface as STEP,
    and a file that is not STEP."""
    import re
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("beam")
    gmsh.model.occ.addBox(0, 0, 0, L, B, B)
    gmsh.model.occ.synchronize()
    for suffix in ("step", "brep"):              # gmsh 4.8 writes no IGES (it reads it through the same OCC path)
        gmsh.write(str(folder / f"beam.{suffix}"))
    gmsh.clear()
    gmsh.model.add("sheet")
    gmsh.model.occ.addRectangle(0, 0, 0, L, B)
    gmsh.model.occ.synchronize()
    gmsh.write(str(folder / "sheet.step"))
    gmsh.finalize()
    step = folder / "beam.step"
    step.write_text(re.sub(r"PRODUCT\('[^']*',\s*'[^']*'", f"PRODUCT('{name}','{name}'", step.read_text()))
    (folder / "beam.stp").write_bytes(step.read_bytes())                             # STEP's other suffix
    (folder / "broken.step").write_text("ISO-10303-21;\nHEADER;\nthis is not STEP\n")
    return folder


@pytest.fixture(scope="module")
def cad(tmp_path_factory):
    return _write_cad(tmp_path_factory.mktemp("cad"))


def _scene(file, **mesh) -> dict:
    return {"title": "CAD beam", "mesh": {"generator": "file", "file": str(file), **mesh},
            "material": {"model": "neo-hookean", "E": E, "nu": 0.3, "rho": RHO},
            "discretization": {"degree": 2}, "load": [{"type": "gravity"}],
            "output": {"picture": False, "fields": False, "probes": {"tip": [0.1, 0.005, 0.005]}}}


def _extent(loaded) -> np.ndarray:
    lo, hi = ff.meshes.bounding_box(loaded.mesh)
    return hi - lo


def test_a_step_beam_in_mm_sags_as_timoshenkos_cantilever(cad, tmp_path, capsys):
    faces, _ = cad_faces(cad / "beam.step", None)
    clamp = next(f["face"] for f in faces if f.get("normal") == [-1.0, 0.0, 0.0])
    scene = _scene(cad / "beam.step", units="mm", h=0.004)
    scene["fix"] = [{"where": {"face": clamp}}]
    path = tmp_path / "beam.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0, capsys.readouterr().err
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    a, i = 0.01**2, 0.01**4 / 12
    q, shear = RHO * G_ACC * a, 5 / 6 * E / (2 * 1.3) * a
    timoshenko = q * 0.1**4 / (8 * E * i) + q * 0.1**2 / (2 * shear)
    assert -res["probes"]["tip"]["displacement"][2] == pytest.approx(timoshenko, rel=0.03)
    assert len(res["mesh"]["faces"]) == 6 and "CAD, 1 solid, 6 faces" in res["mesh"]["source"]


def test_units_names_and_sizes(cad):
    step = load_mesh(ff.Scene.from_dict(_scene(cad / "beam.step")).mesh)            # declares mm: read in m
    assert _extent(step) == pytest.approx([0.1, 0.01, 0.01], rel=1e-9)
    assert "finger" in step.cells                                                    # the CAD's named solid
    stp = load_mesh(ff.Scene.from_dict(_scene(cad / "beam.stp", units="mm")).mesh)   # read in mm, then scaled
    assert _extent(stp) == pytest.approx([0.1, 0.01, 0.01], rel=1e-9)
    brep = load_mesh(ff.Scene.from_dict(_scene(cad / "beam.brep", units="mm")).mesh)  # declares none
    assert _extent(brep) == pytest.approx([0.1, 0.01, 0.01], rel=1e-9)
    coarse = load_mesh(ff.Scene.from_dict(_scene(cad / "beam.step", h=0.005)).mesh)
    fine = load_mesh(ff.Scene.from_dict(_scene(cad / "beam.step", h=0.005,
                                               near=[[0.1, 0.005, 0.005, 0.01, 0.001]])).mesh)
    x = fine.mesh.geometry.x
    near_tip = x[np.linalg.norm(x - [0.1, 0.005, 0.005], axis=1) < 0.004]
    assert fine.mesh.topology.index_map(3).size_global > 3 * coarse.mesh.topology.index_map(3).size_global
    spacing = np.sort(np.linalg.norm(near_tip[:, None] - near_tip[None], axis=2), axis=1)[:, 1]
    assert np.median(spacing) < 0.0013                                               # about h_near = 1 mm there


def test_fem_forms_faces_numbers_them(cad, tmp_path, capsys):
    assert main(["faces", str(cad / "beam.step"), "--out", str(tmp_path / "faces")]) == 0
    printed = capsys.readouterr().out
    data = json.loads((tmp_path / "faces" / "faces.json").read_text())["faces"]
    assert len(data) == 6 and len(printed.strip().splitlines()) == 8
    assert sum(f["area"] for f in data) == pytest.approx(2 * 0.01 * 0.01 + 4 * 0.1 * 0.01, rel=1e-9)
    centre = np.array([0.05, 0.005, 0.005])
    for f in data:                                                    # each face's normal points out of the beam
        out = (np.array(f["centroid"]) - centre) / np.abs(np.array(f["centroid"]) - centre).max()
        assert f["normal"] == pytest.approx(np.round(out), abs=1e-12) and abs(np.linalg.norm(f["normal"]) - 1) < 1e-12
    assert (tmp_path / "faces" / "faces.png").stat().st_size > 20_000


BAD = [({"file": "sheet.step"}, "holds no solid (1 surfaces and no volume"),
       ({"file": "broken.step"}, "gmsh cannot read it"),
       ({"file": "beam.step", "scale": 0.001}, "mesh.scale: a STEP or IGES file declares its length unit"),
       ({"file": "beam.step", "h_min": 0.01, "h_max": 0.002}, "mesh.h_min = 0.01: exceeds h_max = 0.002"),
       ({"file": "beam.step", "near": [[0, 0, 0, -1, 0.001]]}, "mesh.near: each row's r and h must be positive"),
       ({"file": "beam.step", "h": 1e-5}, "more than a scene may ask for"),
       ({"file": "beam.step", "cell": "hexahedron"}, "a CAD file is filled with tetrahedra only")]


@pytest.mark.parametrize("mesh, fragment", BAD, ids=[b[1][:30] for b in BAD])
def test_bad_cad_input_is_one_line(cad, tmp_path, capsys, mesh, fragment):
    scene = _scene(cad / mesh.pop("file"), **mesh)
    scene["fix"] = [{"where": {"face": 1}}]
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and fragment in err[0], err


def test_a_face_number_on_a_mesh_not_from_cad_is_refused(tmp_path, capsys):
    scene = _scene("x")
    scene["mesh"] = {"generator": "box", "size": [0.1, 0.01, 0.01], "cells": [4, 1, 1]}
    scene["fix"] = [{"where": {"face": 1}}]
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 2
    assert "fix[0].where.face: only for a mesh made from a CAD file" in capsys.readouterr().err


def test_the_manuals_bracket_carries_its_load_to_the_wall(tmp_path, capsys):
    """docs/cad.md's L-bracket (docs/examples/bracket.step, a STEP in mm) as its page runs it: the wall's reaction
    balances the traction on the shelf's meshed top face (equilibrium), whose area is the CAD face's to its
    faceting."""
    from fem_forms.meshes.facet_geometry import outward_geometry
    from fem_forms.physics.supports import locate_facets
    from fem_forms.scene import Selector
    from helpers import ROOT
    scene = ROOT / "docs" / "examples" / "bracket.toml"
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "-q"]) == 0, capsys.readouterr().err
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    loaded = load_mesh(ff.Scene.from_file(scene).mesh)
    top = locate_facets(loaded, Selector.parse({"face": 7}, "where"))
    area = float(outward_geometry(loaded.mesh, top)[1].sum())
    assert res["reactions"]["wall"] == pytest.approx([0.0, 0.0, 2.0e4 * area], abs=1e-9 * 2.0e4 * area)
    cad_area = next(f["area"] for f in res["mesh"]["faces"] if f["face"] == 7)
    assert cad_area == pytest.approx((52 * 20 - math.pi * 4**2) * 1e-6, rel=1e-9)     # 52 x 20 mm less the hole
    assert area == pytest.approx(cad_area, rel=0.01)                                    # the hole's polygon
