"""A dynamic run stopped by a signal keeps what it has (issue 48): probes.csv and energy.csv up to the last accepted
step, a checkpoint of it and results.json with "interrupted": true, exit 130 / 143 with one line; `--restart` from
that checkpoint ends where the uninterrupted run ends."""
import json
import os
import signal
import subprocess
import sys

import pytest

from helpers import ROOT, toml_dumps

SWING = {"title": "swinging beam", "analysis": "dynamic", "mesh": {"size": [1.0, 0.1, 0.1], "cells": [20, 2, 2]},
         "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0},
         "fix": [{"where": {"axis": "x", "at": 0.0}}], "load": [{"type": "gravity"}],
         "dynamic": {"duration": 0.3, "dt": 1e-3},
         "output": {"picture": False, "fields": False, "probes": {"tip": [1.0, 0.05, 0.05]}}}
ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1")


def fem_forms(*args) -> list:
    return [sys.executable, "-m", "fem_forms", "run", *map(str, args)]


@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_stopped_dynamic_run_keeps_its_steps_and_continues_to_the_same_end(tmp_path, sig, status):
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_dumps(SWING))
    out = tmp_path / "out"
    p = subprocess.Popen(fem_forms(scene, "--out", out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=ENV, cwd=ROOT)
    first = p.stderr.readline()                     # the first accepted step's line: mid-run
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert "step 1" in first, first + err
    assert p.returncode == status and err.endswith("fem-forms: interrupted\n") and "Traceback" not in err, err
    res = json.loads((out / "results.json").read_text())
    assert res["interrupted"] is True and res["converged"] is False
    steps = res["steps"]
    assert 1 <= steps < 300 and res["time_reached"] == pytest.approx(steps * 1e-3)
    for csv in ("probes.csv", "energy.csv"):         # the start's row and one per accepted step, none half-written
        rows = (out / csv).read_text().splitlines()
        assert len(rows) == 1 + 1 + steps and float(rows[-1].split(",")[0]) == pytest.approx(res["time_reached"])
    assert (out / "checkpoint" / "meta.json").exists() and not list(out.glob(".results-*"))
    cont = subprocess.run(fem_forms(scene, "--out", out, "--restart", out, "-q"), capture_output=True, text=True,
                          env=ENV, cwd=ROOT, timeout=300)
    assert cont.returncode == 0, cont.stderr
    whole = subprocess.run(fem_forms(scene, "--out", tmp_path / "whole", "-q"), capture_output=True, text=True,
                           env=ENV, cwd=ROOT, timeout=300)
    assert whole.returncode == 0, whole.stderr
    a, b = (json.loads((d / "results.json").read_text()) for d in (tmp_path / "whole", out))
    assert b["steps"] == a["steps"] == 300 and "interrupted" not in b
    assert b["probes"]["tip"]["displacement"] == pytest.approx(a["probes"]["tip"]["displacement"], rel=1e-9)
    assert len((out / "probes.csv").read_text().splitlines()) == 302


def test_a_killed_dynamic_run_leaves_its_history_up_to_its_last_step(tmp_path):
    """kill -9 runs no handler: the rows appended after each accepted step are what is left, whole, and no
    results.json (never a half-written one)."""
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_dumps(SWING))
    out = tmp_path / "out"
    p = subprocess.Popen(fem_forms(scene, "--out", out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=ENV, cwd=ROOT)
    p.stderr.readline()                             # the first accepted step is on disk
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=60)
    for csv in ("probes.csv", "energy.csv"):
        rows = [r.split(",") for r in (out / csv).read_text().splitlines()]
        assert len(rows) >= 3                       # the header, t = 0, at least the first step
        assert all(len(r) == len(rows[0]) for r in rows) and float(rows[2][0]) == pytest.approx(1e-3)
    assert not (out / "results.json").exists() and not list(out.glob(".results-*"))
