"""Shared test setup: quiet JIT logs; under mpirun, collect PETSc objects between tests so that collective
destructors run at the same point on every rank.

Layout: tests/unit holds closed forms and small pieces, tests/system whole solves against analytic
solutions and published references (and every demo, tests/system/test_demos.py). Cases that run
`mpirun -n 2` carry the `mpi` marker (`pytest -m mpi`, `pytest -m "not mpi"`). Helpers shared by
both folders live in tests/helpers.py."""
import gc
import os
import sys
from pathlib import Path

# One BLAS thread in this process too (OpenBLAS reads it when numpy loads it, below): the runs made here in-process
# then sum in the same order as the `mpirun` ones they are compared with (threaded BLAS sums in varying order, and a
# frictional contact path amplified that to 0.5 %).
os.environ.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
os.environ.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import pytest  # noqa: E402
from mpi4py import MPI  # noqa: E402

# A pytest-xdist worker inherits the environment of the pytest process that started it, and that process has
# initialised MPI as a singleton (OMPI_MCA_ess, PMIX_* naming its PMIx server): a worker's mpirun then failed at
# once, with no output. A worker forgets them before it initialises MPI itself, as the first process did.
if "PYTEST_XDIST_WORKER" in os.environ:
    for key in [k for k in os.environ if k.startswith(("OMPI_MCA_", "PMIX_", "OMPI_APP_CTX_"))]:
        del os.environ[key]

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
for p in (str(ROOT), str(TESTS)):       # fem_forms and helpers importable from any working directory
    if p not in sys.path:
        sys.path.insert(0, p)

import fem_forms  # noqa: E402
from helpers import beam_scene  # noqa: E402,F401  (kept importable as conftest.beam_scene)

fem_forms.quiet_jit()


@pytest.fixture(autouse=True)
def _collect():
    """Under mpirun (pytest on several ranks), a collection after each test, so that PETSc's collective
    destructors run at the same point on every rank. On one rank (pytest's workers) Python's own collector does
    it: a full collection after every test took 0.15 s, 176 s of the cold suite's 2,205 worker seconds."""
    yield
    if MPI.COMM_WORLD.size > 1:
        gc.collect()
        MPI.COMM_WORLD.barrier()
