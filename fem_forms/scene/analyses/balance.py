"""Balance design analysis: its [balance] section (goal, gravity, contact, margin, shell, elastic, and the
keys of each goal). Declared once here; the reader, the JSON Schema and the runner all read these."""
from __future__ import annotations

from dataclasses import dataclass, field
import math

from fem_forms.errors import InputError
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.analyses.contact_section import CONTACT
from fem_forms.scene.reader import Key, Section, Table, Variants

GOAL = Key("goal", "string", "check: report only; stand, spin, swim, swing: carve the interior so the part "
           "stands, spins, floats upright or rocks back", default="stand",
           choices=("check", "stand", "spin", "swim", "swing"))
COMMON_KEYS = (
    Key("gravity", "vector", "gravitational acceleration for the balance", unit="m/s^2", length=3,
        default_note="the scene's gravity load, else [0, 0, -9.81]"),
    Key("contact_tolerance", "number", "mesh points this close to the lowest point (along gravity) touch the "
        "ground", default=1e-3, unit="m", exclusive_minimum=0),
    Key("margin_angle", "number", "stand: the CoM must lie inside the support polygon shrunk by h tan(angle); "
        "swing: the CoM at least R sin(angle) below the rocking centre", default=5.0, unit="deg",
        minimum=0, exclusive_maximum=90),
    Key("shell", "number", "cells closer than this to the surface stay solid (the wall kept)", default=0.004,
        unit="m", minimum=0),
    Key("elastic", "boolean", "evaluate and design on the shape deformed under gravity (held by [[fix]] or "
        "resting on a [contact] floor)",
        default=False),
    Key("fill_density", "number", "density of carved cells (0: empty; below rho a lighter fill; above rho a "
        "ballast, e.g. steel shot or lead in a hollow)",
        default=0.0, unit="kg/m^3", minimum=0),
    Key("fill_stiffness", "number", "elastic: Young's modulus of the carved cells over the solid's, E_fill / E "
        "(the solid's energy density scaled: same model and Poisson ratio); required when fill_density > 0",
        exclusive_minimum=0, maximum=1,
        default_note="1e-6, an ersatz for empty cells, when fill_density = 0"),
)
SPIN_KEYS = (
    Key("axis", "vector", "spin axis direction (normalised)", default=[0.0, 0.0, 1.0], length=3),
    Key("kind", "string", "top: spins on its lowest point along the axis; yoyo: about its centre",
        default="top", choices=("top", "yoyo")),
)
SWIM_KEYS = (
    Key("water_density", "number", "density of the liquid", default=1000.0, unit="kg/m^3",
        exclusive_minimum=0),
    Key("waterline", "number", "height of the water surface above the lowest point, floating upright",
        unit="m", exclusive_minimum=0, note="must be positive (required for goal = \"swim\")"),
    Key("min_metacentric_height", "number", "GM must be at least this", unit="m", minimum=0,
        default_note="1 % of the part's size"),
)
VARIANTS = Variants(GOAL, {"check": SWIM_KEYS[:2], "stand": (), "spin": SPIN_KEYS, "swim": SWIM_KEYS,
                           "swing": ()})
_K = {k.name: k for k in (GOAL,) + COMMON_KEYS + SPIN_KEYS + SWIM_KEYS}
EMPTY_FILL_STIFFNESS = 1e-6     # relative stiffness of an empty carved cell (elastic): almost none, never 0


def fill_stiffness(b: "BalanceSpec") -> float:
    """E_fill / E of the carved cells: the given fill_stiffness, else the ersatz of an empty fill."""
    return b.fill_stiffness if b.fill_stiffness is not None else EMPTY_FILL_STIFFNESS


@dataclass
class BalanceSpec:
    """[balance]: which balance goal, under which gravity, with which contact, margin and wall."""
    goal: str = _K["goal"].field()
    gravity: list | None = None                    # None: the scene's gravity load, else -z
    contact_tolerance: float = _K["contact_tolerance"].field()
    margin_angle: float = _K["margin_angle"].field()
    shell: float = _K["shell"].field()
    elastic: bool = _K["elastic"].field()
    fill_density: float = _K["fill_density"].field()
    fill_stiffness: float | None = None            # None: EMPTY_FILL_STIFFNESS for an empty fill
    axis: list = field(default_factory=lambda: [0.0, 0.0, 1.0])     # spin: unit length after parsing
    kind: str = _K["kind"].field()
    water_density: float = _K["water_density"].field()
    waterline: float | None = None                 # swim (and check, if given): m above the lowest point
    min_metacentric_height: float | None = None    # swim; None: 1 % of the part's size


