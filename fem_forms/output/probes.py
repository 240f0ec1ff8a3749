"""Point evaluation of fields at points of the undeformed configuration, correct under MPI."""
from __future__ import annotations

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


def evaluate(f: fem.Function, points: dict[str, list]) -> dict[str, list]:
    """{name: value} of f at each named point (located afresh; keep a ProbeSet to evaluate often)."""
    return ProbeSet(f.function_space.mesh, points).evaluate(f)
