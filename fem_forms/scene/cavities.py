"""Rules of the scene's inflated cavities ([[load]] type = "inflation") and of arc-length continuation that
need the whole scene: names, and which analyses can take volume control and arc length."""
from __future__ import annotations

from fem_forms.errors import InputError


def cavity_rules(loads: list, analysis: str, control: str) -> list[str]:
    """Each inflation load's cavity name (its `name`, else cavity<k> for the k-th inflation load; a repeated
    name is an error); volume control and arc-length continuation only where a static solve can take them."""
    names, seen = [], {}
    for i, ld in enumerate(loads):
        if ld.type != "inflation":
            continue
        ld.name = ld.name if ld.name is not None else f"cavity{len(names)}"
        if ld.name in seen:
            raise InputError(f"load[{i}].name: {ld.name!r} already names load[{seen[ld.name]}]")
        seen[ld.name] = i
        names.append(ld.name)
        if ld.volume is not None and analysis not in ("static", "inverse", "design"):
            raise InputError(f"load[{i}].volume: volume control is for analysis = 'static', 'inverse' or 'design' (this "
                             f"scene's is {analysis!r}); give the cavity's pressure instead")
        if ld.volume is not None and control == "arc-length":
            raise InputError(f"load[{i}].volume: solver.control = 'arc-length' steps the load factor; a volume-"
                             "controlled cavity already passes its pressure's limit points: use control = 'load'")
    if control == "arc-length" and analysis != "static":
        raise InputError(f"solver.control = 'arc-length': for analysis = 'static' only (this scene's is {analysis!r})")
    return names
