"""Surface-against-surface contact by the IPC Toolkit (ipctk): the part's triangles against each other
(self-contact, neighbours excluded) or against rigid obstacles given as triangle files (their vertices fixed
within a step). Vertex-face and edge-edge pairs closer than dhat, the area-weighted barrier with gradient and
PSD-projected Hessian, lagged smoothed Coulomb friction, continuous collision detection for the step filter and
an exact intersection test. The toolkit measures squared distances; its stiffness is calibrated so that two
parallel patches a gap dhat / 2 apart push with the pressure an analytic obstacle's barrier has (term.py)."""
from __future__ import annotations

import ipctk
import numpy as np
import scipy.sparse as sp

from fem_forms import threads
from fem_forms.meshes.boundary_surface import BoundarySurface
from fem_forms.physics.contact.mesh_obstacle import FileObstacle, inside

SHORTEN = 0.8          # a step that would make surfaces touch is cut to this share of its time of impact
REACH = 2.0            # no step moves a surface node farther than this many mean surface edges
# Tight Inclusion CCD stopped after this many iterations returns a conservative time of impact: its default (1e7)
# took 247 s on two parallel patches passing through each other, 1e4 took 0.2 s for the same impact (0.477 vs 0.480)
threads.pin_ipctk(ipctk)              # one TBB thread: its sums in a fixed order (fem_forms/threads.py)
CCD = ipctk.TightInclusionCCD(1e-6, 10_000)


def _plates(h: float, gap: float, n: int = 6):
    """Two parallel square patches of n x n cells of size h, `gap` apart (the calibration's probe)."""
    xs = np.arange(n + 1) * h
    P = np.array([[x, y, 0.0] for y in xs for x in xs])
    k = lambda i, j: j * (n + 1) + i                       # noqa: E731
    F = np.array([t for j in range(n) for i in range(n)
                  for t in ([k(i, j), k(i + 1, j), k(i + 1, j + 1)], [k(i, j), k(i + 1, j + 1), k(i, j + 1)])])
    V = np.vstack([P, P + [0.0, 0.0, gap]])
    F = np.vstack([F, F[:, ::-1] + len(P)])
    return V, F, len(P), (n * h) ** 2


