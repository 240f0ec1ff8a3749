"""The ground's frame under gravity: shared by the balance design and its pictures."""
from __future__ import annotations

import numpy as np


def ground_frame(gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(up, e1, e2): up against gravity and two unit vectors spanning the ground plane (right-handed)."""
    up = -np.asarray(gravity, dtype=float) / np.linalg.norm(gravity)
    helper = np.eye(3)[np.argmin(np.abs(up))]
    e1 = np.cross(helper, up)
    e1 /= np.linalg.norm(e1)
    return up, e1, np.cross(up, e1)
