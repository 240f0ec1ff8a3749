"""The one place that turns (cell, element degree, quadrature degree) into a quadrature rule: the dx
metadata every form uses, the points at which fem.Expression evaluates, the rule of mass matrices and the
smallest degree that integrates an element's stiffness to full rank.

Why: basix 0.5.1's default rules on tetrahedra at degrees 3, 7 and 8 have a non-positive weight (degree
3: -0.133 at the centroid), which makes a mass matrix indefinite (CG fails in the stress recovery) and
counts a history variable negatively. Gauss-Jacobi (collapsed Gauss) rules have positive weights at every
degree and FFCx 0.5 takes them with metadata "quadrature_rule": "Gauss-Jacobi"; they are used exactly
where the default is not positive, so scenes on the default degrees keep their rule (and their answers
and compiled forms). On hexahedra and prisms basix's rule is a tensor Gauss rule, positive at every degree:
degree q has (q + 2) // 2 points per direction.

Safe degrees (the smallest degree whose rule makes the linear-elastic stiffness of a free 2x1x1 patch
have exactly the 6 rigid-body null modes; checked at every degree 1..8 in tests/unit/test_quadrature.py):
P1 tetrahedra 1, P2 tetrahedra 2 (also Taylor-Hood P2-P1), Q1 hexahedra 2, Q2 hexahedra 4 (2x2x2 Gauss
leaves 35 hourglass modes), P1 prisms 2. Below them the tangent and the mass are singular."""
from __future__ import annotations

from functools import lru_cache

import basix
import numpy as np

MAX_DEGREE = 8                       # the scene key's range is 1..MAX_DEGREE
POSITIVE_RULE = "Gauss-Jacobi"

# (cell, element degree) -> smallest quadrature degree with a full-rank stiffness (rigid modes aside)
SAFE_DEGREES: dict[tuple[str, int], int] = {
    ("tetrahedron", 1): 1, ("tetrahedron", 2): 2,
    ("hexahedron", 1): 2, ("hexahedron", 2): 4,
    ("prism", 1): 2, ("prism", 2): 4,
}


def _cell(cell_name: str):
    return getattr(basix.CellType, cell_name)


@lru_cache(maxsize=None)
def rule_name(cell_name: str, q: int) -> str:
    """"default" if basix's default rule of degree q on the cell has positive weights, else Gauss-Jacobi."""
    _, weights = basix.make_quadrature(_cell(cell_name), max(q, 1))
    return "default" if np.all(weights > 0) else POSITIVE_RULE


def metadata(cell_name: str, q: int) -> dict:
    """The dx metadata of quadrature degree q: {"quadrature_degree": q}, plus the positive Gauss-Jacobi
    rule where the default rule has a non-positive weight (the key is left out otherwise, so forms that
    compiled before keep their signature)."""
    md = {"quadrature_degree": int(q)}
    if rule_name(cell_name, q) != "default":
        md["quadrature_rule"] = POSITIVE_RULE
    return md


def points(cell_name: str, q: int) -> tuple[np.ndarray, np.ndarray]:
    """(points, weights) of the very rule `metadata(cell_name, q)` selects (fem.Expression, history)."""
    q = max(q, 1)
    if rule_name(cell_name, q) == "default":
        return basix.make_quadrature(_cell(cell_name), q)
    return basix.make_quadrature(basix.QuadratureType.gauss_jacobi, _cell(cell_name), q)


def mass_degree(element_degree: int) -> int:
    """The exact rule of a mass matrix with constant density on affine cells: 2 x element degree."""
    return 2 * element_degree


def mass_metadata(cell_name: str, element_degree: int) -> dict:
    """dx metadata of a mass matrix: its own exact, positive rule, whatever rule the energy uses."""
    return metadata(cell_name, mass_degree(element_degree))


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
