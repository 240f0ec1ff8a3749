"""One thread per process for BLAS and for ipctk unless FEM_FORMS_THREADS says more: the same numbers on
every run and every rank count.

Both libraries sum on several threads in an order that varies: OpenBLAS by its thread count (the README's
first scene takes 17 Newton iterations with two BLAS threads, 18 with one), ipctk's TBB loops from run to
run (a frictional squeeze measured 1e-8 apart between two runs on two threads, amplified to 0.4 % under
load; identical on one). MPI ranks are the package's parallelism; a thread pool per rank on top of them
only oversubscribes the cores. An explicit OPENBLAS_NUM_THREADS wins for BLAS.
"""
from __future__ import annotations

import ctypes
import os

ENV = "FEM_FORMS_THREADS"


def count() -> int:
    """Threads per process for BLAS and ipctk: FEM_FORMS_THREADS, else 1."""
    raw = os.environ.get(ENV, "1")
    try:
        n = int(raw)
    except ValueError:
        n = 0
    if n < 1:       # read at import, before any command line: one line and exit status 1, no traceback
        raise SystemExit(f"fem-forms: {ENV} = {raw!r}: must be a whole number of threads, at least 1")
    return n


def pin_blas_environment() -> None:
    """Before numpy loads OpenBLAS: its thread count for this process and for every child (mpirun runs)."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", str(count()))


def pin_loaded_blas() -> None:
    """The same for an OpenBLAS already loaded (numpy imported before fem_forms): set through its C API."""
    want = int(os.environ.get("OPENBLAS_NUM_THREADS", count()))
    try:
        with open("/proc/self/maps") as maps:
            paths = {line.split()[-1] for line in maps}
    except OSError:
        return
    paths = [p for p in paths if "openblas" in os.path.basename(p) and ".so" in p]
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
            if hasattr(lib, "openblas_get_num_threads") and lib.openblas_get_num_threads() != want:
                lib.openblas_set_num_threads(want)
        except OSError:
            continue


def pin_ipctk(ipctk) -> None:
    """ipctk's TBB pool to the process's thread count."""
    ipctk.set_num_threads(count())
