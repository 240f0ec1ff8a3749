"""The speed/accuracy study and accuracy on request, against beam theory (the extrapolation arithmetic:
unit/test_study_arithmetic.py)."""
import json

import pytest

from fem_forms.cli import main
from helpers import beam_scene, toml_dumps

L, H, E, RHO = 1.0, 0.05, 1e9, 1000.0
EB_SAG = RHO * 9.81 * H * H * L**4 / (8 * E * H**4 / 12)


def scene_file(tmp_path, **extra):
    d = beam_scene(mesh={"generator": "box", "size": [L, H, H], "cells": [4, 1, 1]},
                   material={"model": "neo-hookean", "E": E, "nu": 0.0, "rho": RHO},
                   output={"probes": {"tip": [L, H / 2, H / 2]}})
    d["discretization"].update(extra)
    path = tmp_path / "beam.toml"
    path.write_text(toml_dumps(d))
    return path


def test_study_ladder_converges_to_beam_theory(tmp_path, capsys):
    out = tmp_path / "study"
    code = main(["study", str(scene_file(tmp_path)), "--out", str(out), "--degrees", "1", "2", "--refine", "3"])
    assert code == 0
    rows = [ln.split(",") for ln in (out / "study.csv").read_text().splitlines()[1:]]
    assert len(rows) == 6 and all(r[7] == "1" and r[8] == "relative" for r in rows)
    err = {(int(r[0]), int(r[1])): float(r[4]) for r in rows}          # error vs Richardson
    assert err[(2, 0)] < err[(1, 0)] and err[(2, 2)] < err[(2, 0)]      # P2 beats P1; refinement pays
    assert (out / "study.png").stat().st_size > 0 and "| P2 | 2 |" in (out / "study.md").read_text()
    # the finest P2 run against Euler-Bernoulli (slender, nu = 0)
    finest = json.loads((out / "P2_level2" / "results.json").read_text())
    assert -finest["probes"]["tip"]["displacement"][2] == pytest.approx(EB_SAG, rel=0.01)


def test_accuracy_on_request_picks_a_run_that_meets_the_tolerance(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", str(scene_file(tmp_path, tolerance=0.02)), "--out", str(out)])
    assert code == 0
    s = json.loads((out / "results.json").read_text())
    assert s["error_estimate"] <= 0.02 and s["chosen"]["degree"] == 2      # P1 locks: it cannot meet 2 %
    assert -s["probes"]["tip"]["displacement"][2] == pytest.approx(EB_SAG, rel=0.03)
    assert (out / "deformed.png").exists()
