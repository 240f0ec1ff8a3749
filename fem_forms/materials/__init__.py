"""Materials: energy densities psi(F) (hyperelastic.py), the stresses derived from them (stresses.py), and
their parameters as fem.Constants (constants.py, not imported here: reading a scene needs no dolfinx)."""
from fem_forms.materials.hyperelastic import (Corotated, LinearElastic, Material, MODELS, MooneyRivlin,
                                              NeoHookean, StVenantKirchhoff, UserMaterial, as_material,
                                              lame_from_young_poisson, make_material)
from fem_forms.materials.stresses import cauchy_stress, first_piola_kirchhoff, mixed_energy, von_mises

__all__ = ["MODELS", "Corotated", "LinearElastic", "Material", "MooneyRivlin", "NeoHookean",
           "StVenantKirchhoff", "UserMaterial", "as_material", "lame_from_young_poisson", "make_material",
           "cauchy_stress", "first_piola_kirchhoff", "mixed_energy", "von_mises"]
