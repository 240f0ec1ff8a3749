"""Time histories of the scene ([[t, f], ...] tables of loads, prescribed values and temperatures)."""
from __future__ import annotations

import numpy as np


def piecewise_linear(history: list | None, t: float) -> float:
    """The factor of a [[t, f], ...] history at time t (held constant outside; None: 1)."""
    if not history:
        return 1.0
    ts, fs = zip(*history)
    return float(np.interp(t, ts, fs))
