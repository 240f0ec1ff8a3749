"""Benchmark: cost per time step of the dynamic analysis against the same march in bare dolfinx/PETSc.

A 1 x 0.1 x 0.1 m neo-Hookean cantilever (E 1e8 Pa, nu 0.3, rho 1000 kg/m^3) clamped at x = 0, released
from rest under suddenly applied gravity; P1 tetrahedra, quadrature degree 2 (the package's default for
P1). Three mesh sizes (5,508, 19,683 and 95,175 dofs), three schemes:
  newmark             average acceleration, consistent mass, dt 1e-3 s (~200 steps per first period);
  generalized-alpha   Chung-Hulbert, rho_inf 0.8, the same dt;
  central-difference  explicit, HRZ-lumped mass, dt half the package's stable-step estimate.

"ours" is ``fem_forms.analyses.dynamic.solve_dynamic(scene)`` (no files: the benchmark times the march).
"bare" writes the same effective forms inline (the generalized-alpha incremental potential with the
inertia of the consistent mass; the explicit residual and the HRZ diagonal) and imports nothing from
fem_forms. Implicit bare: one PETSc SNES per step with the same options ours uses (newtonls without line
search, the tangent and its MUMPS LU kept across steps, GMRES on the kept tangent); a second bare variant
("bare LU") assembles and factors afresh at every Newton iteration (plain MUMPS preonly), which measures
what keeping them saves. Explicit bare: one residual assembly and a division by the lumped diagonal per step.

Per run: setup (scene -> ready to march: mesh, forms, initial acceleration; ours also its stable-step
estimate and the mass matrix of its energy account), the first step (implicit: includes the LU
factorisation) and the median of the later steps. Ours is split into the same work as bare (the step,
commit and loop) and its legitimate extras, measured by wrapping them: energy accounting and probes.
LU factorisations are counted by PETSc's log (MatLUFactorNum). Every time is taken as wall and as process
CPU time: with other jobs on the cores, the CPU ratio is the fair one.

One subprocess per (size, scheme) runs a warm-up march on a tiny mesh (JIT cache and PETSc/MUMPS
loaded), then ours, bare, ours, bare, ... interleaved, so load from other jobs hits both alike.

Run (under 5 minutes on a quiet 2-core machine):
    .venv/bin/python benchmarks/dynamic_steps.py            # -> stdout and benchmarks/dynamic_steps.md
    .venv/bin/python benchmarks/dynamic_steps.py --quick    # 5k and 20k dofs only, 2 repeats
"""
from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from dynamic_linear import KINDS, LINEAR_SIZES, linear_table  # noqa: E402
from dynamic_pays import MATERIALS, pays_table  # noqa: E402
from dynamic_bare import (DEGREE, DT_IMPLICIT, E, GRAVITY, LENGTH, LU_STEPS, NU, QUADRATURE, RHO,  # noqa: E402
                          RHO_INF, SCHEMES, SIZES, STEPS, TIP, WARMUP_CELLS, WIDTH, bare_run, lu_count, now, split)


# ============================================================================ ours (fem_forms)
def scene_dict(cells, scheme: str, dt: float, steps: int, linear: str = "auto") -> dict:
    return {"title": "dynamic benchmark", "analysis": "dynamic", "solver": {"linear": linear},
            "mesh": {"generator": "box", "size": [LENGTH, WIDTH, WIDTH], "cells": list(cells),
                     "cell": "tetrahedron"},
            "material": {"model": "neo-hookean", "E": E, "nu": NU, "rho": RHO},
            "discretization": {"degree": DEGREE},
            "fix": [{"where": {"axis": "x", "at": 0.0}}],
            "load": [{"type": "gravity", "g": list(GRAVITY)}],
            "output": {"probes": {"tip": TIP}, "picture": False, "fields": False},
            "dynamic": {"duration": dt * steps, "dt": dt, "scheme": scheme, "rho_inf": RHO_INF,
                        "mass": "lumped" if scheme == "central-difference" else "consistent",
                        "checkpoint_every": 0}}


