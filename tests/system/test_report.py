"""report.html in a real browser (headless Chromium, which setup.sh installs for the suite): a static run's page
opens with no viewer error, its canvas shows the part in the colours of its colour bar, the bar's range is the
run's |u| range, the results table and the supports' legend are there; without three.js the page is left out with
a warning; `fem-forms view` names it; a modal page steps through its modes, a dynamic contact page through
time with its obstacle drawn."""
import json
import shutil
import subprocess

import numpy as np
import pytest

from fem_forms.cli import main
from fem_forms.output import report
from helpers import beam_scene, report_data, toml_dumps

SCENE = beam_scene(output={"probes": {"tip": [1.0, 0.05, 0.05]}, "picture": False, "fields": ["displacement",
                                                                                               "von_mises"]},
                   solver={"steps": 2, "max_step": 0.5})
BROWSER = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
           "--virtual-time-budget=8000"]


def _browser(*args) -> subprocess.CompletedProcess:
    chromium = shutil.which("chromium")
    assert chromium, "Debian's chromium is needed (setup.sh installs it)"
    return subprocess.run([chromium, *BROWSER, *args], capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("report")
    path = folder / "beam.toml"
    path.write_text(toml_dumps(SCENE))
    assert main(["run", str(path), "--out", str(folder / "out"), "-q"]) == 0
    return folder / "out"


def test_the_page_shows_the_part_its_colour_bar_and_numbers(run):
    res = json.loads((run / "results.json").read_text())
    page = run / "report.html"
    assert res["files"]["report"] == "report.html" and page.stat().st_size < 5e6
    dom = _browser("--dump-dom", page.as_uri()).stdout
    assert "<title>fem_forms report: ready</title>" in dom and '<p id="error"></p>' in dom
    assert f"<td>max_displacement</td><td>{res['max_displacement']:.6g}</td>" in dom
    assert "support fix0" in dom and ">|u| (m)<" in dom
    assert 'max="1"' in dom and "load factor 1</span>" in dom            # two load steps on the slider, the last shown
    assert "von Mises (last frame)" in dom
    top = float(dom.split('<span id="cb-max">')[1].split("<")[0])
    assert top == pytest.approx(res["max_displacement"], rel=1e-3)          # the bar spans the run's |u|
    shot = page.parent / "shot.png"
    _browser("--window-size=1000,700", f"--screenshot={shot}", page.as_uri())
    import matplotlib.image
    pixels = matplotlib.image.imread(shot)[60:480, 150:850, :3]             # the 3D view, left of the bar
    colourful = (pixels.max(axis=2) - pixels.min(axis=2)) > 0.25            # not white, grey or black
    assert colourful.mean() > 0.02, "the canvas is blank"
    bar = matplotlib.image.imread(shot)[80:250, 950:990, :3]
    assert (bar.max(axis=2) - bar.min(axis=2) > 0.25).mean() > 0.3         # the colour bar is drawn


def test_without_its_viewer_the_page_is_left_out_with_a_warning(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(report, "THREE", tmp_path / "nowhere")
    path = tmp_path / "beam.toml"
    path.write_text(toml_dumps(SCENE))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    assert "report" not in res["files"] and not (tmp_path / "out" / "report.html").exists()
    assert any("report.html left out: its viewer (three.js) is not installed" in w for w in res["warnings"])


def test_view_names_the_page(run, capsys, monkeypatch):
    import webbrowser
    opened = []
    monkeypatch.setattr(webbrowser, "open", lambda uri: opened.append(uri) or True)
    assert main(["view", str(run)]) == 0
    assert opened == [(run / "report.html").resolve().as_uri()]
    assert main(["view", str(run / "nothing")]) == 2
    assert "no report.html there" in capsys.readouterr().err


def test_a_long_motion_of_a_large_part_keeps_within_the_budget():
    frames = [(f"t{i}", i) for i in range(500)]
    kept = report.within_budget(frames, points=100_000)                 # 2.1 MB a frame: 5 of them in 12 MB
    assert len(kept) <= 6 and kept[0] == frames[0] and kept[-1] == frames[-1]
    assert report.within_budget(frames[:3], points=100) == frames[:3]


def test_rows_of_results(tmp_path):
    rows = dict(report.result_rows({"a": 1, "b": {"c": [1.0, 2.0]}, "warnings": ["x"], "long": list(range(9)),
                                    "nan": float("nan")}))
    assert rows == {"a": "1", "b.c": "[1, 2]", "nan": "nan"}
    tris, origin = report.triangulated(np.array([[0, 1, 2, 3]]))
    assert tris.tolist() == [[0, 1, 2], [0, 2, 3]] and origin.tolist() == [0, 0]


def _open(page):
    """The page's DOM after its viewer ran (asserting no viewer error) and a screenshot's share of coloured
    pixels in the 3D view."""
    dom = _browser("--dump-dom", page.as_uri()).stdout
    assert "<title>fem_forms report: ready</title>" in dom and '<p id="error"></p>' in dom, dom[-500:]
    shot = page.parent / "shot.png"
    _browser("--window-size=1000,700", f"--screenshot={shot}", page.as_uri())
    import matplotlib.image
    pixels = matplotlib.image.imread(shot)[100:480, 150:850, :3]
    return dom, ((pixels.max(axis=2) - pixels.min(axis=2)) > 0.25).mean()


def test_a_modal_page_steps_through_its_modes(tmp_path):
    scene = dict(SCENE, analysis="modal", load=[], modal={"count": 4}, solver={})
    path = tmp_path / "modal.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    dom, coloured = _open(tmp_path / "out" / "report.html")
    assert f"mode 1: {res['frequencies_hz'][0]:.4g} Hz" in dom and 'max="3"' in dom        # 4 modes on the slider
    assert coloured > 0.02 and '<span id="cb-max">1.000</span>' in dom                       # shapes scaled to 1


def test_a_dynamic_contact_page_steps_through_time(tmp_path):
    scene = {"title": "block dropped on a floor", "analysis": "dynamic",
             "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [2, 2, 2]},
             "material": {"E": 1e6, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": 1},
             "load": [{"type": "gravity"}], "dynamic": {"duration": 0.02, "dt": 2e-3, "output_every": 2},
             "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -1e-3],
                                       "normal": [0, 0, 1]}]},
             "output": {"picture": False, "fields": False, "probes": {"c": [0.05, 0.05, 0.1]}}}
    path = tmp_path / "drop.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    dom, coloured = _open(tmp_path / "out" / "report.html")
    assert res["files"]["report"] == "report.html" and coloured > 0.02
    assert "t = 0.02 s" in dom and "<td>intersection_free</td><td>True</td>" in dom
    assert "obstacle floor" in dom and "history.png" not in dom              # picture = false: no plot to embed


