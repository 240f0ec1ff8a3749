"""FFCx's form cache and compiles: a finished entry is loaded by its file name, without the folder scan of ffcx 0.5
(fem_forms.logs.fast_cache_hits), an entry another process has not finished still goes through FFCx; clang reads
Python.h precompiled (fem_forms/python_header.py) into the same forms, and a damaged header is refused quietly."""
import importlib.machinery

import dolfinx.jit
import ffcx.codegeneration.jit as fj
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

from fem_forms import logs, python_header
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


def _energy_of_a_new_form(m, scale: float, volumetric_only: bool = False) -> float:
    """A form compiled into the current cache (the literal makes its code new to this test)."""
    V = fem.VectorFunctionSpace(m, ("Lagrange", 2))
    u = fem.Function(V)
    u.interpolate(lambda x: np.array([0.01 * x[1], 0.02 * x[2], 0.03 * x[0]]))
    F = ufl.Identity(3) + ufl.grad(u)
    J = ufl.det(F)
    shear = 0 if volumetric_only else ufl.tr(F.T * F) - 3 - 2 * ufl.ln(J)
    return fem.assemble_scalar(fem.form((shear + scale * (J - 1) ** 2) * ufl.dx))


@pytest.fixture
def clang_default(monkeypatch):
    """The compile environment the header is made for: clang (setup.sh installs it), no CC, CFLAGS or CPPFLAGS of
    the user's own."""
    for key in ("CC", "CFLAGS", "CPPFLAGS"):
        monkeypatch.delenv(key, raising=False)
    assert logs._fast_compiler_free(), "clang is not installed: setup.sh installs it"


def test_the_precompiled_python_header_gives_the_same_forms(cache, monkeypatch, clang_default):
    """A form compiled with the precompiled Python.h (the default with clang) and the same form compiled without
    it (the user's own CPPFLAGS turn it off) give the same number; the header was built once into the cache."""
    m = mesh.create_unit_cube(MPI.COMM_SELF, 2, 1, 1)
    settle_coordinate_element(m)
    with_header = _energy_of_a_new_form(m, 7.25)
    assert len(list(cache.glob("fem_forms_python_h_*.pch"))) == 1
    monkeypatch.setitem(dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS, "cache_dir", (cache.parent / "plain", "test"))
    monkeypatch.setenv("CPPFLAGS", "")
    without = _energy_of_a_new_form(m, 7.25)
    assert not list((cache.parent / "plain").glob("fem_forms_python_h_*"))
    assert with_header == without and np.isfinite(with_header)


def test_a_damaged_precompiled_header_is_refused_quietly_and_rebuilt_next_time(cache, capfd, clang_default):
    """A header that is not one (a truncated write, another clang's): clang refuses it in the probe, the form
    compiles without it and no complaint reaches the terminal; the file is deleted for the next run to rebuild."""
    m = mesh.create_unit_cube(MPI.COMM_SELF, 2, 1, 1)
    settle_coordinate_element(m)
    first = _energy_of_a_new_form(m, 3.5)
    pch, = cache.glob("fem_forms_python_h_*.pch")
    pch.write_bytes(b"not a header")
    python_header._CHECKED.discard(pch)                   # as in a new process
    capfd.readouterr()
    again = _energy_of_a_new_form(m, 4.5)
    assert np.isclose(again - first, _energy_of_a_new_form(m, 1.0, volumetric_only=True), rtol=1e-9)
    assert not pch.exists() and "error" not in capfd.readouterr().err


def test_a_relative_cache_folder_takes_the_header_too(monkeypatch, tmp_path, capfd, clang_default):
    """dolfinx passes a relative cache folder on as it is, and cffi compiles from inside it: the header is named
    by its absolute path, so the form compiles with it, quietly."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS, "cache_dir", ("relative_jit", "test"))
    m = mesh.create_unit_cube(MPI.COMM_SELF, 2, 1, 1)
    settle_coordinate_element(m)
    capfd.readouterr()
    value = _energy_of_a_new_form(m, 2.75)
    assert np.isfinite(value) and "error" not in capfd.readouterr().err
    pch, = (tmp_path / "relative_jit").glob("fem_forms_python_h_*.pch")
    assert pch.absolute() not in python_header._REFUSED
