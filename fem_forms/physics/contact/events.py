"""Contact events over one time step, for the time march to resolve them with shorter steps: an impact (a point
came into contact moving toward the obstacle by more than the barrier's layer dhat within the step: a thrown ball
landing, a dropped block; with obstacle files and self-contact, whose distances are pairs', the first pair), its
reverse, a release (a bounce), and a stick-slip transition (most of the points in contact switch between sticking
and sliding: a block starts to slide or stops). A part settling or rolling, whose contact patch gains and loses
points that creep into the layer, has none of them."""
from __future__ import annotations

import numpy as np

IMPACT_LAYERS = 1.0       # a point in contact that approached by more than this many dhat within one step: impact
TRANSITION_SHARE = 0.5    # points that switched between sticking and sliding, of those in contact at both ends
TRANSITION_POINTS = 3     # fewer points in contact than this: no transition is told (a point or an edge chatters)


def impact(before: np.ndarray, after: np.ndarray, dhat: float) -> bool:
    """Whether a point in contact at the step's end (closer than dhat: `after`) approached by more than
    IMPACT_LAYERS dhat since its start (`before`): the step jumped the barrier's layer instead of resolving it."""
    near = after < dhat                     # finite: a point left out by [contact] where is at infinity
    return bool(np.any(before[near] - after[near] > IMPACT_LAYERS * dhat))


def release(before: np.ndarray, after: np.ndarray, dhat: float) -> bool:
    """The reverse of an impact: a point in contact at the step's start left by more than IMPACT_LAYERS dhat (a
    bounce)."""
    return impact(after, before, dhat)


def sliding(slip: np.ndarray, eps: float) -> np.ndarray:
    """(k,) whether each point slid over the step: its tangential slip (k, 2) beyond the friction's creep eps."""
    return np.linalg.norm(slip, axis=1) > eps


def transition(nodes_before: np.ndarray, sliding_before: np.ndarray, nodes_now: np.ndarray,
               sliding_now: np.ndarray) -> bool:
    """Whether most points in contact over both steps switched between sticking and sliding."""
    common, i, j = np.intersect1d(nodes_before, nodes_now, return_indices=True)
    if len(common) < TRANSITION_POINTS:
        return False
    return int(np.count_nonzero(sliding_before[i] != sliding_now[j])) >= TRANSITION_SHARE * len(common)


class StepEvents:
    """What a contact term remembers between steps to tell its events: at the step's start, the surface points'
    distances to each obstacle and the number of pairs of each IPC surface; which points slid over the step
    before."""

    def __init__(self):
        self.watched = False           # a time march refines the events (else nothing is remembered)
        self.distances: list[np.ndarray] = []
        self.pairs: list[int] = []
        self.slid: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def start(self, distances: list[np.ndarray], pairs: list[int], friction: list, p: np.ndarray) -> None:
        """A new step starts at positions p: the last step's friction (`friction`, one per obstacle or None) says
        which points slid over it; `distances` and `pairs` are the contacts now."""
        self.slid = {i: (f.nodes, sliding(f.slip(p), f.eps)) for i, f in enumerate(friction) if f is not None}
        self.distances, self.pairs = distances, pairs

    def kind(self, distances: list[np.ndarray], pairs: list[int], friction: list, p: np.ndarray,
             dhat: float) -> str:
        """'impact', 'release', 'stick-slip' or '' for the step ending at positions p with `distances` and
        `pairs`, the barrier's layer dhat thick."""
        if any(impact(b, a, dhat) for b, a in zip(self.distances, distances)) or \
                any(before == 0 < after for before, after in zip(self.pairs, pairs)):
            return "impact"
        if any(release(b, a, dhat) for b, a in zip(self.distances, distances)):
            return "release"
        for i, f in enumerate(friction):
            if f is not None and i in self.slid and transition(*self.slid[i], f.nodes, sliding(f.slip(p), f.eps)):
                return "stick-slip"
        return ""
