"""The supports and loads a run's pictures mark, report.html and deformed.png alike: the boundary facets each acts
on, and the colour each is drawn in (the i-th mark's in both)."""
from __future__ import annotations

import numpy as np

MARK_COLOURS = ("#1565c0", "#c62828", "#2e7d32", "#6a1b9a", "#ef6c00", "#00838f")   # in scene order: fix, then loads


def mark_colour(i: int) -> str:
    """The i-th mark's colour, "#rrggbb"."""
    return MARK_COLOURS[i % len(MARK_COLOURS)]


def mark_rgb(i: int) -> tuple[float, float, float]:
    """The i-th mark's colour as (r, g, b) in [0, 1]."""
    h = mark_colour(i)
    return tuple(int(h[k:k + 2], 16) / 255 for k in (1, 3, 5))


def marked_facets(model) -> list[tuple[str, np.ndarray]]:
    """(label, local facet indices) of each support and load acting on facets: what the pictures mark. A selector
    the solve took cannot fail here; should one (a body load's cells), it is left unmarked, not the run failed."""
    from fem_forms.errors import InputError
    from fem_forms.physics.supports import locate_facets
    from fem_forms.scene.selectors import AREA_SELECTORS
    from fem_forms.scene.spec import fix_names
    scene = model.scene
    wanted = [(f"support {name}", fix.where) for name, fix in zip(fix_names(scene.fix), scene.fix)]
    wanted += [(f"{load.type} load[{i}]", load.where) for i, load in enumerate(scene.load)
               if load.type != "gravity" and load.where is not None]      # gravity's `where` names cells
    out = []
    for label, where in wanted:
        if where.kind in AREA_SELECTORS:
            try:
                out.append((label, locate_facets(model.loaded, where)))
            except InputError:                 # the same verdict on every rank (locate_facets reduces)
                continue
    return out
