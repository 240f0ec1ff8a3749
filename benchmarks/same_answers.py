"""Do two versions of fem_forms give the same answers? Runs every demo and benchmark scene (made small
with --set where they are large) through `python -m fem_forms run`, every demo script and every case of the
verification manual, in a checkout of REF and in this tree, and compares the numbers users read from each
results.json (probe displacements and rest positions, frequencies, max |u|, energy, Newton iterations and
steps, reactions, contact forces and gaps, the crack's numbers, a dynamic run's final energies) to a relative
tolerance (numbers below 1e-6 of a run's largest against that floor).

    .venv/bin/python benchmarks/same_answers.py cb0ef34 [--tol 1e-10] [--out benchmarks/same_answers.md]
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = [
    ("demos/scenes/sagging_beam.toml", []),
    ("demos/scenes/straight_beam_inverse.toml", []),
    ("demos/scenes/straight_beam_inverse.toml", ['inverse.method="adjoint"']),
    ("demos/scenes/goblet_inverse.toml", []),
    ("demos/scenes/struck_bar.toml", []),
    ("benchmarks/scenes/beam_gravity.toml", ["mesh.cells=[20, 2, 2]"]),
    ("benchmarks/scenes/beam_gravity.toml", ["mesh.cells=[20, 2, 2]", 'mesh.cell="hexahedron"']),
    ("benchmarks/scenes/incompressible_block.toml", []),
    ("benchmarks/scenes/modal_beam.toml", ["mesh.cells=[16, 4, 4]"]),
]


def key_numbers(summary: dict) -> dict[str, float]:
    """name -> value of every number a user reads from results.json."""
    out = {}
    for k in ("max_displacement", "energy", "max_rest_offset"):
        if isinstance(summary.get(k), (int, float)):
            out[k] = float(summary[k])
    for i, f in enumerate(summary.get("frequencies_hz") or []):
        out[f"f{i + 1}"] = float(f)
    for name, p in (summary.get("probes") or {}).items():
        for key in ("displacement", "rest_position"):
            for c, v in enumerate(p.get(key) or []):
                out[f"{name}.{key}[{c}]"] = float(v)
    for k in ("newton_iterations", "load_steps", "steps", "time_reached", "min_distance", "damage_max",
              "crack_area", "cracked_volume", "surface_energy", "peak_load_factor", "staggered_sweeps"):
        if isinstance(summary.get(k), (int, float)) and not isinstance(summary.get(k), bool):
            out[k] = float(summary[k])
    for k, v in (summary.get("energy_final") or {}).items():     # a dynamic run's energy account at the end
        out[f"energy_final.{k}"] = float(v)
    for name, c in (summary.get("contact") or {}).items():       # each obstacle's force on the part
        for i, f in enumerate(c.get("force") or []):
            out[f"contact.{name}.force[{i}]"] = float(f)
    for name, r in (summary.get("reactions") or {}).items():
        for i, f in enumerate(r):
            out[f"reactions.{name}[{i}]"] = float(f)
    if summary.get("analysis") == "balance":        # its numbers are the design's mass properties
        for k, v in summary.items():
            if k in BALANCE_KEYS:
                for i, x in enumerate(np.ravel(np.asarray(v, dtype=float))):
                    out[f"{k}[{i}]"] = float(x)
    return out


# the numbers a balance design reports (timings, ranks and file names left out)
BALANCE_KEYS = ("mass", "center_of_mass", "inertia", "principal_moments", "stability_margin", "toppling_angle_deg",
                "carved_fraction", "spin_ratio", "principal_axis_angle_deg", "waterline", "center_of_buoyancy",
                "righting_arm", "curvature_center", "rocking_radius")


def run(tree: Path, scene: str, sets: list[str], out: Path) -> dict:
    cmd = [sys.executable, "-m", "fem_forms", "run", str(ROOT / scene), "--out", str(out)]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1")
    p = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    res = out / "results.json"
    if not res.exists():
        raise RuntimeError(f"{scene} in {tree}: exit {p.returncode}: {p.stderr.strip()[-300:]}")
    return json.loads(res.read_text())


def run_folder(tree: Path, args: list[str], cwd: Path) -> dict[str, dict]:
    """Run `python ARGS` from `tree` in `cwd` (a demo script, the verification runner) and read every
    results.json it wrote under cwd: {relative path: results}."""
    cwd.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1")
    subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True)
    return {str(p.relative_to(cwd)): json.loads(p.read_text()) for p in sorted(cwd.rglob("results.json"))}


def compare(a: dict[str, float], b: dict[str, float]) -> tuple[float, str]:
    """Largest relative difference of b against a (a number missing in b counts as NaN) and its name."""
    scale = max((abs(v) for v in a.values()), default=1.0) or 1.0
    diffs = {k: abs(a[k] - b.get(k, float("nan"))) / max(abs(a[k]), 1e-6 * scale) for k in a}
    worst_key = max(diffs, key=lambda k: (diffs[k] != diffs[k], diffs[k])) if diffs else "-"
    return diffs.get(worst_key, 0.0), worst_key


def runs(ref_tree: Path, tmp: Path):
    """(name, reference results, this tree's results) of every scene, demo run and verification case."""
    for scene, sets in SCENES:
        yield (f"{scene} {' '.join(sets)}", run(ref_tree, scene, sets, tmp / "a" / Path(scene).stem),
               run(ROOT, scene, sets, tmp / "b" / Path(scene).stem))
    jobs = [(f"demos/{p.name}", ["demos/" + p.name]) for p in sorted((ROOT / "demos").glob("*.py"))]
    jobs.append(("verification", ["verification/run.py", "--no-readme", "--out"]))
    for name, args in jobs:
        folder = Path(name).stem
        here = {side: tmp / side / folder for side in "ab"}       # the runner's --out: absolute (it runs from
        extra = {side: [str(here[side] / "out")] if args[-1] == "--out" else [] for side in "ab"}   # its root)
        a = run_folder(ref_tree, [str(ref_tree / args[0]), *args[1:], *extra["a"]], here["a"])
        b = run_folder(ROOT, [str(ROOT / args[0]), *args[1:], *extra["b"]], here["b"])
        for path in a:
            yield f"{name}: {path}", a[path], b.get(path, {})


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ref", help="git revision to compare with (e.g. the previous main)")
    ap.add_argument("--tol", type=float, default=1e-10, help="largest relative difference allowed")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "same_answers.md"))
    args = ap.parse_args()
    rows, worst_all = [], 0.0
    with tempfile.TemporaryDirectory() as tmp:
        ref_tree = Path(tmp) / "ref"
        subprocess.run(["git", "worktree", "add", "--detach", str(ref_tree), args.ref], cwd=ROOT,
                       check=True, capture_output=True)
        try:
            for name, a, b in runs(ref_tree, Path(tmp)):
                a, b = key_numbers(a), key_numbers(b)
                worst, worst_key = compare(a, b)
                worst_all = max(worst_all, worst) if worst == worst else float("nan")
                rows.append(f"| {name} | {len(a)} | {worst:.1e} ({worst_key}) |")
                print(rows[-1], flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(ref_tree)], cwd=ROOT,
                           capture_output=True)
    ok = worst_all <= args.tol                   # NaN (a number missing): not met
    text = (f"# Same answers as {args.ref}\n\n`benchmarks/same_answers.py {args.ref}`: largest relative "
            f"difference of the numbers results.json reports (numbers below 1e-6 of the scene's largest "
            f"are compared with that floor), tolerance {args.tol:g}: {'met' if ok else 'NOT met'}.\n\n"
            "| run | numbers | largest relative difference |\n|---|---:|---|\n" + "\n".join(rows) + "\n")
    Path(args.out).write_text(text)
    print(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
