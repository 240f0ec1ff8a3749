"""The neo-Hookean PneuNet actuator under pressure control past its limit point (issue 47 item 4): the demo's
actuator and mesh (6 mm, P2) with a neo-Hookean body, 20 kPa asked for (its pressure maximum is about 15.6 kPa), run
as a user runs it (`python -m fem_forms run`) with each solver.control; median of `--repeat` runs of the solve
(results.json wall_time_s), the peak pressure, where arc length took over (auto), where and why the run ended.
Writes its table into benchmarks/pneunet_limit.md between the BEGIN and END lines.

    .venv/bin/python benchmarks/pneunet_limit.py [--controls auto arc-length load] [--repeat 3] [--ranks 1]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "demos" / "geometry"))
sys.path.insert(0, str(ROOT / "tests"))
import pneunet  # noqa: E402
from helpers import toml_dumps  # noqa: E402

BEGIN, END = "<!-- BEGIN benchmarks/pneunet_limit.py -->", "<!-- END benchmarks/pneunet_limit.py -->"
PRESSURE = 2.0e4


def scene(mesh: Path, control: str) -> dict:
    """The demo's scene with a neo-Hookean body and the chambers' pressure (not their volume) prescribed."""
    d = tomllib.loads((ROOT / "demos" / "scenes" / "pneunet.toml").read_text())
    d["mesh"]["file"] = str(mesh)
    d["material"][0]["model"] = "neo-hookean"
    d["load"][0].pop("volume")
    d["load"][0]["pressure"] = PRESSURE
    d["solver"]["control"] = control
    d["output"] = {"fields": False, "picture": False}
    return d


def run_once(mesh: Path, control: str, ranks: int, out: Path) -> dict:
    out.mkdir()
    (out / "scene.toml").write_text(toml_dumps(scene(mesh, control)))
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
    cmd = ["mpirun", "-n", str(ranks), "--bind-to", "none", sys.executable, "-m", "fem_forms", "run",
           str(out / "scene.toml"), "--out", str(out / "run"), "-q"]
    load0, t0 = os.getloadavg()[0], time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
    res = json.loads((out / "run" / "results.json").read_text())
    return {"exit": p.returncode, "wall": time.perf_counter() - t0, "solve": res["wall_time_s"],
            "steps": res["load_steps"], "newton": res["newton_iterations"], "dofs": res["dofs"],
            "peak": res.get("peak_load_factor", res["load_reached"]), "from": res.get("arc_length_from"),
            "reached": res["load_reached"], "message": res["message"], "load": (load0, os.getloadavg()[0])}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controls", nargs="+", default=["auto", "arc-length", "load"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--ranks", type=int, default=1)
    args = ap.parse_args()
    lines = [BEGIN,
             f"{args.ranks} MPI rank(s), OPENBLAS_NUM_THREADS=1; the demo's 6 mm mesh, P2, neo-Hookean body, "
             f"{PRESSURE / 1e3:g} kPa asked for; solve = results.json wall_time_s, median of {args.repeat} runs; "
             "load = 1-minute load average before -> after each run.", "",
             "| control | dofs | exit | accepted steps | Newton | peak [kPa] | arc length from [kPa] | ended at [kPa] "
             "| solve [s] | load | why it ended |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as tmp:
        mesh = pneunet.build(Path(tmp) / "pneunet.msh", 0.006, layer=pneunet.LAYER)
        for control in args.controls:
            runs = []
            for i in range(args.repeat):
                runs.append(run_once(mesh, control, args.ranks, Path(tmp) / f"{control}{i}"))
                print(control, {k: v for k, v in runs[-1].items() if k != "message"}, flush=True)
            r = runs[0]
            kpa = lambda lam: "-" if lam is None else f"{lam * PRESSURE / 1e3:.3f}"   # noqa: E731
            m = r["message"]
            why = (m.split("lies beyond the path followed (", 1)[1] if "lies beyond the path followed (" in m
                   else m.removeprefix("limit point: ")).split(";")[0]
            lines.append(f"| {control} | {r['dofs']} | {','.join(str(x['exit']) for x in runs)} | {r['steps']} | "
                         f"{r['newton']} | {kpa(r['peak'])} | {kpa(r['from'])} | {kpa(r['reached'])} | "
                         f"{statistics.median(x['solve'] for x in runs):.1f} | "
                         f"{'; '.join(f'{a:.1f}->{b:.1f}' for a, b in (x['load'] for x in runs))} | {why} |")
    lines.append(END)
    md = ROOT / "benchmarks" / "pneunet_limit.md"
    text = md.read_text() if md.exists() else f"# PneuNet past its limit point (benchmarks/pneunet_limit.py)\n\n{BEGIN}\n{END}\n"
    md.write_text(text[: text.index(BEGIN)] + "\n".join(lines) + text[text.index(END) + len(END):])
    print("\n".join(lines))


if __name__ == "__main__":
    main()
