"""Cache hits of FFCx's forms and elements (fem_forms.logs.fast_cache_hits): a finished entry is loaded by its file
name, without the folder scan of ffcx 0.5; an entry another process has not finished still goes through FFCx."""
import importlib.machinery

import dolfinx.jit
import ffcx.codegeneration.jit as fj
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

from fem_forms.meshes.loader import settle_coordinate_element


@pytest.fixture
def cache(monkeypatch, tmp_path):
    folder = tmp_path / "jit"
    monkeypatch.setitem(dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS, "cache_dir", (folder, "test"))
    return folder


def test_a_finished_entry_loads_without_scanning_the_cache(cache, monkeypatch):
    m = mesh.create_unit_cube(MPI.COMM_SELF, 2, 1, 1)
    settle_coordinate_element(m)                          # as every mesh of a run: the same signature twice
    V = fem.FunctionSpace(m, ("Lagrange", 3))
    f = fem.Function(V)
    f.interpolate(lambda x: x[0] ** 3)
    exact = fem.assemble_scalar(fem.form(f * ufl.dx))
    assert sorted(cache.glob("*.c.cached")), "nothing was compiled into the test's cache"

    def no_scan(*args, **kwargs):
        raise AssertionError("the cache folder was scanned for a finished entry")
    monkeypatch.setattr(importlib.machinery, "FileFinder", no_scan)
    W = fem.FunctionSpace(m, ("Lagrange", 3))            # the same element and dofmap: cache hits
    again = fem.assemble_scalar(fem.form(f * ufl.dx))     # a new UFL form, the same signature: a cache hit
    assert W.dofmap.index_map.size_local == V.dofmap.index_map.size_local
    assert np.isclose(again, exact, rtol=1e-14) and np.isclose(exact, 0.25, rtol=1e-12)


def test_an_unfinished_entry_still_waits_in_ffcx(tmp_path):
    """A .c lock without its .c.cached marker (a compile in another process): FFCx's own wait, here given up after
    its timeout of 1 s."""
    (tmp_path / "libffcx_forms_unfinished.c").write_text("")
    with pytest.raises(TimeoutError, match="JIT compilation timed out"):
        fj.get_cached_module("libffcx_forms_unfinished", ["form_x"], tmp_path, 1)
    assert getattr(fj.get_cached_module, "wrapped_by_fem_forms", False)
