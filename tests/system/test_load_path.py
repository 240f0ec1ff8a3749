"""The load path of a static run: probes.csv and fields.xdmf at every accepted load step, load_path.png,
a limit point that keeps its last converged state, the terms' records, and --set into arrays of tables.

References are closed forms: a linear-elastic bar on rollers under an end traction is in uniform uniaxial
stress, u = (T x / E, -nu T y / E, -nu T z / E) exactly (P1 reproduces it), so every row of probes.csv
lies on u = f * u_full with f the traction's factor at that step; a perfectly plastic bar collapses at
the load factor sigma_y / T; a StVK block in uniaxial compression carries at most E / (3 sqrt 3)."""
import json
import math
from pathlib import Path
import xml.etree.ElementTree as ET

from dolfinx import io
from mpi4py import MPI
import numpy as np
import pytest

import fem_forms as ff
from fem_forms.cli import main
from fem_forms.physics.terms import Term
from helpers import MPIRUN, mpirun, rollered_block, run_scene, toml_dumps

E, NU, T = 2.0e9, 0.3, 2.0e7                  # Pa; the bar's strain T / E = 1e-2
SIZE = (2.0, 1.0, 0.5)
CORNER = list(SIZE)
U_FULL = np.array([T / E * SIZE[0], -NU * T / E * SIZE[1], -NU * T / E * SIZE[2]])   # at the far corner


def bar(steps=4, history=None, **over) -> dict:
    """The rollered linear-elastic bar pulled along x by T (a uniform uniaxial stress)."""
    load = {"type": "traction", "where": {"axis": "x", "at": SIZE[0]}, "value": [T, 0.0, 0.0]}
    if history is not None:
        load["history"] = [list(p) for p in history]
    d = {"title": "bar", "mesh": {"generator": "box", "size": list(SIZE), "cells": [4, 2, 2]},
         "material": {"model": "linear", "E": E, "nu": NU},
         "discretization": {"degree": 1},
         "fix": [{"where": {"axis": a, "at": 0.0}, "components": [a]} for a in "xyz"],
         "load": [load], "solver": {"steps": steps},
         "output": {"probes": {"corner": CORNER, "mid": [1.0, 0.5, 0.25]}, "fields": ["displacement", "von_mises"]}}
    d.update(over)
    return d


def table(path: Path) -> tuple[list[str], np.ndarray]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]], ndmin=2)


def xdmf_times(path: Path) -> dict[str, list[float]]:
    """{field name: its time values} from an XDMF file (which must be well-formed XML)."""
    times: dict[str, list[float]] = {}
    for grid in ET.parse(path).getroot().iter("Grid"):
        if grid.get("GridType") == "Collection":
            times[grid.get("Name")] = [float(t.get("Value")) for t in grid.iter("Time")]
    return times


def mesh_cells(path: Path) -> int:
    """Read the mesh back from fields.xdmf/.h5 (the HDF5 side must be readable too)."""
    with io.XDMFFile(MPI.COMM_SELF, str(path), "r") as f:
        mesh = f.read_mesh(name="mesh")
    return mesh.topology.index_map(3).size_global


