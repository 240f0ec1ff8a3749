"""Contact ([contact]): the scene section's terms. Incremental Potential Contact against rigid obstacles
(term.py: the barrier energy as an array term; obstacles.py: their signed distances; barrier.py: b(d))."""
from __future__ import annotations

from fem_forms.errors import InputError
from fem_forms.physics.contact.term import ContactTerm
from fem_forms.physics.terms import Term, register_terms
from fem_forms.physics.thermoelastic import young_modulus


@register_terms("contact")
def contact_terms(scene, mesh) -> list[Term]:
    """The contact term of a scene with [contact] (none without)."""
    if getattr(scene, "contact", None) is None:
        return []
    if scene.solver.control == "arc-length" or any(ld.type == "inflation" and ld.volume is not None
                                                   for ld in scene.load):
        raise InputError("contact: not with solver.control = 'arc-length' or a volume-controlled cavity yet (their "
                         "bordered Newton solve has no step filter); use load control and a cavity pressure")
    try:
        modulus = max(young_modulus(m.material) for m in scene.materials)
    except InputError:
        raise InputError("contact: needs a built-in material model (its modulus scales the barrier)") from None
    return [ContactTerm(scene.contact, modulus, scene.limits.obstacle_triangles)]
