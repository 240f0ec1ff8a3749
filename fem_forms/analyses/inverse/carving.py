"""Sag and stand in one run ([balance] in an inverse scene, issue 27): carve the interior so that the part
stands (spins, floats, rocks) on the TARGET shape, then design the rest shape of the carved part.

For a fixed target the two decouple: the sagged shape is the target, so the carving is designed there
(the balance LP of fem_forms/design/balance on the target mesh), and the rest shape is then designed with
the carved cells at the fill density and a residual stiffness (balance's fill_stiffness, 1e-6 for an empty
fill: the DG0 `stiffness_factor` scaling psi, as in elastic balance scenes). Mass is rho times a cell's REST
volume (gravity acts per rest volume), while the first carving weighs the cells by their TARGET volumes: the
two differ by the cells' volume change in the sag (nearly none for a nearly incompressible material). So the
carving is designed on target volumes, the rest shape designed, and the carving redone once with each cell's
moments scaled by its rest / target volume measured on that rest shape (for P1, exactly the weights of the
checked sag); if that changes any cell, the rest shape is designed again. Then the stance is measured, never
predicted: the forward check loads the written, carved rest shape (volume groups "solid" and "void"), solves
its sag, and takes the stance from each cell's rest mass carried to the sagged shape. A stance that fails
there makes the design unusable."""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
import time
from typing import Callable

from dolfinx import fem
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.design.balance import setting, stiffness_factors
from fem_forms.design.balance.body import Body
from fem_forms.design.balance.design import Setting, design
from fem_forms.design.balance.evaluate import evaluate, unmet
from fem_forms.design.parameters import InverseResult
from fem_forms.errors import SolveError
from fem_forms.meshes import LoadedMesh
from fem_forms.meshes.cell_faces import surface_triangles
from fem_forms.output import fields
from fem_forms.output.balance import picture
from fem_forms.output.stl import write_stl
from fem_forms.physics import quadrature
from fem_forms.scene import Scene
from fem_forms.scene.analyses.balance import fill_stiffness

SOLID, VOID = "solid", "void"        # the carved rest mesh's volume groups


