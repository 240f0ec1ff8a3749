"""What a user sees: default output folder, progress on stderr, Ctrl-C, a silent Python API, the study table.

Interrupts and the JIT log are tested in real subprocesses: a signal during a real solve (the last accepted
state must be left on disk), an empty FFCx cache.
"""
import io
import json
import math
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import xml.etree.ElementTree as ET

from dolfinx import io as dolfinx_io
from mpi4py import MPI
import pytest

import fem_forms as ff
from fem_forms import progress
from fem_forms.cli import default_out, main
from fem_forms.output import results
from fem_forms.output.progress_line import CLEAR, ProgressLine
from fem_forms.study import Run, write_report
from helpers import ahead_of_the_other_worker, toml_dumps

ROOT = Path(__file__).resolve().parents[2]
PYTHON = sys.executable
ENV = dict(os.environ, PYTHONPATH=str(ROOT), OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OPENBLAS_NUM_THREADS="1")

SMALL = """\
title = "small beam"
[mesh]
generator = "box"
size = [1.0, 0.1, 0.1]
cells = [10, 2, 2]
[material]
model = "neo-hookean"
E = 1e6
nu = 0.3
rho = 1000.0
[discretization]
degree = 1
[solver]
steps = 2
[[fix]]
where = { axis = "x", at = 0.0 }
[[load]]
type = "gravity"
g = [0.0, 0.0, -9.81]
[output]
probes = { tip = [1.0, 0.05, 0.05] }
"""
# a soft P2 beam with 6,027 dofs and several load steps: a solve of a few seconds to interrupt
SLOW = (SMALL.replace("cells = [10, 2, 2]", "cells = [20, 3, 3]").replace("E = 1e6", "E = 1e5")
        .replace("degree = 1", "degree = 2").replace("steps = 2", "steps = 8")
        + "fields = [\"displacement\"]\npicture = false\n")


def scene(tmp_path: Path, text: str = SMALL, name: str = "beam.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# -- default output folder -------------------------------------------------------------------------------

def test_run_without_out_writes_to_out_slash_scene_stem(tmp_path, monkeypatch, capsys):
    (tmp_path / "scenes").mkdir()
    path = scene(tmp_path / "scenes")                 # the folder of the scene does not matter, its stem does
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(path), "-q"]) == 0
    res = json.loads((tmp_path / "out" / "beam" / "results.json").read_text())
    assert res["converged"]
    assert "-> out/beam" in capsys.readouterr().out


def test_study_default_folder_is_beside_the_run_folder_and_documented(capsys):
    assert default_out("run", "demos/scenes/sagging_beam.toml") == Path("out/sagging_beam")
    assert default_out("study", "demos/scenes/sagging_beam.toml") == Path("out/sagging_beam_study")
    with pytest.raises(SystemExit):
        main(["study", "--help"])
    assert "out/<scene file stem>_study/" in " ".join(capsys.readouterr().out.split())


# -- progress ----------------------------------------------------------------------------------------------

def events(reporter):
    """A continuation as the solvers report it: a rejected step, then two accepted ones."""
    reporter("load_step", load=0.5, step=1)
    for it, r in enumerate([10.0, 1.0, 1e-3]):
        reporter("newton", load=0.5, iteration=it, residual=r)
    reporter("step_rejected", load=0.5, iterations=2, why="SNES DIVERGED_LINE_SEARCH")
    for load in (0.25, 1.0):
        reporter("load_step", load=load, step=2)
        for it, r in enumerate([5.0, 1e-2, 1e-9]):
            reporter("newton", load=load, iteration=it, residual=r)
        reporter("step_accepted", load=load, iterations=2, why="")
    reporter("solve_done", converged=True)


def test_plain_progress_is_one_line_per_step_not_per_newton_iteration():
    buf = io.StringIO()
    events(ProgressLine(buf, tty=False))
    lines = buf.getvalue().splitlines()
    assert len(lines) == 3 and "\r" not in buf.getvalue()
    assert "load step 1 (load 0.5)" in lines[0] and "rejected (SNES DIVERGED_LINE_SEARCH)" in lines[0]
    assert "load step 1 (load 0.25)" in lines[1] and "accepted after 2 Newton iterations" in lines[1]
    assert "load step 2 (load 1)" in lines[2] and "residual 1.00e-09" in lines[2] and lines[2].count(" s") >= 1


def test_terminal_progress_is_one_line_rewritten_in_place_and_cleared_at_the_end():
    buf = io.StringIO()
    events(ProgressLine(buf, tty=True))
    text = buf.getvalue()
    assert "\n" not in text and text.count("\r") >= 3
    assert "Newton" in text and "residual" in text
    assert text.endswith(CLEAR)                        # the summary printed next starts on a clean line


