"""Boundary selectors: where a support holds or a load acts (a plane, a box, a gmsh group, the facets facing a
direction, the facets on a plane of any orientation, a cavity's walls, the node nearest a point, the nodes on a
segment), read from a scene's `where` table."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fem_forms.errors import InputError
from fem_forms.scene.reader import AXES, Key, Table, brief, check_vector

SEL_AXIS = Key("axis", "string", "normal axis of a plane of boundary facets (with at)", required=True,
               choices=tuple(AXES))
SEL_AT = Key("at", "number", "coordinate of that plane along its axis", unit="m", required=True)
SEL_BOX = Key("box", "points", "boundary facets inside [[x0, y0, z0], [x1, y1, z1]]", unit="m",
              required=True, length=3, min_items=2, max_items=2)
SEL_GROUP = Key("group", "string", "a gmsh physical group of the mesh file, by name (volume, surface, curve "
                "or point)", required=True)
SEL_POINT = Key("point", "vector", "the mesh node nearest to [x, y, z] (supports only)", unit="m", required=True,
                length=3)
SEL_LINE = Key("line", "points", "the mesh nodes on the segment [[x0, y0, z0], [x1, y1, z1]] (supports only)",
               unit="m", required=True, length=3, min_items=2, max_items=2,
               note="must be two points [[x0, y0, z0], [x1, y1, z1]]")
SEL_NORMAL = Key("normal", "vector", "boundary facets whose outward normal lies within within_deg of this "
                 "direction (a curved part: every facet in that cone)", required=True, length=3)
SEL_WITHIN = Key("within_deg", "number", "the cone's half-angle about normal", unit="deg", default=5.0, minimum=0,
                 maximum=180)
SEL_OBLIQUE = Key("plane", "points", "boundary facets on the plane through a point with a normal, "
                  "[[x, y, z], [nx, ny, nz]] (any orientation)", unit="m, 1", required=True, length=3, min_items=2,
                  max_items=2, note="must be a point and a normal [[x, y, z], [nx, ny, nz]]")
SEL_TOLERANCE = Key("tolerance", "number", "how far from the plane a facet's corners may lie", unit="m",
                    exclusive_minimum=0, default_note="1e-6 x the mesh's bounding-box diagonal")
SEL_CAVITY = Key("cavity", "either", "the walls of a cavity (a closed interior surface of the mesh): 1 the "
                 "largest by enclosed volume, 2 the next, ...; \"all\": every one", required=True, keys=(
                     Key("cavity", "integer", "its rank by enclosed volume, largest first", minimum=1),
                     Key("cavity", "string", "every cavity", choices=("all",))))
SEL_FACE = Key("face", "integer", "a CAD file's face by its number (`fem-forms faces FILE` lists and draws them)",
               required=True, minimum=1)
SELECTOR_KEYS = {"plane": (SEL_AXIS, SEL_AT), "box": (SEL_BOX,), "group": (SEL_GROUP,), "point": (SEL_POINT,),
                 "line": (SEL_LINE,), "normal": (SEL_NORMAL, SEL_WITHIN), "oblique": (SEL_OBLIQUE, SEL_TOLERANCE),
                 "cavity": (SEL_CAVITY,), "face": (SEL_FACE,)}
_SELECTOR_OF = {"axis": "plane", "box": "box", "group": "group", "point": "point", "line": "line",
                "normal": "normal", "plane": "oblique", "cavity": "cavity", "face": "face"}
# what a traction or pressure may act on: facets
AREA_SELECTORS = ("plane", "box", "group", "normal", "oblique", "cavity", "face")


@dataclass
class Selector:
    """Where: a plane (axis, at), a box [[lo], [hi]] or a gmsh physical group of boundary facets, or (for
    supports) the mesh node nearest a point or the nodes on a line segment."""
    kind: str                      # "plane" | "box" | "group" | "point" | "line" | "normal" | "oblique" | "cavity"
    axis: int = 0
    at: float = 0.0
    direction: tuple = ()          # normal: the unit direction; oblique: the plane's unit normal
    within_deg: float = SEL_WITHIN.default
    origin: tuple = ()             # oblique: a point on the plane
    tolerance: float | None = None
    cavity: int | str = 1          # 1, 2, ... or "all"
    face: int = 0                  # a CAD face's number
    lo: tuple = ()
    hi: tuple = ()
    group: str = ""
    point: tuple = ()
    line: tuple = ()               # (start, end)
    key: str = "where"             # the scene key, for messages

    @staticmethod
    def parse(data: Any, key: str, kinds: tuple | None = None) -> "Selector":
        """A selector from {axis, at}, {box}, {group}, {normal}, {plane}, {cavity}, {face}, {point} or {line};
        `kinds` limits which are allowed."""
        t = Table(data, key)
        present = [k for k in _SELECTOR_OF if t.has(k)]
        if len(present) != 1:
            raise InputError(f"{key}: give exactly one of axis/at, box, group, normal, plane, cavity, face, point "
                             "or line")
        kind = _SELECTOR_OF[present[0]]
        if kinds is not None and kind not in kinds:
            if kinds == ("box",):
                raise InputError(f"{key}: must be a box = [[x0, y0, z0], [x1, y1, z1]]")
            if kind in ("point", "line") and kinds == AREA_SELECTORS:
                raise InputError(f"{key}: a {kind} has no area to carry a traction or pressure; "
                                 "select facets with axis/at, box, group, normal, plane, cavity or face")
            raise InputError(f"{key}: must be one of {', '.join(SELECTOR_KEYS[k][0].name for k in kinds)}")
        if kind == "plane":
            sel = Selector("plane", axis=AXES[t.read(SEL_AXIS)], at=t.read(SEL_AT), key=key)
        elif kind == "box":
            box = t.raw("box")
            if not (isinstance(box, list) and len(box) == 2):
                raise InputError(f"{key}.box = {brief(box)}: must be [[x0, y0, z0], [x1, y1, z1]]")
            lo, hi = (check_vector(b, f"{key}.box[{i}]") for i, b in enumerate(box))
            if any(a > b for a, b in zip(lo, hi)):
                raise InputError(f"{key}.box: lower corner {lo} exceeds upper corner {hi}")
            sel = Selector("box", lo=tuple(lo), hi=tuple(hi), key=key)
        elif kind == "point":
            sel = Selector("point", point=tuple(t.read(SEL_POINT)), key=key)
        elif kind == "line":
            a, b = t.read(SEL_LINE)
            if a == b:
                raise InputError(f"{key}.line: its two ends coincide; use point = {a}")
            sel = Selector("line", line=(tuple(a), tuple(b)), key=key)
        elif kind == "normal":
            sel = Selector("normal", direction=_unit(t.read(SEL_NORMAL), f"{key}.normal"),
                           within_deg=t.read(SEL_WITHIN), key=key)
        elif kind == "oblique":
            point, normal = t.read(SEL_OBLIQUE)
            sel = Selector("oblique", origin=tuple(point), direction=_unit(normal, f"{key}.plane[1]"),
                           tolerance=t.read(SEL_TOLERANCE), key=key)
        elif kind == "cavity":
            sel = Selector("cavity", cavity=t.read(SEL_CAVITY), key=key)
        elif kind == "face":
            sel = Selector("face", face=t.read(SEL_FACE), key=key)
        else:
            sel = Selector("group", group=t.read(SEL_GROUP), key=key)
        t.done()
        return sel


def _unit(v: list, key: str) -> tuple:
    norm = sum(c * c for c in v) ** 0.5
    if norm == 0.0:
        raise InputError(f"{key} = {v}: must not be the zero vector")
    return tuple(c / norm for c in v)


def where(doc: str, required: bool = True, kinds: tuple | None = None) -> Key:
    return Key("where", "selector", doc, required=required, parse=Selector.parse, choices=kinds)
