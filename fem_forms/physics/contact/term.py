"""Contact as one array term of the energy (Incremental Potential Contact, Li et al. 2020): a barrier on the
distance of every surface node to every rigid obstacle, kappa sum_v A_v b(d_v) (A_v the node's share of the
rest surface: the barrier acts as a pressure, independent of the mesh's grading), its gradient and its
PSD-projected Hessian beside the UFL terms in the same Newton solve, and a step filter that keeps every Newton
step intersection-free. The surface is gathered on every rank; each rank adds the rows it owns."""
from __future__ import annotations

from typing import TYPE_CHECKING

from dolfinx import fem
from mpi4py import MPI
import numpy as np
from petsc4py import PETSc

from fem_forms.errors import InputError
from fem_forms.meshes.boundary_surface import BoundarySurface, boundary_surface
from fem_forms.physics.contact.barrier import barrier, barrier_first, barrier_second, pressure_at_half, psd_blocks
from fem_forms.physics.contact.events import StepEvents
from fem_forms.physics.contact.lagging import Lag, lag_friction, relag
from fem_forms.physics.contact.mesh_obstacle import FileObstacle
from fem_forms.physics.contact.obstacles import make_obstacle
from fem_forms.physics.contact.pressure import add_pressure_field
from fem_forms.physics.contact.report import obstacle_reports
from fem_forms.physics.array_term import ArrayTerm
from fem_forms.physics.contact.holding import held_motion, surface_points
from fem_forms.physics.contact.hessian_blocks import add_node_blocks, add_triangle_hessian
from fem_forms.physics.terms import Context

if TYPE_CHECKING:
    from fem_forms.physics.contact.ipc_surfaces import IpcSurfaces

DEFAULT_DISTANCE = 1e-3      # dhat as a share of the part's bounding-box diagonal, as in IPC
SLIP_RATE = 1e-3             # friction's slip eps: this share of the bounding-box diagonal per unit of time
TOO_CLOSE = 1e-4             # a gap below this share of dhat doubles kappa (IPC's adaptive stiffness) ...
MAX_RAISE = 1e6              # ... up to this many times its first value
SETTLE_FLOOR = 1e-3          # a start from rest inside the barrier's range lowers kappa at most this far


