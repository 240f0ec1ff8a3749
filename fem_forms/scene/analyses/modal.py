"""Modal analysis: its [modal] and [sound] sections, their keys and rules."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from fem_forms.keys import spec_class
from fem_forms.errors import InputError
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.reader import Key, Section, Table

MODAL_KEYS = (
    Key("count", "integer", "number of elastic modes", default=6, minimum=1,
        note="must be a whole number of modes, at least 1 (a scene may ask for 500; --no-limits lifts that)"),
    Key("up_to", "number", "every elastic mode below this frequency, however many (instead of count)",
        unit="Hz", exclusive_minimum=0),
    Key("prestress", "boolean", "modes about the static equilibrium under the scene's loads", default=False),
    Key("mass", "string", "mass matrix", default="consistent", choices=("consistent", "lumped")),
)


ModalSpec = spec_class("ModalSpec", "[modal]: how many elastic modes, about which state, with which mass matrix.",
                       MODAL_KEYS, __name__)


def _modal_rules(s: ModalSpec, t: Table) -> None:
    if s.up_to is not None and t.has("count"):
        raise InputError(f"{t.key('up_to')}: give either count or up_to, not both")


STRIKE = Key("strike", "table", "where and how the body is struck", required=True, keys=(
    Key("point", "vector", "struck point", unit="m", required=True, length=3),
    Key("direction", "vector", "direction of the blow (normalised)", required=True, length=3)))
# the keys every [sound] shares (a struck part's here, a dynamic scene's impact in impact_section.py)
HEARING_KEYS = (
    Key("duration", "number", "length of the sound", default=2.0, unit="s", exclusive_minimum=0),
    Key("sample_rate", "integer", "samples per second of the WAV", default=44100, unit="Hz",
        minimum=1000, maximum=384000, note="must lie in 1000..384000 Hz"),
    Key("damping", "table", "Rayleigh damping zeta = alpha / (2 omega) + beta omega / 2", keys=(
        Key("alpha", "number", "mass-proportional damping", default=1.0, unit="1/s", minimum=0),
        Key("beta", "number", "stiffness-proportional damping", default=1e-7, unit="s", minimum=0))),
    Key("modal_damping", "points", "[f, zeta] pairs: each mode's damping ratio interpolated linearly in f, "
        "constant beyond the ends (instead of damping)", unit="Hz, 1", length=2, min_items=1,
        note="must list at least one [f, zeta] pair"),
    Key("listener", "vector", "hear the radiated sound pressure at this point in the air instead of the "
        "motion of the struck point", unit="m", length=3),
    Key("air_density", "number", "density of the air the part radiates into", default=1.2, unit="kg/m^3",
        exclusive_minimum=0),
    Key("speed_of_sound", "number", "speed of sound in that air", default=343.0, unit="m/s", exclusive_minimum=0),
)
SOUND_KEYS = (STRIKE, *HEARING_KEYS)
_SOUND = {k.name: k for k in SOUND_KEYS}
_DAMPING = {k.name: k for k in _SOUND["damping"].keys}


@dataclass
class SoundSpec:
    """[sound]: a modal impulse response at a struck point, written as a WAV."""
    point: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    direction: list = field(default_factory=lambda: [0.0, 0.0, 1.0])   # unit length after parsing
    duration: float = _SOUND["duration"].field()
    alpha: float = _DAMPING["alpha"].field()      # Rayleigh damping zeta = alpha / (2 omega) + beta omega / 2
    beta: float = _DAMPING["beta"].field()
    sample_rate: int = _SOUND["sample_rate"].field()
    modal_damping: list | None = _SOUND["modal_damping"].field()   # [[f, zeta], ...]: replaces alpha, beta
    listener: list | None = _SOUND["listener"].field()             # None: the struck point's motion
    air_density: float = _SOUND["air_density"].field()
    speed_of_sound: float = _SOUND["speed_of_sound"].field()


def _damping_table_rules(pairs: list, key: str) -> None:
    for i, (f, zeta) in enumerate(pairs):
        if f <= 0:
            raise InputError(f"{key}[{i}] = {[f, zeta]}: the frequency must be positive")
        if i and f <= pairs[i - 1][0]:
            raise InputError(f"{key}[{i}] = {[f, zeta]}: frequencies must increase")
        if not 0 <= zeta < 1:
            raise InputError(f"{key}[{i}] = {[f, zeta]}: zeta must lie in [0, 1)")


def hearing_rules(s, t: Table) -> None:
    """The rules of the shared [sound] keys: one damping law, a damping table that makes sense (the WAV's length: its
    cap in scene/limits.py)."""
    if s.modal_damping is not None:
        if t.has("damping"):
            raise InputError(f"{t.key('modal_damping')}: give either damping (Rayleigh) or modal_damping, not both")
        _damping_table_rules(s.modal_damping, t.key("modal_damping"))


def _sound_rules(s: SoundSpec, t: Table) -> None:
    hearing_rules(s, t)
    norm = math.sqrt(sum(c * c for c in s.direction))
    if norm == 0:
        raise InputError(f"sound.strike.direction = {s.direction}: must not be the zero vector")
    s.direction = [c / norm for c in s.direction]


def _check(scene) -> None:
    for m in scene.materials:
        if m.rho <= 0:
            raise InputError(f"{m.key}.rho: modal analysis needs a positive density")


ANALYSIS = Analysis(
    name="modal",
    doc="natural frequencies and mode shapes (optionally prestressed) and the sound when struck",
    runner="fem_forms.analyses.modal:run",
    sections=(
        Section("modal", "how many elastic modes, about which state, with which mass matrix", ModalSpec,
                keys=MODAL_KEYS, rules=_modal_rules),
        Section("sound", "a modal impulse response at a struck point, written as a WAV", SoundSpec,
                keys=SOUND_KEYS, rules=_sound_rules, absent=lambda: None,
                refuse=(("impact", "the sound of contacts is for analysis = 'dynamic' with [contact] (a modal "
                                   "scene hears a struck part: [sound.strike])"),)),
    ),
    outputs=("results.json", "modes.xdmf", "modes.png", "sound.wav", "spectrogram.png"),
    check=_check,
)
