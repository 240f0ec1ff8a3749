"""The verification manual: run every benchmark in verification/cases/ through `fem-forms run`, compare
each extracted number with its published or closed-form target, write verification/README.md, and exit
non-zero if any error exceeds its stated tolerance (or a number cannot be read: "not available").

    .venv/bin/python verification/run.py            # all cases, writes verification/README.md
    .venv/bin/python verification/run.py --fast     # the fast ones (CI: tests/system/test_verification.py)
    .venv/bin/python verification/run.py --only fv32 le1 --no-readme

Each case is a scene file in verification/cases/ (meshes of the NAFEMS cases are written first by the
gmsh scripts in verification/geometry/ into the output folder), run once as a subprocess of this tree's
package; its results.json is read, never the package's internals. The cases and their rows are in
catalogue.py; targets are closed forms (targets.py, time_histories.py), published numbers, or (tutorial
beam) a bare-dolfinx reproduction that first has to reproduce the tutorial's published Newton counts. Run outputs go to verification/out/ (not committed).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
from pathlib import Path
import platform
import subprocess
import sys
import time

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PYTHON = sys.executable
sys.path.insert(0, str(HERE / "geometry"))
sys.path.insert(0, str(HERE))

from catalogue import (CASES, Case, NotAvailable, Row, probe)  # noqa: E402,F401 (the test uses Case, Row, probe)


# --- running ------------------------------------------------------------------------------------
def _env() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                OPENBLAS_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def _script_json(script: Path, args: list[str] | None = None, timeout: float = 1800) -> dict:
    p = subprocess.run([PYTHON, str(script)] + (args or []), cwd=ROOT, env=_env(), capture_output=True,
                       text=True, timeout=timeout)
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"{script.name}: exit {p.returncode}: {p.stderr.strip()[-400:]}")
    return json.loads(lines[-1])


def run_case(case: Case, out: Path) -> list[dict]:
    """Run one case; one result dict per row (status pass / FAIL / not available / error)."""
    out.mkdir(parents=True, exist_ok=True)
    base = {"case": case.name, "benchmark": case.benchmark, "source": case.source}
    cmd = [PYTHON, "-m", "fem_forms", "run", str(HERE / "cases" / case.scene), "--out", str(out / "run"), "-q"]
    t0 = time.perf_counter()
    res, ref, err, extra = {}, {}, None, {}
    try:
        if case.mesh is not None:
            module, kwargs = case.mesh
            geo = __import__(module)
            msh = geo.build(out / f"{module}.msh", **kwargs)
            cmd += ["--set", f"mesh.file={json.dumps(str(msh))}"]
        p = subprocess.run(cmd, cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=1800)
        wall = time.perf_counter() - t0
        rj = out / "run" / "results.json"
        if p.returncode != case.exit_status:
            err = f"exit status {p.returncode}, expected {case.exit_status}: {p.stderr.strip()[-300:]}"
        elif not rj.exists():
            err = "no results.json"
        else:
            res = json.loads(rj.read_text())
            res["run_dir"] = str(out / "run")         # where the run's probes.csv lies (dynamic cases)
        if case.reference:
            ref = _script_json(HERE / "reference" / case.reference)
            extra["reference_time_s"] = ref.get("time_s")
        if case.side_check and case.mesh:
            extra["side_check"] = _script_json(HERE / "reference" / case.side_check,
                                               ["--n-arc", str(case.mesh[1]["n_arc"]),
                                                "--n-radial", str(case.mesh[1]["n_radial"])])
    except Exception as e:                              # a crash is a failed case, reported
        wall = time.perf_counter() - t0
        err = f"{type(e).__name__}: {e}"
    rows = []
    for row in case.rows:
        r = dict(base, quantity=row.quantity, unit=row.unit, tolerance=row.tolerance, relative=row.relative,
                 scale=row.scale, dofs=res.get("dofs"), solve_time_s=res.get("wall_time_s"), wall_time_s=wall,
                 newton_iterations=res.get("newton_iterations"), **extra)
        try:
            target = row.target if not callable(row.target) else row.target(ref if case.reference else res)
            r["target"] = float(target)
        except Exception as e:
            r.update(status="error", note=f"target: {type(e).__name__}: {e}")
            rows.append(r)
            continue
        if err is not None:
            r.update(status="error", note=err)
        else:
            try:
                value = row.extract(res, ref)
                error = (value - target) / abs(target) if row.relative else value - target
                r.update(result=value, error=error,
                         status="pass" if abs(error) <= row.tolerance else "FAIL")
            except NotAvailable as e:
                r.update(status="not available", note=str(e))
            except Exception as e:
                r.update(status="error", note=f"{type(e).__name__}: {e}")
        rows.append(r)
    return rows


def run_cases(cases: list[Case], out: Path, echo: bool = True) -> list[dict]:
    rows = []
    for case in cases:
        t0 = time.perf_counter()
        got = run_case(case, out / case.name)
        rows += got
        if echo:
            bad = [r for r in got if r["status"] != "pass"]
            print(f"{case.name:22s} {'pass' if not bad else bad[0]['status']:14s} "
                  f"{time.perf_counter() - t0:6.1f} s", flush=True)
            for r in bad:
                print(f"    {r['quantity']}: {r.get('note') or _fmt_err(r)}", flush=True)
    return rows


# --- README -----------------------------------------------------------------------------------
def _fmt(v, scale=1.0) -> str:
    if v is None:
        return "-"
    v = v * scale
    return f"{v:.6g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.5e}"


def _fmt_err(r: dict) -> str:
    if "error" not in r:
        return "-"
    return f"{100 * r['error']:+.3g} %" if r["relative"] else f"{r['error']:+.3g}"


def _fmt_tol(r: dict) -> str:
    return f"{100 * r['tolerance']:.3g} %" if r["relative"] else f"{r['tolerance']:g}"


def machine_note() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        import dolfinx
        dv = dolfinx.__version__
    except Exception:
        dv = "?"
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"{platform.node()}: {os.cpu_count()} cores ({cpu}), {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, dolfinx {dv}, OPENBLAS_NUM_THREADS=1, one run per case; "
            f"load average at the end {load} (times are noisy when other jobs share the machine)")


def write_readme(rows: list[dict], cases: list[Case], path: Path, command: str, total_s: float) -> None:
    passed = sum(r["status"] == "pass" for r in rows)
    lines = [
        "# Verification manual",
        "",
        "Written by `verification/run.py`; do not edit by hand. Each benchmark is a scene file in "
        "`verification/cases/` run by `fem-forms run` (one run per case); the number is read from its "
        "`results.json` and compared with the target. A row passes when |error| <= tolerance; "
        "\"not available\" (the package does not write that number yet) and \"error\" (the run failed) "
        "count as failures. `run.py --fast` runs the cases marked fast (CI: "
        "`tests/system/test_verification.py`).",
        "",
        f"- date: {datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}",
        f"- machine: {machine_note()}",
        f"- command: `{command}`",
        f"- {passed} of {len(rows)} rows pass; total {total_s:.0f} s",
        "",
        "| case | benchmark | source | quantity | target | result | error | tolerance | status | dofs | "
        "time (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    seen = set()
    for r in rows:
        unit = f" {r['unit']}" if r["unit"] else ""
        first = r["case"] not in seen                  # benchmark and source once per case
        seen.add(r["case"])
        cell = lambda text: str(text).replace("|", "\\|")   # noqa: E731  (a pipe would split the cell)
        t = r.get("wall_time_s")
        st = r["status"] if r["status"] in ("pass", "FAIL") else f"**{r['status']}**"
        if r["status"] == "FAIL":
            st = "**FAIL**"
        lines.append(
            f"| {r['case'] if first else ''} | {cell(r['benchmark']) if first else ''} | "
            f"{cell(r['source']) if first else ''} | {cell(r['quantity'])} | "
            f"{_fmt(r.get('target'), r['scale'])}{unit} | {_fmt(r.get('result'), r['scale'])} | {_fmt_err(r)} | "
            f"{_fmt_tol(r)} | {st} | {r.get('dofs') or '-'} | "
            f"{'-' if t is None else f'{t:.1f}'} |")
    lines += ["", "Time: wall time of the `fem-forms run` subprocess (start-up and form compilation "
              "included; the solve alone is `wall_time_s` in each results.json).", "", "## Cases", ""]
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"], []).append(r)
    for case in cases:
        if case.name not in by_case:
            continue
        rs = by_case[case.name]
        lines.append(f"### {case.name}: {case.benchmark}")
        lines.append("")
        lines.append(f"Scene `verification/cases/{case.scene}`"
                     + (f", mesh `verification/geometry/{case.mesh[0]}.py` {case.mesh[1]}" if case.mesh else "")
                     + (f", reference `verification/reference/{case.reference}`" if case.reference else "")
                     + f"; {'fast' if case.fast else 'full run only'}. Source: {case.source}.")
        lines.append("")
        lines.append(case.notes)
        r0 = rs[0]
        facts = []
        if r0.get("newton_iterations") is not None:
            facts.append(f"fem_forms took {r0['newton_iterations']} Newton iterations")
        if r0.get("solve_time_s") is not None:
            facts.append(f"solve {r0['solve_time_s']:.2f} s")
        if r0.get("reference_time_s") is not None:
            facts.append(f"reference script {r0['reference_time_s']:.1f} s")
        if facts:
            lines += ["", "This run: " + ", ".join(facts) + "."]
        sc = r0.get("side_check")
        if sc:
            lines += ["", f"Side check (bare dolfinx, `verification/reference/{case.side_check}`, not the "
                      f"package's result and not counted): sigma_yy at D = {sc['sigma_yy_D_projected_MPa']:.4g} MPa "
                      f"(L2 projection onto Q2; {sc['error_pct']:+.2f} % from 92.7), raw cell values "
                      f"{', '.join(f'{v:.4g}' for v in sc['sigma_yy_D_cells_MPa'])} MPa, {sc['dofs']} dofs."]
        notes = {r["note"] for r in rs if r.get("note")}
        if notes:
            lines += ["", "Not passed: " + "; ".join(sorted(notes)) + "."]
        lines.append("")
    path.write_text("\n".join(lines))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="only the cases marked fast")
    ap.add_argument("--only", nargs="+", metavar="CASE", help="only these cases (by name)")
    ap.add_argument("--out", default=str(HERE / "out"), help="folder for the runs (default verification/out)")
    ap.add_argument("--no-readme", action="store_true", help="do not write verification/README.md")
    ap.add_argument("--readme", default=str(HERE / "README.md"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    cases = [c for c in CASES if (not a.fast or c.fast) and (not a.only or c.name in a.only)]
    if a.only and len(cases) != len(a.only):
        known = ", ".join(c.name for c in CASES)
        print(f"run.py: unknown case in {a.only} (known: {known})", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    rows = run_cases(cases, Path(a.out).resolve())    # the cases run from the repository root: absolute
    total = time.perf_counter() - t0
    failed = [r for r in rows if r["status"] != "pass"]
    print(f"{len(rows) - len(failed)} of {len(rows)} rows pass in {total:.0f} s")
    if not a.no_readme:
        cmd = "OPENBLAS_NUM_THREADS=1 .venv/bin/python verification/run.py" + (" --fast" if a.fast else "") \
            + (f" --only {' '.join(a.only)}" if a.only else "")
        write_readme(rows, cases, Path(a.readme), cmd, total)
        print(f"wrote {a.readme}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