def test_every_step_of_a_linear_bar_lies_on_the_straight_line(tmp_path, capsys):
    code, res, err, out = run_scene(tmp_path, bar(), capsys)
    assert code == 0 and res["converged"], err
    head, rows = table(out / "probes.csv")
    assert head == ["load_factor", "time", "corner_ux", "corner_uy", "corner_uz", "mid_ux", "mid_uy", "mid_uz"] + \
        [f"fix{i}_F{c}" for i in range(3) for c in "xyz"]
    # the roller at x = 0 holds the bar against f T on its end area; the others carry nothing (uniaxial stress)
    area = SIZE[1] * SIZE[2]
    np.testing.assert_allclose(rows[:, 8], -rows[:, 0] * T * area, rtol=1e-8)
    np.testing.assert_allclose(rows[:, 9:], 0.0, atol=1e-8 * T * area)
    assert len(rows) == res["load_steps"] >= 3 and rows[-1, 0] == 1.0
    assert np.all(np.diff(rows[:, 0]) > 0) and np.array_equal(rows[:, 1], rows[:, 0])   # time = load factor
    for lam, *u in rows[:, [0, 2, 3, 4]]:
        np.testing.assert_allclose(u, lam * U_FULL, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(rows[:, 5:8], rows[:, [0]] * U_FULL / 2, rtol=1e-8, atol=1e-14)   # at the middle
    times = xdmf_times(out / "fields.xdmf")
    assert list(times) == ["displacement", "von_mises"]
    for t in times.values():
        np.testing.assert_allclose(t, rows[:, 0], rtol=1e-9)
    assert mesh_cells(out / "fields.xdmf") == 4 * 2 * 2 * 6
    assert res["files"]["probes"] == "probes.csv" and res["files"]["load_path_picture"] == "load_path.png"
    assert (out / "load_path.png").stat().st_size > 0
    np.testing.assert_allclose(res["probes"]["corner"]["displacement"], U_FULL, rtol=1e-8)


def test_time_column_follows_the_load_history(tmp_path, capsys):
    """Load up to T at t = 1 s, back to T / 2 at t = 2 s: time = 2 lambda and u = h(time) u_full."""
    history = [(0.0, 0.0), (1.0, 1.0), (2.0, 0.5)]
    code, res, err, out = run_scene(tmp_path, bar(steps=3, history=history), capsys)
    assert code == 0, err
    _, rows = table(out / "probes.csv")
    np.testing.assert_allclose(rows[:, 1], 2.0 * rows[:, 0], rtol=1e-9)
    assert 1.0 in rows[:, 1]                                          # the history's corner is a step end
    h = np.interp(rows[:, 1], [p[0] for p in history], [p[1] for p in history])
    np.testing.assert_allclose(rows[:, 2:5], h[:, None] * U_FULL, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(xdmf_times(out / "fields.xdmf")["displacement"], rows[:, 1], rtol=1e-9)


def test_single_step_run_keeps_its_outputs(tmp_path, capsys):
    code, res, err, out = run_scene(tmp_path, bar(steps=1), capsys)
    assert code == 0 and res["load_steps"] == 1
    assert set(res["files"]) == {"fields", "picture", "surface", "newton_history", "report"}
    assert not (out / "probes.csv").exists() and not (out / "load_path.png").exists()
    assert xdmf_times(out / "fields.xdmf") == {"displacement": [0.0], "von_mises": [0.0]}   # as before


def test_terms_records_become_columns(tmp_path, capsys, monkeypatch):
    """A term's record() (here a made-up one on the traction: its factor times T) is a probes.csv column."""
    def record(self):
        return {"traction_magnitude": float(self.factor.value) * T} if self.role == "load" else {}
    monkeypatch.setattr(Term, "record", record)
    code, res, err, out = run_scene(tmp_path, bar(steps=3, history=[(0.0, 0.0), (1.0, 1.0)]), capsys)
    assert code == 0, err
    head, rows = table(out / "probes.csv")
    assert head[-1] == "traction_magnitude"
    np.testing.assert_allclose(rows[:, -1], rows[:, 0] * T, rtol=1e-9)
    assert res["records"] == {"traction_magnitude": pytest.approx(T)}


def test_plastic_bar_past_collapse_stops_at_a_limit_point_with_its_last_state(tmp_path, capsys):
    """Perfectly plastic bar under 1.1 sigma_y: collapse at load factor sigma_y / T; the last accepted state
    is elastic to round-off, u_x(L) = lambda T L / E, and the support carries lambda T A."""
    Tp, sy, Ep = 275e6, 250e6, 200e9
    d = rollered_block("linear", Tp, plasticity={"model": "von-mises", "yield_stress": sy}, analysis="static",
                       solver={"steps": 4}, output={"probes": {"end": [2.0, 0.5, 0.25]}, "fields": ["displacement"]})
    code, res, err, out = run_scene(tmp_path, d, capsys)
    assert code == 3 and "plastic collapse" in err and "limit point" in err
    lam = res["load_reached"]
    assert res["converged"] is False and res["message"].startswith("limit point: load factor ")
    assert sy / Tp * (1 - 1e-3) < lam <= sy / Tp and res["collapse"]["load_factor"] == lam
    assert res["probes"]["end"]["displacement"][0] == pytest.approx(lam * Tp * 2.0 / Ep, rel=1e-3)
    assert res["reactions"]["fix0"][0] == pytest.approx(-lam * Tp * 0.5, rel=1e-6)
    _, rows = table(out / "probes.csv")
    assert rows[-1, 0] == pytest.approx(lam, rel=1e-9)
    assert xdmf_times(out / "fields.xdmf")["displacement"][-1] == pytest.approx(lam, rel=1e-9)
    assert mesh_cells(out / "fields.xdmf") > 0
    assert {"fields", "probes", "load_path_picture", "newton_history"} <= set(res["files"])


def crushed_stvk_block(control: str) -> dict:
    d = bar(steps=1, material={"model": "stvk", "E": E, "nu": 0.0},
            mesh={"generator": "box", "size": [1.0, 1.0, 1.0], "cells": [2, 2, 2]},
            load=[{"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [-2 * E, 0.0, 0.0]}],
            output={"probes": {"corner": [1.0, 1.0, 1.0]}, "fields": ["displacement"], "picture": False})
    d["solver"].update(max_cutbacks=8, control=control)
    return d


def test_crushed_stvk_block_passes_its_limit_load_with_the_default_control(tmp_path, capsys):
    """StVK in uniaxial compression (nu = 0) carries at most |P| = E / (3 sqrt 3), at stretch 1/sqrt 3; asked for
    2 E, the default control (auto) steps the load until a step fails there, then arc length follows the load
    down past that stretch to zero (solver.load_drop = 1): a limit point with its peak, exit 3."""
    code, res, err, out = run_scene(tmp_path, crushed_stvk_block("auto"), capsys)
    assert code == 3 and res["message"].startswith("limit point"), err
    limit = E / (3 * math.sqrt(3))
    assert res["peak_load_factor"] * 2 * E == pytest.approx(limit, rel=0.005)
    assert 0.9 * res["peak_load_factor"] < res["arc_length_from"] < res["peak_load_factor"]
    _, rows = table(out / "probes.csv")
    stretch = 1 + rows[:, 2]
    assert np.all(np.diff(stretch) < 1e-12)                   # crushed on, step after step (no turning back)
    assert stretch[-1] < 1 / math.sqrt(3) < stretch[int(np.argmax(rows[:, 0]))] + 0.05
    assert res["load_reached"] < 0.05 * res["peak_load_factor"]
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "two"), "-q"])
    assert p.returncode == 3, p.stderr[-2000:]
    two = json.loads((tmp_path / "two" / "results.json").read_text())
    assert two["mpi_ranks"] == 2 and two["load_steps"] == res["load_steps"]
    for key in ("peak_load_factor", "arc_length_from", "load_reached"):
        assert two[key] == pytest.approx(res[key], rel=1e-6, abs=1e-12), key


def test_crushed_stvk_block_stops_at_its_limit_load(tmp_path, capsys):
    """StVK in uniaxial compression (nu = 0) carries at most E / (3 sqrt 3); asked for 2 E under load control, it
    stops there."""
    code, res, err, out = run_scene(tmp_path, crushed_stvk_block("load"), capsys)
    last = err.strip().splitlines()[-1]                               # after the progress lines
    assert code == 3 and last.startswith("fem-forms: error: bar: limit point: "), err
    assert res["message"].startswith("limit point") and "collapse" not in res
    limit = E / (3 * math.sqrt(3))
    assert 0.97 * limit < res["load_reached"] * 2 * E <= limit * (1 + 1e-5)
    _, rows = table(out / "probes.csv")
    assert rows[-1, 0] == pytest.approx(res["load_reached"], rel=1e-9)
    assert rows[-1, 2] == pytest.approx(res["probes"]["corner"]["displacement"][0], rel=1e-9)
    assert rows[-1, 2] < 0


@pytest.mark.mpi
def test_two_ranks_write_the_serial_load_path(tmp_path, capsys):
    d = bar(steps=3, history=[(0.0, 0.0), (1.0, 1.0), (2.0, 0.5)], output={"probes": {"corner": CORNER}})
    code, _, err, out = run_scene(tmp_path, d, capsys)
    assert code == 0, err
    path = tmp_path / "scene.toml"
    p = mpirun(["-m", "fem_forms", "run", str(path), "--out", str(tmp_path / "two"), "-q"])
    assert p.returncode == 0, p.stderr
    head1, rows1 = table(out / "probes.csv")
    head2, rows2 = table(tmp_path / "two" / "probes.csv")
    assert head1 == head2 and rows1.shape == rows2.shape
    np.testing.assert_allclose(rows2[:, :5], rows1[:, :5], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(rows2[:, 5:], rows1[:, 5:], rtol=1e-9, atol=1e-9 * T)    # reactions: round-off of T
    assert xdmf_times(tmp_path / "two" / "fields.xdmf") == xdmf_times(out / "fields.xdmf")


# -- --set into arrays of tables ---------------------------------------------------------------------------

def test_set_reaches_tables_in_arrays(tmp_path, capsys):
    path = tmp_path / "bar.toml"
    path.write_text(toml_dumps(bar(steps=1)))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "-q", "--set", f"load.0.value=[{2 * T}, 0, 0]",
                 "--set", "fix.0.value=[1e-3, 0, 0]", "--set", "output.probes.corner.0=1.0"]) == 0
    res = json.loads((out / "results.json").read_text())
    u = res["probes"]["corner"]["displacement"]       # the corner now at x = 1 m, the x = 0 face moved 1 mm
    assert u[0] == pytest.approx(1e-3 + 2 * T / E * 1.0, rel=1e-8)
    assert u[1] == pytest.approx(2 * U_FULL[1], rel=1e-8)
    scene = ff.Scene.from_file(path, overrides={"load.0.value": [3e7, 0, 0], "fix.1.value": [0.0, 0.0, 1e-3]})
    assert scene.load[0].value == [3e7, 0, 0] and scene.fix[1].value == [0.0, 0.0, 1e-3]


@pytest.mark.parametrize("setting, words", [
    ("load.1.value=1", ["load.1.value", "out of range", "1 entry"]),
    ("load.first.value=1", ["load.first.value", "index it with an integer"]),
    ("fix.-1.value=1", ["fix.-1.value", "index it with an integer"]),
    ("solver.steps.0=1", ["solver.steps.0", "not a table or an array"]),
    ("contact.0.value=1", ["contact.0.value", "no 'contact' array"]),
])
def test_set_with_a_bad_index_is_one_line_naming_the_key(tmp_path, capsys, setting, words):
    path = tmp_path / "bar.toml"
    path.write_text(toml_dumps(bar(steps=1)))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q", "--set", setting]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and all(w in err for w in words), err
    assert not (tmp_path / "out").exists()
