"""Benchmark: contact in time with each implicit scheme, on two scenes as a user writes them (issue 47, items 1 and 6).

- A stiff block (0.1 m cube, E 10 MPa, 1 kg, the box generator's tetrahedra on 4 x 4 x 4 cells) released at rest
  0.1 mm above a 20 degree slope (inside the default barrier distance), friction 0.2, dt 2 ms, 0.3 s: the slide's
  acceleration against g (sin - mu cos) (fitted on t > 0.05 s), steps, rejected steps, Newton iterations, wall time
  (median of 3 runs, one process each).
- A solid rubber hemisphere (R 5 cm, dome down, E 1 MPa, nu 0.4, 1100 kg/m^3) placed on a floor with friction 0.8
  and set rocking at 1.6 rad/s about its contact point, dt 2 ms, 1.2 s = 600 steps: the rocking period against
  rolling without slip, T = 2 pi sqrt(I_P / (m g d)), d = 3R/8 (0.591 s; amplitude 8.6 deg adds about 0.1 %). The
  issue's scene: P1 on a gmsh mesh graded from 2.5 mm within 12 mm of the lowest point to 1 cm (the contact point
  rolls 7.5 mm each way), each scheme; and the default P2 on a uniform 1 cm mesh (its facets are 11 degrees wide,
  more than the swing: P1 there rocks on facet edges, period -17 %), backward Euler. One run each, stopped by
  SIGTERM after 2.4 LIMIT_S (6 minutes; backward Euler P2 10: the run keeps its steps and says how far it got).
- Where the hemisphere's time goes (the issue's scene, backward Euler, 0.3 s, in this process under cProfile):
  tangent assembly, the linear solves inside SNES, residuals, line-search energies, the contact term, the rest.

Run: `.venv/bin/python benchmarks/contact_schemes.py` (about 25 minutes, alone on the machine). Writes
benchmarks/contact_schemes.md.
"""
from __future__ import annotations

import cProfile
import json
import math
import os
import pstats
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
PY = sys.executable
LIMIT_S = 150
G, SLOPE, MU = 9.81, math.radians(20.0), 0.2
R, E, NU, RHO = 0.05, 1e6, 0.4, 1100.0
SCHEMES = ("newmark", "generalized-alpha", "backward-euler")


def run(scene: dict, work: Path, limit: float = LIMIT_S) -> tuple[dict | None, Path, float]:
    """The scene run in a process of its own (this script with --one): (results.json or None if stopped, out folder,
    wall seconds)."""
    work.mkdir(parents=True, exist_ok=True)
    (work / "scene.json").write_text(json.dumps(scene))
    out = work / "out"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    t = time.perf_counter()
    p = subprocess.Popen([PY, __file__, "--one", str(work / "scene.json"), str(out)], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        p.wait(timeout=limit)
    except subprocess.TimeoutExpired:
        p.terminate()                  # SIGTERM: the run keeps its steps and says how far it got (interrupted)
        p.wait(timeout=120)
    wall = time.perf_counter() - t
    path = out / "results.json"
    return (json.loads(path.read_text()) if path.exists() else None), out, wall


def block(scheme: str) -> dict:
    g = [G * math.sin(SLOPE), 0.0, -G * math.cos(SLOPE)]
    return {"title": "block released on a slope", "analysis": "dynamic",
            "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [4, 4, 4]},
            "material": {"E": 1e7, "nu": 0.3, "rho": 1000.0}, "load": [{"type": "gravity", "g": g}],
            "dynamic": {"duration": 0.3, "dt": 2e-3, "scheme": scheme},
            "contact": {"obstacle": [{"name": "slope", "shape": "plane", "point": [0, 0, -1e-4], "normal": [0, 0, 1],
                                      "friction": MU}]},
            "output": {"picture": False, "fields": False, "probes": {"c": [0.05, 0.05, 0.1]}}}


def hemisphere(mesh: Path, scheme: str, initial: str = "rest", duration: float = 1.2, degree: int = 1) -> dict:
    return {"title": "rocking hemisphere", "analysis": "dynamic", "mesh": {"generator": "file", "file": str(mesh)},
            "discretization": {"degree": degree},
            "material": {"model": "neo-hookean", "E": E, "nu": NU, "rho": RHO}, "load": [{"type": "gravity"}],
            "dynamic": {"duration": duration, "dt": 2e-3, "scheme": scheme, "initial": initial, "output_every": 50,
                        "initial_velocity": {"angular": [0.0, 1.6, 0.0], "about": [0.0, 0.0, -R]}},
            "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -R - 5e-5],
                                      "normal": [0, 0, 1], "friction": 0.8}]},
            "output": {"picture": False, "fields": False,
                       "probes": {"centre": [0.0, 0.0, 0.0], "low": [0.0, 0.0, -0.04]}}}