class OursTimer:
    """Wraps solve_dynamic's march, energy accounting and probe rows to time each step and its extras, and
    the implicit step's acceptance checks (det F > 0 everywhere; a residual re-assembly if ever called)."""

    def __init__(self):
        import fem_forms.analyses.dynamic.solve as solve
        from fem_forms.analyses.dynamic.energy import EnergyAccount
        from fem_forms.model import Model
        from fem_forms.solvers import snes
        self.solve = solve
        self.options = None
        march, advance, probe_row = solve.march, EnergyAccount.advance, solve.probe_row
        build, solve_step = snes.SNESDriver.rebuild, snes.SNESDriver.solve_step
        residual_norm, inadmissible = snes.SNESDriver.residual_norm, Model.inadmissible

        def timed_march(stepper, t0, t_end, dt, on_accept, **kw):
            self.t_march = now()
            self.check_now = 0.0 * now()

            def accept(t, h, step):
                on_accept(t, h, step)
                self.stamps.append(now())
                self.checks.append(self.check_now)
                self.check_now = 0.0 * now()
            return march(stepper, t0, t_end, dt, accept, **kw)

        def timed_advance(account, *a):
            t = now()
            out = advance(account, *a)
            self.energy.append(now() - t)
            return out

        def timed_probe_row(*a):
            t = now()
            out = probe_row(*a)
            self.probes.append(now() - t)
            return out

        def timed_check(f):
            def checked(*a):
                t = now()
                out = f(*a)
                self.check_now = self.check_now + now() - t
                return out
            return checked

        def counted_solve_step(driver, *a, **kw):
            rec = solve_step(driver, *a, **kw)
            self.krylov += rec.krylov_iterations
            return rec

        def recording_build(driver):
            build(driver)
            self.options = dict(driver.options)
        solve.march, solve.probe_row = timed_march, timed_probe_row
        EnergyAccount.advance = timed_advance
        snes.SNESDriver.rebuild = recording_build
        snes.SNESDriver.solve_step = counted_solve_step
        snes.SNESDriver.residual_norm, Model.inadmissible = timed_check(residual_norm), timed_check(inadmissible)

    def run(self, cells, scheme: str, dt: float, steps: int, linear: str = "auto") -> dict:
        import fem_forms as ff
        import numpy as np
        self.stamps, self.energy, self.probes, self.checks, self.krylov = [], [], [], [], 0
        self.check_now = 0.0 * now()
        scene = ff.Scene.from_dict(scene_dict(cells, scheme, dt, steps, linear))
        lu0 = lu_count()
        t0 = now()
        res = self.solve.solve_dynamic(scene)
        t_end = now()
        self.probes = self.probes[1:]                  # the row at t = 0 belongs to the setup
        durations = np.diff(np.array([self.t_march] + self.stamps), axis=0)
        energy, probes = np.array(self.energy), np.array(self.probes)
        same = durations - energy - probes
        checks = np.array(self.checks)
        lu = lu_count()
        u = res.system.u.x.array.reshape(-1, 3)
        comm = res.system.model.mesh.comm
        return {"dofs": res.system.model.dofs, **split(self.t_march - t0, "setup"), **split(t_end - t0, "total"),
                "steps": res.report.steps, **split(same[0], "first"), **split(np.median(same[1:], axis=0), "later"),
                **split(np.median(durations[1:], axis=0), "later_full"),
                **split(np.median(energy[1:], axis=0), "energy"), **split(np.median(checks[1:], axis=0), "checks"),
                **split(np.median((same - checks)[1:], axis=0), "later_unchecked"), **split(np.median(probes[1:], axis=0), "probes"),
                "newton": res.report.newton_iterations, "krylov": self.krylov,
                "builds": res.solver.get("preconditioner_builds", 0),
                "lu": lu[0] - lu0[0], "lu_time": lu[1] - lu0[1], "dt": dt, "dt_stable": res.dt_stable,
                "max_u": comm.allreduce(float(np.linalg.norm(u, axis=1).max()), op=max),
                "options": self.options if scheme != "central-difference" else None}


def stable_dt(cells) -> float:
    """The package's stable-step estimate for the explicit scheme on this mesh (outside any timing)."""
    import fem_forms as ff
    from fem_forms.analyses.dynamic.explicit import stable_step
    from fem_forms.analyses.dynamic.system import build_system
    system = build_system(ff.Scene.from_dict(scene_dict(cells, "central-difference", 1e-9, 1)))
    return stable_step(system)[0]