class ContactTerm(ArrayTerm):
    """kappa sum_obstacles sum_v A_v b(d_v): the part's surface nodes against the scene's analytic obstacles;
    the part's triangles against themselves and against obstacle files through the IPC Toolkit (`ipc`)."""
    name, role, keys = "contact (IPC barrier)", "contact", ("contact",)
    lagging = True                 # friction's normal forces and tangent planes, the obstacles' positions
    energy_columns = ("contact",)

    def __init__(self, spec, modulus: float, max_triangles: int | None):
        self.modulus = modulus
        self.max_triangles = max_triangles         # an obstacle file's cap (scene/limits.py)
        self.surface: BoundarySurface | None = None
        self.selfc: IpcSurfaces | None = None      # the part against itself
        self.filec: IpcSurfaces | None = None      # the part against the obstacle files
        self.kappa = self.kappa0 = 0.0
        self.intersection_free = True
        self.blocked = False                       # an obstacle file moved onto the part at the step's time
        self.time = self.start_time = 0.0
        self.friction: list = []                   # per obstacle: its LaggedFriction, or None
        self._lagged_at = None                     # the state the friction was lagged from
        self.events = StepEvents()                 # impacts and stick-slip transitions of each time step
        self.only = None                           # the surface points [contact] where leaves to the obstacles
        self.rest_offset = None                    # a designed rest shape's d (on_rest.py), else None
        self.lag: Lag | None = None                # what the friction's slips are measured from (lagging.py)
        self.set_spec(spec)

    def set_spec(self, spec) -> None:
        self.spec = spec
        self.obstacles = [make_obstacle(ob) for ob in spec.obstacle if ob.shape != "file"]
        self.file_index = [i for i, ob in enumerate(spec.obstacle) if ob.shape == "file"]   # their scene index
        self.files = [FileObstacle(spec.obstacle[i], f"contact.obstacle[{i}]", self.max_triangles)
                      for i in self.file_index]
        for ob in self.obstacles + self.files:
            ob.move_to(self.time)
        for ob in self.obstacles:
            ob.only = self.only

    @property
    def ipc(self) -> list[IpcSurfaces]:
        return [c for c in (self.selfc, self.filec) if c is not None]

    def set_values(self, scene) -> None:
        self.set_spec(scene.contact)
        if self.surface is not None:
            self._scale()

    def prepare(self, ctx: Context) -> None:
        if not isinstance(ctx.u, fem.Function) or ctx.deformation is not None:
            raise InputError("contact: available with formulation = 'displacement' in forward analyses and the "
                             "adjoint inverse design only")
        self.surface = boundary_surface(ctx.u.function_space)
        self.rest_offset, self.mesh_rest = ctx.rest_offset, self.surface.rest.copy()   # on_rest.follow_rest
        if self.spec.where is not None:
            self.only = surface_points(self.surface, ctx.u.function_space, ctx.loaded, self.spec.where)
            for ob in self.obstacles:
                ob.only = self.only
        self.state = ctx.u.vector                       # the state `record` reports after each accepted step
        self.friction_at_start = np.zeros((self.surface.size, 3))
        self._start_positions = self.surface.rest.copy()
        self._scale()
        analytic = [i for i in range(len(self.spec.obstacle)) if i not in self.file_index]
        for i, ob in zip(analytic, self.obstacles):
            d = ob.distance(self.surface.rest)
            if d.min() <= 0.0:
                raise InputError(f"contact.obstacle[{i}] ({ob.name}): intersects or touches the part at the start "
                                 f"(smallest distance {d.min():.3g} m); the barrier needs a gap: move it at least "
                                 f"{-d.min() + self.dhat / 2:.3g} m away")
        if self.filec is not None and (self.filec.intersects(self.surface.rest)
                                       or self.filec.min_distance(self.surface.rest) <= 0.0):
            names = ", ".join(ob.name for ob in self.files)
            raise InputError(f"contact.obstacle ({names}): an obstacle file intersects, touches or encloses the part "
                             "at the start (or lies inside it); the barrier needs a gap between the surfaces")

    @property
    def widens_pattern(self) -> bool:
        """Self-contact couples surface nodes no element joins (its Hessian widens the tangent's pattern)."""
        return bool(self.spec.self)

    def _scale(self) -> None:
        """dhat (the scene's, else 1e-3 x the bounding-box diagonal) and kappa: the barrier's push at a gap of
        dhat / 2 equals the elastic pressure of a surface displacement dhat over one surface edge (E dhat / h),
        so its stiffness is of the elastic Hessian's scale."""
        rest = self.surface.rest
        self.diagonal = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
        self.dhat = self.spec.distance or DEFAULT_DISTANCE * self.diagonal
        e = self.surface.edges()
        h = float(np.mean(np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1)))
        self.kappa = self.kappa0 = self.modulus / (h * pressure_at_half(self.dhat))
        if self.spec.self or self.files:
            from fem_forms.physics.contact.ipc_surfaces import IpcSurfaces   # the IPC Toolkit, when it is used
        self.selfc = IpcSurfaces(self.surface, self.dhat) if self.spec.self else None
        for ob, i in zip(self.files, self.file_index):
            ob.refine(h, f"contact.obstacle[{i}]")
        self.filec = IpcSurfaces(self.surface, self.dhat, self.files, self_pairs=False) if self.files else None
        for c in self.ipc:                         # the same push at dhat / 2 between triangles
            c.calibrate(h, self.modulus * self.dhat / h)

    def update(self, t: float) -> None:
        """Move the obstacles to time t and lag the friction from the current state (the step's start). A state
        that changed since the last call was accepted at the last call's time: the step now starts there."""
        x = self.state.array_r
        moved = self._lagged_at is None or len(x) != len(self._lagged_at) or not np.array_equal(x, self._lagged_at)
        moved = self.surface.comm.allreduce(moved, op=MPI.LOR)      # one decision for all ranks
        if moved:
            self.friction_at_start = self._friction_forces(self.surface.positions(self.state))
            self.start_time, self._lagged_at = self.time, x.copy()
        self.time = t
        for ob in self.obstacles + self.files:
            ob.move_to(self.start_time)
        p = self._start_positions = self.surface.positions(self.state)
        if moved:
            self._adapt(self.min_distance(self.state))     # kappa changes between steps only, as in IPC
            if self.events.watched:
                self.events.start(*self._contacts(p), self.friction, p)
        eps = max(SLIP_RATE * self.diagonal * (t - self.start_time), 1e-9 * self.diagonal)
        for c in self.ipc:
            c.lag_friction(p, self.start_time, t, eps, self.spec.friction)
        for ob in self.files:
            ob.move_to(t)
        # an obstacle file moved onto the part at t: no step from here is safe (the step is cut back)
        self.blocked = self.filec is not None and self.filec.intersects(p)
        starts = [ob.offset.copy() for ob in self.obstacles]
        self.lag = Lag(p, eps, [np.zeros(3)] * len(self.obstacles))
        self.friction = lag_friction(self, p, self.lag)          # with the obstacles where the step starts
        for ob, start, fr in zip(self.obstacles, starts, self.friction):
            ob.move_to(t)
            if fr is not None:
                fr.obstacle_move = ob.offset - start
        self.lag.moves = [ob.offset - start for ob, start in zip(self.obstacles, starts)]

    relag = relag          # (x, tolerance): the friction re-lagged at x where its normal forces moved (lagging.py)

    def _contacts(self, p: np.ndarray) -> tuple[list, list]:
        """At positions p: per obstacle, the surface points' distances to it; per IPC surface, how many pairs."""
        return [ob.distance(p) for ob in self.obstacles], [len(c.collisions(c.vertices(p))) for c in self.ipc]

    def watch_events(self) -> None:
        self.events.watched = True

    def step_event(self, x: PETSc.Vec) -> str:
        """'impact', 'release', 'stick-slip' or '' for the step from its start to x (events.py), rank 0's everywhere."""
        p = self.surface.positions(x)
        return self.surface.comm.bcast(self.events.kind(*self._contacts(p), self.friction, p, self.dhat),
                                     root=0)

    def start(self, state) -> None:
        """A new solve's pseudo-time (or time) starts at 0."""
        self.resume(0.0)

    def saved(self) -> dict:
        return {"kappa": self.kappa, "kappa0": self.kappa0, "ipc": [c.stiffness for c in self.ipc]}

    def restore(self, values: dict) -> None:
        """The barrier's stiffness where the checkpointed run had raised it (and its first value)."""
        self.kappa, self.kappa0 = values["kappa"], values["kappa0"]
        for c, k in zip(self.ipc, values["ipc"]):
            c.stiffness = k

    def resume(self, t: float) -> None:
        """Continue from a restored state at time t (a dynamic --restart): the next step starts there, with the
        barrier's stiffness the checkpoint restored and the friction from no force at the start."""
        self.time, self._lagged_at, self.friction, self.lag = t, None, [], None
        for ob in self.obstacles + self.files:
            ob.move_to(t)

    # --- the energy, its gradient and Hessian at x ------------------------------------------------------
    def _gaps(self, p: np.ndarray) -> list[tuple]:
        """Per obstacle: the active nodes (gap below dhat), their gaps, gradients and Hessians of the gap."""
        out = []
        for ob in self.obstacles:
            d = ob.distance(p)
            act = np.flatnonzero(d < self.dhat)
            _, g, H = ob.derivatives(p[act]) if len(act) else (None, np.zeros((0, 3)), np.zeros((0, 3, 3)))
            out.append((act, d[act], g, H, float(d.min()) if len(d) else np.inf))
        return out

    def barrier_energy(self, x: PETSc.Vec) -> float:
        """The barriers' stored energy at x (J): obstacles and self-contact, without friction's potential."""
        p = self.surface.positions(x)
        A = self.surface.area
        push = sum(self.kappa * np.sum(A[act] * barrier(d, self.dhat)) for act, d, *_ in self._gaps(p))
        return float(push + sum(c.barrier_energy(p) for c in self.ipc))

    def energy_value(self, x: PETSc.Vec) -> float:
        """The barriers' and friction's energy at x, rank 0's value on every rank: ipctk sums on several threads,
        so ranks differ in the last digits, and an energy line search must decide alike on all of them."""
        p = self.surface.positions(x)
        value = self.barrier_energy(x) + float(sum(f.energy(p) for f in self.friction if f is not None)) \
            + sum(c.friction_energy(p) for c in self.ipc)
        return self.surface.comm.bcast(value, root=0)

    def nodal_forces(self, x: PETSc.Vec) -> list[tuple]:
        """Per obstacle: active nodes and the force (n, 3) the obstacle exerts on each, -dE/dx_v."""
        p = self.surface.positions(x)
        A = self.surface.area
        out = []
        for (act, d, g, *_), fr in zip(self._gaps(p), self.friction or [None] * len(self.obstacles)):
            push = -(self.kappa * A[act] * barrier_first(d, self.dhat))[:, None] * g
            if fr is not None:
                act, push = np.concatenate([act, fr.nodes]), np.concatenate([push, -fr.gradient(p)])
            out.append((act, push))
        return out

    def add_gradient(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        mine = np.full(self.surface.size, -1)
        mine[self.surface.owned] = self.surface.owned_local
        rows = b.array.reshape(-1, 3)
        for act, force in self.nodal_forces(x):
            keep = mine[act] >= 0
            np.add.at(rows, mine[act][keep], -force[keep])
        if self.ipc:
            p = self.surface.positions(x)                   # one gather for all triangle contacts
            for c in self.ipc:
                rows[self.surface.owned_local] += c.gradient(p)[self.surface.owned]

    def add_hessian(self, x: PETSc.Vec, A: PETSc.Mat, constrained: np.ndarray, barrier: bool = True,
                    friction: bool = True) -> None:
        """The barriers' and the obstacles' friction's Hessian into A (a standing design's adjoint takes each alone)."""
        p = self.surface.positions(x)
        gaps = self._gaps(p)
        owned = np.zeros(self.surface.size, bool)
        owned[self.surface.owned] = True
        for c in self.ipc if barrier else ():
            add_triangle_hessian(A, c.hessian(p), self.surface, owned, constrained)
        area = self.surface.area
        for (act, d, g, H, _), fr in zip(gaps, self.friction or [None] * len(gaps)):
            if fr is not None and friction:
                keep = owned[fr.nodes]
                add_node_blocks(A, self.surface, fr.nodes[keep], fr.hessian(p)[keep], constrained)
            keep = owned[act]
            act, d, g, H = act[keep], d[keep], g[keep], H[keep]
            if not len(act) or not barrier:
                continue
            w = self.kappa * area[act]
            blocks = (w * barrier_second(d, self.dhat))[:, None, None] * g[:, :, None] * g[:, None, :] \
                + (w * barrier_first(d, self.dhat))[:, None, None] * H
            add_node_blocks(A, self.surface, act, psd_blocks(blocks), constrained)

    def settle(self, factor: float) -> float:
        """A body at rest inside the barrier's range at t = 0: kappa scaled so the barrier's push balances the
        loads there (IPC's initial barrier stiffness), not the launch a push of the elastic scale would give;
        at least SETTLE_FLOOR x kappa (no load pressing: the push is all but gone), at most MAX_RAISE x (a gap at
        the range's edge, where the push vanishes)."""
        factor = min(max(float(factor), SETTLE_FLOOR), MAX_RAISE)
        self.kappa *= factor
        self.kappa0 = self.kappa
        for c in self.ipc:
            c.stiffness *= factor
        return factor

    def _adapt(self, smallest: float) -> None:
        """Double kappa when the accepted state's smallest gap is below TOO_CLOSE x dhat: the same contact force
        then sits at a larger gap, away from the barrier's singularity (IPC's adaptive barrier stiffness)."""
        if smallest < TOO_CLOSE * self.dhat and self.kappa < MAX_RAISE * self.kappa0:
            self.kappa *= 2.0
            for c in self.ipc:
                c.stiffness *= 2.0

    def max_step(self, x: PETSc.Vec, dx: PETSc.Vec) -> float:
        if self.blocked:
            return 0.0
        p0, dp = self.surface.positions(x), self.surface.displacement(dx)
        return min([c.safe_fraction(p0, dp) for c in self.ipc] + [ob.safe_fraction(p0, dp) for ob in self.obstacles])

    # --- what results.json and probes.csv report -----------------------------------------------------------
    def _friction_forces(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) the friction force on each surface node at positions p, with the current lag."""
        out = np.zeros((self.surface.size, 3))
        for f in self.friction:
            if f is not None:
                np.add.at(out, f.nodes, -f.gradient(p))
        return out + sum((c.friction_forces(p) for c in self.ipc), np.zeros_like(out))

    def friction_work(self, x: PETSc.Vec) -> float:
        """The energy friction dissipated over the current step, up to the state x (J): the slip times the mean
        of the friction forces at the step's ends (the trapezoidal rule Newmark's energy identity has)."""
        p = self.surface.positions(x)
        start = self._start_positions
        mean = 0.5 * (self.friction_at_start + self._friction_forces(p))
        return float(-np.sum(mean * (p - start)))

    def stored_energies(self, x: PETSc.Vec) -> dict[str, float]:
        return {"contact": self.barrier_energy(x)}

    def step_dissipation(self, x: PETSc.Vec) -> float:
        return self.friction_work(x)

    def support_forces(self, x: PETSc.Vec) -> np.ndarray:
        """(obstacles, 3): the force each obstacle exerts on the body."""
        return np.array([r["force"] for r in self.report(x).get("contact", {}).values()]).reshape(-1, 3)

    def surface_forces(self, body: str, x: PETSc.Vec) -> tuple | None:
        names = [ob.name for ob in self.obstacles]
        if body not in names:
            return None
        act, force = self.nodal_forces(x)[names.index(body)]
        return act, force, self.surface

    def add_output_field(self, name: str, f) -> None:
        if name == "contact_pressure":
            add_pressure_field(self, f)

    def min_distance(self, x: PETSc.Vec) -> float:
        p = self.surface.positions(x)
        return min([c.min_distance(p) for c in self.ipc] + [float(ob.distance(p).min()) for ob in self.obstacles])

    def inadmissible(self, x: PETSc.Vec) -> str | None:
        """Why the state at x is not intersection-free (a surface node on or inside an obstacle), or None."""
        p = self.surface.positions(x)
        for ob in self.obstacles:
            d = ob.distance(p)
            if d.min() <= 0.0:
                return f"the surface meets obstacle {ob.name!r} ({int(np.sum(d <= 0))} nodes at or inside it)"
        if self.selfc is not None and self.selfc.intersects(p):
            return "the surface intersects itself"
        if self.filec is not None and self.filec.intersects(p):
            return "the surface meets an obstacle file (" + ", ".join(ob.name for ob in self.files) + ")"
        return None

    def report(self, x: PETSc.Vec) -> dict:
        """results.json: contact {NAME: the obstacle's numbers (report.py), self, files}, min_distance (m),
        intersection_free, barrier numbers."""
        p = self.surface.positions(x)
        out = obstacle_reports(self, x)
        if self.filec is not None:
            out.update(self.filec.obstacle_reports(p))
        if self.selfc is not None:
            out["self"] = self.selfc.report(p, self.selfc.gradient(p))
        smallest = self.min_distance(x)
        self.intersection_free = self.intersection_free and smallest > 0.0
        return {"contact": out, "min_distance": smallest, "intersection_free": self.intersection_free,
                "contact_distance": self.dhat, "barrier_stiffness": self.kappa}

    def nodal_pressure(self, x: PETSc.Vec) -> np.ndarray:
        """(n,) the contact pressure at each surface node (Pa): the barriers' push on it (obstacles and the
        part's own pieces, friction left out) per its share of the rest surface; the same on every rank."""
        p = self.surface.positions(x)
        push = np.zeros(self.surface.size)
        for act, d, *_ in self._gaps(p):
            np.add.at(push, act, -self.kappa * self.surface.area[act] * barrier_first(d, self.dhat))
        for c in self.ipc:
            push += np.linalg.norm(c.full_gradient(p, friction=False)[:c.n], axis=1)
        return push / self.surface.area

    def record(self) -> dict[str, float]:
        """probes.csv columns after every accepted step: each obstacle's force and active points, the smallest gap."""
        rep = self.report(self.state)
        out = {f"{n}_F{c}": f for n, r in rep["contact"].items() for c, f in zip("xyz", r["force"])}
        out["min_distance"] = rep["min_distance"]
        out.update({f"{n}_active": r["active_points"] for n, r in rep["contact"].items() if "active_points" in r})
        return out

    support_hint = ("an obstacle holds what lies within contact.distance at the start; without friction only along "
                    "its normal")

    def holds(self, model, modes: list) -> np.ndarray:
        """What the obstacles hold of each rigid mode (their push at rest), as columns."""
        return np.array([self.held_motion(self.surface.displacement(m)) for m in modes]).T

    def held_motion(self, values: np.ndarray) -> np.ndarray:
        """The parts of a motion (its values at the surface nodes, (n, 3)) the obstacles resist at rest (holding.py)."""
        return held_motion(self, values)
