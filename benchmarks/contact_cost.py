"""Benchmark: what contact costs per Newton iteration, against the same press without contact.

A silicone slab 200 x 200 x 50 mm (P1 tetrahedra, 40 x 40 x 10 boxes of 6: 55,473 dofs, 4,962 surface nodes),
E 1 MPa, nu 0.3, its top pressed down 1 mm. Its bottom is either clamped (no contact: the reference), or
rests on a floor: an analytic plane with friction (mu 0.5), or a frictionless STL table (a 240 x 240 x 5 mm box,
refined on reading to the slab's surface edge; the IPC Toolkit's triangle pairs), or is clamped with self-contact switched on (every surface triangle checked against every other,
none touching: the cost of the broad phase alone). Per case: Newton iterations, wall time of the solve, the
time spent in the contact term (energy, gradient, Hessian, step filter; measured by timing its methods), and
the cost of one Newton iteration against the clamped slab's. Medians of 2 runs after one that compiled the
forms; one core. (The STL table with friction 0.5 did not converge at this size: the triangle pairs' Hessian,
projected per pair with the table's nodes and then restricted to the slab's, is not the exact one, and
Newton crept linearly then stalled; see the manual, docs/analyses/contact.md.)

Run: `.venv/bin/python benchmarks/contact_cost.py` (about 6 minutes). Writes benchmarks/contact_cost.md.
"""
from __future__ import annotations

import functools
import statistics
import tempfile
import time
from pathlib import Path

import fem_forms as ff
from fem_forms.physics.contact.term import ContactTerm

HERE = Path(__file__).resolve().parent
SIZE, CELLS, DHAT = [0.2, 0.2, 0.05], [40, 40, 10], 1e-4
CLOCK = {"contact": 0.0}


def timed(method):
    """A ContactTerm method that adds its wall time to CLOCK (nested calls counted once)."""
    @functools.wraps(method)
    def wrapper(*args, **kwargs):
        if CLOCK.get("inside"):
            return method(*args, **kwargs)
        CLOCK["inside"] = True
        t0 = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            CLOCK["contact"] += time.perf_counter() - t0
            CLOCK["inside"] = False
    return wrapper


for _name in ("energy_value", "add_gradient", "add_hessian", "max_step", "update", "intersection"):
    setattr(ContactTerm, _name, timed(getattr(ContactTerm, _name)))


def table_file(folder: Path) -> str:
    """A closed box surface under the slab, its top DHAT / 2 below the slab's bottom (12 triangles)."""
    import meshio
    import numpy as np
    lo, hi = [-0.02, -0.02, -0.005], [0.22, 0.22, -DHAT / 2]
    P = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    F = np.array([[0, 2, 1], [1, 2, 3], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6],
                  [1, 3, 5], [3, 7, 5], [4, 5, 6], [5, 7, 6]])
    path = folder / "table.stl"
    meshio.write(str(path), meshio.Mesh(P.astype(float), [("triangle", F)]), file_format="stl")
    return str(path)


def scene(case: str, folder: Path) -> ff.Scene:
    press = {"name": "press", "where": {"axis": "z", "at": SIZE[2]}, "value": [0.0, 0.0, -0.001]}
    d = {"title": f"slab ({case})", "mesh": {"generator": "box", "size": SIZE, "cells": CELLS},
         "material": {"E": 1e6, "nu": 0.3}, "discretization": {"degree": 1}, "fix": [press],
         "output": {"picture": False, "fields": False}}
    floor = {"name": "floor", "friction": 0.5}
    if case == "clamped":
        d["fix"].append({"name": "bottom", "where": {"axis": "z", "at": 0.0}})
    elif case == "floor (plane)":
        d["contact"] = {"distance": DHAT, "obstacle": [dict(floor, shape="plane", point=[0, 0, -DHAT / 2],
                                                            normal=[0, 0, 1])]}
    elif case == "floor (STL file, frictionless)":
        d["contact"] = {"distance": DHAT, "obstacle": [dict(floor, friction=0.0, shape="file",
                                                            file=table_file(folder))]}
    else:                                                     # clamped, self-contact on
        d["fix"].append({"name": "bottom", "where": {"axis": "z", "at": 0.0}})
        d["contact"] = {"self": True, "distance": DHAT}
    return ff.Scene.from_dict(d)


def main() -> None:
    ff.quiet_jit()
    folder = Path(tempfile.mkdtemp())
    rows, reference = [], None
    for case in ("clamped", "floor (plane)", "floor (STL file, frictionless)", "clamped + self-contact"):
        runs = []
        for run in range(3):
            CLOCK["contact"] = 0.0
            t0 = time.perf_counter()
            result = ff.solve_static(scene(case, folder))
            runs.append((time.perf_counter() - t0, CLOCK["contact"], result.report.newton_iterations))
            assert result.report.converged, case
        wall = statistics.median(r[0] for r in runs[1:])
        inside = statistics.median(r[1] for r in runs[1:])
        its = runs[-1][2]
        per = wall / its
        reference = reference or per
        rows.append(f"| {case} | {result.model.dofs:,} | {its} | {wall:.2f} s | {inside:.2f} s | {per:.3f} s | "
                    f"{per / reference:.2f}x |")
        print(rows[-1], flush=True)
    lines = ["# Contact: cost per Newton iteration", "",
             "Generated by `benchmarks/contact_cost.py` (see its docstring): a slab of 55,473 dofs and 4,962 "
             "surface nodes pressed 1 mm, clamped or resting on a floor. Medians of 2 runs after one that compiled, "
             "one core.", "",
             "| bottom | dofs | Newton iterations | solve | in the contact term | per iteration | per iteration "
             "against clamped |", "|---|---|---|---|---|---|---|"] + rows
    (HERE / "contact_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
