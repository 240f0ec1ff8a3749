"""The [thermal] section (conduction, expansion, E(T), boundary conditions): one declaration read by the
thermal analysis and by the static and dynamic analyses it couples into."""
from __future__ import annotations

from dataclasses import dataclass

from fem_forms.keys import spec_class
from fem_forms.errors import InputError
from fem_forms.scene.materials import THERMAL_CONSTANTS
from fem_forms.scene.reader import Key, Section, Table
from fem_forms.scene.selectors import AREA_SELECTORS, Selector, where

BOUNDARY_KINDS = ("temperature", "convection", "radiation")
BOUNDARY_KEYS = (
    where("boundary facets the condition acts on", kinds=AREA_SELECTORS),
    Key("temperature", "either", "prescribed temperature: a number, or { history = [[t, T], ...] } "
        "(piecewise linear in time, held after the last)", keys=(
            Key("temperature", "number", "a fixed temperature", unit="K"),
            Key("temperature", "table", "a temperature history", keys=(
                Key("history", "points", "[time, temperature] pairs", unit="s, K", length=2, required=True,
                    min_items=1, note="must list [time, temperature] pairs"),)))),
    Key("convection", "either", "heat loss h (T - ambient) per unit area", keys=(
        Key("convection", "table", "{ h = ..., ambient = ... }", keys=(
            Key("h", "number", "film coefficient", unit="W/(m^2 K)", required=True, exclusive_minimum=0),
            Key("ambient", "number", "ambient temperature", unit="K", required=True))),)),
    Key("radiation", "either", "heat loss emissivity sigma_SB (T^4 - ambient^4) per unit area (absolute "
        "temperatures: see thermal.absolute_zero)", keys=(
            Key("radiation", "table", "{ emissivity = ..., ambient = ... }", keys=(
                Key("emissivity", "number", "surface emissivity", required=True, exclusive_minimum=0,
                    maximum=1, note="emissivity must lie in (0, 1]"),
                Key("ambient", "number", "ambient (surroundings) temperature", unit="K", required=True))),)),
)

THERMAL_KEYS = (
    Key("conductivity", "number", "thermal conductivity k (required unless every material gives its own)",
        unit="W/(m K)", exclusive_minimum=0),
    Key("specific_heat", "number", "specific heat c (transient heat needs it, with material.rho)",
        unit="J/(kg K)", exclusive_minimum=0),
    Key("expansion", "number", "linear thermal expansion coefficient alpha", default=0.0, unit="1/K"),
    Key("reference_temperature", "number", "stress-free temperature", default=0.0, unit="K"),
    Key("initial_temperature", "number", "temperature at t = 0 (transient)", default=0.0, unit="K"),
    Key("modulus_slope", "number", "dE/dT: E(T) = E + modulus_slope (T - reference_temperature)", default=0.0,
        unit="Pa/K"),
    Key("damping_heat", "boolean", "power dissipated by viscous damping heats the part (dynamic only)",
        default=False),
    Key("absolute_zero", "number", "absolute zero in the scene's temperature unit, for radiation (0 for kelvin, "
        "-273.15 for Celsius)", default=0.0, unit="K"),
    Key("boundary", "tables", "thermal boundary conditions [[thermal.boundary]]: where, and exactly one of "
        "temperature, convection, radiation (boundaries not named are insulated)", default=[],
        keys=BOUNDARY_KEYS),
)


@dataclass
class ThermalBoundary:
    """One boundary condition: a prescribed temperature (constant or history), convection or radiation."""
    where: Selector
    kind: str                          # one of BOUNDARY_KINDS
    value: float = 0.0                 # temperature (kind temperature, no history)
    history: list | None = None        # [[t, T], ...] piecewise linear
    h: float = 0.0                     # convection film coefficient
    emissivity: float = 0.0
    ambient: float = 0.0

    @property
    def type(self) -> str:
        """The kind, under the name the facet tagging of loads reads (physics/supports.py load_regions)."""
        return self.kind


