"""FFCx's just-in-time compilation as a run needs it: quiet (without touching anybody else's logging), patient
with a form another process is compiling, fast (clang where installed), and leaving no lock behind when a compile
is interrupted.

What prints the compile log in this stack (measured with an empty XDG_CACHE_HOME, dolfinx 0.5.2, ffcx 0.5.0,
setuptools 66): ffcx builds each new form with cffi, cffi runs setuptools' bundled distutils, and distutils
logs "running build_ext", "building 'libffcx_forms_...' extension" and the compiler command lines at INFO on the
*root* logger (it even lowers the root level to INFO for the build); ffcx's ``logging.basicConfig()`` at
import gave the root logger a stderr handler, so every line reaches the terminal. The "ffcx" and "UFL"
loggers print nothing below WARNING here. So the one thing to silence is distutils' records below WARNING
on the root logger: a filter on the root logger drops exactly those, and the user's own log records
(any level, any logger) pass untouched. ``import fem_forms`` installs it.
"""
from __future__ import annotations

import contextlib
import logging
import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Callable

_DISTUTILS_DIRS = (f"{os.sep}distutils{os.sep}", f"{os.sep}_distutils{os.sep}")


class _CompileLogFilter(logging.Filter):
    """Drop distutils' build chatter (below WARNING) logged on the root logger by FFCx's cffi builds."""

    def filter(self, record: logging.LogRecord) -> bool:
        return record.levelno >= logging.WARNING or not any(d in record.pathname for d in _DISTUTILS_DIRS)


_FILTER = _CompileLogFilter()


def quiet_jit(verbose: bool = False) -> None:
    """Hide the FFCx/cffi compile log (the default since ``import fem_forms``); verbose=True shows it."""
    root = logging.getLogger()
    if verbose:
        root.removeFilter(_FILTER)
    else:
        root.addFilter(_FILTER)          # a no-op if already there


# How long FFCx waits for a form another process is compiling into the same cache before it gives up with
# TimeoutError. dolfinx's default, 10 s, is shorter than the largest forms took to compile here with gcc (25-35 s
# cold for a Q2 hexahedron at quadrature degree 8 on 2 shared cores): two runs sharing a cold cache (two scenes
# started together, the test suite on two workers) would fail on the first such form.
JIT_WAIT_S = 900


# gcc/clang flags of the forms' C: dolfinx's -O2 -g0, and -fno-math-errno, which lets the compiler inline sqrt
# and keep exp/log/pow calls out of errno's way (nothing reads errno; NaN and inf come out as before). Measured on
# P2 tangents and residuals of the rubber-cost beam: Ogden 0.45 -> 0.39 s and 0.038 -> 0.020 s, Yeoh 0.124 ->
# 0.099 s and 0.010 -> 0.006 s, neo-Hookean 0.108 -> 0.103 s.
COMPILE_FLAGS = ["-O2", "-g0", "-fno-math-errno"]


def patient_jit(seconds: int = JIT_WAIT_S) -> None:
    """Wait up to `seconds` for a form another process is compiling, compile with COMPILE_FLAGS, and take no JIT
    settings from the current folder (``import fem_forms`` calls it)."""
    import dolfinx.jit
    defaults = dolfinx.jit.DOLFINX_DEFAULT_JIT_PARAMETERS
    defaults["timeout"] = (int(seconds), defaults["timeout"][1])
    defaults["cffi_extra_compile_args"] = (list(COMPILE_FLAGS), defaults["cffi_extra_compile_args"][1])
    ignore_folder_jit_files()


def ignore_folder_jit_files() -> None:
    """dolfinx and FFCx read dolfinx_jit_parameters.json and ffcx_parameters.json from the current folder (once,
    cached): a folder shared with a scene could hold one that moves the form cache out of the output folder or
    passes the C compiler a plugin to load. Both caches are filled here from an empty folder, so only the user's
    own ~/.config files (and the defaults) count."""
    import dolfinx.jit
    import ffcx.parameters
    import tempfile
    try:
        here = os.getcwd()
    except FileNotFoundError:                    # the folder was deleted: nothing to read from it either
        here = None
    with tempfile.TemporaryDirectory() as empty:
        os.chdir(empty)
        try:
            dolfinx.jit._load_parameters.cache_clear()          # read before fem_forms was imported: read again
            ffcx.parameters._load_parameters.cache_clear()
            dolfinx.jit._load_parameters()
            ffcx.parameters._load_parameters()
        finally:
            if here is not None:
                os.chdir(here)


# The C compiler of FFCx's forms. cffi builds each new form through distutils, which takes the compiler from CC
# (gcc by default). A large form's kernel is one huge function, on which gcc -O2 spends its time in register
# allocation: clang -O2 compiled the test suite's 15 largest modules in 14.4 s against gcc's 66.6 s (a spread of
# 26 others: 5.6 s against 6.5 s), into kernels that assemble as fast (P2 neo-Hookean and Mooney-Rivlin tangents,
# 61k dofs: 0.32 and 0.78 s with either) and give the same matrix norms to 13 digits. setup.sh installs clang; a
# CC the user set wins, and without clang nothing changes.
FAST_CC = "clang"


def _fast_compiler_free() -> bool:
    """Whether the compile may use FAST_CC: it is installed and the user set no CC."""
    return "CC" not in os.environ and shutil.which(FAST_CC) is not None


