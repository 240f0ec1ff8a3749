"""[thermal] input: one line naming what is wrong, before anything is solved or written; the section's keys
are in the JSON Schema."""
import json

import pytest

import fem_forms as ff
from fem_forms.cli import main
from fem_forms.errors import InputError
from fem_forms.scene.schema import scene_schema
from helpers import toml_dumps


def scene(analysis="thermal", thermal=None, dynamic=None, rho=1.0, **more) -> dict:
    th = {"conductivity": 1.0, "specific_heat": 1.0,
          "boundary": [{"where": {"axis": "x", "at": 0.0}, "temperature": 1.0}]}
    th.update(thermal or {})
    d = {"analysis": analysis, "mesh": {"size": [1.0, 0.1, 0.1], "cells": [4, 1, 1]},
         "material": {"E": 1e6, "nu": 0.3, "rho": rho}, "thermal": th}
    if dynamic is not None:
        d["dynamic"] = dynamic
    d.update(more)
    return d


SIDE = {"where": {"axis": "x", "at": 1.0}}
CASES = [
    (scene(thermal={"conductivity": 0.0}), "thermal.conductivity = 0.0: must be positive"),
    (scene(thermal={"specific_heat": -1.0}), "thermal.specific_heat = -1.0: must be positive"),
    (scene(thermal={"boundary": [dict(SIDE, radiation={"emissivity": 1.5, "ambient": 300.0})]}),
     "thermal.boundary[0].radiation.emissivity = 1.5: emissivity must lie in (0, 1]"),
    (scene(thermal={"boundary": [dict(SIDE, radiation={"emissivity": 0.0, "ambient": 300.0})]}),
     "thermal.boundary[0].radiation.emissivity = 0.0: emissivity must lie in (0, 1]"),
    (scene(thermal={"boundary": [dict(SIDE, temperature=1.0, convection={"h": 5.0, "ambient": 0.0})]}),
     "thermal.boundary[0]: give exactly one of temperature, convection or radiation (got temperature, convection)"),
    (scene(thermal={"boundary": [SIDE]}), "thermal.boundary[0]: give exactly one of temperature, convection or radiation"),
    (scene(thermal={"boundary": [dict(SIDE, convection={"h": -5.0, "ambient": 0.0})]}),
     "thermal.boundary[0].convection.h = -5.0: must be positive"),
    (scene(thermal={"boundary": [dict(SIDE, convection={"h": 5.0})]}),
     "thermal.boundary[0].convection.ambient: missing"),
    (scene(thermal={"boundary": [dict(SIDE, convection=5.0)]}), "thermal.boundary[0].convection = 5.0: must be"),
    (scene(thermal={"boundary": [dict(SIDE, temperature=1.0, colour="red")]}), "thermal.boundary[0].colour: unknown key"),
    (scene(thermal={"boundary": [{"temperature": 1.0}]}), "thermal.boundary[0].where: missing"),
    (scene(thermal={"boundary": []}), "thermal.boundary: a steady temperature needs at least one"),
    (scene(thermal={"colour": 1}), "thermal.colour: unknown key"),
    (scene(thermal={"boundary": [dict(SIDE, temperature={"history": [[1.0, 0.0], [0.5, 1.0]]})]},
           dynamic={"duration": 1.0, "dt": 0.1}), "thermal.boundary[0].temperature.history: times must increase"),
    (scene(thermal={"boundary": [dict(SIDE, temperature={"history": [[0.0, 0.0], [1.0, 1.0]]})]}),
     "thermal.boundary: a temperature history needs a transient analysis"),
    (scene(dynamic={"duration": 1.0, "dt": 0.1}, rho=0.0), "material.rho: transient heat needs a positive density"),
    (scene(thermal={"specific_heat": None}, dynamic={"duration": 1.0, "dt": 0.1}),
     "thermal.specific_heat: missing (required for transient heat)"),
    (scene(dynamic={"duration": 1.0, "dt": 0.1, "scheme": "newmark"}), "dynamic.scheme: unknown key"),
    (scene(dynamic={"duration": 1.0, "dt": 2.0}), "dynamic.dt = 2.0: longer than duration"),
    (scene(analysis="static", thermal={"damping_heat": True}), "thermal.damping_heat: only for analysis = 'dynamic'"),
    (scene(analysis="modal"), "thermal: only for analysis = 'static' or 'dynamic' or 'thermal'"),
    (scene(analysis="dynamic", thermal={"damping_heat": True}), "thermal.damping_heat: needs viscous damping"),
    ({k: v for k, v in scene().items() if k != "thermal"}, "thermal: missing (required table for analysis = 'thermal')"),
    (scene(thermal={"boundary": [dict(SIDE, radiation={"emissivity": 0.5, "ambient": 20.0})],
                    "absolute_zero": -273.15}) | {"thermal": {"conductivity": 1.0, "absolute_zero": 0.0,
           "boundary": [dict(SIDE, radiation={"emissivity": 0.5, "ambient": -20.0})]}},
     "thermal.boundary: radiation ambient -20.0 is below absolute zero"),
]


@pytest.mark.parametrize("data, message", CASES, ids=[m[:40] for _, m in CASES])
def test_bad_thermal_input_is_one_line(data, message):
    data = {k: v for k, v in data.items()}
    if data.get("thermal", {}).get("specific_heat", 1) is None:
        data["thermal"] = {k: v for k, v in data["thermal"].items() if k != "specific_heat"}
    with pytest.raises(InputError) as e:
        ff.Scene.from_dict(data)
    assert str(e.value).startswith(message) and "\n" not in str(e.value)


def test_the_cli_refuses_with_exit_2_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(toml_dumps(scene(thermal={"conductivity": -2.0})))
    code = main(["run", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "thermal.conductivity = -2.0: must be positive" in err and "Traceback" not in err
    assert not (tmp_path / "out" / "results.json").exists()


def test_schema_has_the_thermal_keys():
    s = scene_schema()
    th = s["properties"]["thermal"]
    assert {"conductivity", "specific_heat", "expansion", "reference_temperature", "initial_temperature",
            "modulus_slope", "damping_heat", "absolute_zero", "boundary"} <= set(th["properties"])
    boundary = th["properties"]["boundary"]["items"]["properties"]
    assert {"where", "temperature", "convection", "radiation"} == set(boundary)
    assert "thermal" in s["properties"]["analysis"]["enum"]
    json.dumps(s)


def test_a_modulus_that_turns_negative_is_refused_in_one_line():
    d = scene(analysis="static", thermal={"modulus_slope": -1e5, "expansion": 1e-5,
                                          "boundary": [{"where": {"axis": "x", "at": 0.0}, "temperature": 20.0}]},
              fix=[{"where": {"axis": "x", "at": 0.0}}])
    with pytest.raises(InputError, match=r"^thermal.modulus_slope = -100000.0: E\(T\) = -1e\+06 Pa at T = 20 is not positive$"):
        ff.solve_static(ff.Scene.from_dict(d))
