"""FFCx's forms compile with clang (fem_forms/logs.py: 4.6x faster than gcc on the large ones; setup.sh installs
it), a C compiler the user names in CC wins, and the environment is left as it was: each compile below goes
into a fresh cache folder, and the compiler that built the module is read from its .comment section."""
import os
import shutil

from dolfinx import fem, mesh
from mpi4py import MPI
import ufl

import fem_forms  # noqa: F401  (installs the compile wrapper)
from fem_forms.logs import FAST_CC


def built_by_clang(cache) -> bool:
    (module,) = cache.glob("libffcx_forms_*.so")
    return b"clang version" in module.read_bytes()


def compile_fresh(cache) -> None:
    m = mesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1)
    u = fem.Function(fem.FunctionSpace(m, ("Lagrange", 1)))
    fem.form(u * u * ufl.dx, jit_params={"cache_dir": str(cache)})


def test_forms_compile_with_clang_and_leave_cc_unset(tmp_path, monkeypatch):
    assert shutil.which(FAST_CC), "clang is missing: ./setup.sh installs it"
    monkeypatch.delenv("CC", raising=False)
    compile_fresh(tmp_path)
    assert built_by_clang(tmp_path) and "CC" not in os.environ


def test_a_compiler_the_user_names_wins(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "gcc")
    compile_fresh(tmp_path)
    assert not built_by_clang(tmp_path) and os.environ["CC"] == "gcc"
