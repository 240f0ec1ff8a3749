"""What the demo tests share: which test checks each demo, running the demos as a user runs them (two at a
time in worker threads, the machines have 2 cores) and reading the numbers they print. A test module that
imports `demo` gets the demos its own selected tests check, started when the module's first test asks.
Every run is also compared with the output its tutorial page in the manual shows (docs/demo_transcripts.py):
a demo whose printed numbers changed fails until `python docs/refresh_demos.py NAME` refreshes the page."""
import importlib.util
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import pytest

from helpers import ROOT

DEMOS = ROOT / "demos"
_spec = importlib.util.spec_from_file_location("demo_transcripts", ROOT / "docs" / "demo_transcripts.py")
transcripts = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(transcripts)
# the test that checks each demo (a new demo without a check fails test_every_demo_is_checked)
CHECKS = {"loaded_vs_unloaded_modes": "test_loaded_vs_unloaded_modes_demo",    # longest first
          "sagging_beam": "test_demo_scene_solves_and_writes_outputs",
          "inverse_design": "test_inverse_design_demo",
          "struck_bar": "test_struck_bar_demo_scene",
          "leaning_figure": "test_leaning_figure_demo",
          "soft_figure": "test_soft_figure_demo",
          "sag_and_stand": "test_sag_and_stand_demo",
          "spinning_top": "test_spinning_top_demo",
          "floating_boat": "test_floating_boat_demo",
          "roly_poly": "test_roly_poly_demo",
          "heated_strip": "test_heated_strip_demo",
          "silicone_swing": "test_silicone_swing_demo",
          "struck_bar_in_time": "test_struck_bar_in_time_demo",
          "bent_spoon": "test_bent_spoon_demo",
          "pneunet_actuator": "test_pneunet_actuator_demo",
          "fitted_actuator": "test_fitted_actuator_demo",
          "rocking_toy": "test_rocking_toy_demo",
          "finger_on_ball": "test_finger_on_ball_demo",
          "figure_on_table": "test_figure_on_table_demo",
          "standing_figure": "test_standing_figure_demo",
          "balloon_segment": "test_balloon_segment_demo",
          "pneunet_layout": "test_pneunet_layout_demo",
          "bimetal_strip": "test_bimetal_strip_demo",
          "printed_hook": "test_printed_hook_demo",
          "torn_silicone_strip": "test_torn_silicone_strip_demo",
          "dropped_aluminium_part": "test_dropped_aluminium_part_demo"}
NUMBER = r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"


class DemoRuns:
    """Runs the selected demos as subprocesses, two at a time, each into its own output folder."""

    def __init__(self, names, tmp):
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))      # this tree's package
        self.out = {name: tmp / name for name in names}
        self._pool = ThreadPoolExecutor(max_workers=2)
        self._runs = {name: self._pool.submit(
            subprocess.run, [sys.executable, str(DEMOS / f"{name}.py"), str(self.out[name])],
            cwd=tmp, env=env, capture_output=True, text=True, timeout=600) for name in names}

    def __call__(self, name):
        """(stdout, output folder) of a demo that exited 0 without a traceback."""
        p = self._runs[name].result()
        assert p.returncode == 0, f"{name}.py exited {p.returncode}:\n{p.stdout}\n{p.stderr}"
        assert "Traceback" not in p.stderr, p.stderr
        transcripts.check(name, p.stdout, self.out[name])           # the manual's page shows these numbers
        return p.stdout, self.out[name]

    def close(self):
        self._pool.shutdown(wait=True)


@pytest.fixture(scope="module")
def demo(request, tmp_path_factory):
    selected = {item.originalname for item in request.session.items if getattr(item, "module", None) is request.module}
    runs = DemoRuns([n for n, test in CHECKS.items() if test in selected], tmp_path_factory.mktemp("demos"))
    yield runs
    runs.close()


def scene_dict(name: str) -> dict:
    import tomllib
    return tomllib.loads((DEMOS / "scenes" / f"{name}.toml").read_text())


def grab(pattern: str, text: str) -> list:
    m = re.search(pattern, text)
    assert m, f"{pattern!r} not in the demo's output:\n{text}"
    return [float(g) for g in m.groups()]
