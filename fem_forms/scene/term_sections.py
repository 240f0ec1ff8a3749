"""Scene sections of the physics terms every analysis that models the body takes (static, modal, inverse,
dynamic, balance): read like the core sections, listed in the manual and the JSON Schema by themselves.
A new term's section is its declaration module (dolfinx-free, beside this one) and one entry here; its term
registers in physics/ (`register_terms("name")`)."""
from __future__ import annotations

from fem_forms.scene.spring_section import SPRING

TERM_SECTIONS: tuple = (SPRING,)
