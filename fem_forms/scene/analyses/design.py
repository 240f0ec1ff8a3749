"""The layout design analysis: its [design] section (the two materials, the stiff volume's bound, the filter, the
targets). Declared once here; the reader, the JSON Schema and the runner all read these."""
from __future__ import annotations

from fem_forms.errors import InputError
from fem_forms.keys import spec_class
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.reader import Key, Section, Table

TARGET_KEYS = (
    Key("probe", "string", "name of an [output.probes] point", required=True),
    Key("position", "vector", "where that point should be in the loaded part (or give `angle`)", unit="m",
        length=3),
    Key("axes", "axes", "the position's coordinates that count (the others are free: a tip's height, say)",
        default=["x", "y", "z"]),
    Key("angle", "number", "instead of a position: how far the segment from probe `from` to `probe` should turn "
        "about `about` in the loaded part (right-handed, within -180..180)", unit="deg", minimum=-180, maximum=180),
    Key("from", "string", "the segment's other end (an [output.probes] point), with `angle`"),
    Key("about", "vector", "the axis the angle turns about, with `angle`", length=3),
)
DESIGN_KEYS = (
    Key("materials", "names", "the two [[material]] names: the body's (everywhere the design puts nothing else) "
        "and the one the design places (its `where`, if any, is where it may go)", required=True, length=2),
    Key("stiff_fraction", "number", "the placed material fills at most this fraction of the volume it may take",
        default=0.3, exclusive_minimum=0, maximum=1),
    Key("filter_radius", "number", "the layout's smallest feature (the density filter's radius)", unit="m",
        exclusive_minimum=0, default_note="2 x the cells' mean size"),
    Key("penalty", "number", "SIMP exponent p: a cell of density rho has the energy (1 - rho^p) psi_body + "
        "rho^p psi_placed", default=3.0, minimum=1, maximum=6),
    Key("iterations", "integer", "layouts the optimizer may try (each one equilibrium and one adjoint solve; then "
        "up to nine casts of the optimum at thresholds 0.1 ... 0.9, and the chosen one once more from rest)",
        default=100, minimum=1),
    Key("reach", "number", "how near its target the layout must bring each probe (in the target's counted "
        "coordinates; with reach_angle one budget, root mean square over the targets): the design is the least "
        "placed material that does",
        unit="m", default=1e-4, exclusive_minimum=0),
    Key("reach_angle", "number", "how near its target each target angle must come (with reach one budget)",
        unit="deg",
        default=0.5, exclusive_minimum=0),
    Key("target", "tables", "[[design.target]]: a probe and where it should be in the loaded part, or how far a "
        "segment between two probes should turn", required=True,
        keys=TARGET_KEYS),
)

DesignSpec = spec_class("DesignSpec", "[design]: which material goes where so that probes reach their targets.",
                        DESIGN_KEYS, __name__)


def _rules(s, t: Table) -> None:
    if not s.target:
        raise InputError(f"{t.key('target')}: give at least one [[design.target]] (a probe and its position, or an "
                         "angle)")
    written = t.data.get("target") or []
    seen: dict = {}
    for i, target in enumerate(s.target):
        where = f"{t.key('target')}[{i}]"
        given = {k for k, v in target.items() if v is not None}
        if "angle" in given and i < len(written) and "axes" in written[i]:
            raise InputError(f"{where}.axes: belongs to a `position` target (an angle target counts its turn about "
                             "`about`)")
        name = f"{target.get('from')}->{target['probe']}" if "angle" in given else target["probe"]
        if name in seen:                                 # results.json reports each target under this name
            raise InputError(f"{where}: a second target for {name!r} (the first is {t.key('target')}[{seen[name]}]"
                             "; give one target per probe, one angle per segment)")
        seen[name] = i
        if ("position" in given) == ("angle" in given):
            raise InputError(f"{where}: give either `position` (where the probe should be) or `angle` (how far the "
                             "segment from `from` to the probe should turn), not both or neither")
        if "angle" in given:
            if "from" not in given or "about" not in given:
                raise InputError(f"{where}: an `angle` target needs `from` (the segment's other probe) and `about` "
                                 "(the axis it turns about)")
            if target["from"] == target["probe"]:
                raise InputError(f"{where}.from = {target['from']!r}: the segment's two ends are the same probe")
            if sum(c * c for c in target["about"]) == 0:
                raise InputError(f"{where}.about: the zero vector is no axis")
        elif "from" in given or "about" in given:
            raise InputError(f"{where}: `from` and `about` belong to an `angle` target")


def _check(scene) -> None:
    """The design's materials, targets and physics against the rest of the scene."""
    d = scene.design
    if d is None:
        raise InputError("design: missing (required table for analysis = 'design')")
    names = [m.name for m in scene.materials]
    for i, name in enumerate(d.materials):
        if name not in names:
            raise InputError(f"design.materials[{i}] = {name!r}: no [[material]] has this name (the scene's: "
                             f"{', '.join(map(repr, names))})")
    if len(scene.materials) != 2:
        raise InputError(f"material: a design scene has exactly the two materials design.materials names "
                         f"(this one has {len(scene.materials)})")
    body = next(m for m in scene.materials if m.name == d.materials[0])
    if body.where is not None:
        raise InputError(f"{body.key}.where: the body's material takes every cell the design leaves (no `where`)")
    for m in scene.materials:
        if m.plasticity_model is not None or m.prony is not None:
            raise InputError(f"{m.key}: plasticity and viscoelasticity are not implemented in a design")
        if m.fiber_direction is not None or m.fiber_field is not None:
            raise InputError(f"{m.key}.fibers: fibres are not implemented in a design")
    if scene.mesh.cell == "prism":
        raise InputError("mesh.cell = 'prism': a design writes its layout for tetrahedra and hexahedra only")
    probes = scene.output.probes
    for i, target in enumerate(d.target):
        for key in ("probe", "from"):
            if target.get(key) is not None and target[key] not in probes:
                raise InputError(f"design.target[{i}].{key} = {target[key]!r}: no such point in [output.probes] "
                                 f"(it has: {', '.join(map(repr, probes)) or 'none'})")
        if target.get("angle") is not None:
            segment = [b - a for a, b in zip(probes[target["from"]], probes[target["probe"]])]
            axis = target["about"]
            cross = [segment[1] * axis[2] - segment[2] * axis[1], segment[2] * axis[0] - segment[0] * axis[2],
                     segment[0] * axis[1] - segment[1] * axis[0]]
            if sum(c * c for c in cross) <= 1e-12 * sum(c * c for c in segment) * sum(c * c for c in axis):
                raise InputError(f"design.target[{i}].about = {list(axis)}: the segment from "
                                 f"{target['from']!r} to {target['probe']!r} lies along it (no turn about it to "
                                 "measure)")
    if scene.thermal is not None:
        raise InputError("thermal: not implemented in a design")


ANALYSIS = Analysis(
    name="design",
    doc="where to put a stiffer second material so that the loaded part's probes reach their targets (SIMP, "
        "adjoint gradients, L-BFGS-B)",
    runner="fem_forms.analyses.design:run",
    sections=(Section("design", "which material goes where so that probes reach their targets", DesignSpec,
                      keys=DESIGN_KEYS, rules=_rules, absent=lambda: None),),
    outputs=("results.json", "layout.xdmf", "layout.msh", "placed.stl", "body.stl", "design_history.csv",
             "layout.png"),
    check=_check,
)
