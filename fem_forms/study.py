"""Speed against accuracy, measured: solve a scene on a ladder of meshes and element degrees, estimate
each run's error on the scene's key numbers (probe displacements, rest positions or frequencies)
against the finest run and by Richardson extrapolation, and show error against wall time.

Each run is a separate `fem-forms run --set ...` process, so its time and peak memory are its own.
"""
from __future__ import annotations

from dataclasses import dataclass
import json
import math
import os
from pathlib import Path
import shutil
import subprocess
import sys

from mpi4py import MPI
import numpy as np

from fem_forms.errors import InputError, SolveError
from fem_forms.output.results import write_json_atomic
from fem_forms.scene import LIMITS, Limits, Scene

PACKAGE_ROOT = Path(__file__).resolve().parent.parent     # the folder fem_forms is imported from
# Key numbers whose norm is below this fraction of the part's size (the largest probe point or displacement;
# for frequencies the highest one) are zero to the solver's accuracy: a probe on a clamp, an unloaded part.
# Their relative errors would be a ratio of two round-off numbers, so the study reports absolute errors.
KEY_ROUNDOFF = 1e-10


@dataclass
class Run:
    degree: int
    level: int               # 0 = the scene's own mesh (coarsest); each level refines by 2
    overrides: dict
    folder: Path
    dofs: int = 0
    wall: float = math.nan
    memory_mb: float = math.nan
    values: np.ndarray | None = None
    error_finest: float = math.nan
    error_richardson: float = math.nan
    ok: bool = False
    size: float = 0.0        # the magnitude the key numbers are measured against (part size, top frequency)
    error_kind: str = "relative"


def key_numbers(summary: dict) -> np.ndarray | None:
    """The numbers a study compares: modal frequencies, inverse rest positions or static probes."""
    if "frequencies_hz" in summary:
        return np.asarray(summary["frequencies_hz"], dtype=float)
    probes = summary.get("probes") or {}
    vals = []
    for name in sorted(probes):
        p = probes[name]
        vals.extend(p.get("rest_position") or p.get("displacement") or [])
    return np.asarray(vals, dtype=float) if vals else None


def key_size(summary: dict) -> float:
    """What the key numbers are small or large against: the highest frequency, or the largest probe
    point, rest position or displacement magnitude (m)."""
    if "frequencies_hz" in summary:
        return float(np.max(np.abs(summary["frequencies_hz"]), initial=0.0))
    sizes = [abs(float(summary.get("max_displacement") or 0.0))]
    for p in (summary.get("probes") or {}).values():
        for key in ("point", "rest_position", "displacement"):
            if p.get(key):
                sizes.append(float(np.linalg.norm(p[key])))
    return max(sizes)


def mesh_level(scene: Scene, level: int) -> dict:
    """Scene overrides that refine the mesh by 2^level (box cells doubled, gmsh h halved)."""
    m = scene.mesh
    if level == 0:
        return {}
    if m.generator == "box":
        return {"mesh.cells": [c * 2**level for c in m.cells]}
    if m.generator in ("cylinder", "sphere", "revolve"):
        return {"mesh.h": m.h / 2**level}
    raise InputError("study: a mesh file cannot be refined here; use --refine 1 to vary the degree only")


def _run_one(scene_path: Path, run: Run, ranks: int, limits: Limits) -> None:
    cmd = [sys.executable, "-m", "fem_forms", "run", str(scene_path), "--out", str(run.folder), "--no-adapt", "-q"]
    if limits != LIMITS:             # the study's user lifted or changed the caps (the base scene met them)
        cmd.append("--no-limits")
    for k, v in run.overrides.items():
        cmd += ["--set", f"{k}={json.dumps(v)}"]
    # the current folder is not searched for modules (a shared folder's json.py is not imported): fem_forms is
    # found where this one was
    env = {**os.environ, "PYTHONSAFEPATH": "1",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(PACKAGE_ROOT), os.environ.get("PYTHONPATH")]))}
    if ranks > 1:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
        cmd = [shutil.which("mpirun") or "mpirun", "-n", str(ranks), "--bind-to", "none"] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    res = run.folder / "results.json"
    if p.returncode in (0, 3) and res.exists():
        s = json.loads(res.read_text())
        run.dofs = s.get("dofs", 0)
        run.wall = s.get("wall_time_s", math.nan)
        run.memory_mb = s.get("peak_memory_mb", math.nan)
        run.values = key_numbers(s)
        run.size = key_size(s)
        run.ok = p.returncode == 0 and run.values is not None
    elif p.returncode == 2:
        raise InputError(p.stderr.strip().splitlines()[-1].replace("fem-forms: error: ", ""))