@dataclass
class Carving:
    """The carving designed on the target shape: one rank's cells, their solid fractions, the LP's numbers."""
    scene: Scene
    loaded: LoadedMesh            # the target mesh
    body: Body                    # the part on the target shape
    setting: Setting
    solid: np.ndarray             # 0/1 per carvable cell of body
    on_target: dict               # evaluate() of the binary carving on the target (after the re-carve: each
                                  # cell's moments weighed by its rest volume, i.e. its mass)
    timing: object = None         # the LPs' cost (lp.Timing), rank 0
    design_time_s: float = 0.0
    recarved_cells: int = 0       # cells the re-carve on rest-volume weights changed
    inverse_solves: int = 0       # rest-shape designs (2 when the re-carve changed the carving)
    weights: str = "target volumes"   # what on_target's moments weigh each cell by
    recarve_outcome: str = "not run (goal check)"

    def recarve(self, ratios: np.ndarray) -> bool:
        """Carve again with each cell's moments scaled by its rest / target volume (the cell's mass is rho x
        its rest volume, placed on the target: for P1 exactly what the forward check's sag weighs). Keeps
        the first carving if the re-carve misses the goal. Whether the carving changed."""
        t0 = time.perf_counter()
        body = replace(self.body, moments=self.body.moments * ratios[:, None])
        try:
            solid, P = design(body, self.setting)
        except SolveError as e:
            self.recarve_outcome = f"first carving kept: no carving on rest-volume weights ({e})"
            return False
        numbers = evaluate(body, self.setting, solid)
        self.design_time_s += time.perf_counter() - t0
        if why := unmet(numbers, self.setting):
            self.recarve_outcome = f"first carving kept: the re-carve misses the goal ({why})"
            return False
        comm = self.loaded.mesh.comm
        self.recarved_cells = comm.allreduce(int(np.sum(solid != self.solid)), op=MPI.SUM)
        self.body, self.solid, self.on_target = body, solid, numbers
        self.weights = "rest volumes of the first rest shape"
        self.recarve_outcome = (f"changed {self.recarved_cells} cells: rest shape designed again"
                                if self.recarved_cells else "the same carving")
        if P is not None and self.timing is not None:
            self.timing = self.timing.add(P.timing)
        return self.recarved_cells > 0

    @property
    def carved(self) -> np.ndarray:
        """A flag per owned cell of the target mesh: carved (void or fill)."""
        c = np.zeros(len(self.body.ids), dtype=bool)
        c[self.body.carvable] = self.solid < 0.5
        return c

    @property
    def any_carved(self) -> bool:
        return self.loaded.mesh.comm.allreduce(bool(self.carved.any()), op=MPI.LOR)

    def _cell_values(self, mesh, void: np.ndarray) -> tuple[fem.Function, np.ndarray]:
        """The stiffness factor (DG0) and the density per local cell, given which local cells are void."""
        b = self.setting.spec
        factor = fields.cell_function(mesh, np.where(void, fill_stiffness(b), 1.0), "stiffness_factor")
        return factor, np.where(void, b.fill_density, self.scene.material.rho)

    def design_fields(self) -> dict:
        """What the inverse design takes: the stiffness factor and the density on the target mesh."""
        mesh = self.loaded.mesh
        factors = stiffness_factors(self.body, self.solid, fill_stiffness(self.setting.spec))
        factor = fields.cell_function(mesh, factors, "stiffness_factor")
        return {"extra": {"stiffness_factor": factor},
                "density": self.body.density(self.solid, self.setting.rho, self.setting.spec.fill_density)}

    def cell_groups(self) -> dict | None:
        """On rank 0, the gathered cells' rows of each volume group (collective; None: nothing carved)."""
        if not self.any_carved:
            return None
        flags = fields.gather_cell_values(self.loaded.mesh, self.carved)
        if flags is None:
            return None
        return {SOLID: np.flatnonzero(~flags), VOID: np.flatnonzero(flags)}

    def on_mesh(self, loaded: LoadedMesh) -> dict:
        """The forward model's fields on a loaded carved mesh, read from its "void" volume group."""
        mesh = loaded.mesh
        imap = mesh.topology.index_map(3)
        void = np.zeros(imap.size_local + imap.num_ghosts, dtype=bool)
        void[np.asarray(loaded.cells.get(VOID, []), dtype=np.int64)] = True
        factor, density = self._cell_values(mesh, void)
        return {"extra": {"stiffness_factor": factor}, "density": density}

    def write_void(self, out: Path, v: fem.Function) -> str | None:
        """void.stl: the carved cells' surface on the REST shape (target + v), normals into the void. A write
        error becomes the returned problem on every rank (never rank 0's traceback while the others wait)."""
        mesh = self.loaded.mesh
        gathered = fields.gather_mesh(mesh, fields.node_values(v))
        flags = fields.gather_cell_values(mesh, self.carved)
        problem = None
        if mesh.comm.rank == 0:
            points, cells, _ = gathered
            void = surface_triangles(cells[flags]) if flags.any() else np.empty((0, 3), dtype=np.int64)
            try:
                write_stl(out / "void.stl", points, void[:, ::-1], "carved void")
            except OSError as e:
                problem = f"cannot write the void surface: {e}"
        return mesh.comm.bcast(problem, root=0)

    def sagged(self, static) -> tuple[dict, dict, Body, np.ndarray]:
        """The stance of the forward check's result: the carved rest mesh it loaded (its void group), each
        cell's rest mass carried by the displacement. Returns (numbers on the rest shape, on the sagged
        shape, the rest body, its void flags)."""
        model = static.model
        mesh = model.mesh
        n = mesh.topology.index_map(3).size_local
        void = np.zeros(n, dtype=bool)
        cells = np.asarray(model.loaded.cells.get(VOID, []), dtype=np.int64)
        void[cells[cells < n]] = True
        st = setting(self.scene, mesh, model.loaded)
        rest = replace(Body.rest(mesh, self.setting.spec.shell), carvable=void)
        hollow = np.zeros(int(void.sum()))
        at_rest = evaluate(rest, st, hollow)
        bent = evaluate(rest.deformed(static.u), st, hollow, rest)
        return at_rest, bent, rest, void


def rest_volume_ratios(v: fem.Function) -> np.ndarray:
    """Per owned cell of the target mesh: its rest volume over its target volume, int det(I + grad v) dx over
    int 1 dx, exact: on a reference cell the integrand is det(dX/dxi) of the rest map, of degree 3 (p - 1) in a
    straight-sided tetrahedron and 3p - 1 in each direction of a hexahedron (Qp)."""
    mesh = v.function_space.mesh
    Q = fem.FunctionSpace(mesh, ("DG", 0))
    w = ufl.TestFunction(Q)
    p = v.function_space.ufl_element().degree()
    q = 3 * p - 1 if mesh.topology.cell_name() == "hexahedron" else max(1, 3 * (p - 1))
    dx = ufl.dx(metadata=quadrature.metadata(mesh.topology.cell_name(), q))
    n = mesh.topology.index_map(3).size_local
    dofs = Q.dofmap.list.array[:n]
    values = []
    for integrand in (ufl.det(ufl.Identity(3) + ufl.grad(v)), fem.Constant(mesh, 1.0)):
        vec = fpetsc.assemble_vector(fem.form(integrand * w * dx))
        values.append(vec.array[dofs].copy())
        vec.destroy()
    return values[0] / values[1]


