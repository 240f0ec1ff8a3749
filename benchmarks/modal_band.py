"""`[modal] up_to` against `count`: the audible modes of a struck bar.

The free aluminium bar of demos/scenes/struck_bar.toml (300 x 30 x 10 mm, E 70 GPa, nu 0.33, rho 2700)
on 90 x 9 x 3 P2 tetrahedra (72,219 dofs) is solved three ways, each in a fresh process:

- count = 100: the user's guess, most of them above hearing;
- up_to = 20000 Hz: every mode below the hearing limit, counted by an inertia, then found;
- count = N: as many modes as up_to found (what a user who knew N beforehand would pay).

`solve_modal` is timed end to end (mesh, forms, assembly, inertia, eigensolve, signs); the table
reports medians over --repeats runs and checks that the three agree on the modes below 20 kHz.

"listener pressures" times the radiated pressure of every computed mode at the issue's listener
[0.0, 0.5, 0.2] (output/radiation.py; its forms compiled beforehand by the JIT warm-up run).

Run: `.venv/bin/python benchmarks/modal_band.py [--write]` (about 5 minutes on 2 cores).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
UP_TO = 20000.0
LISTENER = [0.0, 0.5, 0.2]


def scene_dict(cells: list, modal: dict) -> dict:
    d = tomllib.loads((ROOT / "demos" / "scenes" / "struck_bar.toml").read_text())
    d.pop("sound")
    d["mesh"]["cells"] = cells
    d["modal"] = modal
    return d


def child(cells: list, modal: dict) -> dict:
    """One measurement in this (fresh) process."""
    sys.path.insert(0, str(ROOT))
    import fem_forms as ff
    from fem_forms.analyses.modal import solve_modal
    from fem_forms.output.radiation import Radiation
    ff.quiet_jit()
    scene = ff.Scene.from_dict(scene_dict(cells, modal))
    t0 = time.perf_counter()
    res = solve_modal(scene)
    total = time.perf_counter() - t0
    s = res.summary()
    t0 = time.perf_counter()                 # the listener's pressure from every mode (form compiled before)
    radiation = Radiation(res.model.V, LISTENER, 1.2, 343.0)
    pressures = [abs(radiation.pressure(m, 2 * math.pi * f)) for m, f in zip(res.modes, res.frequencies_hz)]
    return {"total_s": total, "eigensolve_s": res.eigensolve_time_s, "dofs": res.model.dofs,
            "freqs": res.frequencies_hz.tolist(), "band": s.get("band"), "radiation_s": time.perf_counter() - t0,
            "pressures": pressures, "maxrss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def run_child(cells: list, modal: dict) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, __file__, "--child", json.dumps([cells, modal])], env=env,
                       capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs=3, default=[90, 9, 3])
    ap.add_argument("--count", type=int, default=100, help="the guessed count")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--write", action="store_true", help="also write benchmarks/modal_band.md")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(*json.loads(args.child))))
        return

    t_start = time.perf_counter()
    run_child([3, 1, 1], {"up_to": UP_TO})                   # warm the JIT cache: not measured
    first = run_child(args.cells, {"up_to": UP_TO})
    n = len(first["freqs"])
    cases = [("count", {"count": args.count}), ("up_to", {"up_to": UP_TO}), ("count", {"count": n})]
    runs = {i: [] for i in range(len(cases))}
    runs[1].append(first)
    for r in range(args.repeats):                            # interleaved: machine load hits all alike
        for i, (_, modal) in enumerate(cases):
            if len(runs[i]) < args.repeats:
                runs[i].append(run_child(args.cells, modal))
    ref = first["freqs"]
    lines = ["| run | modes computed | of them below 20 kHz | total [s] | eigensolve [s] | inertia count [s] | "
             "listener pressures [s] | peak RSS [MB] | max rel. diff to up_to below 20 kHz | runs |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for i, (name, modal) in enumerate(cases):
        rs = runs[i]
        f = rs[0]["freqs"]
        audible = [x for x in f if x < UP_TO]
        diff = max(abs(a - b) / b for a, b in zip(audible, ref)) if audible else float("nan")
        inertia = statistics.median(r["band"]["inertia_time_s"] for r in rs) if rs[0]["band"] else None
        label = f"`up_to = {UP_TO:.0f}`" if name == "up_to" else f"`count = {modal['count']}`"
        lines.append(f"| {label} | {len(f)} | {len(audible)} | {statistics.median(r['total_s'] for r in rs):.2f} | "
                     f"{statistics.median(r['eigensolve_s'] for r in rs):.2f} | "
                     f"{'-' if inertia is None else f'{inertia:.2f}'} | "
                     f"{statistics.median(r['radiation_s'] for r in rs):.2f} | "
                     f"{statistics.median(r['maxrss_mb'] for r in rs):.0f} | {diff:.1e} | {len(rs)} |")
    total = time.perf_counter() - t_start
    band = first["band"]
    text = (f"{first['dofs']:,} dofs; up_to's inertia count: {band['eigenvalues_below_limit']} eigenvalues below "
            f"(2 pi 20 kHz)^2, {band['rigid_modes']} of them rigid-body modes, so {band['modes_below_limit']} "
            f"elastic modes ({band['method']}).\n\n" + "\n".join(lines) + f"\n\nTotal benchmark time {total:.0f} s.\n")
    print(text)
    if args.write:
        (HERE / "modal_band.md").write_text(
            "# Modes by band: `up_to = 20000` against `count` on the struck bar\n\n"
            "Produced by `benchmarks/modal_band.py` (serial, OPENBLAS_NUM_THREADS=1, one fresh process per run, "
            "medians over `runs`). The free aluminium bar of `demos/scenes/struck_bar.toml` on 90 x 9 x 3 P2 "
            "tetrahedra; \"total\" is `solve_modal` end to end, \"eigensolve\" the SLEPc solve alone (factorisation "
            "included), \"inertia count\" the LDL^T factorisation that counts the modes below the limit.\n\n" + text)


if __name__ == "__main__":
    main()