def test_time_steps_show_time_and_an_eta():
    buf = io.StringIO()
    rep = ProgressLine(buf, tty=True)
    rep("time_step", time=0.0, dt=0.1, step=0, total_time=1.0)
    rep._time0 = (rep._time0[0] - 2.0, 0.0)            # pretend 2 s of wall time went by
    rep("time_step", time=0.5, dt=0.1, step=5, total_time=1.0)
    line = buf.getvalue().rsplit("\r", 1)[-1]
    assert "t = 0.5 / 1 s (step 5, dt 0.1)" in line
    eta = float(line.split("ETA ")[1].split(" s")[0])
    assert eta == pytest.approx(2.0, abs=0.6)


def test_time_steps_in_a_log_get_lines_at_most_twice_a_second_and_a_last_line(monkeypatch):
    """A dynamic run writes to a log as it goes: its first step, every rejected step, an accepted step at most every
    PLAIN_EVERY_S with the count of those in between, and where it ended."""
    import fem_forms.output.progress_line as progress_line
    monkeypatch.setattr(progress_line, "PLAIN_EVERY_S", 1e6)   # however slow the machine: the steps are "fast"
    buf = io.StringIO()
    rep = ProgressLine(buf, tty=False)
    rep._last_line = -math.inf                        # the first step gets its line
    for k in range(1, 101):                           # 100 fast steps (well under a second)
        rep("newton", load=1.0, iteration=0, residual=1e-3)
        rep("newton", load=1.0, iteration=1, residual=1e-11)
        if k == 50:
            rep("step_rejected", load=0.049, iterations=7, why="SNES DIVERGED_MAX_IT")
        rep("time_step", time=k * 1e-3, dt=1e-3, step=k, total_time=0.1, iterations=2)
    rep._last_line = -math.inf                        # pretend a long time went by
    rep("time_step", time=0.101, dt=1e-3, step=101, total_time=0.101, iterations=2)
    rep("march_done", time=0.101, steps=101, rejected=1)
    lines = buf.getvalue().splitlines()
    assert len(lines) == 4, lines
    assert "t = 0.001 / 0.1 s (step 1, dt 0.001)" in lines[0] and "accepted after 2 Newton iterations" in lines[0]
    assert "residual 1.00e-11" in lines[0]
    assert "rejected (SNES DIVERGED_MAX_IT)" in lines[1]
    assert "t = 0.101" in lines[2] and "(and 99 steps before it)" in lines[2]      # steps 2-100, none lost
    assert lines[3].startswith("fem-forms: reached t = 0.101 s in 101 steps (1 rejected)")


def test_a_dynamic_run_prints_its_progress(tmp_path, capsys):
    d = {"title": "swing", "analysis": "dynamic", "mesh": {"size": [0.2, 0.02, 0.02], "cells": [4, 1, 1]},
         "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": 1},
         "fix": [{"where": {"axis": "x", "at": 0.0}}], "load": [{"type": "gravity"}],
         "dynamic": {"duration": 0.02, "dt": 1e-3}, "output": {"picture": False, "fields": False}}
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(d))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert "t = 0.001 / 0.02 s (step 1, dt 0.001)" in err and "accepted after" in err
    assert "fem-forms: reached t = 0.02 s in 20 steps" in err


