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

The safe degrees per element (no basix needed: the scene checks them) are in fem_forms/elements.py."""
from __future__ import annotations

from functools import lru_cache

import basix
import numpy as np


POSITIVE_RULE = "Gauss-Jacobi"


def _cell(cell_name: str):
    return getattr(basix.CellType, cell_name)


@lru_cache(maxsize=None)
def rule_name(cell_name: str, q: int) -> str:
    """"default" if basix's default rule of degree q on the cell has positive weights, else Gauss-Jacobi."""
    _, weights = basix.make_quadrature(_cell(cell_name), max(q, 1))
    return "default" if np.all(weights > 0) else POSITIVE_RULE


# basix's rule of degree q on hexahedra, quadrilaterals and prisms is a (collapsed) tensor Gauss rule of
# (q + 2) // 2 points per direction: degrees 2k and 2k + 1 are one rule. Forms name it by its odd degree, so that
# one rule compiles once (580 of the suite's tests compiled 26 forms twice into the same code, at degrees 2|3, 4|5
# and 6|7, 25 on hexahedra, 1 on prisms).
TENSOR_CELLS = ("hexahedron", "quadrilateral", "prism")


def rule_degree(cell_name: str, q: int) -> int:
    """The degree the forms name the rule of degree q by: the highest degree that rule integrates exactly on
    tensor cells (TENSOR_CELLS), q itself on simplices (each degree its own rule)."""
    q = int(q)
    return 2 * ((max(q, 0) + 2) // 2) - 1 if cell_name in TENSOR_CELLS else q


def metadata(cell_name: str, q: int) -> dict:
    """The dx metadata of quadrature degree q: {"quadrature_degree": rule_degree(q)}, plus the positive
    Gauss-Jacobi rule where the default rule has a non-positive weight (the key is left out otherwise, so forms
    that compiled before keep their signature)."""
    q = rule_degree(cell_name, q)
    md = {"quadrature_degree": q}
    if rule_name(cell_name, q) != "default":
        md["quadrature_rule"] = POSITIVE_RULE
    return md


def points(cell_name: str, q: int) -> tuple[np.ndarray, np.ndarray]:
    """(points, weights) of the very rule `metadata(cell_name, q)` selects (fem.Expression, history)."""
    q = max(rule_degree(cell_name, q), 1)
    if rule_name(cell_name, q) == "default":
        return basix.make_quadrature(_cell(cell_name), q)
    return basix.make_quadrature(basix.QuadratureType.gauss_jacobi, _cell(cell_name), q)


def mass_degree(element_degree: int) -> int:
    """The exact rule of a mass matrix with constant density on affine cells: 2 x element degree."""
    return 2 * element_degree


def mass_metadata(cell_name: str, element_degree: int) -> dict:
    """dx metadata of a mass matrix: its own exact, positive rule, whatever rule the energy uses."""
    return metadata(cell_name, mass_degree(element_degree))