# ============================================================================ driver
def worker(cells, scheme: str, runs: int, mode: int) -> None:
    """Warm-up, then ours and bare interleaved `runs` times (mode 1: also 'bare LU' once; mode 2: ours
    with direct and with iterative linear solves instead); one JSON line per run on stdout."""
    import logging
    from petsc4py import PETSc
    sys.path.insert(0, str(ROOT))
    import fem_forms as ff
    ff.quiet_jit()
    logging.disable(logging.INFO)
    PETSc.Log.begin()
    ours = OursTimer()
    steps = STEPS[scheme]
    if scheme == "central-difference":
        dt, dt_warm = 0.5 * stable_dt(cells), 0.5 * stable_dt(WARMUP_CELLS)
    else:
        dt = dt_warm = DT_IMPLICIT
    ours.run(WARMUP_CELLS, scheme, dt_warm, 3, "iterative" if mode == 2 else "auto")
    ours.run(WARMUP_CELLS, scheme, dt_warm, 3) if mode == 2 else bare_run(WARMUP_CELLS, scheme, dt_warm, 3)
    for r in range(runs):
        impls = list(KINDS) if mode == 2 else ["ours", "bare"] + (["bare LU"] if mode == 1 and r == 0 else [])
        for impl in (impls if r % 2 == 0 else impls[::-1]):
            gc.collect()
            load = os.getloadavg()[0]
            res = ours.run(cells, scheme, dt, steps, impl) if impl in KINDS else ours.run(cells, scheme, dt, steps) \
                if impl == "ours" else \
                bare_run(cells, scheme, dt, steps if impl == "bare" else LU_STEPS, lu_every_newton=impl == "bare LU")
            res.update(impl=impl, load=load)
            print("RESULT " + json.dumps(res), flush=True)


def run_worker(timeout: float, *args) -> list:
    """This script as a subprocess with the given arguments; its RESULT lines as dicts."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), *(str(a) for a in args)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout, cwd=ROOT)
    rows = [json.loads(ln[len("RESULT "):]) for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode != 0 or not rows:
        raise RuntimeError(f"{args} failed (exit {p.returncode}):\n{p.stdout[-2000:]}\n{p.stderr[-4000:]}")
    return rows


def med(rows: list, key: str) -> float:
    return statistics.median(r[key] for r in rows)


def ms(x: float) -> str:
    return f"{1e3 * x:,.1f}" if x < 1 else f"{1e3 * x:,.0f}"



# ============================================================================ when each scheme pays
def pays_worker(cells) -> None:
    """The package's explicit stable-step estimate on this mesh for a stiff and a soft part."""
    import logging
    sys.path.insert(0, str(ROOT))
    import fem_forms as ff
    from fem_forms.analyses.dynamic.explicit import stable_step
    from fem_forms.analyses.dynamic.system import build_system
    ff.quiet_jit()
    logging.disable(logging.INFO)
    for name, (e, nu, rho) in MATERIALS.items():
        d = scene_dict(cells, "central-difference", 1e-9, 1)
        d["material"] = {"model": "neo-hookean", "E": e, "nu": nu, "rho": rho}
        dt = stable_step(build_system(ff.Scene.from_dict(d)))[0]
        print("RESULT " + json.dumps({"material": name, "dt_stable": dt}), flush=True)


