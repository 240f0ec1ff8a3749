"""Two ranks add contact blocks to an assembled tangent without hanging (fem_forms/physics/contact/hessian_blocks.py).

Triangle contact's Hessian widens the tangent's pattern by MatAXPY, which resets the matrix's options; an
obstacle's blocks added after it (add_entries) then allowed new nonzeros only on the ranks that add entries,
and MatAssemblyEnd's collective steps differed between ranks: 2 ranks hung (self-contact plus a floor touched
on one rank only). Here the real add_triangle_hessian widens a 2-rank matrix, rank 0 alone adds an off-pattern
entry through add_entries, and both ranks must finish the assembly."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import MPIRUN, run_ahead

SCRIPT = """
from types import SimpleNamespace
import numpy as np
import scipy.sparse as sp
from petsc4py import PETSc
from fem_forms.physics.contact.hessian_blocks import add_triangle_hessian
from fem_forms.physics.array_term import add_entries
comm = PETSc.COMM_WORLD
A = PETSc.Mat().createAIJ(((6, None), (6, None)), nnz=(3, 0), comm=comm)      # 4 nodes x 3 dofs, 2 per rank
lo, hi = A.getOwnershipRange()
for i in range(lo, hi):
    A.setValue(i, i, 1.0)
A.assemble()
A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)       # as ArrayTerms.add_hessian does
# a triangle-contact Hessian coupling node 0 with node 3 (on the other rank), as ipctk hands it back
H = sp.coo_matrix((np.ones(2), ([0, 9], [9, 0])), shape=(12, 12))
surface = SimpleNamespace(blocks=np.arange(4))
owned = np.zeros(4, bool)
owned[2 * comm.rank:2 * comm.rank + 2] = True
add_triangle_hessian(A, H, surface, owned, np.empty(0, PETSc.IntType))
if comm.rank == 0:                                     # an obstacle's block on rank 0's rows only, off the pattern
    add_entries(A, np.array([1]), np.array([10]), np.array([2.0]), np.empty(0, PETSc.IntType))
A.assemble()
assert A.getValue(1, 10) == 2.0 if comm.rank == 0 else True
done = comm.tompi4py().allreduce(1)                  # every rank past the assembly; one line from rank 0
if comm.rank == 0:
    print(f"assembled on {done} ranks", flush=True)
"""


@pytest.mark.mpi
def test_contact_blocks_after_a_widened_pattern_assemble_on_two_ranks():
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
    try:
        proc = run_ahead([MPIRUN, "-n", "2", "--bind-to", "none", "--oversubscribe", sys.executable, "-c", SCRIPT],
                         90, env=env, cwd=Path(__file__).resolve().parents[2])
    except subprocess.TimeoutExpired:
        pytest.fail("two ranks hung in MatAssemblyEnd after contact blocks were added")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "assembled on 2 ranks"        # (two ranks' own lines came interleaved)
