"""Materials: energy densities psi(F) (hyperelastic.py) and the stresses derived from them (stresses.py)."""
from fem_forms.materials.hyperelastic import (LinearElastic, Material, MODELS, MooneyRivlin, NeoHookean,
                                              StVenantKirchhoff, UserMaterial, as_material, bind_constants,
                                              lame_from_young_poisson, make_material, parameter_value,
                                              set_parameters)
from fem_forms.materials.stresses import cauchy_stress, first_piola_kirchhoff, mixed_energy, von_mises

__all__ = ["MODELS", "LinearElastic", "Material", "MooneyRivlin", "NeoHookean", "StVenantKirchhoff",
           "UserMaterial", "as_material", "bind_constants", "lame_from_young_poisson", "make_material",
           "parameter_value", "set_parameters", "cauchy_stress", "first_piola_kirchhoff", "mixed_energy",
           "von_mises"]