def richardson(values: list[np.ndarray]) -> np.ndarray | None:
    """Extrapolated limit from the three finest values of one degree (h, h/2, h/4 order): observed
    order p = log2(|Q1 - Q2| / |Q2 - Q3|), limit Q3 + (Q3 - Q2) / (2^p - 1). None if not convergent."""
    if len(values) < 3:
        return None
    q1, q2, q3 = values[-3:]
    d12, d23 = np.linalg.norm(q1 - q2), np.linalg.norm(q2 - q3)
    if d23 == 0:
        return q3
    ratio = d12 / d23
    if not np.isfinite(ratio) or ratio <= 1.0:
        return None
    p = math.log2(ratio)
    return q3 + (q3 - q2) / (2**p - 1)


def study(scene_path: Path, out: Path, degrees: list[int], refine: int, overrides: dict | None = None,
          ranks: int = 1, echo: bool = True, limits: Limits = LIMITS) -> list[Run]:
    """Run the ladder (the scene's mesh, then refined by 2 per level) and fill in error estimates; each run of it
    within `limits` (NO_LIMITS: --no-limits)."""
    overrides = dict(overrides or {})
    scene = Scene.from_file(scene_path, overrides, limits)           # validates once, up front
    if any(d not in (1, 2) for d in degrees):
        raise InputError(f"study --degrees {degrees}: element degrees 1 and 2 are available")
    if refine < 1:
        raise InputError(f"study --refine {refine}: needs at least 1 level")
    runs = []
    for degree in sorted(set(degrees)):
        # a warm-up run on the coarsest mesh compiles this degree's forms, so no timed run pays JIT
        _run_one(scene_path, Run(degree, 0, {**overrides, "discretization.degree": degree},
                                 out / f"P{degree}_warmup"), ranks, limits)
        shutil.rmtree(out / f"P{degree}_warmup", ignore_errors=True)
        for level in range(refine):
            o = {**overrides, "discretization.degree": degree, **mesh_level(scene, level)}
            run = Run(degree, level, o, out / f"P{degree}_level{level}")
            _run_one(scene_path, run, ranks, limits)
            if echo:
                print(f"  degree {degree}, level {level}: {run.dofs} dofs, {run.wall:.2f} s"
                      + ("" if run.ok else " (failed)"), flush=True)
            runs.append(run)
    good = [r for r in runs if r.ok]
    if not good:
        raise SolveError("study: no run of the ladder converged")
    estimate_errors(good, degrees)
    return runs


def estimate_errors(good: list[Run], degrees: list[int]) -> None:
    """Each converged run's error against the finest run and the highest degree's Richardson limit:
    relative to the finest run's key numbers, or absolute (error_kind) when those are at round-off."""
    shortest = min(len(r.values) for r in good)      # `up_to` finds more modes on some meshes than on others:
    for r in good:                                   # compare the modes every run has
        r.values = r.values[:shortest]
    finest = max(good, key=lambda r: (r.degree, r.level))
    limits = []
    for degree in sorted(set(degrees)):
        series = [r.values for r in sorted((r for r in good if r.degree == degree), key=lambda r: r.level)]
        lim = richardson(series)
        if lim is not None:
            limits.append((degree, lim))
    reference = limits[-1][1] if limits else None               # highest degree's extrapolation
    magnitude = float(np.linalg.norm(finest.values))
    relative = magnitude > KEY_ROUNDOFF * max(r.size for r in good)
    scale = magnitude if relative else 1.0
    for r in good:
        r.error_kind = "relative" if relative else "absolute"
        r.error_finest = np.linalg.norm(r.values - finest.values) / scale
        if reference is not None:
            r.error_richardson = np.linalg.norm(r.values - reference) / scale


