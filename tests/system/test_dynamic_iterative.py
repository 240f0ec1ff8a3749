"""The implicit step with [solver] linear = "iterative" (CG + GAMG, GMRES when damping leaves no energy):
the same motion as MUMPS (another linear solver, the reference), the multigrid hierarchy kept across
Newton iterations and time steps (built fewer times than there are Newton iterations), and 1 vs 2 ranks."""

import numpy as np
import pytest

from helpers import run_scene, serial_and_two_ranks

L, H = 1.0, 0.1


def cantilever(linear: str, scheme: str = "newmark", damping: dict | None = None) -> dict:
    """A soft neo-Hookean cantilever under a sudden tip load (large, nonlinear motion), P1 tetrahedra."""
    d = {"title": "iterative dynamics", "analysis": "dynamic",
         "mesh": {"size": [L, H, H], "cells": [16, 3, 3], "cell": "tetrahedron"},
         "material": {"model": "neo-hookean", "E": 1.0e6, "nu": 0.3, "rho": 1000.0},
         "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "x", "at": 0.0}}],
         "load": [{"type": "traction", "where": {"axis": "x", "at": L}, "value": [0.0, 0.0, -300.0]}],
         "output": {"probes": {"tip": [L, H / 2, H / 2], "mid": [L / 2, H / 2, H]}, "picture": False,
                    "fields": False},
         "solver": {"linear": linear},
         "dynamic": {"duration": 0.03, "dt": 1e-3, "scheme": scheme, "rho_inf": 0.8}}
    if damping:
        d["damping"] = damping
    return d


def run(tmp_path, d, name, capsys):
    (tmp_path / name).mkdir()
    code, res, err, out = run_scene(tmp_path / name, d, capsys)
    assert code == 0, err
    return res, np.loadtxt(out / "probes.csv", delimiter=",", skiprows=1)


@pytest.mark.parametrize("scheme, damping", [("newmark", None), ("generalized-alpha", None),
                                             ("newmark", {"rayleigh": {"alpha": 2.0, "beta": 1e-4}})])
def test_iterative_gives_the_direct_motion_with_a_kept_hierarchy(tmp_path, capsys, scheme, damping):
    direct, p_direct = run(tmp_path, cantilever("direct", scheme, damping), "direct", capsys)
    it, p_it = run(tmp_path, cantilever("iterative", scheme, damping), "iterative", capsys)
    assert direct["linear_solver"] == "direct" and it["linear_solver"] == "iterative"
    assert it["steps"] == direct["steps"] == 30 and it["rejected_steps"] == 0
    scale = np.abs(p_direct[:, 1:]).max(axis=0)
    assert scale[2] > 1e-3                                    # the tip did move (uz column)
    assert np.array_equal(p_it[:, 0], p_direct[:, 0])
    assert np.allclose(p_it[:, 1:], p_direct[:, 1:], rtol=1e-6, atol=1e-6 * scale)   # each column to 1e-6
    # the multigrid hierarchy outlives Newton iterations and steps (the cost rule keeps it)
    assert 1 <= it["preconditioner_builds"] < it["steps"] < it["newton_iterations"]
    assert it["krylov_iterations"] > it["newton_iterations"]   # CG indeed (MUMPS + GMRES: about 1 per Newton)


@pytest.mark.mpi
def test_iterative_two_ranks_agree_with_one(tmp_path):
    d = cantilever("iterative", "generalized-alpha")
    d["dynamic"]["duration"] = 0.01
    outs = serial_and_two_ranks(tmp_path, d)
    probes = [np.loadtxt(tmp_path / folder / "probes.csv", delimiter=",", skiprows=1) for folder in ("out", "two")]
    assert all(o["linear_solver"] == "iterative" and o["preconditioner_builds"] < o["newton_iterations"]
               for o in outs)
    scale = np.abs(probes[0][:, 1:]).max(axis=0)
    head = (tmp_path / "out" / "probes.csv").read_text().splitlines()[0].split(",")[1:]
    # the clamp's force is the residual of terms that nearly cancel there (inertia, stress): CG's 1e-8 shows in it
    # at 1e-5 of its size between 1 and 2 ranks (measured), so it is compared at 1e-4 of its largest component
    forces = [i for i, name in enumerate(head) if name.startswith("fix0_F")]
    scale[forces] = 100 * scale[forces].max()
    assert np.allclose(probes[1][:, 1:], probes[0][:, 1:], rtol=1e-6, atol=1e-6 * scale)


@pytest.mark.parametrize("linear", ["direct", "iterative"])
def test_the_step_check_reads_the_residual_a_fresh_assembly_gives(linear):
    """The step's residual check uses SNES's last residual norm instead of re-assembling it: at every accepted
    state an independent assembly of the residual gives the same norm."""
    import fem_forms as ff
    from fem_forms.analyses.dynamic.implicit import ImplicitStepper
    from fem_forms.analyses.dynamic.solve import initial_acceleration
    from fem_forms.analyses.dynamic.system import build_system
    system = build_system(ff.Scene.from_dict(cantilever(linear)))
    initial_acceleration(system, set())
    system.state.commit()
    stepper = ImplicitStepper(system, set())
    drv, records = stepper.driver, []
    solve_step = drv.solve_step
    drv.solve_step = lambda **kw: records.append(solve_step(**kw)) or records[-1]
    for k in range(6):
        assert stepper.step(k * 1e-3, 1e-3).accepted
        last, fresh = records[-1].residuals[-1], drv.residual_norm()
        assert fresh == pytest.approx(last, rel=1e-12)          # measured: equal to the last bit
        system.state.commit()
    assert len(records) == 6


def test_auto_falls_back_to_mumps_when_cg_fails(monkeypatch):
    """"auto" above its size threshold starts with CG + GAMG; a CG failure on a fresh hierarchy (here forced by
    ksp_max_it = 1) switches the run to MUMPS, as the static continuation does, and the step is solved again at
    the same dt: no step is cut and the motion is the direct one."""
    import fem_forms as ff
    from fem_forms.analyses.dynamic import solve_dynamic
    from fem_forms.solvers import linear
    direct = solve_dynamic(ff.Scene.from_dict(cantilever("direct")))
    monkeypatch.setattr(linear, "ITERATIVE_ABOVE_DOFS", 100)          # this small beam counts as large
    d = cantilever("auto")
    d["solver"]["petsc"] = {"ksp_max_it": 1}
    auto = solve_dynamic(ff.Scene.from_dict(d))
    s = auto.summary()
    assert s["linear_solver"] == "direct" and s["preconditioner_builds"] >= 1       # started iterative
    assert s["preconditioner_builds"] == 1 and auto.report.rejected == 0
    assert auto.report.steps == direct.report.steps
    ref = np.array(direct.probe_rows)[:, 1:]
    assert np.allclose(np.array(auto.probe_rows)[:, 1:], ref, rtol=1e-6, atol=1e-6 * np.abs(ref).max(axis=0))
