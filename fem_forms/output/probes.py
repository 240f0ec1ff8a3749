"""Point evaluation of fields at points of the undeformed configuration, correct under MPI, and the one CSV
writer of per-step records (probes.csv and energy.csv of a dynamic run, probes.csv of a static load path)."""
from __future__ import annotations

import os
from pathlib import Path

from dolfinx import fem, geometry, mesh as dmesh
from mpi4py import MPI
import numpy as np

from fem_forms.errors import InputError


class ProbeSet:
    """Named points located once in a mesh (each on the lowest rank owning a cell that contains it), then
    evaluated for any field on that mesh: a dynamic run evaluates its probes every step, and building the
    bounding-box tree each time cost 10x the explicit step itself (measured, benchmarks/dynamic_steps.md).
    A point outside the mesh is an error."""

    def __init__(self, mesh: dmesh.Mesh, points: dict[str, list]):
        self.mesh, self.points = mesh, points
        self.names = list(points)
        self.X = np.array([points[n] for n in self.names], dtype=np.float64).reshape(-1, 3)
        self.cells = np.full(len(self.names), -1, dtype=np.int32)
        if not self.names:
            return
        tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
        candidates = geometry.compute_collisions(tree, self.X)
        colliding = geometry.compute_colliding_cells(mesh, candidates, self.X)
        nowned = mesh.topology.index_map(mesh.topology.dim).size_local
        found = np.full(len(self.names), mesh.comm.size, dtype=np.int32)
        for i in range(len(self.names)):
            cells = [c for c in colliding.links(i) if c < nowned]
            if cells:
                found[i], self.cells[i] = mesh.comm.rank, cells[0]
        owner = np.empty_like(found)
        mesh.comm.Allreduce(found, owner, op=MPI.MIN)
        missing = [n for n, o in zip(self.names, owner) if o == mesh.comm.size]
        if missing:
            raise InputError(f"output.probes.{missing[0]} = {points[missing[0]]}: point lies outside the mesh")
        self.mine = owner == mesh.comm.rank

    def evaluate(self, f: fem.Function) -> dict[str, list]:
        """{name: value} of f at each point, shared with all ranks."""
        if not self.names:
            return {}
        values = np.zeros((len(self.names), f.function_space.dofmap.index_map_bs))
        for i in np.flatnonzero(self.mine):
            values[i] = f.eval(self.X[i:i + 1], self.cells[i:i + 1])
        total = np.empty_like(values)
        self.mesh.comm.Allreduce(values, total, op=MPI.SUM)
        return {n: total[i].tolist() for i, n in enumerate(self.names)}


def nearest_nodes(V: fem.FunctionSpace, points) -> tuple[np.ndarray, np.ndarray]:
    """Each point's nearest owned node of V (the lowest rank owning one as near takes it): (its local node index
    on that rank, -1 elsewhere; its position, on every rank). The designs' targets sit on nodes this way."""
    comm = V.mesh.comm
    X = V.tabulate_dof_coordinates()[:V.dofmap.index_map.size_local]
    points = np.atleast_2d(np.asarray(points, dtype=float))
    node, at = np.full(len(points), -1), np.zeros((len(points), 3))
    for i, p in enumerate(points):
        dist = np.linalg.norm(X - p, axis=1) if len(X) else np.array([np.inf])
        k = int(np.argmin(dist))
        best = comm.allreduce(float(dist[k]), op=MPI.MIN)
        owner = comm.allreduce(comm.rank if dist[k] <= best else comm.size, op=MPI.MIN)
        if comm.rank == owner:
            node[i] = k
        at[i] = comm.allreduce(X[k] if comm.rank == owner else np.zeros(3), op=MPI.SUM)
    return node, at


def evaluate(f: fem.Function, points: dict[str, list]) -> dict[str, list]:
    """{name: value} of f at each named point (located afresh; keep a ProbeSet to evaluate often)."""
    return ProbeSet(f.function_space.mesh, points).evaluate(f)


DISPLACEMENT = ("ux", "uy", "uz")


def columns(names: list[str], components: tuple = DISPLACEMENT) -> list[str]:
    """Column names of probe values: NAME_ux, NAME_uy, ... for each probe in order."""
    return [f"{n}_{c}" for n in names for c in components]


def append_row(path: Path, row: list, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """One more line of numbers at the end of a table write_table began (rank 0, one write, flushed): a run
    killed outright still leaves its rows up to the last one appended."""
    if comm.rank != 0:
        return
    with open(path, "a") as f:
        f.write(",".join(f"{x:.10g}" for x in row) + "\n")
        f.flush()


def write_table(path: Path, head: list[str], rows: list, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """A CSV (header, then one line of numbers per row, 10 significant digits) written by rank 0 only (no
    collective call: it may run where other ranks have stopped) through a temporary file renamed over
    `path`, so a reader or an interrupt never sees half a table."""
    if comm.rank != 0:
        return
    lines = [",".join(head)] + [",".join(f"{x:.10g}" for x in row) for row in rows]
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text("\n".join(lines) + "\n")
    os.replace(tmp, path)