def write_report(runs: list[Run], out: Path, title: str) -> str:
    """Markdown table, CSV and a PNG of error against wall time with the Pareto front."""
    absolute = any(r.ok and r.error_kind == "absolute" for r in runs)
    err = "absolute error [m]" if absolute else "error"
    rows = [f"| degree | mesh level | dofs | {err} vs finest | {err} vs Richardson | wall time [s] "
            "| peak memory [MB] |",
            "|---|---|---|---|---|---|---|"]
    csv = ["degree,level,dofs,error_finest,error_richardson,wall_time_s,peak_memory_mb,converged,error_kind"]
    for r in runs:
        rows.append(f"| P{r.degree} | {r.level} | {r.dofs} | {_cell(r.error_finest, '.2e')} | "
                    f"{_cell(r.error_richardson, '.2e')} | {_cell(r.wall, '.2f')} | {_cell(r.memory_mb, '.0f')} |"
                    if r.ok else
                    f"| P{r.degree} | {r.level} | {r.dofs} | failed | | | |")
        csv.append(f"{r.degree},{r.level},{r.dofs},{_field(r.error_finest)},{_field(r.error_richardson)},"
                   f"{_field(r.wall)},{_field(r.memory_mb)},{int(r.ok)},{r.error_kind}")
    table = "\n".join(rows) + "\n"
    if absolute:
        table += (f"\nThe key numbers are zero to the solver's accuracy (below {KEY_ROUNDOFF:g} of the part's size): "
                  "errors are absolute, in m, not relative.\n")
    (out / "study.md").write_text(f"# {title}\n\n" + table)
    (out / "study.csv").write_text("\n".join(csv) + "\n")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 5))
    good = [r for r in runs if r.ok]
    for degree, marker in ((1, "o"), (2, "s")):
        pts = [(r.wall, r.error_richardson if np.isfinite(r.error_richardson) else r.error_finest, r.dofs)
               for r in good if r.degree == degree]
        pts = [p for p in pts if p[1] > 0]
        if pts:
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker=marker, label=f"P{degree}")
            for t, e, n in pts:
                ax.annotate(f"{n}", (t, e), textcoords="offset points", xytext=(4, 4), fontsize=7)
    front = pareto(good)
    if front:
        ax.loglog([r.wall for r in front], [_err(r) for r in front], "k--", lw=0.8, label="Pareto front")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel(f"{err} of the key numbers" if absolute else "relative error of the key numbers")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "study.png", dpi=110)
    plt.close(fig)
    return table


def _cell(x: float, spec: str) -> str:
    """A table cell: the number, or "-" where no estimate exists (NaN: e.g. no Richardson limit)."""
    return format(x, spec) if math.isfinite(x) else "-"


def _field(x: float) -> str:
    """A CSV field: the number, or empty where no estimate exists."""
    return repr(float(x)) if math.isfinite(x) else ""


def _err(r: Run) -> float:
    return r.error_richardson if np.isfinite(r.error_richardson) else r.error_finest


def pareto(runs: list[Run]) -> list[Run]:
    """Runs no other run beats in both time and error, by increasing time."""
    front, best = [], math.inf
    for r in sorted(runs, key=lambda r: r.wall):
        e = _err(r)
        if e > 0 and e < best:
            front.append(r)
            best = e
    return front


def run_study(scene_path: Path, out: Path, degrees: list[int], refine: int, overrides: dict,
              ranks: int = 1, echo: bool = True, limits: Limits = LIMITS) -> list[Run]:
    if MPI.COMM_WORLD.size > 1:
        raise InputError("study: run it serially; use --ranks N for parallel runs of the ladder")
    out.mkdir(parents=True, exist_ok=True)
    title = Scene.from_file(scene_path, overrides, limits).title
    print(f"study of {title}: degrees {degrees}, {refine} mesh levels")
    runs = study(scene_path, out, degrees, refine, overrides, ranks, echo=echo, limits=limits)
    print(write_report(runs, out, title))
    print(f"-> {out}/study.md, study.csv, study.png")
    return runs


def cheapest_meeting(runs: list[Run], tolerance: float) -> Run | None:
    """The fastest converged run whose estimated error is within the tolerance (relative; for absolute errors,
    key numbers at round-off, the tolerance times the part's size)."""
    def allowed(r: Run) -> float:
        return tolerance * (r.size if r.error_kind == "absolute" else 1.0)
    ok = [r for r in runs if r.ok and np.isfinite(_err(r)) and _err(r) <= allowed(r)]
    return min(ok, key=lambda r: r.wall) if ok else None


def solve_to_tolerance(scene_path: Path, out: Path, tolerance: float, overrides: dict,
                       degrees=(1, 2), refine: int = 3, limits: Limits = LIMITS) -> dict:
    """Accuracy on request: run the ladder, pick the cheapest run whose estimated error meets the
    tolerance, and make its results the answer in `out` (results.json gains "error_estimate")."""
    runs = study(scene_path, out / "study", list(degrees), refine, overrides, echo=False, limits=limits)
    write_report(runs, out / "study", "accuracy on request")
    best = cheapest_meeting(runs, tolerance)
    if best is None:
        errs = [_err(r) for r in runs if r.ok and np.isfinite(_err(r))]
        raise SolveError(f"discretization.tolerance = {tolerance}: no run of the ladder meets it (best estimate "
                         f"{min(errs) if errs else float('nan'):.2e}; refine the scene's mesh)")
    for f in best.folder.iterdir():
        if f.name != "results.json":
            shutil.copy2(f, out / f.name)
    summary = json.loads((best.folder / "results.json").read_text())
    summary["error_estimate"] = _err(best)
    summary["error_kind"] = best.error_kind          # "absolute" (m) when the key numbers are at round-off
    summary["tolerance"] = tolerance
    summary["chosen"] = {"degree": best.degree, "mesh_level": best.level, "overrides": best.overrides}
    summary["study"] = "study/study.md"
    write_json_atomic(out / "results.json", summary)
    return summary
