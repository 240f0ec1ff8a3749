"""Will it break? The safety factor of a solved part against each material's [material.strength]: `tensile`
over the largest principal Cauchy stress (brittle), `yield` over the von Mises stress (ductile).

Stresses are each element's own, straight from the finite element solution, at the quadrature points of the
dx rule and at the element's corners (where surface peaks are: the corner values are what FEBio and CalculiX
extrapolate integration points to): not smoothed across the interfaces of materials of different strength,
each point judged by its own cell's material (with plastic or Prony history, which lives on the dx rule's points,
at those only). The safety factor is the smallest strength / stress over the part (1 / the largest utilization),
with the point (rest and deformed position), material and criterion where it is reached; the `utilization`
field is each cell's largest stress / strength (DG0, for ParaView). Same answer on any number of ranks."""
from __future__ import annotations

import basix
from dolfinx import fem
import numpy as np
import ufl

from fem_forms.output import measures
from fem_forms.physics.plastic import quadrature_rule

CRITERIA = ("max principal stress", "von Mises")
ROUND_OFF = 1e-8            # a largest principal stress below this share of the stress's size is no tension


def has_strength(scene) -> bool:
    """Does any material give a strength?"""
    return any(m.strength_tensile is not None or m.strength_yield is not None for m in scene.materials)


class StrengthCheck:
    """The compiled stress and position at the quadrature points of one model, and each cell's strengths."""

    def __init__(self, model, sigma):
        mesh = model.mesh
        self.mesh, self.regions = mesh, model.context.materials
        gauss, _ = quadrature_rule(mesh, model.scene.discretization.quadrature)
        corners = basix.geometry(basix.cell.string_to_type(mesh.topology.cell_name()))
        # a stress with quadrature-space history (plastic strain, Prony stresses) exists at the dx rule's points
        # only (FFCx refuses other points for it): there the corners are left out
        history = model.solid.quadrature_history
        points = gauss if history else np.vstack([gauss, corners])
        self.sigma = fem.Expression(sigma, points)
        X = ufl.SpatialCoordinate(mesh)
        self.rest = fem.Expression(X, points)
        self.current = fem.Expression(X + model.u, points)
        self.n_points = len(points)
        specs = model.scene.materials
        self.names = [m.name for m in specs]
        index = self.regions.index[:self.regions.n_owned]
        inverse = [[1.0 / v if v else 0.0 for v in (m.strength_tensile, m.strength_yield)] for m in specs]
        self.inverse = np.asarray(inverse)[index]               # (cells, 2): 1 / strength, 0 where none
        self.cells = np.arange(len(index), dtype=np.int32)

    def utilization(self) -> np.ndarray:
        """(cells, points, 2): stress / strength per criterion (0 where the material gives none; a compressive
        largest principal stress counts 0: it does not crack)."""
        s = self.sigma.eval(self.cells).reshape(len(self.cells), self.n_points, 3, 3)
        s = 0.5 * (s + np.swapaxes(s, -1, -2))
        principal = np.linalg.eigvalsh(s)[..., -1] if s.size else np.zeros(s.shape[:2])
        size = np.linalg.norm(s, axis=(-2, -1))
        tension = np.where(principal > ROUND_OFF * size, principal, 0.0)    # not a compression's round-off
        stress = np.stack([tension, measures.von_mises(s)], axis=-1)
        return stress * self.inverse[:, None, :]

    def report(self) -> dict:
        """{safety_factor, criterion, where, where_deformed, material, utilization_max}: the smallest safety
        factor over the part (None where nothing is stressed towards a strength)."""
        u = self.utilization()
        best = (0.0, -1)
        if u.size:
            flat = int(np.argmax(u))
            best = (float(u.ravel()[flat]), flat)
        values = self.mesh.comm.allgather(best[0])
        rank = int(np.argmax(values))
        found = None
        if self.mesh.comm.rank == rank and best[1] >= 0:
            cell, point, criterion = np.unravel_index(best[1], u.shape)
            rest = self.rest.eval(self.cells[cell:cell + 1]).reshape(self.n_points, 3)[point]
            now = self.current.eval(self.cells[cell:cell + 1]).reshape(self.n_points, 3)[point]
            found = (int(criterion), rest.tolist(), now.tolist(), self.names[self.regions.index[cell]])
        found = self.mesh.comm.bcast(found, root=rank)
        top = values[rank]
        if found is None or top <= 0:
            return {"safety_factor": None, "criterion": None, "where": None, "material": None,
                    "utilization_max": 0.0, "message": "nothing is stressed towards a given strength"}
        criterion, rest, now, material = found
        return {"safety_factor": 1.0 / top, "criterion": CRITERIA[criterion], "where": rest,
                "where_deformed": now, "material": material, "utilization_max": top}

    def field(self) -> fem.Function:
        """utilization: each cell's largest stress / strength over its points and criteria (DG0)."""
        f = self.regions.field([0.0] * len(self.names), "utilization")
        n = len(self.cells)
        f.x.array[:n] = self.utilization().max(axis=(1, 2)) if n else 0.0
        f.x.scatter_forward()
        return f


class StrengthWatch:
    """The lowest safety factor over a run's accepted steps (dynamics), with the time it is reached."""

    def __init__(self, model, sigma):
        self.check = StrengthCheck(model, sigma)
        self.lowest: dict | None = None

    def step(self, t: float) -> None:
        r = self.check.report()
        if self.lowest is None or (r["safety_factor"] is not None and (
                self.lowest["safety_factor"] is None or r["safety_factor"] < self.lowest["safety_factor"])):
            self.lowest = {**r, "time": t}


def summary_line(s: dict) -> str | None:
    """The CLI's one line on strength, or None without a strength."""
    st = s.get("strength")
    if not st:
        return None
    if st["safety_factor"] is None:
        return "  strength: " + st["message"]
    verdict = "holds" if st["safety_factor"] >= 1 else "FAILS"
    return (f"  strength: safety factor {st['safety_factor']:.3g} ({verdict}; {st['criterion']} in {st['material']} "
            f"at [{', '.join(f'{v:.4g}' for v in st['where'])}])")