@contextlib.contextmanager
def _c_compiler():
    """CC = FAST_CC for one compile, where _fast_compiler_free."""
    if not _fast_compiler_free():
        yield
        return
    os.environ["CC"] = FAST_CC
    try:
        yield
    finally:
        os.environ.pop("CC", None)


def _compile(compile_with: Callable[[list], object], cache_dir: Path, extra_args: list | None) -> object:
    """compile_with(FFCx's extra compiler arguments) under FAST_CC, the arguments naming the precompiled Python.h
    (python_header.py) where it serves (the compile step only: the module's name was hashed before); where the
    C compile fails with it and succeeds without, it is not offered again in this process."""
    import cffi
    from fem_forms import python_header
    extra = list(extra_args or [])
    header = None
    if _fast_compiler_free() and not any(k in os.environ for k in ("CFLAGS", "CPPFLAGS")):   # not the user's
        try:
            header = python_header.precompiled(FAST_CC, cache_dir.absolute(), extra)
        except (OSError, subprocess.SubprocessError, UnicodeError):
            header = None
    with _c_compiler():
        if header is None:
            return compile_with(extra)
        try:
            return compile_with(extra + ["-include-pch", str(header)])
        except cffi.VerificationError:                  # cffi's CompileError or LinkError
            result = compile_with(extra)
            python_header.refuse(header)
            return result


def wrap_form_compiles() -> None:
    """FFCx's compile of a new form as a run needs it (``import fem_forms`` installs it): with clang where installed
    (FAST_CC), and a compile stopped by Ctrl-C or SIGTERM gives up its cache entry as a failed compile does. FFCx
    takes the entry (the module's .c file, created first as a lock) and marks it failed (renamed .c.failed) only on
    an Exception; KeyboardInterrupt and the CLI's Terminated are not Exceptions, so the lock stayed and the next
    run needing that form waited the whole JIT timeout (900 s), then failed with TimeoutError (seen after killed
    runs). SIGKILL still leaves the lock: no code runs."""
    import ffcx.codegeneration.jit as fj
    if getattr(fj._compile_objects, "wrapped_by_fem_forms", False):
        return
    original = fj._compile_objects

    def compile_objects(decl, ufl_objects, object_names, module_name, parameters, cache_dir, *args, **kwargs):
        extra = args[0] if args else kwargs.pop("cffi_extra_compile_args", None)
        rest = args[1:]

        def compile_with(extra_args: list):
            return original(decl, ufl_objects, object_names, module_name, parameters, cache_dir, extra_args,
                            *rest, **kwargs)
        try:
            return _compile(compile_with, Path(cache_dir), extra)
        except Exception:
            raise                                    # FFCx's own handler marks the entry failed
        except BaseException:
            lock = Path(cache_dir) / f"{module_name}.c"
            if not lock.with_suffix(".c.cached").exists():      # finished already: the entry is good
                with contextlib.suppress(OSError):
                    os.replace(lock, lock.with_suffix(".c.failed"))
            raise

    compile_objects.wrapped_by_fem_forms = True
    fj._compile_objects = compile_objects


# A form or element FFCx compiled before is loaded from its cache entry: ffcx 0.5's get_cached_module finds the
# module's file with a fresh importlib FileFinder, which lists the whole cache folder every time (about 3 ms with
# the suite's 6,000 entries, more in a cache that kept every version's forms): most of the time of creating a
# FunctionSpace or a form already compiled (measured: a TensorFunctionSpace 4.2 ms, 0.95 ms without the scan; a
# cached form 3.3 ms, 0.13 ms). The finished entry (its .c.cached marker is written after the module) is opened
# here by its file name instead; a missing or unfinished entry goes through FFCx as before.
def fast_cache_hits() -> None:
    """Load finished cache entries by their file name (``import fem_forms`` installs it)."""
    import importlib.machinery
    import importlib.util
    import ffcx.codegeneration.jit as fj
    if getattr(fj.get_cached_module, "wrapped_by_fem_forms", False):
        return
    original = fj.get_cached_module

    def get_cached_module(module_name, object_names, cache_dir, timeout):
        folder = Path(cache_dir)
        if folder.joinpath(f"{module_name}.c.cached").exists():
            for suffix in importlib.machinery.EXTENSION_SUFFIXES:
                path = folder / f"{module_name}{suffix}"
                if path.exists():
                    spec = importlib.util.spec_from_file_location(module_name, path)
                    module = importlib.util.module_from_spec(spec)
                    spec.loader.exec_module(module)
                    return [getattr(module.lib, name) for name in object_names], module
        return original(module_name, object_names, cache_dir, timeout)

    get_cached_module.wrapped_by_fem_forms = True
    fj.get_cached_module = get_cached_module


def stale_compile_lock(error: BaseException) -> str | None:
    """The form-cache file to delete when `error` is FFCx giving up on a form whose compile never finished (a run
    killed while compiling left its lock), else None. Serial runs see FFCx's TimeoutError; under MPI dolfinx
    raises it again as a RuntimeError on every rank, naming the file on rank 0 only ("the form's .c file")."""
    text = str(error)
    if "JIT compilation timed out" not in text and "Compilation failed on root node" not in text:
        return None
    named = re.search(r"remove ([^\s)]+\.c)", text)
    return named.group(1) if named else "the form's .c file"
