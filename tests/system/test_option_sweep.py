"""Every valid scene runs (issue 22, item 1): a seeded sweep of combinations of the scene's options
(analysis, cell, degree, quadrature degree 1..8 or default, material model, formulation, linear solver,
output fields, probes) on a 3x1x1 box, each through the CLI in-process under a time limit. Each must give
its answer (exit 0, finite numbers in results.json) or end with exit 2 (refused when read) or 3 (gave up)
and one line saying why: never a traceback, never a hang. The scenes share a palette of 36 form-deciding
entries (every quadrature rule on every element), so a cold run compiles 36 sets of forms; the same seed
draws the same scenes, so those forms are in FFCx's cache on the next runs."""
from __future__ import annotations

import json
import math
import random
import signal
import time

import pytest

from fem_forms import cli
from helpers import to_toml

N = 100
SEED = 22
LIMIT_S = 120                    # per run; a cold compile of the largest forms took ~25 s here (2 shared cores)
MODELS = ("linear", "stvk", "neo-hookean", "mooney-rivlin", "corotated")
FIELDS = ("displacement", "von_mises", "cauchy_stress", "pk2_stress", "principal_stresses", "green_strain",
          "hencky_strain", "deformation_gradient")


def palette(rng: random.Random) -> list[dict]:
    """The keys that decide which forms compile, one entry per (quadrature degree, cell, element degree):
    every rule meets every element (where under-integration shows), each entry with an analysis, a material
    model (the five in turn), a formulation, a mass and output fields. The 100 scenes share these entries,
    so a cold run compiles 36 sets of forms, not one per scene."""
    keys = [(q, cell, degree) for q in (None, 1, 2, 3, 4, 5, 6, 7, 8)
            for cell in ("tetrahedron", "hexahedron") for degree in (1, 2)]
    rng.shuffle(keys)
    entries = []
    for k, (q, cell, degree) in enumerate(keys):
        analysis = ("static", "modal", "static", "dynamic")[k % 4]
        formulation = "mixed" if analysis == "static" and degree == 2 and rng.random() < 0.25 else "displacement"
        disc = {"degree": degree, "formulation": formulation}
        if q is not None:
            disc["quadrature_degree"] = q
        entries.append({"analysis": analysis, "cell": cell, "discretization": disc, "model": MODELS[k % len(MODELS)],
                        "mass": rng.choice(("consistent", "lumped")),
                        "fields": rng.sample(FIELDS, rng.randint(0, 3))})
    return entries


def draw(rng: random.Random, entry: dict) -> dict:
    """One scene on a palette entry, with the keys that compile nothing drawn anew (linear solver, probes,
    mode count, time step); mostly valid: invalid ones must be refused with exit 2."""
    analysis = entry["analysis"]
    scene = {
        "title": "sweep", "analysis": analysis,
        "mesh": {"generator": "box", "cell": entry["cell"], "size": [1.0, 0.2, 0.2], "cells": [3, 1, 1]},
        "material": {"model": entry["model"], "E": 1e7, "nu": 0.3, "rho": 1000.0},
        "discretization": dict(entry["discretization"]),
        "solver": {"linear": rng.choice(("direct", "iterative", "auto"))},
        "fix": [{"where": {"axis": "x", "at": 0.0}}],
        "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81]}],
        "output": {"picture": False, "fields": list(entry["fields"]),
                   "probes": {"tip": [1.0, 0.1, 0.1]} if rng.random() < 0.7 else {}},
    }
    if analysis == "modal":
        scene["modal"] = {"count": rng.choice((2, 4)), "mass": entry["mass"]}
    if analysis == "dynamic":
        scene["dynamic"] = {"duration": 3e-3, "dt": rng.choice((1e-3, 1.5e-3)), "checkpoint_every": 0,
                            "mass": entry["mass"]}
    return scene


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang()


def finite(obj) -> bool:
    """Every number in a results.json value is finite (None allowed: not applicable)."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, str):
        return True
    if isinstance(obj, (int, float)):
        return math.isfinite(obj)
    if isinstance(obj, dict):
        return all(finite(v) for v in obj.values())
    return all(finite(v) for v in obj)


PALETTE = palette(random.Random(SEED))
SCENES = [draw(random.Random(SEED * 1000 + i), PALETTE[i % len(PALETTE)]) for i in range(N)]


def test_the_sweep_covers_the_options():
    seen = {k: {repr(f(s)) for s in SCENES} for k, f in {
        "analysis": lambda s: s["analysis"], "cell": lambda s: s["mesh"]["cell"],
        "degree": lambda s: s["discretization"]["degree"], "model": lambda s: s["material"]["model"],
        "q": lambda s: s["discretization"].get("quadrature_degree"),
        "formulation": lambda s: s["discretization"]["formulation"], "linear": lambda s: s["solver"]["linear"]}.items()}
    assert len(SCENES) >= 100
    assert [len(seen[k]) for k in ("analysis", "cell", "degree", "model", "q", "formulation", "linear")] == \
        [3, 2, 2, 5, 9, 2, 3], seen
    d = [s["discretization"] for s in SCENES]
    rules = {(x.get("quadrature_degree"), s["mesh"]["cell"], x["degree"]) for x, s in zip(d, SCENES)}
    assert len(rules) == 9 * 2 * 2                     # every rule on every element
    assert len({(s["analysis"], s["material"]["model"]) for s in SCENES}) == 3 * 5


@pytest.mark.parametrize("i", range(N))
def test_every_scene_answers_or_says_why(i, tmp_path, capsys):
    scene = SCENES[i]
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(scene))
    out = tmp_path / "out"
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(LIMIT_S)
    t0 = time.perf_counter()
    try:
        code = cli.main(["run", str(path), "--out", str(out), "-q"])
    except Hang:
        pytest.fail(f"scene {i} ran past {LIMIT_S} s: {json.dumps(scene)}")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("fem-forms: error:")]
    assert "Traceback" not in err, err
    assert code in (0, 2, 3), (code, err, scene)
    if code == 0:
        summary = json.loads((out / "results.json").read_text())
        assert finite({k: v for k, v in summary.items() if k not in ("title", "warnings", "physics")}), summary
    else:
        assert len(lines) == 1, (err, scene)
        if code == 3:
            assert json.loads((out / "results.json").read_text()).get("converged") is False or \
                scene["analysis"] != "dynamic", err
    print(f"sweep {i}: exit {code} in {time.perf_counter() - t0:.1f} s {lines[0] if lines else ''}")