def test_cli_shows_progress_unless_quiet_and_the_api_stays_silent(tmp_path, capsys):
    path = scene(tmp_path)
    assert main(["run", str(path), "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "fem-forms: load step 1" in err and "accepted" in err
    assert progress._reporter is None                  # the CLI removes its reporter when it returns
    assert main(["run", str(path), "--out", str(tmp_path / "b"), "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    ff.solve_static(ff.Scene.from_file(path))
    assert capsys.readouterr() == ("", "")
    ff.show_progress()
    try:
        ff.solve_static(ff.Scene.from_file(path))
    finally:
        ff.show_progress(False)
    assert "accepted" in capsys.readouterr().err


# -- interrupts --------------------------------------------------------------------------------------------

def start_and_interrupt(cmd: list, sig: int, out: Path) -> tuple[subprocess.CompletedProcess, str]:
    """Start a run, wait for its first step's progress line (a load step was solved: we are mid-solve) and for that
    step's row in probes.csv (written just after the line), then send sig."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, cwd=ROOT)
    if Path(cmd[0]).name == "mpirun":
        ahead_of_the_other_worker(p.pid)
    first = p.stderr.readline()
    while " boundary facets" in first:              # what each selector took, said as solving starts
        first = p.stderr.readline()
    deadline = time.monotonic() + 60
    while not (out / "probes.csv").exists() and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    p.send_signal(sig)
    out_text, err = p.communicate(timeout=120)
    return subprocess.CompletedProcess(cmd, p.returncode, out_text, err), first


def check_interrupted_outputs(out: Path, tets: int = 20 * 3 * 3 * 6) -> dict:
    """results.json says interrupted at the last accepted step, which probes.csv and fields.xdmf (a mesh of
    `tets` tetrahedra) end with."""
    res = json.loads((out / "results.json").read_text())
    assert res["interrupted"] is True and res["converged"] is False
    rows = (out / "probes.csv").read_text().splitlines()
    assert rows[0] == "load_factor,time,tip_ux,tip_uy,tip_uz,fix0_Fx,fix0_Fy,fix0_Fz" and len(rows) - 1 == res["load_steps"] >= 1
    last = [float(x) for x in rows[-1].split(",")]
    assert last[0] == pytest.approx(res["load_reached"], rel=1e-9) and 0 < last[0] < 1
    assert last[2:5] == pytest.approx(res["probes"]["tip"]["displacement"], rel=1e-9)
    assert last[5:] == pytest.approx(res["reactions"]["fix0"], rel=1e-9)       # the clamp's force at that step
    times = [float(t.get("Value")) for t in ET.parse(out / "fields.xdmf").getroot().iter("Time")]
    assert len(times) == res["load_steps"] and times[-1] == pytest.approx(res["load_reached"], rel=1e-9)
    with dolfinx_io.XDMFFile(MPI.COMM_SELF, str(out / "fields.xdmf"), "r") as f:
        assert f.read_mesh(name="mesh").topology.index_map(3).size_global == tets
    assert res["files"] == {"fields": "fields.xdmf", "probes": "probes.csv"}
    assert not list(out.glob(".results-*")) and not list(out.glob(".*.tmp"))
    return res


@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_interrupt_exits_with_one_line_and_leaves_the_last_accepted_state(tmp_path, sig, status):
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.json").write_text('{"converged": true, "from": "an earlier run"}')
    p, first = start_and_interrupt([PYTHON, "-m", "fem_forms", "run", str(scene(tmp_path, SLOW)), "--out", str(out)],
                                   sig, out)
    assert "accepted" in first, first + p.stderr
    assert p.returncode == status, p.stderr
    assert p.stderr == "fem-forms: interrupted\n" and p.stdout == ""
    assert "from" not in check_interrupted_outputs(out)        # this run's, not the earlier run's


def test_interrupted_write_leaves_old_results_and_no_temporary_file(tmp_path, monkeypatch):
    path = tmp_path / "results.json"
    path.write_text('{"old": 1}')

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(results.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        results.write_json_atomic(path, {"new": 2})
    monkeypatch.undo()
    assert json.loads(path.read_text()) == {"old": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]
    results.write_json_atomic(path, {"new": 2, "nan": math.nan})
    assert json.loads(path.read_text()) == {"new": 2, "nan": None}


@pytest.mark.mpi
def test_two_ranks_show_progress_once_and_stop_on_interrupt(tmp_path):
    """Under mpirun, progress comes from rank 0 only. mpirun turns Ctrl-C into SIGTERM to every rank (1 s
    later, then SIGKILL 1 s after that); rank 0 writes the interrupted results.json at once, without any
    collective call, and prints the one line; the ranks stop together at the next accepted step if they get
    that far. Exit status is mpirun's own (1 here, not 130)."""
    out = tmp_path / "out"
    # mpirun's SIGKILL 5 s (not 1 s) after its SIGTERM: on a loaded machine (the suite on two workers) rank 0 could
    # still be inside one C call (a factorisation of a large beam) when the default second ran out, and died without
    # a word. SLOW's beam in 400 load steps of 0.25 %: a step takes ~0.15 s and no C call more than a few hundredths
    # of a second, the run ~60 s (it cannot end on its own before the signals). mpirun's wait scales with the
    # timeout (measured 20 s from SIGINT to exit with 10 s, 5.4 s with 3 s).
    many_steps = SLOW.replace("steps = 8", "steps = 400\nmax_step = 0.0025")
    cmd = [shutil.which("mpirun"), "-n", "2", "--bind-to", "none", "--oversubscribe",
           "--mca", "odls_base_sigkill_timeout", "5", PYTHON, "-m", "fem_forms",
           "run", str(scene(tmp_path, many_steps)), "--out", str(out)]
    p, first = start_and_interrupt(cmd, signal.SIGINT, out)
    assert first.startswith("fem-forms: load step 1 ") and "accepted" in first, first + p.stderr
    assert "load step 1 " not in p.stderr              # the second rank printed no copy of it
    assert p.returncode != 0 and p.stderr.count("fem-forms: interrupted") == 1, p.stderr
    assert "Traceback" not in p.stderr
    res = check_interrupted_outputs(out)
    assert res["load_reached"] < 0.5                   # stopped mid-path, not at its end


# -- compilation log ---------------------------------------------------------------------------------------

JIT_SCRIPT = textwrap.dedent("""\
    import logging, sys
    import fem_forms
    if sys.argv[1] == "verbose":
        fem_forms.quiet_jit(verbose=True)
    logging.basicConfig(level=logging.INFO, force=True)        # the user's own logging keeps working
    logging.getLogger("user").info("user record")
    from mpi4py import MPI
    from dolfinx import fem, mesh
    import ufl
    m = mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    V = fem.FunctionSpace(m, ("Lagrange", 1))
    fem.form(ufl.inner(ufl.grad(ufl.TrialFunction(V)), ufl.grad(ufl.TestFunction(V))) * ufl.dx)
    print("compiled")
""")


@pytest.mark.parametrize("mode", ["quiet", "verbose"])
def test_api_prints_no_compile_log_unless_asked(tmp_path, mode):
    script = tmp_path / "jit.py"
    script.write_text(JIT_SCRIPT)
    (tmp_path / "cache").mkdir()                       # an empty FFCx cache: every form is compiled
    p = subprocess.run([PYTHON, str(script), mode], capture_output=True, text=True, cwd=tmp_path, timeout=300,
                       env=dict(ENV, XDG_CACHE_HOME=str(tmp_path / "cache")))
    assert p.returncode == 0, p.stderr
    assert any((tmp_path / "cache" / "fenics").iterdir())      # it did compile
    both = p.stdout + p.stderr
    assert "compiled" in p.stdout and "user record" in p.stderr
    compile_lines = [ln for ln in both.splitlines() if "build_ext" in ln or "gcc" in ln or "libffcx" in ln]
    if mode == "quiet":
        assert compile_lines == [], both
    else:
        assert any("running build_ext" in ln for ln in compile_lines), both


# -- study table -------------------------------------------------------------------------------------------

def test_study_table_shows_a_dash_where_no_estimate_exists(tmp_path):
    runs = [Run(1, 0, {}, tmp_path, dofs=100, wall=0.5, memory_mb=80.0, error_finest=0.1, ok=True),
            Run(2, 0, {}, tmp_path, dofs=300, wall=1.0, memory_mb=90.0, error_finest=0.0, ok=True),
            Run(2, 1, {}, tmp_path, dofs=900, ok=False)]
    table = write_report(runs, tmp_path, "no Richardson limit")
    assert "nan" not in table.lower() and "nan" not in (tmp_path / "study.md").read_text().lower()
    assert "| P1 | 0 | 100 | 1.00e-01 | - | 0.50 | 80 |" in table
    assert "| P2 | 1 | 900 | failed | | | |" in table
    rows = (tmp_path / "study.csv").read_text().splitlines()
    assert rows[1].split(",")[3:6] == ["0.1", "", "0.5"]


@pytest.mark.parametrize("ranks", ["serial", "mpi"])
def test_a_compile_lock_left_by_a_killed_run_ends_in_one_line_naming_the_file(tmp_path, monkeypatch, capsys, ranks):
    """FFCx gives up waiting for a form whose cache entry a killed run left locked: its TimeoutError (serial), or
    dolfinx's RuntimeError wrapping it on every rank (mpi, as rank 0 sees it), ends the run with exit 1 and one
    line naming the file to delete, not a traceback."""
    import ffcx.codegeneration.jit as fj

    def locked(module_name, *args, **kwargs):
        ffcx_says = (f"JIT compilation timed out, probably due to a failed previous compile.\n        Try cleaning "
                     f"cache (e.g. remove {tmp_path / module_name}.c) or increase timeout parameter.")
        if ranks == "serial":
            raise TimeoutError(ffcx_says)
        raise RuntimeError(f"Failed just-in-time compilation of form: {ffcx_says}")
    monkeypatch.setattr(fj, "get_cached_module", locked)
    status = main(["run", str(scene(tmp_path)), "--out", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err
    assert status == 1, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fem-forms: error: a form's compile never finished"), err
    assert f"delete {tmp_path / 'libffcx_'}" in lines[0] and lines[0].endswith(".c and run again"), err
