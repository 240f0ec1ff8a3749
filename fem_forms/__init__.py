"""fem_forms: hyperelastic solids on FEniCSx, from UFL energies to PETSc solves.

Python API::

    import fem_forms as ff
    scene = ff.Scene.from_file("demos/scenes/sagging_beam.toml")
    result = ff.solve_static(scene)            # or solve_static(scene, material=my_psi)
    print(result.summary()["max_displacement"])

The API prints nothing while it works: no FFCx compile log (``quiet_jit(verbose=True)`` shows it) and no
progress (``show_progress()`` shows load steps, Newton iterations and residuals on stderr).
"""
from fem_forms import petsc_start, threads

threads.pin_blas_environment()          # before numpy loads OpenBLAS (fem_forms/threads.py says why)
petsc_start.skip_petscrc()              # before PETSc starts: a shared folder's .petscrc is not read

from fem_forms.analyses.modal import write_modal_outputs
from fem_forms.analyses.static import write_static_outputs
from fem_forms.analyses.static.solve import StaticResult, solve_static
from fem_forms.errors import InputError, SolveError
from fem_forms.logs import fast_cache_hits, patient_jit, quiet_jit, wrap_form_compiles
from fem_forms.materials import (Corotated, LinearElastic, MooneyRivlin, NeoHookean, StVenantKirchhoff,
                                 UserMaterial)
from fem_forms.materials.hyperelastic import make_material
from fem_forms.materials.stresses import cauchy_stress, first_piola_kirchhoff, von_mises
from fem_forms.analyses.modal import ModalResult, solve_modal
from fem_forms.output.progress_line import show_progress
from fem_forms.scene import Scene

__all__ = ["quiet_jit", "show_progress", "InputError", "SolveError", "Scene", "LinearElastic", "StVenantKirchhoff", "NeoHookean",
           "MooneyRivlin", "Corotated", "UserMaterial", "make_material", "first_piola_kirchhoff", "cauchy_stress",
           "von_mises", "StaticResult", "solve_static", "write_static_outputs", "ModalResult",
           "solve_modal", "write_modal_outputs"]
__version__ = "0.1.0"

threads.pin_loaded_blas()
quiet_jit()
patient_jit()
wrap_form_compiles()
fast_cache_hits()
