"""The combinations of contact that users write, swept as an orthogonal array (issue 47 item 5): {static, implicit
dynamic} x {plane, sphere, STL obstacle, self-contact} x {frictionless, friction} x {P1, P2} x {tet, hex} x {1, 2
ranks}. Eight runs of L8 (a 4-level factor from two columns, four 2-level factors orthogonal to it and to each other):
every pair of levels of the obstacle and any 2-level factor, and of any two 2-level factors, is run at least once;
ranks follow the obstacle's interaction column (the sphere and the STL file on 2 ranks; a plane and self-contact on
2 ranks are in tests/system/test_contact.py).

The part: a 0.1 m cube (1 kg) under gravity, resting on the obstacle from a gap inside the default barrier distance,
its top held sideways (x, y) so that the obstacle alone carries its weight. Checked against what must hold whatever
the combination: the obstacle carries the weight m g exactly and its sideways push (friction) is the support's, within
Coulomb's cone (statics); released at rest in contact, the part stays within the barrier's distance and the energy
balances to the scheme's accuracy (dynamics, the default scheme: Newmark); nothing intersects, every run converges.
Not held yet (found by this sweep): a block on a 1 m ball (one node in the barrier's range) is refused as free to
tilt, which the ball's curvature and gravity do hold; the ball here is 100 m (every bottom node in range)."""
import json
import math

import meshio
import numpy as np
import pytest

from helpers import mpirun, run_scene, toml_dumps

G, GAP, A = 9.81, 5e-5, 0.1
R_BALL = 100.0                  # the sphere under the part: its corners 12.5 um lower than its centre, all in range
OBSTACLES = ("plane", "sphere", "file", "self")


def l8() -> list[tuple]:
    """(obstacle, ranks, analysis, friction, degree, cell) of the eight runs."""
    rows = []
    for a in (0, 1):
        for b in (0, 1):
            for c in (0, 1):
                rows.append((OBSTACLES[2 * a + b], 2 if a ^ b else 1, ("static", "dynamic")[c],
                             (0.0, 0.5)[a ^ c], 1 + (b ^ c), ("tetrahedron", "hexahedron")[a ^ b ^ c]))
    return rows


def box_stl(path) -> str:
    """A closed box surface under the part: its top face GAP below the part's bottom."""
    lo, hi = np.array([-0.05, -0.05, -0.1]), np.array([0.15, 0.15, -GAP])
    corners = np.array([[x, y, z] for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]   # outward
    tris = [t for q in quads for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
    meshio.write(str(path), meshio.Mesh(corners, [("triangle", np.array(tris))]))
    return str(path)


def scene(tmp_path, obstacle: str, analysis: str, friction: float, degree: int, cell: str) -> dict:
    floor = {"name": "floor", "shape": "plane", "point": [0, 0, -GAP], "normal": [0, 0, 1], "friction": friction}
    contact = {"obstacle": [floor]}
    if obstacle == "sphere":
        contact = {"obstacle": [{"name": "floor", "shape": "sphere", "center": [A / 2, A / 2, -R_BALL - GAP],
                                 "radius": R_BALL, "friction": friction}]}
    elif obstacle == "file":
        contact = {"obstacle": [{"name": "floor", "shape": "file", "file": box_stl(tmp_path / "table.stl"),
                                 "friction": friction}]}
    elif obstacle == "self":
        contact = {"self": True, "friction": friction, "obstacle": [floor]}
    d = {"title": f"{obstacle} {analysis}", "analysis": analysis,
         "mesh": {"generator": "box", "size": [A, A, A], "cells": [2, 2, 2], "cell": cell},
         "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": degree},
         "fix": [{"name": "sideways", "where": {"axis": "z", "at": A}, "components": ["x", "y"]}],
         "load": [{"type": "gravity"}], "contact": contact,
         "output": {"picture": False, "fields": False, "probes": {"bottom": [A / 2, A / 2, 0.0]}}}
    if analysis == "dynamic":
        d["dynamic"] = {"duration": 0.02, "dt": 2e-3}
    return d


def run(tmp_path, d: dict, ranks: int) -> tuple[dict, object]:
    if ranks == 1:
        code, r, _, out = run_scene(tmp_path, d)
        assert code == 0, r and r.get("message")
        return r, out
    (tmp_path / "scene.toml").write_text(toml_dumps(d))
    p = mpirun(["-m", "fem_forms", "run", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out"), "-q"], ranks)
    assert p.returncode == 0, p.stderr[-2000:]
    r = json.loads((tmp_path / "out" / "results.json").read_text())
    assert r["mpi_ranks"] == ranks
    return r, tmp_path / "out"


@pytest.mark.parametrize("obstacle,ranks,analysis,friction,degree,cell", l8(),
                         ids=lambda v: str(v).replace("hedron", ""))
def test_a_resting_block_is_carried_by_what_it_rests_on(tmp_path, obstacle, ranks, analysis, friction, degree,
                                                        cell):
    r, out = run(tmp_path, scene(tmp_path, obstacle, analysis, friction, degree, cell), ranks)
    assert r["converged"] and r["intersection_free"] and r["min_distance"] > 0
    weight = 1.0 * G
    if analysis == "static":
        force = np.array(r["contact"]["floor"]["force"])
        assert force[2] == pytest.approx(weight, rel=1e-6)           # z held by nothing else
        side = np.array(r["reactions"]["sideways"])
        assert np.allclose(force[:2], -side[:2], atol=1e-6 * weight)  # sideways: the support and the obstacle balance
        assert np.hypot(*force[:2]) <= (friction * force[2] if friction else 1e-6 * weight)   # Coulomb, or none
        assert r["equilibrium_error"] < 1e-8
    else:                                      # released at rest in contact: it stays there, the energy balances
        h = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
        assert np.abs(h["bottom_uz"]).max() < 2 * r["contact_distance"]
        # to the barrier's and the lagged friction's trapezoidal accuracy under Newmark's ringing (measured 0.02-0.13
        # of the largest energy, 1e-4 J); some steps are cut and retried (measured 0-5 of 10-11), none given up
        assert r["energy_balance_error"] < 0.2 and r["time_reached"] == pytest.approx(0.02)


def test_the_sweep_covers_every_pair():
    """The design itself: each obstacle meets both levels of each 2-level factor, and each pair of 2-level factors
    meets all four combinations (what makes eight runs stand for 128)."""
    rows = l8()
    for j in range(2, 6):
        assert {(r[0], r[j]) for r in rows} == {(o, v) for o in OBSTACLES for v in {r[j] for r in rows}}
        for k in range(j + 1, 6):
            assert len({(r[j], r[k]) for r in rows}) == 4
    assert math.prod(len({r[j] for r in rows}) for j in range(6)) == 128