ThermalSpec = spec_class(
    "ThermalSpec", "[thermal]: conduction, heat capacity, expansion, E(T) and the boundary conditions.",
    THERMAL_KEYS, __name__)


def _boundary(data: dict, key: str) -> ThermalBoundary:
    given = [k for k in BOUNDARY_KINDS if data.get(k) is not None]
    if len(given) != 1:
        raise InputError(f"{key}: give exactly one of temperature, convection or radiation"
                         + (f" (got {', '.join(given)})" if given else ""))
    kind, value = given[0], data[given[0]]
    b = ThermalBoundary(where=data["where"], kind=kind)
    if kind == "temperature":
        if isinstance(value, dict):
            b.history = value["history"]
            if any(q[0] <= p[0] for p, q in zip(b.history, b.history[1:])):
                raise InputError(f"{key}.temperature.history: times must increase")
        else:
            b.value = value
    elif kind == "convection":
        b.h, b.ambient = value["h"], value["ambient"]
    else:
        b.emissivity, b.ambient = value["emissivity"], value["ambient"]
    return b


def _thermal_rules(s: ThermalSpec, t: Table) -> None:
    s.boundary = [_boundary(d, f"{t.key('boundary')}[{i}]") for i, d in enumerate(s.boundary)]
    radiating = [b for b in s.boundary if b.kind == "radiation"]
    for b in radiating:
        if b.ambient < s.absolute_zero:
            raise InputError(f"{t.key('boundary')}: radiation ambient {b.ambient} is below absolute zero "
                             f"({s.absolute_zero}); set thermal.absolute_zero for the scene's temperature unit")


THERMAL = Section("thermal", "heat conduction, thermal expansion and E(T): temperature is a field of the analysis",
                  ThermalSpec, keys=THERMAL_KEYS, rules=_thermal_rules, absent=lambda: None)

def check_coupled(scene) -> None:
    """Rules across sections for any analysis with [thermal]."""
    th = scene.thermal
    if th is None:
        given = next(((m, k) for m in scene.materials for k in THERMAL_CONSTANTS if getattr(m, k) is not None),
                     None)
        if given is not None:
            raise InputError(f"{given[0].key}.{given[1]}: needs a [thermal] section (no temperature field without)")
        return
    transient = scene.analysis == "dynamic" or (scene.analysis == "thermal" and scene.dynamic is not None)
    for m in scene.materials:
        if m.conductivity is None and th.conductivity is None:
            raise InputError(f"thermal.conductivity: missing (required: {m.key} gives no conductivity of "
                             "its own)")
        if transient and m.specific_heat is None and th.specific_heat is None:
            raise InputError("thermal.specific_heat: missing (required for transient heat"
                             + (f"; {m.key} gives none of its own)" if scene.several_materials else ")"))
        if transient and m.rho <= 0:
            raise InputError(f"{m.key}.rho: transient heat needs a positive density")
    if scene.several_materials and th.modulus_slope != 0.0:
        raise InputError("thermal.modulus_slope: not implemented for several materials (one E(T) slope for "
                         "materials of different E has no meaning yet)")
    if th.damping_heat and scene.analysis != "dynamic":
        raise InputError(f"thermal.damping_heat: only for analysis = 'dynamic' (this scene's is {scene.analysis!r})")
    if th.damping_heat and not (scene.damping.shear or scene.damping.bulk):
        raise InputError("thermal.damping_heat: needs viscous damping ([damping] viscous = { shear = ..., bulk = ... })")
    if not transient and not th.boundary:
        raise InputError("thermal.boundary: a steady temperature needs at least one [[thermal.boundary]] with "
                         "temperature, convection or radiation (all insulated: no unique answer)")
    if any(b.history for b in th.boundary) and not transient:
        raise InputError("thermal.boundary: a temperature history needs a transient analysis "
                         "(analysis = 'thermal' with [dynamic])")
