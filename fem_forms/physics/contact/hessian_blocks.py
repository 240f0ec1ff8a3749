"""The contact Hessians' entries into the assembled tangent: 3x3 blocks on the diagonal of the surface nodes (the
obstacles' barriers and friction: in every tangent's pattern) and the triangle contacts' coupling blocks (nodes no
element joins: the pattern widens)."""
from __future__ import annotations

from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.physics.array_term import add_entries


def add_triangle_hessian(A: PETSc.Mat, H, surface, owned: np.ndarray, constrained: np.ndarray) -> None:
    """Triangle contact's Hessian H (COO over the surface's dofs) in the rows of the owned nodes. It couples nodes no
    element joins: it is assembled into its own matrix and added with MatAXPY, which widens A's pattern (inserting
    new nonzeros into an assembled parallel A crashed PETSc on 2 ranks)."""
    to_global = lambda i: 3 * surface.blocks[i // 3] + i % 3        # noqa: E731
    rows, cols = to_global(H.row), to_global(H.col)
    keep = owned[H.row // 3] & (H.data != 0.0) & ~np.isin(rows, constrained) & ~np.isin(cols, constrained)
    if not A.comm.tompi4py().allreduce(bool(keep.any()), op=MPI.LOR):
        return
    lo, hi = A.getOwnershipRange()
    rows, cols, vals = rows[keep] - lo, cols[keep], H.data[keep]
    order = np.lexsort((cols, rows))
    rows, cols, vals = rows[order], cols[order], vals[order]
    indptr = np.searchsorted(rows, np.arange(hi - lo + 1)).astype(PETSc.IntType)
    C = PETSc.Mat().createAIJ(A.getSizes(), csr=(indptr, cols.astype(PETSc.IntType), vals), comm=A.comm)
    C.assemble()
    A.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    C.destroy()
    # the widening axpy (collective: every rank is here) resets A's options: new nonzeros allowed again on
    # every rank, or the obstacle blocks that follow (add_entries) would allow them on some ranks only, and
    # MatAssemblyEnd's collective steps then differ between ranks (2 ranks hung there)
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)


def add_node_blocks(A: PETSc.Mat, surface, nodes: np.ndarray, blocks: np.ndarray, constrained: np.ndarray) -> None:
    """One 3x3 block per surface node on the diagonal of A (in every tangent's pattern)."""
    base = 3 * surface.blocks[nodes]
    rows = np.repeat(base[:, None] + np.arange(3), 3, axis=1).ravel()
    cols = np.tile(base[:, None] + np.arange(3), (1, 3)).ravel()
    add_entries(A, rows.astype(PETSc.IntType), cols.astype(PETSc.IntType), blocks.reshape(-1), constrained)