# ============================================================================ report
def step_table(results: dict) -> str:
    head = ("| dofs | scheme | steps | setup s | first step ms | later steps ms (wall) | later steps ms (CPU) | "
            "ratio wall | ratio CPU | ours' checks ms/step CPU | ratio CPU without them | ours' extras ms/step CPU "
            "(energy + probes) | Newton (Krylov) its | LU factorisations |\n"
            "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    rows = []
    for (cells, scheme), rs in results.items():
        o = [r for r in rs if r["impl"] == "ours"]
        b = [r for r in rs if r["impl"] == "bare"]
        cell = lambda k, f=ms: f"{f(med(o, k))} / {f(med(b, k))}"       # noqa: E731
        rows.append(f"| {o[0]['dofs']:,} | {scheme} | {o[0]['steps']} | {cell('setup', lambda x: f'{x:.2f}')} | "
                    f"{cell('first')} | {cell('later')} | {cell('later_cpu')} | "
                    f"{med(o, 'later') / med(b, 'later'):.2f} | {med(o, 'later_cpu') / med(b, 'later_cpu'):.2f} | "
                    f"{ms(med(o, 'checks_cpu'))} | {med(o, 'later_unchecked_cpu') / med(b, 'later_cpu'):.2f} | "
                    f"{ms(med(o, 'energy_cpu'))} + {ms(med(o, 'probes_cpu'))} | "
                    f"{o[0]['newton']} ({o[0]['krylov']}) / {b[0]['newton']} ({b[0]['krylov']}) | "
                    f"{o[0]['lu']} / {b[0]['lu']} |")
    return head + "\n".join(rows) + "\n"


def reuse_table(results: dict) -> str:
    head = ("| dofs | scheme | later steps ms CPU: ours / bare (kept) / bare LU (fresh at every Newton iteration) | "
            "LU factorisations (steps) | one factorisation ms | keeping them saves |\n|---:|---|---|---|---:|---:|\n")
    rows = []
    for (cells, scheme), rs in results.items():
        by = {k: [r for r in rs if r["impl"] == k] for k in ("ours", "bare", "bare LU")}
        if not by["bare LU"]:
            continue
        o, b, f = by["ours"], by["bare"], by["bare LU"]
        rows.append(f"| {o[0]['dofs']:,} | {scheme} | {ms(med(o, 'later_cpu'))} / {ms(med(b, 'later_cpu'))} / "
                    f"{ms(med(f, 'later_cpu'))} | {o[0]['lu']} ({o[0]['steps']}) / {b[0]['lu']} ({b[0]['steps']}) / "
                    f"{f[0]['lu']} ({f[0]['steps']}) | {ms(med(f, 'lu_time') / f[0]['lu'])} | "
                    f"{med(f, 'later_cpu') / med(o, 'later_cpu'):.1f}x per step |")
    return head + "\n".join(rows) + "\n"


def checks(results: dict) -> list:
    """Same problem, same options, same answer: one line per (size, scheme)."""
    notes = []
    for (cells, scheme), rs in results.items():
        o = next(r for r in rs if r["impl"] == "ours")
        same = [r for r in rs if r["steps"] == o["steps"]]
        worst = max(abs(r["max_u"] - o["max_u"]) / abs(o["max_u"]) for r in same)
        if any(r["impl"] == "bare" and r["options"] != o["options"] for r in rs):
            notes.append(f"WARNING {o['dofs']:,} dofs {scheme}: PETSc options of ours and bare differ")
        notes.append(f"{o['dofs']:,} dofs {scheme}: max |u| after {o['steps']} steps {o['max_u']:.9e} m, largest "
                     f"relative difference among the {len(same)} runs (ours and bare) {worst:.1e}"
                     + ("; ours used the bare PETSc options exactly" if o["options"] else ""))
    return notes


def markdown(results: dict, linear_results: dict, stable: dict, sizes: list, runs: int, loads: list,
             wall: float) -> str:
    """The benchmark's page: the step, reuse, pays and linear tables with their explanations and the machine."""
    last = {s: next(r for r in results[(sizes[-1], s)] if r["impl"] == "ours") for s in SCHEMES}
    agg = {s: {k: med([r for r in results[(sizes[-1], s)] if r["impl"] == "ours"], k + "_cpu")
               for k in ("first", "later_full")} for s in SCHEMES}
    cd = [r for r in results[(sizes[-1], "central-difference")]]
    sps = {k: 1.0 / med([r for r in cd if r["impl"] == k], "later_cpu") for k in ("ours", "bare")}
    sps_full = 1.0 / med([r for r in cd if r["impl"] == "ours"], "later_full_cpu")
    all_loads = [r["load"] for rs in (*results.values(), *linear_results.values()) for r in rs]
    md = ["# Dynamics: cost per time step, fem_forms (ours) against bare dolfinx/PETSc (bare)", "",
          f"1 x 0.1 x 0.1 m neo-Hookean cantilever (E {E:g} Pa, nu {NU}, rho {RHO:g} kg/m^3) clamped at x = 0, "
          f"released from rest under gravity; P{DEGREE} tetrahedra, quadrature degree {QUADRATURE}. Implicit "
          f"schemes dt {DT_IMPLICIT:g} s (generalized-alpha rho_inf {RHO_INF}), consistent mass, Newton "
          "with the tangent and its MUMPS LU kept across steps (GMRES on the kept tangent); central difference HRZ-lumped mass, "
          "dt half the package's stable-step estimate. Serial, OPENBLAS_NUM_THREADS=1, one process per "
          f"(size, scheme) after a warm-up march (JIT excluded), ours and bare interleaved, median of {runs} "
          f"runs ({min(runs, 2)} at the largest size; 'bare LU' once, {LU_STEPS} steps); steps per run: "
          f"{', '.join(f'{k} {v}' for k, v in STEPS.items())}; each cell is ours / bare; ratio = ours / bare of "
          "the later steps (the CPU ratio is the fair one on a loaded machine).", "",
          step_table(results),
          "setup: scene to the first step (mesh, forms, initial acceleration; ours also its stable-step "
          "estimate, probe location and the energy account's mass matrix); first step: includes the LU "
          "factorisation for the implicit schemes; later steps: median wall time per step after the first, "
          "ours without its energy accounting and probes (the same work as bare: the step, commit and loop), "
          "which are listed separately; checks: the implicit step's acceptance check inside the same work that "
          "bare does not do (det F > 0 at every quadrature point; the residual test reads SNES's own last norm, "
          "taken at the accepted state); Newton and Krylov iterations and LU factorisations: totals of one run.", "",
          f"**Explicit steps per second at {last['central-difference']['dofs']:,} dofs** (P1, lumped mass): "
          f"CPU time per step: ours {sps['ours']:.0f} (same work), {sps_full:.0f} with energy accounting and probes every step; "
          f"bare {sps['bare']:.0f}.", "",
          "## The tangent and its LU factor kept across steps", "",
          reuse_table(results),
          "## When each scheme pays", "",
          "Explicit: dt at most the package's stable-step estimate (0.9 x 2 / omega_max, power iteration) on "
          "this mesh; both schemes at most the accuracy step min(event / 100, T1 / 20) (T1: first bending "
          "period, Euler-Bernoulli); the implicit ones have no stability limit. Costs = steps x the measured "
          "per-step CPU cost above (ours with energy accounting and probes; implicit: first step + later "
          f"steps, Newmark), for this mesh and the benchmark's {last['newmark']['newton'] / last['newmark']['steps']:.1f} "
          "Newton iterations per step (a soft part in large motion needs more).", "",
          pays_table(last["newmark"]["dofs"], stable, agg["newmark"], agg["central-difference"]),
          *([] if not linear_results else [
              "## Direct (MUMPS) or iterative (CG + GAMG)", "",
              "Ours only, `[solver] linear = \"direct\"` (the tangent and its LU kept across steps, GMRES on the "
              "kept tangent) against `\"iterative\"` (CG + GAMG with the rigid-body near-nullspace, a fresh tangent "
              "at every Newton iteration, the multigrid hierarchy kept across Newton iterations and time steps by the "
              "driver's cost rule), interleaved, median of 2 runs; each cell is direct / iterative; 'iterative "
              "cheaper for': the run lengths (steps, first step + later steps) for which the iterative path costs "
              "less CPU time in all; max |u| relative difference: the two answers after the last step.", "",
              linear_table(linear_results)]),
          *[f"- {n}" for n in checks(results)], "",
          f"Machine: {platform.node()}, {os.cpu_count()} cores, Python {platform.python_version()}; load average "
          f"(1, 5, 15 min) {tuple(round(x, 2) for x in loads[0])} at the start and "
          f"{tuple(round(x, 2) for x in loads[-1])} at the end, 1-minute load before each run {min(all_loads):.1f} to "
          f"{max(all_loads):.1f} (the benchmark itself accounts for 1; more means other jobs shared the 2 cores). "
          f"Benchmark wall time {wall / 60:.1f} min.", ""]
    return "\n".join(md)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the two smaller sizes, 2 repeats")
    ap.add_argument("--runs", type=int, default=None, help="repeats per configuration (default 3, quick 2)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "dynamic_steps.md"), help="markdown ('' for none)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds allowed per subprocess")
    ap.add_argument("--linear", action="store_true", help="also MUMPS against CG + GAMG (ours) at 95k and 266k dofs")
    args = ap.parse_args()
    sizes = SIZES[:2] if args.quick else SIZES
    runs = args.runs or (2 if args.quick else 3)
    t_start = time.perf_counter()
    loads = [os.getloadavg()]
    results: dict = {}
    for cells in sizes:
        for scheme in SCHEMES:
            n = runs if cells != SIZES[-1] else min(runs, 2)      # the largest size: at most 2 (time)
            rows = run_worker(args.timeout, "--worker", scheme, n, int(scheme == "newmark"), *cells)
            results[(cells, scheme)] = rows
            for r in rows:
                print(f"  {r['dofs']:>7,} dofs {scheme:18s} {r['impl']:7s}: setup {r['setup']:.2f} s, first "
                      f"{ms(r['first'])} ms, later {ms(r['later'])} ms, {r['newton']} Newton, {r['lu']} LU, "
                      f"load {r['load']:.1f}", file=sys.stderr, flush=True)
    linear_results = {(cells, scheme): run_worker(args.timeout, "--worker", scheme, min(runs, 2), 2, *cells)
                      for cells in (LINEAR_SIZES if args.linear else []) for scheme in SCHEMES[:2]}
    stable = {r["material"]: r["dt_stable"] for r in run_worker(args.timeout, "--pays", *sizes[-1])}
    loads.append(os.getloadavg())
    wall = time.perf_counter() - t_start
    text = markdown(results, linear_results, stable, sizes, runs, loads, wall)
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    if "--worker" in sys.argv:
        i = sys.argv.index("--worker")
        scheme, runs, mode, *cells = sys.argv[i + 1: i + 7]
        worker(tuple(int(c) for c in cells), scheme, int(runs), int(mode))
    elif "--pays" in sys.argv:
        i = sys.argv.index("--pays")
        pays_worker(tuple(int(c) for c in sys.argv[i + 1: i + 4]))
    else:
        main()
