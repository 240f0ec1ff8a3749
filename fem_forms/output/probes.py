"""Point evaluation of fields at points of the undeformed configuration, correct under MPI."""
from __future__ import annotations

from dolfinx import fem, geometry
from mpi4py import MPI
import numpy as np

from fem_forms.errors import InputError


def evaluate(f: fem.Function, points: dict[str, list]) -> dict[str, list]:
    """{name: value} of f at each named point; each point is evaluated on the lowest rank owning a
    cell that contains it and then shared with all ranks. A point outside the mesh is an error."""
    if not points:
        return {}
    mesh = f.function_space.mesh
    names = list(points)
    X = np.array([points[n] for n in names], dtype=np.float64)
    tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
    candidates = geometry.compute_collisions(tree, X)
    colliding = geometry.compute_colliding_cells(mesh, candidates, X)
    nowned = mesh.topology.index_map(mesh.topology.dim).size_local
    vs = f.function_space.dofmap.index_map_bs
    found = np.full(len(names), mesh.comm.size, dtype=np.int32)
    values = np.zeros((len(names), vs))
    for i in range(len(names)):
        cells = [c for c in colliding.links(i) if c < nowned]
        if cells:
            found[i] = mesh.comm.rank
            values[i] = f.eval(X[i:i + 1], np.array(cells[:1], dtype=np.int32))
    owner = np.empty_like(found)
    mesh.comm.Allreduce(found, owner, op=MPI.MIN)
    missing = [n for n, o in zip(names, owner) if o == mesh.comm.size]
    if missing:
        raise InputError(f"output.probes.{missing[0]} = {points[missing[0]]}: point lies outside the mesh")
    mine = np.where((owner == mesh.comm.rank)[:, None], values, 0.0)
    total = np.empty_like(mine)
    mesh.comm.Allreduce(mine, total, op=MPI.SUM)
    return {n: total[i].tolist() for i, n in enumerate(names)}