class IpcSurfaces:
    """The barrier between the part's surface and itself (`self_pairs`) and/or the `obstacles`' triangles, with
    `stiffness` (set by `calibrate`). Positions p are the part's surface nodes (n, 3); the obstacles' vertices
    follow at their current offsets (FileObstacle.move_to) and carry no unknowns."""

    def __init__(self, surface: BoundarySurface, dhat: float, obstacles: list[FileObstacle] = (),
                 self_pairs: bool = True):
        self.surface, self.dhat, self.obstacles, self.n = surface, dhat, list(obstacles), surface.size
        sizes = [len(ob.points) for ob in self.obstacles]
        starts = np.cumsum([self.n] + sizes)
        self.owner = np.repeat(np.arange(-1, len(sizes)), [self.n] + sizes)     # -1: the part
        faces = np.vstack([surface.faces] + [ob.triangles + s for ob, s in zip(self.obstacles, starts)])
        self.faces = np.asfortranarray(faces, np.int32)
        self.edge_list = np.asfortranarray(ipctk.edges(self.faces), np.int32)
        self.mesh = ipctk.CollisionMesh(np.asfortranarray(self.vertices(surface.rest)), self.edge_list, self.faces)
        self.mesh.can_collide = ipctk.make_static_obstacle_filter(self.n) if self_pairs else \
            ipctk.make_vertex_patches_filter((self.owner >= 0).astype(np.int32))
        self.potential = ipctk.BarrierPotential(dhat, 1.0)
        self.stiffness = 1.0
        self.friction: ipctk.TangentialCollisions | None = None
        self._cache = (None, None)
        e = surface.edges()
        self.edge = float(np.mean(np.linalg.norm(surface.rest[e[:, 0]] - surface.rest[e[:, 1]], axis=1)))

    def vertices(self, p: np.ndarray, t: float | None = None) -> np.ndarray:
        """The collision mesh's vertices: the part's at p, the obstacles' at their offsets (or at time t)."""
        obs = [ob.points_at(t) if t is not None else ob.current_points() for ob in self.obstacles]
        return np.asfortranarray(np.vstack([p] + obs))

    def calibrate(self, h: float, pressure: float) -> None:
        """Stiffness such that patches of cells h, dhat / 2 apart, push each other with `pressure` (Pa)."""
        V, F, n, area = _plates(h, self.dhat / 2)
        mesh = ipctk.CollisionMesh(V, ipctk.edges(F).astype(np.int32), F.astype(np.int32))
        c = self._build(mesh, V)
        push = self.potential.gradient(c, mesh, V).reshape(-1, 3)[:n, 2].sum()    # dE/dz of the lower patch > 0
        self.stiffness = pressure * area / push

    def _build(self, mesh, V: np.ndarray, dhat: float | None = None) -> ipctk.NormalCollisions:
        c = ipctk.NormalCollisions()
        c.use_area_weighting = True
        c.build(mesh, np.asfortranarray(V), dhat or self.dhat)
        return c

    def collisions(self, V: np.ndarray) -> ipctk.NormalCollisions:
        """The pairs closer than dhat at vertices V (kept for the last V: energy, gradient and Hessian share)."""
        last, c = self._cache
        if last is None or last.shape != V.shape or not np.array_equal(last, V):
            c = self._build(self.mesh, V)
            self._cache = (V.copy(), c)
        return c

    # --- lagged friction -------------------------------------------------------------------------------------
    def lag_friction(self, p: np.ndarray, t0: float, t1: float, eps: float, mu_self: float) -> None:
        """Friction of the step from t0 to t1: normal forces and tangent planes of the pairs at the step's start
        (part at p, obstacles at t0), each pair's coefficient its obstacle's (mu_self between the part's own
        pieces), the obstacles moving to t1; slips below eps (m) are mollified (f0 of IPC)."""
        mus = np.array([mu_self] + [ob.friction for ob in self.obstacles])
        self.friction = None
        if not mus.any():
            return
        V0 = self.vertices(p, t0)
        normal = self._build(self.mesh, V0)
        fr = ipctk.TangentialCollisions()
        fr.build(self.mesh, V0, normal, ipctk.BarrierPotential(self.dhat, self.stiffness), 1.0)
        for k in range(len(fr)):
            pair = fr[k]
            owners = self.owner[[i for i in pair.vertex_ids(self.edge_list, self.faces) if i >= 0]]
            pair.mu_s = pair.mu_k = float(mus[1 + owners.max()])
        fr.reset_lagged_anisotropic_friction_coefficients()     # the potential reads these effective copies
        self.friction, self._lag, self._end = fr, V0, self.vertices(p, t1)[self.n:]
        self._slip = ipctk.FrictionPotential(eps)

    def _slips(self, p: np.ndarray) -> np.ndarray:
        return np.asfortranarray(np.vstack([p, self._end]) - self._lag)

    # --- energy, gradient, Hessian on the part's nodes ------------------------------------------------------
    def barrier_energy(self, p: np.ndarray) -> float:
        V = self.vertices(p)
        return float(self.stiffness * self.potential(self.collisions(V), self.mesh, V))

    def friction_energy(self, p: np.ndarray) -> float:
        return float(self._slip(self.friction, self.mesh, self._slips(p))) if self.friction is not None else 0.0

    def full_gradient(self, p: np.ndarray, friction: bool = True) -> np.ndarray:
        """(N, 3) dE/dx of every collision-mesh vertex (the obstacles' rows: minus the force on them)."""
        V = self.vertices(p)
        g = self.stiffness * self.potential.gradient(self.collisions(V), self.mesh, V)
        if friction and self.friction is not None:
            g = g + self._slip.gradient(self.friction, self.mesh, self._slips(p))
        return g.reshape(-1, 3)

    def gradient(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) dE/dx of every part surface node."""
        return self.full_gradient(p)[:self.n]

    def friction_forces(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) friction's force on every part surface node (zero without friction)."""
        if self.friction is None:
            return np.zeros((self.n, 3))
        return -self._slip.gradient(self.friction, self.mesh, self._slips(p)).reshape(-1, 3)[:self.n]

    def hessian(self, p: np.ndarray) -> sp.coo_matrix:
        """(3n, 3n) the PSD-projected Hessian on the part's nodes, node-major (3 i + c), as triplets."""
        V = self.vertices(p)
        H = self.stiffness * self.potential.hessian(self.collisions(V), self.mesh, V, ipctk.PSDProjectionMethod.CLAMP)
        if self.friction is not None:
            H = H + self._slip.hessian(self.friction, self.mesh, self._slips(p), ipctk.PSDProjectionMethod.CLAMP)
        H = H.tocoo()
        keep = (H.row < 3 * self.n) & (H.col < 3 * self.n)
        return sp.coo_matrix((H.data[keep], (H.row[keep], H.col[keep])), shape=(3 * self.n, 3 * self.n))

    # --- the step filter and the checks ----------------------------------------------------------------------
    def safe_fraction(self, p0: np.ndarray, dp: np.ndarray) -> float:
        """The largest safe share of the step p0 -> p0 + dp; first limited to moving no node farther than
        REACH surface edges (a far step's candidate pairs grow quadratically: 3 GB and no end were seen on a
        ring whose first Newton step moved nodes 30 edges), then cut before any time of impact."""
        longest = float(np.linalg.norm(dp, axis=1).max(initial=0.0))
        reach = min(1.0, REACH * self.edge / longest) if longest > 0 else 1.0
        s = ipctk.compute_collision_free_stepsize(self.mesh, self.vertices(p0), self.vertices(p0 + reach * dp),
                                                  narrow_phase_ccd=CCD)
        return reach if s >= 1.0 else SHORTEN * s * reach

    def intersects(self, p: np.ndarray) -> bool:
        """Whether surfaces cross at p, or (obstacles) the part lies inside one or one inside the part."""
        V = self.vertices(p)
        if ipctk.has_intersections(self.mesh, V):
            return True
        part = (p, self.surface.faces)
        return any(inside(p, ob.current_points(), ob.triangles) or inside(ob.current_points(), *part)
                   for ob in self.obstacles)

    def min_distance(self, p: np.ndarray) -> float:
        """The smallest gap between surface pieces that may touch, within 10 dhat (inf if none that close)."""
        V = self.vertices(p)
        c = self._build(self.mesh, V, 10 * self.dhat)
        return float(np.sqrt(c.compute_minimum_distance(self.mesh, V))) if len(c) else np.inf

    def report(self, p: np.ndarray, rows: np.ndarray) -> dict:
        """results.json entry of the pushes on the part's nodes `rows` (n, 3) (dE/dx): their force on the part,
        the rest area of the surface triangles whose nodes all push, the largest push per node area, and how
        many nodes push."""
        push = np.linalg.norm(rows, axis=1)
        active = push > 0.0
        faces = active[self.surface.faces].all(axis=1)
        return {"force": (-rows.sum(axis=0)).tolist(), "area": float(self.surface.face_areas()[faces].sum()),
                "max_pressure": float((push[active] / self.surface.area[active]).max(initial=0.0)),
                "active_points": int(active.sum())}

    def obstacle_reports(self, p: np.ndarray) -> dict:
        """results.json contact entries of the file obstacles: the force each exerts on the part (the sum of its
        own vertices' dE/dx, Newton's third law), with the area, pressure and nodes of the part it pushes."""
        g = self.full_gradient(p)
        out = {}
        for k, ob in enumerate(self.obstacles):
            mine = self.only(p, k)
            entry = self.report(p, mine)
            entry["force"] = g[self.owner == k].sum(axis=0).tolist()
            out[ob.name] = entry
        return out

    def only(self, p: np.ndarray, k: int) -> np.ndarray:
        """(n, 3) the barrier's dE/dx on the part's nodes from the pairs with obstacle k alone."""
        V = self.vertices(p)
        mesh = ipctk.CollisionMesh(np.asfortranarray(self.mesh.rest_positions), self.edge_list, self.faces)
        mesh.can_collide = ipctk.make_vertex_patches_filter(np.where(self.owner == k, 1, 0).astype(np.int32)) \
            & ipctk.make_static_obstacle_filter(self.n)
        c = self._build(mesh, V)
        return self.stiffness * self.potential.gradient(c, mesh, V).reshape(-1, 3)[:self.n]
