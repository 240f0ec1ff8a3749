"""Will a mesh fit? Memory estimated from cell and dof counts, before anything is allocated, against
the memory of the machine(s) the ranks run on.

The estimate is a lower bound on what a solve needs: mesh and dofmap (about 0.5 kB per cell) and the
assembled tangent, a few copies of it (BAIJ matrix, the solver's work arrays), 12 bytes per stored
entry. A direct factorisation needs far more; the estimate only refuses what cannot possibly fit,
naming the number, instead of a MemoryError traceback or a machine brought to a halt by swapping.
"""
from __future__ import annotations

import math
import os
import socket

from mpi4py import MPI
import numpy as np

from fem_forms.errors import InputError
from fem_forms.scene import MeshSpec

BYTES_PER_CELL = 500
BYTES_PER_ENTRY = 12            # a double and a column index
MATRIX_COPIES = 3
# coupled nodes per node (each with 3 components): the stencil of one row block
STENCIL = {("tetrahedron", 1): 15, ("tetrahedron", 2): 30, ("hexahedron", 1): 27, ("hexahedron", 2): 80,
           ("prism", 1): 21, ("prism", 2): 50}
CELLS_PER_CUBE = {"tetrahedron": 6, "hexahedron": 1, "prism": 2}


def host_memory() -> int:
    """Physical memory of this machine in bytes (MemTotal of /proc/meminfo, else sysconf)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def machine_memory(comm: MPI.Comm = MPI.COMM_WORLD) -> int:
    """Memory of all the hosts the ranks of comm run on (each host counted once)."""
    per_host = comm.allgather((socket.gethostname(), host_memory()))
    return sum(dict(per_host).values())


def box_counts(cells: list, cell_type: str, degree: int) -> tuple[int, int]:
    """(cells, dofs) of the built-in box before it is built."""
    nx, ny, nz = (int(n) for n in cells)
    if degree == 1:
        nodes = (nx + 1) * (ny + 1) * (nz + 1)
    elif cell_type == "hexahedron":
        nodes = (2 * nx + 1) * (2 * ny + 1) * (2 * nz + 1)
    else:                     # vertices + edges: 7 edges per cube of 6 tetrahedra, plus the boundary's
        nodes = (nx + 1) * (ny + 1) * (nz + 1) + 7 * nx * ny * nz + 3 * (nx * ny + ny * nz + nx * nz)
    return CELLS_PER_CUBE[cell_type] * nx * ny * nz, 3 * nodes


def tetrahedra_counts(volume: float, h: float, degree: int) -> tuple[int, int]:
    """(cells, dofs) of a tetrahedral mesh of size h filling `volume` (regular tetrahedra of edge h)."""
    cells = int(volume / (h**3 / 8.485))
    return cells, tetrahedra_dofs(cells, degree)


def tetrahedra_dofs(cells: int, degree: int) -> int:
    """The displacement dofs of a tetrahedral mesh of `cells` cells (5.5 cells per vertex; P2: 1.4 nodes a cell)."""
    return int(3 * (cells / 5.5 if degree == 1 else cells * 1.4))


def estimate_bytes(cells: int, dofs: int, cell_type: str, degree: int) -> float:
    """Lower bound of the memory a static solve needs."""
    stencil = STENCIL[(cell_type, min(max(degree, 1), 2))]
    return BYTES_PER_CELL * cells + MATRIX_COPIES * BYTES_PER_ENTRY * dofs * 3 * stencil


def check_cap(cells: int, cap: int | None, key: str, estimated: bool = False) -> None:
    """Refuse a mesh of more cells than the scene may ask for (scene/limits.py; None: no cap)."""
    if cap is not None and cells > cap:
        raise InputError(f"{key}: {'about ' if estimated else ''}{cells:,} cells, more than a scene may ask for "
                         f"({cap:,}); --no-limits lifts it")


def check_fits(cells: int, dofs: int, cell_type: str, degree: int, key: str, limit: int) -> None:
    """Refuse a mesh whose estimated memory exceeds `limit` bytes, naming the estimate."""
    need = estimate_bytes(cells, dofs, cell_type, degree)
    if need > limit:
        raise InputError(f"{key}: {cells:.3g} cells, {dofs:.3g} dofs (P{degree}) need at least "
                         f"{need / 2**30:.3g} GiB, more than this machine's {limit / 2**30:.3g} GiB; "
                         "use fewer cells or a coarser h")


def solid_volume(spec: MeshSpec) -> float:
    """Volume of a generated solid (revolve: Pappus, outline area times the path of its centroid)."""
    if spec.generator == "cylinder":
        return math.pi * spec.radius**2 * spec.height
    if spec.generator == "sphere":
        return 4.0 / 3.0 * math.pi * spec.radius**3
    r, z = np.array(spec.profile, dtype=float).T
    cross = r * np.roll(z, -1) - np.roll(r, -1) * z
    area = cross.sum() / 2.0
    centroid = ((r + np.roll(r, -1)) * cross).sum() / (6.0 * area) if area else 0.0
    return abs(2.0 * math.pi * centroid * area)