def make_hemisphere(path: Path, graded: bool = True) -> Path:
    """The dome (flat face up at z = 0), tetrahedra of 1 cm; `graded`: 2.5 mm within 12 mm of the lowest point,
    growing to 1 cm at 36 mm."""
    from fem_forms.meshes.occ_parts import write_part

    def dome(occ):
        d, _ = occ.cut([(3, occ.addSphere(0, 0, 0, R))], [(3, occ.addBox(-2 * R, -2 * R, 0, 4 * R, 4 * R, 2 * R))])
        if graded:
            import gmsh
            occ.synchronize()
            f = gmsh.model.mesh.field
            low = f.add("Distance")
            f.setNumbers(low, "PointsList", [occ.addPoint(0, 0, -R)])
            size = f.add("Threshold")
            f.setNumber(size, "InField", low)
            for key, value in (("SizeMin", 2.5e-3), ("SizeMax", 0.01), ("DistMin", 0.012), ("DistMax", 0.036)):
                f.setNumber(size, key, value)
            f.setAsBackgroundMesh(size)
            for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
                gmsh.option.setNumber(key, 0)
        return d
    return write_part(path, dome, 0.01)


def rolling_period() -> float:
    d = 3 * R / 8
    return 2 * math.pi * math.sqrt((0.4 * R * R - d * d + (R - d) ** 2) / (G * d))


def slide_error(out: Path) -> float:
    h = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    late = h["time"] > 0.05
    a = 2 * np.polyfit(h["time"][late], h["c_ux"][late], 2)[0]
    return a / (G * (math.sin(SLOPE) - MU * math.cos(SLOPE))) - 1


def rocking_period(out: Path) -> float | None:
    h = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    tilt = np.arctan2(h["centre_ux"] - h["low_ux"], 0.04 + h["centre_uz"] - h["low_uz"])
    s = np.sign(tilt)
    k = np.flatnonzero((s[1:] != s[:-1]) & (h["time"][1:] > 0.05))
    if len(k) < 2:
        return None
    t = h["time"][k] - tilt[k] * (h["time"][k + 1] - h["time"][k]) / (tilt[k + 1] - tilt[k])
    return 2 * float(np.mean(np.diff(t)))


def row(name: str, r: dict | None, wall: float, measure: str) -> str:
    if r is None:
        return f"| {name} | stopped after {wall:.0f} s | | | | {measure} |"
    done = "" if r["converged"] else f" (stopped at t = {r['time_reached']:.3g} s)"
    seconds = r["wall_time_s"] if r["converged"] else wall          # an interrupted run's own clock stops early
    return (f"| {name} | {r['steps']}{done} | {r['rejected_steps']} | {r['newton_iterations']} | "
            f"{seconds:.1f} s | {measure} |")


