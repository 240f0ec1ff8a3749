"""Wall time of the PneuNet actuator (demos/pneunet_actuator.py) inflated to its scene's volume on 2 MPI ranks,
at cell sizes giving about 12k and 30k P2 dofs; the median of `--repeat` runs, load averages before and after
each run (the machine is shared). Writes its table into benchmarks/pneunet.md, between the BEGIN and END
lines (the rest of that file is kept: the measurements of earlier versions).

    .venv/bin/python benchmarks/pneunet.py [--sizes 0.006 0.0035] [--repeat 3] [--ranks 2]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BEGIN, END = "<!-- BEGIN benchmarks/pneunet.py -->", "<!-- END benchmarks/pneunet.py -->"


def run_once(h: float, ranks: int, out: Path) -> dict:
    """One demo run; its results.json numbers, the curve's last tip angle, wall time and load averages."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
    cmd = ["mpirun", "-n", str(ranks), "--bind-to", "none", sys.executable, str(ROOT / "demos" / "pneunet_actuator.py"),
           str(out), str(h)]
    load0, t0 = os.getloadavg()[0], time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    res = json.loads((out / "results.json").read_text()) if (out / "results.json").exists() else {}
    angle = float((out / "curve.csv").read_text().splitlines()[-1].split(",")[2]) if (out / "curve.csv").exists() else float("nan")
    return {"h": h, "exit": p.returncode, "wall": wall, "solve": res.get("wall_time_s", float("nan")),
            "dofs": res.get("dofs"), "steps": res.get("load_steps"), "newton": res.get("newton_iterations"),
            "angle": angle, "pressure": res.get("cavities", {}).get("chambers", {}).get("pressure", float("nan")),
            "load": (load0, os.getloadavg()[0])}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.006, 0.0035])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--ranks", type=int, default=2)
    args = ap.parse_args()
    lines = [BEGIN,
             f"{args.ranks} MPI ranks, `--bind-to none`, OPENBLAS_NUM_THREADS=1; the demo's scene (P2, MUMPS LDL^T);"
             " wall = the whole demo process (gmsh, JIT from cache, solve, outputs); solve = results.json"
             " wall_time_s; median of the runs; load = 1-minute load average before -> after each run.", "",
             "| h [mm] | dofs | exit | load steps | Newton | tip angle [deg] | pressure [kPa] | solve [s] | wall [s] | load |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for h in args.sizes:
        runs = []
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as tmp:
                runs.append(run_once(h, args.ranks, Path(tmp)))
            print(runs[-1], flush=True)
        r = runs[0]
        loads = "; ".join(f"{a:.1f}->{b:.1f}" for a, b in (x["load"] for x in runs))
        lines.append(f"| {h * 1e3:g} | {r['dofs']} | {','.join(str(x['exit']) for x in runs)} | {r['steps']} | "
                     f"{r['newton']} | {r['angle']:.2f} | {r['pressure'] / 1e3:.3f} | "
                     f"{statistics.median(x['solve'] for x in runs):.1f} | "
                     f"{statistics.median(x['wall'] for x in runs):.1f} | {loads} |")
    lines.append(END)
    md = ROOT / "benchmarks" / "pneunet.md"
    text = md.read_text()
    md.write_text(text[: text.index(BEGIN)] + "\n".join(lines) + text[text.index(END) + len(END):])
    print("\n".join(lines))


if __name__ == "__main__":
    main()
