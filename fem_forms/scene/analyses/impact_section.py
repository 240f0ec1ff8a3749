"""[sound] in a dynamic scene: [sound.impact], the sound of the contacts with an obstacle of [contact].

The contact forces of the run drive the part's free vibration modes (analyses/dynamic/impact.py); the keys that
say how it is heard (duration, sample rate, damping, listener) are the struck part's [sound] keys, declared once
in modal.py."""
from __future__ import annotations

from dataclasses import dataclass

from fem_forms.errors import InputError
from fem_forms.scene.analyses.modal import HEARING_KEYS, hearing_rules
from fem_forms.scene.reader import Key, Section, Table

HEARING_LIMIT = 20000.0          # Hz: the default upper end of the modes, the upper limit of hearing
IMPACT_KEYS = (
    Key("impact", "table", "the sound of the contacts: the contact forces of the run drive the part's free "
        "vibration modes", required=True, keys=(
            Key("obstacle", "string", "the [[contact.obstacle]] (by name) whose contact forces are heard",
                required=True),)),
    *HEARING_KEYS,
    Key("up_to", "number", "impact: every elastic mode of the free part (at rest, unloaded) below this frequency "
        "(by the modal analysis's inertia count)", unit="Hz", exclusive_minimum=0,
        default_note="20000 Hz, or the WAV's Nyquist frequency sample_rate / 2 if lower"),
    Key("count", "integer", "impact: the lowest elastic modes, this many (instead of up_to)", minimum=1,
        note="must be a whole number of modes, at least 1 (a scene may ask for 500; --no-limits lifts that)"),
)
_K = {k.name: k for k in IMPACT_KEYS}
_H = {k.name: k for k in HEARING_KEYS}
_D = {k.name: k for k in _H["damping"].keys}


@dataclass
class ImpactSoundSpec:
    """[sound] with [sound.impact]: which obstacle's contacts are heard, how many modes ring, how it is heard."""
    obstacle: str = ""
    duration: float = _H["duration"].field()
    alpha: float = _D["alpha"].field()            # Rayleigh damping zeta = alpha / (2 omega) + beta omega / 2
    beta: float = _D["beta"].field()
    sample_rate: int = _H["sample_rate"].field()
    modal_damping: list | None = _H["modal_damping"].field()
    listener: list | None = _H["listener"].field()
    air_density: float = _H["air_density"].field()
    speed_of_sound: float = _H["speed_of_sound"].field()
    up_to: float | None = _K["up_to"].field()      # Hz; None with count
    count: int | None = _K["count"].field()


def _impact_rules(s: ImpactSoundSpec, t: Table) -> None:
    hearing_rules(s, t)
    if s.count is not None and s.up_to is not None:
        raise InputError(f"{t.key('up_to')}: give either count or up_to, not both")
    if s.count is None and s.up_to is None:
        s.up_to = min(HEARING_LIMIT, s.sample_rate / 2)


IMPACT_SOUND = Section("sound", "the sound of the contacts with an obstacle, written as a WAV", ImpactSoundSpec,
                       keys=IMPACT_KEYS, rules=_impact_rules, absent=lambda: None,
                       refuse=(("strike", "a struck part's ring is for analysis = 'modal' (a dynamic scene hears "
                                          "its contacts: [sound.impact] obstacle = NAME)"),))


def check_impact(scene) -> None:
    """[sound.impact] names an analytic obstacle of the scene's [contact]."""
    s = scene.sound
    if s is None:
        return
    if scene.contact is None:
        raise InputError("sound.impact: needs a [contact] section with the obstacle it names (this scene has none)")
    names = [ob.name for ob in scene.contact.obstacle]
    if s.obstacle not in names:
        known = ", ".join(repr(n) for n in names) or "none"
        raise InputError(f"sound.impact.obstacle = {s.obstacle!r}: not an obstacle of [contact] (its obstacles: "
                         f"{known})")
    if scene.contact.obstacle[names.index(s.obstacle)].shape == "file":
        raise InputError(f"sound.impact.obstacle = {s.obstacle!r}: an obstacle file; the impact sound hears the "
                         "analytic obstacles (plane, sphere, box, cylinder)")
