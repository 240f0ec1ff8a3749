"""A precompiled Python.h for the C of FFCx's forms, when clang compiles them (fem_forms/logs.py, FAST_CC).

cffi wraps every form module in C that first includes Python.h: 12,000 lines parsed again for each of the
1,300 modules a cold test suite compiles. clang reads them from a precompiled header instead (`-include-pch`).
Measured: 34 modules of the suite's cache with distutils' own flags compiled in 8.8 s instead of 10.8 s, into the
same object files byte for byte; 30 new forms created and assembled from an empty cache, 5.8 s instead of 6.9 s
(medians of 3). The header is cffi's own prefix (its _cffi_include.h up to and including `#include <Python.h>`),
built once into the form cache folder under a name that hashes that prefix, the flags, clang's version and
Python.h's time stamp, and tried once a process by a quiet probe compile (clang refuses a header whose flags or
inputs changed, and a form's own compile would print its complaint): a refused header is deleted for the next
run to build afresh. It is named in FFCx's extra compiler arguments, which reach the compile step only (not the
link) after the module's name was hashed. A form whose C compile still fails with it and not without it is
compiled without it, and the header is not offered again in that process."""
from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import subprocess
import sysconfig
from pathlib import Path

_REFUSED: set = set()          # headers that failed, in this process: not offered again
_CHECKED: set = set()          # headers a probe compile read without complaint, in this process


@functools.lru_cache(maxsize=None)
def prefix_source() -> str | None:
    """The C cffi writes before and up to its `#include <Python.h>` in every module, or None if not found (read
    once a process)."""
    import cffi
    text = (Path(cffi.__file__).parent / "_cffi_include.h").read_text()
    head, found, _ = text.partition("#include <Python.h>")
    return f"#define _CFFI_\n{head}{found}\n" if found else None


@functools.lru_cache(maxsize=None)
def _compiler_version(cc: str) -> str:
    """`cc --version` (once a process): a header of another clang is not read."""
    return subprocess.run([cc, "--version"], capture_output=True, text=True, check=True).stdout


def compile_flags(extra_args: list) -> list[str]:
    """The flags distutils gives the compiler for a cffi module (Python's CFLAGS and CCSHARED, the include folders
    of FFCx and Python), then FFCx's extra arguments."""
    import ffcx.codegeneration
    flags = f"{sysconfig.get_config_var('CFLAGS')} {sysconfig.get_config_var('CCSHARED')}".split()
    includes = [f"-I{ffcx.codegeneration.get_include_path()}", f"-I{sysconfig.get_paths()['include']}"]
    return flags + includes + list(extra_args or [])


def precompiled(cc: str, cache_dir: Path, extra_args: list) -> Path | None:
    """The precompiled header for compiles by `cc` with these FFCx arguments (built into cache_dir first if
    missing, and checked once a process), or None where there is none to offer."""
    source = prefix_source()
    if source is None:
        return None
    flags = compile_flags(extra_args)
    python_h = Path(sysconfig.get_paths()["include"]) / "Python.h"
    stamp = "\0".join([source, *flags, _compiler_version(cc), str(python_h.stat().st_mtime_ns)])
    header = cache_dir / f"fem_forms_python_h_{hashlib.sha1(stamp.encode()).hexdigest()[:20]}.h"
    pch = header.with_suffix(".pch")
    if pch in _REFUSED:
        return None
    if not pch.exists() and not _build(cc, flags, source, header, pch):
        return None
    if pch not in _CHECKED and not _probe(cc, flags, source, pch):
        refuse(pch, delete=True)
        return None
    _CHECKED.add(pch)
    return pch


def _probe(cc: str, flags: list[str], source: str, pch: Path) -> bool:
    """Whether clang takes the header for cffi's prefix with these flags (it checks the flags and every input's
    time stamp), quietly: a form's own compile would print clang's complaint on the terminal."""
    done = subprocess.run([cc, *flags, "-include-pch", str(pch), "-fsyntax-only", "-x", "c", "-"],
                          input=source + "int fem_forms_probe;\n", capture_output=True, text=True)
    return done.returncode == 0


def _build(cc: str, flags: list[str], source: str, header: Path, pch: Path) -> bool:
    """Write the prefix (never replaced once there: clang checks its time stamp) and precompile it through a file
    of this process renamed into place (two processes may build the same header at once)."""
    tmp = f".{os.getpid()}.tmp"
    cache = header.parent
    try:
        cache.mkdir(parents=True, exist_ok=True)
        if not header.exists():
            (cache / (header.name + tmp)).write_text(source)
            with contextlib.suppress(FileExistsError):
                os.link(cache / (header.name + tmp), header)
        done = subprocess.run([cc, *flags, "-x", "c-header", str(header), "-o", str(cache / (pch.name + tmp))],
                              capture_output=True)
        if done.returncode != 0:
            _REFUSED.add(pch)
            return False
        os.replace(cache / (pch.name + tmp), pch)
        return True
    except OSError:
        _REFUSED.add(pch)
        return False
    finally:
        for name in (header.name, pch.name):
            with contextlib.suppress(OSError):
                (cache / (name + tmp)).unlink()


def refuse(pch: Path, delete: bool = False) -> None:
    """The header failed: not offered again in this process; with `delete` (clang refused it in the probe) also
    deleted, for the next run to build afresh (a header another process uses is left to it otherwise)."""
    _REFUSED.add(pch)
    if delete:
        with contextlib.suppress(OSError):
            pch.unlink()
