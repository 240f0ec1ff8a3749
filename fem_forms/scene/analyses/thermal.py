"""The thermal analysis: heat alone, steady without [dynamic], transient by backward Euler with [dynamic]
duration, dt, output_every (the only [dynamic] keys it reads). Its [thermal] section is scene/analyses/thermal_section.py."""
from __future__ import annotations

from fem_forms.errors import InputError
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.analyses.dynamic import DYNAMIC_KEYS, DynamicSpec
from fem_forms.scene.analyses.thermal_section import THERMAL, check_coupled
from fem_forms.scene.reader import Section, Table

# the thermal analysis reads only the time keys of [dynamic]
_TIME_KEYS = tuple(k for k in DYNAMIC_KEYS if k.name in ("duration", "dt", "output_every"))
HEAT_TIME = Section("dynamic", "transient heat: duration, time step, output every N steps", DynamicSpec,
                    keys=_TIME_KEYS, rules=lambda s, t: _time_rules(s, t), absent=lambda: None)


def _time_rules(s: DynamicSpec, t: Table) -> None:
    if s.dt > s.duration:
        raise InputError(f"{t.key('dt')} = {s.dt}: longer than duration = {s.duration}")


def _check(scene) -> None:
    if scene.thermal is None:
        raise InputError("thermal: missing (required table for analysis = 'thermal')")
    check_coupled(scene)


ANALYSIS = Analysis(
    name="thermal",
    doc="heat conduction: steady, or transient (backward Euler) with [dynamic] duration and dt",
    runner="fem_forms.analyses.thermal:run",
    sections=(THERMAL, HEAT_TIME),
    outputs=("results.json", "temperature.xdmf", "probes.csv"),
    check=_check,
)
