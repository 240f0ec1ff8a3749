"""A dynamic run stopped by a signal keeps what it has (issue 48): probes.csv and energy.csv up to the last accepted
step, a checkpoint of it and results.json with "interrupted": true, exit 130 / 143 with one line; `--restart` from
that checkpoint ends where the uninterrupted run ends. Stopped at a random step of a block bouncing on a floor with
friction (contact: the barrier's stiffness is state the checkpoint carries; the restart ends where the whole run does)."""
import json
import os
import random
import re
import signal
import subprocess
import sys

import pytest

from helpers import ROOT, toml_dumps

BOUNCE = {"title": "bouncing block", "analysis": "dynamic",
          "mesh": {"size": [0.1, 0.1, 0.1], "cells": [2, 2, 2]}, "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0},
          "load": [{"type": "gravity"}],
          "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -2e-3], "normal": [0, 0, 1],
                                    "friction": 0.3}]},
          "dynamic": {"duration": 0.06, "dt": 1e-3, "initial": "rest"},
          "output": {"picture": False, "fields": False, "probes": {"tip": [0.05, 0.05, 0.0]}}}
ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1")


def fem_forms(*args) -> list:
    return [sys.executable, "-m", "fem_forms", "run", *map(str, args)]


def step_lines(p: subprocess.Popen, n: int) -> tuple[str, int]:
    """The progress lines up to the n-th that names a time step (a log gets one every half second), and that
    step's number: the steps before it are on disk."""
    seen, step = "", 0
    while seen.count("(step ") < n:
        line = p.stderr.readline()
        assert line, seen
        seen += line
        if m := re.search(r"\(step (\d+),", line):
            step = int(m.group(1))
    return seen, step


@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_stopped_dynamic_run_keeps_its_steps_and_continues_to_the_same_end(tmp_path, sig, status):
    scene = tmp_path / "scene.toml"
    d = BOUNCE
    scene.write_text(toml_dumps(d))
    out = tmp_path / "out"
    duration = d["dynamic"]["duration"]
    p = subprocess.Popen(fem_forms(scene, "--out", out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=ENV, cwd=ROOT)
    seen, at = step_lines(p, random.randint(1, 2))          # a random step, mid-run
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    err = seen + err
    assert p.returncode == status and err.endswith("fem-forms: interrupted\n") and "Traceback" not in err, err
    res = json.loads((out / "results.json").read_text())
    assert res["interrupted"] is True and res["converged"] is False
    steps = res["steps"]
    assert at - 1 <= steps and res["time_reached"] < duration, (at, err)
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
    # the same steps (the bounce's impacts refined alike: the checkpoint holds the next step's size), the same end
    assert b["steps"] == a["steps"] and b["refined_steps"] == a["refined_steps"] and "interrupted" not in b
    assert steps < a["steps"]                                # it was stopped before the end
    assert b["time_reached"] == pytest.approx(duration)
    assert b["probes"]["tip"]["displacement"] == pytest.approx(a["probes"]["tip"]["displacement"], rel=1e-6, abs=1e-12)
    assert len((out / "probes.csv").read_text().splitlines()) == a["steps"] + 2


def test_a_killed_dynamic_run_leaves_its_history_up_to_its_last_step(tmp_path):
    """kill -9 runs no handler: the rows appended after each accepted step are what is left, whole, and no
    results.json (never a half-written one)."""
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_dumps(BOUNCE))
    out = tmp_path / "out"
    p = subprocess.Popen(fem_forms(scene, "--out", out), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=ENV, cwd=ROOT)
    _, at = step_lines(p, random.randint(1, 2))    # the steps before that one are on disk
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=60)
    for csv in ("probes.csv", "energy.csv"):
        rows = [r.split(",") for r in (out / csv).read_text().splitlines()]
        assert len(rows) >= 1 + at, at             # the header, t = 0, at least the steps before that one
        assert all(len(r) == len(rows[0]) for r in rows) and float(rows[2][0]) == pytest.approx(1e-3)
        assert [float(r[0]) for r in rows[1:]] == pytest.approx([1e-3 * i for i in range(len(rows) - 1)])
    assert not (out / "results.json").exists() and not list(out.glob(".results-*"))
