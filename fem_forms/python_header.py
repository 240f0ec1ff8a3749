"""A precompiled Python.h for the C of FFCx's forms, when clang compiles them (fem_forms/logs.py, FAST_CC).

cffi wraps every form module in C that first includes Python.h: 12,000 lines parsed again for each of the
1,300 modules a cold test suite compiles. clang reads them from a precompiled header instead (`-include-pch`).
Measured: 34 modules of the suite's cache with distutils' own flags compiled in 8.8 s instead of 10.8 s, into the
same object files byte for byte; 30 new forms created and assembled from an empty cache, 5.8 s instead of 6.9 s
(medians of 3). The header is cffi's own prefix (its _cffi_include.h up to and including `#include <Python.h>`),
built once into the form cache folder under a name that hashes that prefix, the flags, clang's version and
Python.h's time stamp, and tried once a process by a quiet probe compile (clang refuses a header whose flags or
inputs changed; a form's own compile would print its complaint). A form whose compile still fails with it is
compiled again without it, and the header is deleted for the next run to build afresh."""
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


def prefix_source() -> str | None:
    """The C cffi writes before and up to its `#include <Python.h>` in every module, or None if not found."""
    import cffi
    text = (Path(cffi.__file__).parent / "_cffi_include.h").read_text()
    head, found, _ = text.partition("#include <Python.h>")
    return f"#define _CFFI_\n{head}{found}\n" if found else None


@functools.lru_cache(maxsize=None)
def _compiler_version(cc: str) -> str:
    return subprocess.run([cc, "--version"], capture_output=True, text=True, check=True).stdout


def compile_flags(extra_args) -> list[str]:
    """The flags distutils gives the compiler for a cffi module (Python's CFLAGS and CCSHARED, the include folders
    of FFCx and Python), then FFCx's extra arguments."""
    import ffcx.codegeneration
    flags = f"{sysconfig.get_config_var('CFLAGS')} {sysconfig.get_config_var('CCSHARED')}".split()
    includes = [f"-I{ffcx.codegeneration.get_include_path()}", f"-I{sysconfig.get_paths()['include']}"]
    return flags + includes + list(extra_args or [])


def precompiled(cc: str, cache_dir: Path, extra_args) -> Path | None:
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
        refuse(pch)
        return None
    _CHECKED.add(pch)
    return pch


def cflags(pch: Path) -> str:
    """CFLAGS that make clang read `pch` (distutils splits them as a shell would; the link step gets them too)."""
    return f'-include-pch "{pch}" -Wno-unused-command-line-argument'


def _probe(cc: str, flags: list[str], source: str, pch: Path) -> bool:
    """Whether clang takes the header for cffi's prefix with these flags (it checks the flags and every input's
    time stamp), quietly: a form's own compile would print clang's complaint on the terminal."""
    done = subprocess.run([cc, *flags, "-include-pch", str(pch), "-fsyntax-only", "-x", "c", "-"],
                          input=source + "int fem_forms_probe;\n", capture_output=True, text=True)
    return done.returncode == 0


def _build(cc: str, flags: list[str], source: str, header: Path, pch: Path) -> bool:
    """Write the prefix and precompile it, each through a file of this process renamed into place (two processes
    may build the same header at once)."""
    tmp = f".{os.getpid()}.tmp"
    try:
        cache = header.parent
        cache.mkdir(parents=True, exist_ok=True)
        if not header.exists():
            (cache / (header.name + tmp)).write_text(source)
            os.replace(cache / (header.name + tmp), header)
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
        with contextlib.suppress(OSError):
            (header.parent / (pch.name + tmp)).unlink()


def refuse(pch: Path) -> None:
    """The header failed: not offered again in this process, and deleted (the next run builds it afresh)."""
    _REFUSED.add(pch)
    with contextlib.suppress(OSError):
        pch.unlink()
