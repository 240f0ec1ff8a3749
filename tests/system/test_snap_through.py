"""Arc length through a snap-through: a shallow arch on pinned, immovable ends pushed down at its crown.

Its load-deflection path rises to a limit point, falls almost to zero while the arch flattens, and rises
again once it has snapped into the inverted shape. Load control cannot follow it past the peak. The
reference is another method on the same mesh: displacement control, the crown's line of nodes pushed down
step by step and the load read as that support's reaction (probes.csv), which follows the whole path
without arc length because the deflection keeps increasing along it. Arc length (a dead traction on the
crown, its factor an unknown) must land on that curve, peak included.

One-mode shallow-arch theory (sinusoidal arch of rise e on pinned ends, radius of gyration r, Timoshenko &
Gere, Theory of Elastic Stability, 7.7): q = EI k^4 [(e - a) + (e^2 - a^2) a / (4 r^2)] for the crown rise
a, k = pi / L; its limit point exists for e > 2 r and comes before the antisymmetric bifurcation for
e < sqrt(22) r. With e = 4 r it is q_max = 8 EI k^4 r; a crown load P counts as q L / 2 in that mode. The
one-mode shape is stiffer than the arch's (a Ritz bound), so the peak must lie a little below it."""
import math

import meshio
import numpy as np
import pytest

from helpers import run_scene

L, B, T = 1.0, 0.02, 0.02                      # span, width, thickness (m)
R_GYR = T / math.sqrt(12)
RISE = 4 * R_GYR                               # between 2 r (a limit point exists) and sqrt(22) r
E = 1.0e7
NX = 20
CROWN_TOP = RISE + T


def arch_mesh(path) -> str:
    """Hexahedra of a straight strip (NX x 1 x 2) lifted by RISE sin(pi x / L): a shallow sinusoidal arch."""
    xs, zs = np.linspace(0, L, NX + 1), np.linspace(0, T, 3)
    points = np.array([[x, y, z + RISE * math.sin(math.pi * x / L)] for x in xs for y in (0.0, B) for z in zs])

    def node(i, j, k):
        return (2 * i + j) * len(zs) + k
    cells = [[node(i, 0, k), node(i + 1, 0, k), node(i + 1, 1, k), node(i, 1, k),
              node(i, 0, k + 1), node(i + 1, 0, k + 1), node(i + 1, 1, k + 1), node(i, 1, k + 1)]
             for i in range(NX) for k in range(len(zs) - 1)]
    meshio.write(path, meshio.Mesh(points, [("hexahedron", np.array(cells))]))
    return str(path)


def arch_scene(mesh: str, **extra) -> dict:
    """Pinned at mid-thickness of both ends (lines across the width), held in its plane (nu = 0: no
    stress from that), Q2 hexahedra, a probe on the crown's top."""
    d = {"title": "shallow arch", "analysis": "static", "mesh": {"generator": "file", "file": mesh},
         "material": {"model": "neo-hookean", "E": E, "nu": 0.0}, "discretization": {"degree": 2},
         "fix": [{"name": "left", "where": {"line": [[0.0, 0.0, T / 2], [0.0, B, T / 2]]}},
                 {"name": "right", "where": {"line": [[L, 0.0, T / 2], [L, B, T / 2]]}},
                 {"name": "back", "where": {"axis": "y", "at": 0.0}, "components": ["y"]},
                 {"name": "front", "where": {"axis": "y", "at": B}, "components": ["y"]}],
         "output": {"picture": False, "fields": False, "probes": {"crown": [L / 2, B / 2, CROWN_TOP]}}}
    d.update(extra)
    return d


def table(path) -> np.ndarray:
    return np.genfromtxt(path, delimiter=",", names=True)


def peak(deflection: np.ndarray, load: np.ndarray) -> float:
    """The first maximum of the load, from a parabola through the highest sample and its neighbours."""
    i = next(k for k in range(1, len(load) - 1) if load[k] >= load[k - 1] and load[k] > load[k + 1])
    c = np.polyfit(deflection[i - 1:i + 2], load[i - 1:i + 2], 2)
    return float(c[2] - c[1] ** 2 / (4 * c[0]))


@pytest.fixture(scope="module")
def pushed(tmp_path_factory):
    """Displacement control: the crown's top line pushed down 2.5 rises in 30 equal steps."""
    tmp = tmp_path_factory.mktemp("pushed")
    d = arch_scene(arch_mesh(tmp / "arch.vtu"), solver={"steps": 30, "max_step": 1 / 30})
    d["fix"].append({"name": "crown", "where": {"line": [[L / 2, 0.0, CROWN_TOP], [L / 2, B, CROWN_TOP]]},
                     "components": ["z"], "value": [0.0, 0.0, -2.5 * RISE]})
    code, res, err, out = run_scene(tmp, d)
    assert code == 0, err
    rows = table(out / "probes.csv")
    # max_step: the path sampled evenly; the quadratic predictor starts one step so close to equilibrium (residual
    # 5.5e-6 before any Newton step) that the energy line search fails on round-off and that step is halved: 31
    assert len(rows) in (30, 31)
    return np.r_[0.0, -rows["crown_uz"]], np.r_[0.0, -rows["crown_Fz"]]


def test_arc_length_follows_a_snap_through_that_displacement_control_traces(tmp_path, capsys, pushed):
    half_width = L / NX                                        # the two top facets on either side of the crown
    patch = {"box": [[L / 2 - half_width - 1e-9, -1.0, CROWN_TOP - 0.05 * RISE], [L / 2 + half_width + 1e-9, 1.0, 1.0]]}
    d = arch_scene(arch_mesh(tmp_path / "arch.vtu"),
                   load=[{"type": "traction", "where": patch, "value": [0.0, 0.0, -300.0]}],
                   solver={"steps": 16, "control": "arc-length"})
    code, res, err, out = run_scene(tmp_path, d, capsys)
    assert code == 0 and res["converged"], err
    full = -res["applied_load"][2]                             # N at load factor 1 (300 Pa on the patch)
    rows = table(out / "probes.csv")
    w, P = -rows["crown_uz"], full * rows["load_factor"]
    assert np.all(np.diff(w) > 0)                              # the crown goes down at every step
    top = int(np.argmax(P[: len(P) // 2]))
    bottom = top + int(np.argmin(P[top:]))
    assert 0 < top < bottom < len(P) - 1 and P[bottom] < 0.1 * P[top]    # up, down nearly to zero, up again
    assert rows["load_factor"][-1] == 1.0
    # on the displacement-controlled curve at every step (that curve's own sampling: about 1 % near the peak)
    w_ref, P_ref = pushed
    assert np.max(np.abs(P - np.interp(w, w_ref, P_ref))) < 0.025 * P[top]
    assert peak(w, P) == pytest.approx(peak(w_ref, P_ref), rel=0.01)
    # and a little below the one-mode theory's limit load
    k = math.pi / L
    P_theory = 8 * E * B * T**3 / 12 * k**4 * R_GYR * L / 2
    assert 0.9 < peak(w, P) / P_theory < 1.0, (peak(w, P), P_theory)