def test_a_page_colours_by_contact_pressure_and_material(tmp_path):
    """A two-material block resting on a floor: the page's contact pressure, integrated over the bottom face as
    the P1 field it is (triangle area x mean of its corners), carries the block's weight m g; it is zero away
    from the bottom; its material field holds the two indices."""
    scene = {"title": "two-material block on a floor", "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1],
                                                               "cells": [3, 3, 3]},
             "material": [{"name": "soft", "E": 1e5, "nu": 0.3, "rho": 1000.0},
                          {"name": "stiff", "E": 1e6, "nu": 0.3, "rho": 1000.0,
                           "where": {"box": [[-1, -1, 0.05], [1, 1, 1]]}}],
             "discretization": {"degree": 1}, "load": [{"type": "gravity"}],
             "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -5e-5],
                                       "normal": [0, 0, 1], "friction": 0.5}]},
             "output": {"picture": False, "fields": False}}
    path = tmp_path / "block.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    res = json.loads((tmp_path / "out" / "results.json").read_text())
    rest, tris, fields = report_data(tmp_path / "out" / "report.html")
    unit, (pressure,) = fields["contact pressure"]
    bottom = (np.abs(rest[tris][:, :, 2]) < 1e-9).all(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(rest[tris[:, 1]] - rest[tris[:, 0]], rest[tris[:, 2]] - rest[tris[:, 0]]),
                                axis=1)
    weight = 1000.0 * 0.1 ** 3 * 9.81
    assert unit == "Pa" and (area * pressure[tris].mean(axis=1))[bottom].sum() == pytest.approx(weight, rel=1e-5)
    assert res["contact"]["floor"]["force"][2] == pytest.approx(weight, rel=1e-6)
    assert np.all(pressure[np.abs(rest[:, 2]) > 1e-9] == 0.0)                 # the floor pushes the bottom only
    unit, (material,) = fields["material (scene order from 0)"]
    assert unit == "" and set(np.unique(material)) == {0.0, 1.0}


def test_the_deformed_picture_draws_the_obstacles_where_they_are(tmp_path):
    """deformed.png of a block resting on a floor: the floor drawn in translucent grey (named in the legend), and,
    the picture's up being +z, lying below the block (its grey pixels' centre under the coloured part's), as a
    floor does; without contact nothing grey is drawn there."""
    import matplotlib.image
    scene = {"title": "block on a floor", "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1], "cells": [2, 2, 2]},
             "material": {"E": 1e5, "nu": 0.3, "rho": 1000.0}, "discretization": {"degree": 1},
             "load": [{"type": "gravity"}],
             "contact": {"obstacle": [{"name": "floor", "shape": "plane", "point": [0, 0, -5e-5],
                                       "normal": [0, 0, 1], "friction": 0.5}]},
             "output": {"picture": True, "fields": False, "report": False}}
    path = tmp_path / "block.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    pixels = matplotlib.image.imread(tmp_path / "out" / "deformed.png")[..., :3]
    spread = pixels.max(axis=2) - pixels.min(axis=2)
    coloured = spread > 0.25                                                   # the part, in viridis
    grey = (spread < 0.08) & (pixels.mean(axis=2) > 0.5) & (pixels.mean(axis=2) < 0.95)
    grey[:60] = False                                                          # not the title's and legend's text
    rows = np.arange(pixels.shape[0])[:, None]
    assert coloured.mean() > 0.02 and grey.mean() > 0.05
    assert (rows * grey).sum() / grey.sum() > (rows * coloured).sum() / coloured.sum()   # below the part