def breakdown(mesh: Path, work: Path) -> list[str]:
    """Where a backward-Euler run of the hemisphere spends its time (0.3 s, this process, cProfile)."""
    import fem_forms as ff
    from fem_forms.analyses.dynamic.solve import solve_dynamic
    ff.quiet_jit()
    scene = ff.Scene.from_dict(hemisphere(mesh, "backward-euler", duration=0.3))     # the scene (P1)
    solve_dynamic(scene)                                   # compiles the forms
    prof = cProfile.Profile()
    t = time.perf_counter()
    prof.enable()
    result = solve_dynamic(scene)
    prof.disable()
    total = time.perf_counter() - t
    stats = pstats.Stats(prof).stats

    def cum(fragment: str, name: str) -> float:
        return sum(v[3] for k, v in stats.items() if fragment in k[0] and k[2] == name)

    def own(fragment: str) -> float:
        """The time spent in the functions themselves whose names contain `fragment` (C++ calls: their own)."""
        return sum(v[2] for k, v in stats.items() if fragment in k[2])
    parts = {"tangent assembly (UFL)": own("cpp.fem.petsc.assemble_matrix"),
             "linear solves and PETSc inside SNES (LU: MUMPS)": own("'solve' of 'petsc4py.PETSc.SNES'"),
             "residual assembly (UFL)": own("cpp.fem.assemble_vector"),
             "line-search energies (UFL)": own("cpp.fem.assemble_scalar"),
             "contact term (gaps, barrier, friction: numpy)": sum(cum("physics/contact", n) for n in
                                                                  ("add_gradient", "add_hessian", "energy_value",
                                                                   "update", "max_step"))}
    parts["the rest (Python around them, output)"] = total - sum(parts.values())
    its = result.report.newton_iterations
    lines = [f"Where the time goes (backward Euler, 0.3 s = {result.report.steps} steps, {its} Newton iterations, "
             f"{total:.1f} s under cProfile):", "", "| part | time | share | per Newton iteration |", "|---|---|---|---|"]
    for name, sec in parts.items():
        lines.append(f"| {name} | {sec:.2f} s | {100 * sec / total:.0f} % | {1e3 * sec / its:.1f} ms |")
    return lines


def main() -> None:
    work = Path(tempfile.mkdtemp())
    lines = ["# Contact in time: each implicit scheme on a sliding block and a rocking hemisphere", "",
             "Generated by `benchmarks/contact_schemes.py` (see its docstring), one process per run, one core.", "",
             "| block on a 20 degree slope | steps | rejected | Newton iterations | wall (median of 3) | "
             "acceleration against g (sin - mu cos) |", "|---|---|---|---|---|---|"]
    for scheme in SCHEMES:
        runs = [run(block(scheme), work / f"block-{scheme}-{i}") for i in range(3)]
        r, out, _ = runs[-1]
        wall = statistics.median(x[0]["wall_time_s"] for x in runs if x[0])
        r = dict(r, wall_time_s=wall)
        lines.append(row(scheme, r, wall, f"{100 * slide_error(out):+.2f} %"))
    mesh = make_hemisphere(work / "dome.msh")
    uniform = make_hemisphere(work / "dome-uniform.msh", graded=False)
    T = rolling_period()
    lines += ["", f"| rocking hemisphere (600 steps) | steps | rejected | Newton iterations | wall | period against "
              f"rolling {T:.3f} s |", "|---|---|---|---|---|---|"]
    for scheme, initial, degree, limit in [("backward-euler", "rest", 1, 2.4 * LIMIT_S),
                                           ("generalized-alpha", "rest", 1, 2.4 * LIMIT_S),
                                           ("newmark", "rest", 1, 2.4 * LIMIT_S),
                                           ("newmark", "static", 1, 2.4 * LIMIT_S),
                                           ("backward-euler", "rest", 2, 4 * LIMIT_S)]:
        scene = hemisphere(mesh if degree == 1 else uniform, scheme, initial, degree=degree)
        r, out, wall = run(scene, work / f"dome-{scheme}-{initial}-{degree}", limit)
        period = rocking_period(out) if (out / "probes.csv").exists() else None
        measure = f"{period:.3f} s ({100 * (period / T - 1):+.1f} %)" if period else "no full swing"
        where = "P1 graded" if degree == 1 else "P2 uniform 1 cm"
        lines.append(row(f"{scheme}, initial = {initial}, {where}", r, wall, measure))
    lines += [""] + breakdown(mesh, work)
    (HERE / "contact_schemes.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def one(scene_json: str, out: str) -> None:
    """One run, as `fem-forms run` does it (results.json written, quiet)."""
    import fem_forms as ff
    from fem_forms.analyses import run_analysis
    ff.quiet_jit()
    run_analysis(ff.Scene.from_dict(json.loads(Path(scene_json).read_text())), Path(out))


if __name__ == "__main__":
    if sys.argv[1:2] == ["--one"]:
        one(*sys.argv[2:4])
    else:
        main()
