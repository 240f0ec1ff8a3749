"""What a scene file may ask for without the user's say-so: caps on mesh cells, load steps (and their halvings),
iterations, time steps, modes, probes, sound samples and obstacle triangles, and on the scene file itself (its size
and nesting, checked before and while it is parsed). A shared scene is data: it cannot make a run that fills a 24 GB
machine or runs for days unless the user lifts the caps with `--no-limits` (Python: `Scene.from_file(path,
limits=NO_LIMITS)`).

Each cap sits well above what this package's demos, benchmarks and verification cases use, and below what a
24 GB machine can hold (2 million P2 tetrahedra on the iterative path: about 8 million dofs, 2.7 GiB per million
measured in benchmarks/scale_beam_1m.md)."""
from __future__ import annotations

from dataclasses import dataclass, fields

from fem_forms.errors import InputError
from fem_forms.scene.analyses.impact_section import ImpactSoundSpec

LIFT = "--no-limits lifts it"


@dataclass(frozen=True)
class Limits:
    """The caps (None: no cap)."""
    cells: int | None = 2_000_000                 # mesh cells (a box's, a gmsh mesh's estimate, a file's)
    load_steps: int | None = 10_000               # [solver] steps, 1 / max_step
    cutbacks: int | None = 60                     # [solver] max_cutbacks (2^-60 of a step: below round-off)
    iterations: int | None = 100_000              # [fracture] max_iterations, [inverse] iterations
    time_steps: int | None = 1_000_000            # [dynamic] duration / dt
    modes: int | None = 500                       # [modal] count, [sound.impact] count
    probes: int | None = 1_000                    # [output] probes
    sound_samples: int | None = 2**26             # [sound] duration x sample_rate (25 minutes at 44.1 kHz)
    obstacle_triangles: int | None = 300_000      # an obstacle file's triangles (also once refined)
    scene_bytes: int | None = 8_000_000           # the scene file's size, refused before it is parsed
    nesting: int | None = 32                      # tables and arrays inside each other

    def check(self, cap: str, value: float, key: str, what: str) -> None:
        """One line naming the key, the value, the cap and the flag that lifts it, when value exceeds the cap."""
        limit = getattr(self, cap)
        if limit is not None and value > limit:
            raise InputError(f"{key}: {value:,.0f} {what}, more than a scene may ask for ({limit:,}); {LIFT}")


LIMITS = Limits()
NO_LIMITS = Limits(**{f.name: None for f in fields(Limits)})


def nesting_depth(node, depth: int = 0) -> int:
    """How deep tables and arrays sit inside each other in a parsed scene (iteratively: no recursion limit)."""
    deepest, stack = depth, [(node, depth)]
    while stack:
        item, d = stack.pop()
        deepest = max(deepest, d)
        if isinstance(item, dict):
            stack.extend((v, d + 1) for v in item.values())
        elif isinstance(item, list):
            stack.extend((v, d + 1) for v in item)
    return deepest


def check_scene(sc, limits: Limits) -> None:
    """The caps a read scene's own numbers can be checked against (the mesh's cells and an obstacle's triangles
    are checked when they are known: mesh.max_cells, the contact term's max_triangles)."""
    limits.check("load_steps", sc.solver.steps, "solver.steps", "load steps")
    limits.check("load_steps", 1.0 / sc.solver.max_step, "solver.max_step", "load steps at least (1 / max_step)")
    limits.check("cutbacks", sc.solver.max_cutbacks, "solver.max_cutbacks", "halvings of a step")
    limits.check("iterations", sc.inverse.iterations, "inverse.iterations", "iterations")
    if sc.fracture is not None:
        limits.check("iterations", sc.fracture.max_iterations, "fracture.max_iterations", "sweeps")
    limits.check("probes", len(sc.output.probes or {}), "output.probes", "probes")
    if sc.analysis == "dynamic":
        limits.check("time_steps", sc.dynamic.duration / sc.dynamic.dt, "dynamic.duration / dynamic.dt",
                     "time steps")
    if sc.analysis == "modal" and sc.modal.count is not None:
        limits.check("modes", sc.modal.count, "modal.count", "modes")
    sound = sc.sound
    if isinstance(sound, ImpactSoundSpec) and sound.count is not None:
        limits.check("modes", sound.count, "sound.impact.count", "modes")
    if sound is not None:
        limits.check("sound_samples", sound.duration * sound.sample_rate, "sound.duration x sound.sample_rate",
                     "samples")
    sc.mesh.max_cells = limits.cells
