"""The [contact] section: the part's surface against rigid obstacles ([[contact.obstacle]]) and against itself,
by Incremental Potential Contact (a barrier on surface distances, never an intersection). One declaration read
by every analysis that can take contact."""
from __future__ import annotations


from fem_forms.keys import spec_class
from fem_forms.errors import InputError
from fem_forms.scene.reader import Key, Section, Table
from fem_forms.scene.selectors import AREA_SELECTORS, where

SHAPES = ("plane", "sphere", "box", "cylinder", "file")
# shape -> the keys that place it (all required for that shape)
SHAPE_KEYS = {"plane": ("point", "normal"), "sphere": ("center", "radius"), "box": ("min", "max"),
              "cylinder": ("point", "axis", "radius"), "file": ("file",)}
OBSTACLE_KEYS = (
    Key("name", "string", "the obstacle's name in results.json contact", default_note="obstacle0, obstacle1, ..."),
    Key("shape", "string", "the obstacle's shape (rigid; the part stays on its outer side)", required=True,
        choices=SHAPES),
    Key("point", "vector", "plane: a point on it; cylinder: a point on its axis", unit="m", length=3),
    Key("normal", "vector", "plane: its normal, pointing to the part's side", length=3),
    Key("center", "vector", "sphere: its centre", unit="m", length=3),
    Key("radius", "number", "sphere or cylinder: its radius", unit="m", exclusive_minimum=0),
    Key("min", "vector", "box: its lowest corner", unit="m", length=3),
    Key("max", "vector", "box: its highest corner", unit="m", length=3),
    Key("axis", "vector", "cylinder: the direction of its (infinite) axis", length=3),
    Key("file", "file", "file: a closed triangle surface (.stl, .obj, .ply, .off), in the scene's units (m)"),
    Key("friction", "number", "Coulomb coefficient between the part and this obstacle (0: frictionless)",
        default=0.0, minimum=0),
    Key("motion", "points", "[t, dx, dy, dz] rigid translation of the obstacle, piecewise linear in time (static: "
        "the pseudo-time of the load steps), held after the last", unit="s, m", length=4, min_items=1,
        note="must list [t, dx, dy, dz] rows"),
)
CONTACT_KEYS = (
    Key("self", "boolean", "the part's surface against itself (and parts of one mesh against each other)",
        default=False),
    Key("friction", "number", "Coulomb coefficient of self-contact (0: frictionless)", default=0.0, minimum=0),
    Key("distance", "number", "barrier activation distance dhat: surfaces closer than this push each other apart; "
        "contact is accurate to about this gap", unit="m", exclusive_minimum=0,
        default_note="1e-3 x the part's bounding-box diagonal"),
    Key("obstacle", "tables", "rigid obstacles [[contact.obstacle]]: name, shape and the keys that place it, "
        "friction, motion", default=[], keys=OBSTACLE_KEYS),
    where("the part's boundary facets that may touch the obstacles (a sole, a fingertip; default: the whole "
          "surface); plane, sphere, box and cylinder obstacles only", required=False, kinds=AREA_SELECTORS),
)


Obstacle = spec_class("Obstacle", "One rigid obstacle as the scene gives it.", OBSTACLE_KEYS, __name__)


ContactSpec = spec_class(
    "ContactSpec", "[contact]: self-contact, its friction, the barrier distance and the obstacles.",
    CONTACT_KEYS, __name__)


def _obstacle(data: dict, key: str, index: int) -> Obstacle:
    """An Obstacle from its checked keys, with the rules that involve several of them."""
    shape = data["shape"]
    needed = SHAPE_KEYS[shape]
    for name in needed:
        if data.get(name) is None:
            raise InputError(f"{key}.{name}: missing (required for shape = {shape!r})")
    for name in ("point", "normal", "center", "radius", "min", "max", "axis", "file"):
        if data.get(name) is not None and name not in needed:
            owners = " or ".join(repr(s) for s, ks in SHAPE_KEYS.items() if name in ks)
            raise InputError(f"{key}.{name}: only for shape = {owners} (this obstacle's shape is {shape!r})")
    for name in ("normal", "axis"):
        if data.get(name) is not None and sum(c * c for c in data[name]) == 0.0:
            raise InputError(f"{key}.{name} = {data[name]}: must not be the zero vector")
    if shape == "box" and any(a >= b for a, b in zip(data["min"], data["max"])):
        raise InputError(f"{key}.max: every coordinate must exceed min's ({data['min']} -> {data['max']})")
    motion = data.get("motion")
    if motion is not None and any(b[0] <= a[0] for a, b in zip(motion, motion[1:])):
        raise InputError(f"{key}.motion: times must increase (a motion history cannot go backwards in time)")
    if shape == "file" and str(data["file"]).lower().rsplit(".", 1)[-1] not in ("stl", "obj", "ply", "off"):
        raise InputError(f"{key}.file: a triangle surface (.stl, .obj, .ply, .off) is needed")
    name = data.get("name") or f"obstacle{index}"
    return Obstacle(name=name, **{k: v for k, v in data.items() if k != "name" and v is not None})


def _contact_rules(spec: ContactSpec, t: Table) -> None:
    spec.obstacle = [_obstacle(d, f"{t.key('obstacle')}[{i}]", i) for i, d in enumerate(spec.obstacle)]
    seen: dict = {}
    for i, ob in enumerate(spec.obstacle):
        if ob.name == "self":
            raise InputError(f"{t.key('obstacle')}[{i}].name: 'self' names self-contact in results.json; choose "
                             "another name")
        if ob.name in seen:
            raise InputError(f"{t.key('obstacle')}[{i}].name: {ob.name!r} already names obstacle[{seen[ob.name]}]")
        seen[ob.name] = i
    if not spec.self and not spec.obstacle:
        raise InputError(f"{t.key('self')}: [contact] with neither self = true nor a [[contact.obstacle]] has "
                         "nothing to touch")
    if spec.where is not None and (spec.self or any(ob.shape == "file" for ob in spec.obstacle)):
        raise InputError(f"{t.key('where')}: only with plane, sphere, box and cylinder obstacles (self-contact and "
                         "obstacle files take the whole surface); leave where out")
    if spec.friction > 0.0 and not spec.self:
        raise InputError(f"{t.key('friction')}: the friction of self-contact needs self = true (an obstacle's "
                         "friction is its own key)")


CONTACT = Section("contact", "contact with rigid obstacles and with itself (Incremental Potential Contact)",
                  ContactSpec, keys=CONTACT_KEYS, rules=_contact_rules, absent=lambda: None)
