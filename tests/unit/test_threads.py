"""fem_forms runs BLAS and ipctk on one thread unless FEM_FORMS_THREADS says more (fem_forms/threads.py)."""
import os
import subprocess
import sys

PROBE = """
import numpy, ctypes                     # numpy (OpenBLAS) loaded before fem_forms: pinned all the same
import fem_forms, ipctk
import fem_forms.physics.contact.ipc_surfaces
path = next(l.split()[-1] for l in open('/proc/self/maps') if 'openblas' in l.split()[-1].rsplit('/', 1)[-1])
print(ctypes.CDLL(path).openblas_get_num_threads(), ipctk.get_num_threads())
"""


def probe(**env):
    clean = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "FEM_FORMS_THREADS")}
    return subprocess.run([sys.executable, "-c", PROBE], env={**clean, **env}, capture_output=True, text=True,
                          timeout=120)


def test_one_thread_each_by_default_even_when_numpy_came_first():
    proc = probe()
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["1", "1"]


def test_fem_forms_threads_gives_both_more():
    proc = probe(FEM_FORMS_THREADS="2")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["2", "2"]


def test_an_explicit_openblas_thread_count_wins_for_blas():
    proc = probe(OPENBLAS_NUM_THREADS="2")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["2", "1"]


def test_a_bad_thread_count_is_one_line_and_exit_1():
    proc = probe(FEM_FORMS_THREADS="two")
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == "fem-forms: FEM_FORMS_THREADS = 'two': must be a whole number of threads, at least 1"