def _rules(s: BalanceSpec, t: Table) -> None:
    for name in ("gravity", "axis"):
        v = getattr(s, name)
        if v is not None:
            n = math.sqrt(sum(c * c for c in v))
            if n == 0:
                raise InputError(f"{t.key(name)} = {v}: must not be the zero vector")
    s.axis = [c / math.sqrt(sum(c * c for c in s.axis)) for c in s.axis]


def _inverse_rules(s: BalanceSpec, t: Table) -> None:
    """[balance] in an inverse scene: the sag is the inverse design's own, so elastic has no place."""
    _rules(s, t)
    if s.elastic:
        raise InputError(f"{t.key('elastic')} = true: not in an inverse scene (its sagged shape is the target, "
                         "so the carving is designed there and the rest shape for the carving); remove it")


def check_carving(scene) -> None:
    """Rules of [balance] in an inverse scene (absent: scene.balance is None): the balance rules, with the
    carved cells' stiffness as in an elastic balance scene."""
    b = scene.balance
    if b is None:
        return
    if scene.inverse.method != "direct":
        raise InputError(f"inverse.method = {scene.inverse.method!r}: with [balance] (carving) only 'direct'")
    if scene.several_materials:
        raise InputError("balance: carving in an inverse scene takes one [material] (the carved rest mesh's "
                         "volume groups are \"solid\" and \"void\")")
    load_g = next((ld.g for ld in scene.load if ld.type == "gravity"), None)
    if b.gravity is not None and load_g is not None and list(b.gravity) != list(load_g):
        raise InputError(f"balance.gravity = {list(b.gravity)}: differs from the gravity load's g = {list(load_g)}, "
                         "which sags the part; the stance is judged under that one (leave balance.gravity out)")
    _check(scene, elastic=True)


def _check(scene, elastic: bool | None = None) -> None:
    b = scene.balance
    elastic = b.elastic if elastic is None else elastic
    for m in scene.materials:
        if m.rho <= 0:
            raise InputError(f"{m.key}.rho: balance design needs a positive density")
    if all(b.fill_density == m.rho for m in scene.materials) and b.goal != "check":
        raise InputError(f"balance.fill_density = {b.fill_density}: equals material.rho: carving would move "
                         "no mass (lighter fills hollow the part, heavier ones ballast it)")
    if b.goal == "swim" and b.waterline is None:
        raise InputError("balance.waterline: missing (required for goal = 'swim')")
    if elastic and b.fill_density > 0 and b.fill_stiffness is None:
        raise InputError(f"balance.fill_stiffness: missing: with elastic = true or in an inverse scene the fill (fill_density = "
                         f"{b.fill_density}) is a second material; give its Young's modulus over the solid's, "
                         f"E_fill / E")
    contact = getattr(scene, "contact", None)
    if b.elastic and not scene.fix and contact is None:
        raise InputError("balance.elastic = true: needs [[fix]] supports that hold the part (e.g. its foot) or a "
                         "[contact] floor it rests on")
    if contact is not None and not b.elastic:
        raise InputError("contact: for balance only with elastic = true (the rigid part meets its ground at "
                         "balance.contact_tolerance)")


BALANCE = Section("balance", "what must balance and how the interior may be carved", BalanceSpec,
                  keys=COMMON_KEYS, variants=VARIANTS, rules=_rules)
# [balance] in an inverse scene: the same keys, the carving designed on the target; absent: no carving
INVERSE_BALANCE = Section("balance", "inverse: carve the interior too, designed on the target shape (elastic "
                          "refused: the sag is the inverse design's own)", BalanceSpec, keys=COMMON_KEYS,
                          variants=VARIANTS, rules=_inverse_rules, absent=lambda: None)

ANALYSIS = Analysis(
    name="balance",
    doc="mass properties, and carving the interior so the part stands, spins, floats upright or rocks back",
    runner="fem_forms.analyses.balance:run",
    sections=(BALANCE,
              CONTACT),                  # [contact]: elastic = true, the sag resting on a floor instead of clamps
    outputs=("results.json", "void.stl", "outer.stl", "density.xdmf", "balance.png", "solid.vtu (when carved)"),
    check=_check,
)