def test_the_deformed_picture_marks_the_supports_and_the_loads_where_they_act(tmp_path):
    """deformed.png of a cantilever clamped at x = 0 and pulled down at x = L: against the same picture without the
    model (nothing marked), the pixels the marks change are at the part's two ends only (the picture's x axis runs
    to the right), bluer at the clamped end (the first mark, report.html's blue) and redder at the loaded one (its
    yellow turns red: less green)."""
    import matplotlib.image
    import fem_forms as ff
    from fem_forms.analyses.static.solve import solve_static
    from fem_forms.output import pictures
    scene = ff.Scene.from_dict({
        "title": "cantilever", "mesh": {"generator": "box", "size": [0.2, 0.02, 0.02], "cells": [20, 2, 2]},
        "material": {"E": 1e6, "nu": 0.3}, "fix": [{"name": "wall", "where": {"axis": "x", "at": 0.0}}],
        "load": [{"type": "traction", "where": {"axis": "x", "at": 0.2}, "value": [0.0, 0.0, -200.0]}]})
    result = solve_static(scene)
    pictures.picture(tmp_path / "marked.png", result.u, "cantilever", model=result.model)
    pictures.picture(tmp_path / "plain.png", result.u, "cantilever")
    marked, plain = (matplotlib.image.imread(tmp_path / f)[..., :3] for f in ("marked.png", "plain.png"))
    marked, plain = marked[60:], plain[60:]                                     # below the title and the legend
    changed = np.abs(marked - plain).max(axis=2) > 0.05
    part = (plain.max(axis=2) - plain.min(axis=2)) > 0.1                       # the part, in viridis
    part[:, 700:] = False                                                       # not the colour bar
    columns = np.flatnonzero(part.any(axis=0))
    left, right = columns.min(), columns.max()
    near = 0.06 * (right - left)
    cols = np.nonzero(changed)[1]
    assert changed.sum() > 200
    assert np.all((cols <= left + near) | (cols >= right - near))              # at the ends only
    assert (cols <= left + near).any() and (cols >= right - near).any()        # both ends
    change = marked - plain
    at_wall, at_load = change[:, : left + int(near)][changed[:, : left + int(near)]], \
        change[:, right - int(near):][changed[:, right - int(near):]]
    assert (at_wall[:, 2] - at_wall[:, 0]).mean() > 0.15                       # bluer (measured 0.33)
    assert (at_load[:, 0] - at_load[:, 1]).mean() > 0.15                       # redder against green (0.32)


def test_a_moving_obstacle_follows_its_motion_through_the_frames(tmp_path):
    """A ball moving 0.2 m along x over a clamped block in two load steps (pseudo-time = load factor): the page
    holds its translation at each frame's time (0.1 and 0.2 m, its motion's rows interpolated by hand), frames the
    ball along its way, and report.html#frame=K opens frame K with the ball drawn there: its grey pixels further
    right in the last frame than in the first (the view's x axis runs to the right)."""
    import matplotlib.image
    scene = {"title": "a ball passing over a block", "mesh": {"generator": "box", "size": [0.1, 0.1, 0.1],
                                                             "cells": [2, 2, 2]},
             "material": {"E": 1e5, "nu": 0.3, "rho": 1000.0}, "load": [{"type": "gravity"}],
             "fix": [{"where": {"axis": "z", "at": 0.0}}],
             "contact": {"obstacle": [{"name": "ball", "shape": "sphere", "center": [-0.05, 0.05, 0.2],
                                       "radius": 0.03, "motion": [[0, 0, 0, 0], [1, 0.2, 0, 0]]}]},
             "solver": {"steps": 2, "max_step": 0.5}, "output": {"picture": False, "fields": False}}
    path = tmp_path / "ball.toml"
    path.write_text(toml_dumps(scene))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 0
    page = tmp_path / "out" / "report.html"
    data = json.loads(page.read_text().split('<script id="report-data" type="application/json">')[1]
                      .split("</script>")[0])
    (ball,) = data["obstacles"]
    assert [f["label"] for f in data["frames"]] == ["load factor 0.5", "load factor 1"]
    assert ball["offset0"] == [0, 0, 0] and np.allclose(ball["offsets"], [[0.1, 0, 0], [0.2, 0, 0]], atol=1e-12)
    centres = []
    for k in (0, 1):
        shot = tmp_path / f"frame{k}.png"
        _browser("--window-size=1000,700", f"--screenshot={shot}", page.as_uri() + f"#frame={k}")
        pixels = matplotlib.image.imread(shot)[100:460, 150:850, :3]
        grey = (pixels.max(axis=2) - pixels.min(axis=2) < 0.05) & (pixels.mean(axis=2) > 0.6) & \
            (pixels.mean(axis=2) < 0.9)
        assert grey.sum() > 500, f"frame {k}: no ball drawn"
        centres.append(np.nonzero(grey)[1].mean())
    assert centres[1] > centres[0] + 40
    dom = _browser("--dump-dom", page.as_uri() + "#frame=0").stdout
    assert '<p id="error"></p>' in dom and "load factor 0.5</span>" in dom
