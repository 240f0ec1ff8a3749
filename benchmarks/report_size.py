"""Benchmark: how large report.html is for a 300,000-tetrahedron part, how long it takes to write, and how soon
headless Chromium has drawn it (the goal, issue 50: under 20 MB, open in under 3 s).

Two parts of 300,000 tetrahedra (P1): a block (50 x 50 x 20 box cells; its surface small next to its volume) and
a sheet (250 x 200 x 1; nearly every node on its surface: the worst case), each with a smooth displacement
field (no solve: the page's size and drawing depend on the surface, not on the physics), as a static run's page
(one state) and as a dynamic run's (100 frames, thinned to the page's frame budget). "Drawn within" is the
shortest of Chromium's --timeout values (0.5 to 5 s, from launching the browser, SwiftShader's software WebGL)
after which the page's title says its viewer is ready, median of 3.

Run: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/report_size.py` (about 2 minutes). Writes
benchmarks/report_size.md.
"""
from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import fem_forms as ff  # noqa: E402
from fem_forms.model import build_model  # noqa: E402
from fem_forms.output import report  # noqa: E402

PARTS = {"block": ([0.5, 0.5, 0.2], [50, 50, 20]), "sheet": ([2.5, 2.0, 0.01], [250, 200, 1])}
TIMEOUTS_MS = (500, 1000, 1500, 2000, 3000, 5000)
BROWSER = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]


def drawn_within(page: Path) -> float:
    """The shortest --timeout (s) after which the page's viewer said it is ready (inf: not within 5 s)."""
    for ms in TIMEOUTS_MS:
        dom = subprocess.run([shutil.which("chromium"), *BROWSER, f"--timeout={ms}", "--dump-dom", page.as_uri()],
                             capture_output=True, text=True, timeout=120).stdout
        if "<title>fem_forms report: ready</title>" in dom:
            return ms / 1000
    return float("inf")


def main() -> None:
    rows = []
    folder = Path(tempfile.mkdtemp())
    for name, (size, cells) in PARTS.items():
        scene = ff.Scene.from_dict({"title": f"300k-tet {name}", "mesh": {"generator": "box", "size": size,
                                                                         "cells": cells},
                                    "material": {"E": 1e6, "nu": 0.3}, "fix": [{"where": {"axis": "x", "at": 0}}],
                                    "discretization": {"degree": 1}, "output": {"fields": False}})
        model = build_model(scene)
        model.u.interpolate(lambda x: np.vstack([0.01 * x[0] ** 2, 0.005 * np.sin(3 * x[0]), -0.02 * x[0] ** 2]))
        tets = model.mesh.topology.index_map(3).size_global
        for kind, frames in (("static", 1), ("dynamic, 100 frames", 100)):
            out = folder / f"{name}_{frames}"
            out.mkdir()
            shapes = report.surface_frames([("final", model.u)])
            shapes = [(f"t{i}", None if shapes[0][1] is None else (i + 1) / frames * shapes[0][1])
                      for i in range(frames)]
            t0 = time.perf_counter()
            report.write_model_report(model, model.u, shapes, None, out, {"analysis": kind}, kind)
            write_s = time.perf_counter() - t0
            page = out / "report.html"
            drawn = statistics.median(drawn_within(page) for _ in range(3))
            rows.append((name, tets, kind, page.stat().st_size / 1e6, write_s, drawn))
            print(rows[-1], flush=True)
    lines = ["# report.html of a 300,000-tetrahedron part", "", __doc__.split("\n\n")[1].replace("\n", " "), "",
             "| part | tetrahedra | page | size MB | written in s | drawn within s |", "|---|---:|---|---:|---:|---:|"]
    lines += [f"| {n} | {t:,} | {k} | {mb:.1f} | {w:.2f} | {d:g} |" for n, t, k, mb, w, d in rows]
    lines += ["", "Goal: under 20 MB and drawn in under 3 s. Machine: 2 cores, Chromium "
              + subprocess.run([shutil.which("chromium"), "--version"], capture_output=True, text=True).stdout.split()[1]
              + " headless with SwiftShader (software WebGL: a browser with a GPU draws faster)."]
    (HERE / "report_size.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