def design_carved(scene: Scene, material, loaded: LoadedMesh, solve: Callable) -> InverseResult:
    """The carving on the target, the rest shape of the carved part by `solve` (the direct method), and one
    re-carve with each cell weighed by its REST volume (its mass) measured on that rest shape; if that
    changes the carving, the rest shape is designed again. (The rest volumes of the second design differ
    from those of the first by a second-order change: the forward check measures the result.)"""
    cut = carve_on_target(scene, loaded)
    res = solve(scene, material, loaded, **cut.design_fields())
    cut.inverse_solves = 1
    if not res.converged:
        cut.recarve_outcome = "not run: no rest shape"
    if res.converged and scene.balance.goal != "check" and cut.recarve(rest_volume_ratios(res.v)):
        res = solve(scene, material, loaded, **cut.design_fields())
        cut.inverse_solves = 2
    res.carving = cut
    return res


def carve_on_target(scene: Scene, loaded: LoadedMesh) -> Carving:
    """The goal's carving of the part on the target shape; SolveError (one line) when no carving meets it."""
    t0 = time.perf_counter()
    b = scene.balance
    st = setting(scene, loaded.mesh, loaded)
    body = Body.rest(loaded.mesh, b.shell)
    solid = np.ones(int(body.carvable.sum()))
    timing = None
    if b.goal != "check":
        solid, P = design(body, st)
        timing = P.timing if P is not None else None
    numbers = evaluate(body, st, solid)
    if b.goal != "check" and (why := unmet(numbers, st)):
        raise SolveError(f"{scene.title}: balance: the binary carving misses its goal on the target shape: {why}")
    return Carving(scene, loaded, body, st, solid, numbers, timing, time.perf_counter() - t0)


def _pick(numbers: dict) -> dict:
    """evaluate()'s numbers as results.json holds them (all of them: each goal is judged by its own)."""
    return {k: v for k, v in numbers.items() if k != "deformed"}


def check_stance(carving: Carving, static, out: Path, title: str, picture_too: bool) -> tuple[dict, list]:
    """results.json's "balance" and the problems of the stance on the forward check's sagged result."""
    b = carving.setting.spec
    comm = carving.loaded.mesh.comm
    summary = {"goal": b.goal, "shell": b.shell, "fill_density": b.fill_density,
               "fill_stiffness": fill_stiffness(b), "design_time_s": carving.design_time_s,
               "cells": comm.allreduce(len(carving.body.ids)),
               "carvable_cells": comm.allreduce(int(carving.body.carvable.sum())),
               "carved_cells": comm.allreduce(int(carving.carved.sum())),
               "carved_fraction": carving.on_target["carved_fraction"], "mass_on_target": carving.on_target["mass"],
               "recarved_cells": carving.recarved_cells, "recarve": carving.recarve_outcome,
               "inverse_solves": carving.inverse_solves, "on_target_weights": carving.weights,
               "on_target": _pick(carving.on_target), "void_surface": "void.stl"}
    if carving.timing is not None:
        summary["lp"] = {"setup_s": carving.timing.setup_s, "solve_s": carving.timing.solve_s,
                         "lps": carving.timing.lps, "binarise_s": carving.timing.binarise_s}
    if static is None or not static.report.converged:
        return summary, ["the stance could not be checked: the forward check has no sagged shape"]
    at_rest, bent, rest, void = carving.sagged(static)
    summary["mass"] = bent["mass"]
    summary["sagged"] = _pick(bent)
    problems = []
    if b.goal != "check" and (why := unmet(bent, carving.setting)):
        problems.append(f"the carved rest shape, sagged in the forward check, misses the balance goal: {why}")
    if picture_too:
        picture(out / "balance.png", rest.mesh, void, at_rest, dict(at_rest, deformed=bent), title,
                f" ({b.goal}: the rest shape to fabricate, sagged in the forward check)",
                sag=fields.node_values(static.u), up=carving.setting.frame[0], labels=("rest shape", "sagged"))
        summary["picture"] = "balance.png"
    return summary, problems


def balance_line(s: dict) -> str:
    """One line of the echo: the goal, the carving, the stance on the target and on the checked sag."""
    line = f"balance {s['goal']}: carved {100 * s['carved_fraction']:.1f} % ({s['carved_cells']} cells)"
    for label, key in (("on the target", "on_target"), ("sagged (forward check)", "sagged")):
        nums = s.get(key, {})
        if "toppling_angle_deg" in nums:
            line += (f"; {label}: toppling angle {nums['toppling_angle_deg']:.3g} deg "
                     f"({'stands' if nums['stands'] else 'topples'})")
    return line + (f"; void surface {s['void_surface']}" if s["carved_cells"] else "")
