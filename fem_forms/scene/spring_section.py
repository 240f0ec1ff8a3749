"""The [[spring]] section: the body held by springs to fixed points in space (physics/springs.py)."""
from __future__ import annotations

from dataclasses import dataclass

from fem_forms.errors import InputError
from fem_forms.scene.reader import Key, Section, Table
from fem_forms.scene.selectors import AREA_SELECTORS, Selector, where

SPRING_KEYS = (
    Key("name", "string", "the spring's name in results.json springs", default_note="spring0, spring1, ..."),
    where("the surface the spring pulls on (its pull spread over that area)", kinds=AREA_SELECTORS),
    Key("anchor", "vector", "the fixed point the spring is tied to", unit="m", length=3, required=True),
    Key("stiffness", "number", "the spring's stiffness along its line", unit="N/m", required=True,
        exclusive_minimum=0),
    Key("length", "number", "the spring's rest length (shorter than its length at the start: it pulls from "
        "the start)", unit="m", minimum=0, default_note="its length at the start: no force at rest"),
)


@dataclass
class SpringSpec:
    """One [[spring]] table."""
    where: Selector
    anchor: list
    stiffness: float
    name: str | None = None
    length: float | None = None


def _rules(s: SpringSpec, t: Table) -> None:
    if s.name is not None and not s.name.replace("_", "").replace("-", "").isalnum():
        raise InputError(f"{t.key('name')} = {s.name!r}: letters, digits, '-' and '_' only")


SPRING = Section("spring", "a spring tying a surface of the body to a fixed point", SpringSpec, keys=SPRING_KEYS,
                 array=True, rules=_rules)
