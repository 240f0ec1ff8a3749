"""Shared test setup: quiet JIT logs, collect PETSc objects between tests so that collective
destructors run at the same point on every rank."""
import gc
import os
import sys
from pathlib import Path

import pytest
from mpi4py import MPI

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import fem_forms  # noqa: E402

fem_forms.quiet_jit()
os.environ.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
os.environ.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


@pytest.fixture(autouse=True)
def _collect():
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()


def beam_scene(**over) -> dict:
    """A small clamped beam scene as a dict (tests tweak it)."""
    d = {
        "title": "test beam",
        "mesh": {"generator": "box", "size": [1.0, 0.1, 0.1], "cells": [10, 2, 2]},
        "material": {"model": "neo-hookean", "E": 1e6, "nu": 0.3, "rho": 1000.0},
        "discretization": {"degree": 1},
        "fix": [{"where": {"axis": "x", "at": 0.0}}],
        "load": [{"type": "gravity", "g": [0.0, 0.0, -9.81]}],
        "output": {"probes": {"tip": [1.0, 0.05, 0.05]}},
    }
    for k, v in over.items():
        d[k] = v
    return d
