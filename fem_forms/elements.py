"""Which quadrature degrees an element can take: the safe (full-rank) degree of each element and the scene's
refusal of a rule that under-integrates. Pure data, no basix: reading a scene needs no dolfinx.

Safe degrees (the smallest degree whose rule makes the linear-elastic stiffness of a free 2x1x1 patch
have exactly the 6 rigid-body null modes; checked at every degree 1..8 in tests/unit/test_quadrature.py):
P1 tetrahedra 1, P2 tetrahedra 2 (also Taylor-Hood P2-P1), Q1 hexahedra 2, Q2 hexahedra 4 (2x2x2 Gauss
leaves 35 hourglass modes), P1 prisms 2. Below them the tangent and the mass are singular."""
from __future__ import annotations

MAX_DEGREE = 8                       # the scene key's range is 1..MAX_DEGREE

# (cell, element degree) -> smallest quadrature degree with a full-rank stiffness (rigid modes aside)
SAFE_DEGREES: dict[tuple[str, int], int] = {
    ("tetrahedron", 1): 1, ("tetrahedron", 2): 2,
    ("hexahedron", 1): 2, ("hexahedron", 2): 4,
    ("prism", 1): 2, ("prism", 2): 4,
}


def safe_degree(cell_name: str, element_degree: int) -> int:
    """Smallest quadrature degree that integrates the element's stiffness (and mass) to full rank."""
    return SAFE_DEGREES.get((cell_name, element_degree), 2 * element_degree)


def element_name(cell_name: str, element_degree: int, formulation: str = "displacement") -> str:
    """How messages name the element: P1/P2 on simplices, Q1/Q2 on hexahedra, Taylor-Hood when mixed."""
    letter = "Q" if cell_name == "hexahedron" else "P"
    name = f"{letter}{element_degree}"
    if formulation == "mixed":
        name += f"-{letter}{element_degree - 1} (Taylor-Hood)"
    return f"{name} {cell_name}"


def check_degree(cell_name: str, element_degree: int, q: int | None, formulation: str = "displacement") -> str | None:
    """Why quadrature degree q cannot work for the element (one line naming the key and the smallest safe
    degree), or None. q None is the default 2 x degree, always safe."""
    if q is None:
        return None
    if q > MAX_DEGREE:
        return (f"discretization.quadrature_degree = {q}: above the largest supported degree {MAX_DEGREE} "
                f"(use {safe_degree(cell_name, element_degree)}..{MAX_DEGREE})")
    safe = safe_degree(cell_name, element_degree)
    if q < safe:
        return (f"discretization.quadrature_degree = {q}: under-integrates the "
                f"{element_name(cell_name, element_degree, formulation)} element (singular stiffness and "
                f"mass: hourglass modes); use {safe} or more (default {2 * element_degree})")
    return None
