"""The head of every results.json, written the same way by every analysis: what was run (analysis, title),
its size (dofs), where (MPI ranks) and its cost (peak memory, wall time)."""
from __future__ import annotations

import resource

from mpi4py import MPI


def peak_memory_mb(comm) -> float:
    """Peak resident memory of this process so far, summed over ranks (MB). Collective."""
    return comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, op=MPI.SUM)


def header(analysis: str, scene, comm, dofs: int | None = None, wall_time_s: float | None = None,
           memory: bool = True) -> dict:
    """results.json's first keys: analysis, title, dofs (where there are any), mpi_ranks, peak_memory_mb
    (collective: every rank must call; `memory=False` on one rank alone) and wall_time_s (where known)."""
    out = {"analysis": analysis, "title": scene.title}
    if dofs is not None:
        out["dofs"] = int(dofs)
    out["mpi_ranks"] = comm.size
    if memory:
        out["peak_memory_mb"] = peak_memory_mb(comm)
    if wall_time_s is not None:
        out["wall_time_s"] = wall_time_s
    return out
