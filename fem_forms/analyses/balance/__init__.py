"""Balance design (issue 14): mass properties, and carving the interior so that the part stands, spins,
floats upright or rocks back (Make It Stand, Spin-It, buoyancy design, Make it swing), optionally on the
shape sagging under gravity. Each design is a linear program in the carvable cells' solid fractions
(fem_forms/design/balance/goals.py), binarised and checked from the binary carving's own mass properties
(evaluate.py there); this package runs it on the rest shape (rigid) or on the sagging one (elastic.py).

run(scene, out, echo): results.json, void.stl, outer.stl, density.xdmf, balance.png.
"""
from __future__ import annotations

from pathlib import Path
import sys
import time

import numpy as np

from fem_forms.analyses.balance.elastic import sag_design
from fem_forms.design.balance import gravity, setting
from fem_forms.design.balance.body import Body
from fem_forms.design.balance.design import Setting, design
from fem_forms.design.balance.evaluate import evaluate, unmet
from fem_forms.errors import SolveError
from fem_forms.meshes import load_mesh
from fem_forms.output import results
from fem_forms.output.balance import picture, write_outputs
from fem_forms.output.fields import node_values
from fem_forms.output.summary import header
from fem_forms.scene import Scene


def _rigid(scene: Scene, st: Setting, body: Body) -> dict:
    t0 = time.perf_counter()
    solid = np.ones(int(body.carvable.sum()))
    before = evaluate(body, st, solid)
    timing = None
    if st.spec.goal != "check":
        solid, P = design(body, st)
        timing = P.timing if P is not None else None
    after = evaluate(body, st, solid)
    return {"solid": solid, "before": before, "after": after, "timing": timing,
            "design_time_s": time.perf_counter() - t0}


def run(scene: Scene, out, echo: bool = False) -> dict:
    """Mass properties and the goal's design; results.json last. SolveError (exit 3) when no design
    exists or the binary design misses a requirement."""
    t0 = time.perf_counter()
    out = Path(out)
    b = scene.balance
    if b.elastic:
        r = sag_design(scene, gravity(scene), lambda loaded: setting(scene, loaded.mesh, loaded))
        mesh, body, st = r["mesh"], r["rest"], r["setting"]
    else:
        loaded = load_mesh(scene.mesh)
        mesh = loaded.mesh
        st = setting(scene, mesh, loaded)
        body = Body.rest(mesh, b.shell)
        r = _rigid(scene, st, body)
    after = r["after"]
    if b.goal != "check":
        why = unmet(after.get("deformed", after), st)
        if why:
            shape = (f" on the shape sagged under gravity (after {len(r['history'])} static solves)"
                     if b.elastic else "")
            raise SolveError(f"balance: the binary design misses its goal{shape}: {why}")
    comm = mesh.comm
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    carved = np.zeros(len(body.ids), dtype=bool)
    carved[body.carvable] = r["solid"] < 0.5
    files = write_outputs(out, mesh, body.density(r["solid"], st.rho, b.fill_density), carved)
    if scene.output.picture:
        picture(out / "balance.png", mesh, carved, r["before"], after, scene.title, f" ({b.goal})",
                sag=node_values(r["u"]) if b.elastic else None, up=st.frame[0], check=b.goal == "check")
        files["picture"] = "balance.png"
    summary = {**header("balance", scene, comm, wall_time_s=time.perf_counter() - t0), "goal": b.goal,
               "elastic": b.elastic, **after, "before": r["before"], "cells": comm.allreduce(len(body.ids)),
               "carvable_cells": comm.allreduce(int(body.carvable.sum())), "files": files}
    if r.get("timing") is not None:
        tm = r["timing"]
        summary["lp"] = {"setup_s": tm.setup_s, "solve_s": tm.solve_s, "lps": tm.lps, "sifted_lps": tm.sifted,
                         "sifting_rounds": tm.rounds, "sifting_fallbacks": tm.fallbacks,
                         "binarise_s": tm.binarise_s, "fractional_cells": tm.fractional}
    if "design_time_s" in r:
        summary["design_time_s"] = r["design_time_s"]
    if b.elastic:
        summary["elastic_iterations"] = r["history"]
        summary["static_solves"] = len(r["history"])
    results.write_json_atomic(out / "results.json", summary, comm)
    if echo and comm.rank == 0:
        _echo(summary, out)
    return summary


def _echo(s: dict, out: Path) -> None:
    line = (f"{s['title']}: balance {s['goal']}: mass {s['mass']:.6g} kg, CoM "
            f"[{', '.join(f'{v:.4g}' for v in s['center_of_mass'])}], carved {100 * s['carved_fraction']:.1f} %")
    if "stands" in s:
        line += f", toppling angle {s['toppling_angle_deg']:.3g} deg ({'stands' if s['stands'] else 'topples'})"
    if "deformed" in s:
        d = s["deformed"]
        line += f"; deformed: toppling angle {d['toppling_angle_deg']:.3g} deg"
        if "stands" in d:
            line += f" ({'stands' if d['stands'] else 'topples'})"
    print(line + f" -> {out}")
    if s.get("warnings"):
        for w in s["warnings"]:
            print(f"fem-forms: warning: {w}", file=sys.stderr)
