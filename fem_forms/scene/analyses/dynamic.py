"""Transient dynamics: its [dynamic] (time, scheme, mass, start) and [damping] sections."""
from __future__ import annotations


from fem_forms.keys import spec_class
from fem_forms.errors import InputError
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.analyses.contact_section import CONTACT
from fem_forms.scene.analyses.fracture_section import FRACTURE
from fem_forms.scene.analyses.impact_section import IMPACT_SOUND, check_impact
from fem_forms.scene.analyses.thermal_section import THERMAL, check_coupled
from fem_forms.scene.reader import Key, Section, Table

SCHEMES = ("newmark", "generalized-alpha", "backward-euler", "central-difference")
DYNAMIC_KEYS = (
    Key("duration", "number", "simulated time", default=1.0, unit="s", exclusive_minimum=0),
    Key("dt", "number", "time step (implicit schemes may cut or adapt it)", default=1e-3, unit="s",
        exclusive_minimum=0),
    Key("scheme", "string", "newmark (average acceleration), generalized-alpha (Chung-Hulbert), backward-euler "
        "(first order, damps vibrations: robust with contact) or central-difference (explicit, lumped mass)",
        default="newmark", choices=SCHEMES),
    Key("rho_inf", "number", "generalized-alpha spectral radius at infinite frequency", default=0.8,
        minimum=0, maximum=1),
    Key("mass", "string", "mass matrix: consistent, or lumped (HRZ; required for central-difference)",
        default="consistent", choices=("consistent", "lumped")),
    Key("adaptive", "boolean", "error-controlled step size (implicit schemes)", default=False),
    Key("tolerance", "number", "adaptive: local error per step relative to the largest displacement",
        default=1e-3, exclusive_minimum=0),
    Key("refine_events", "integer", "with contact (implicit schemes): a step with an impact, a bounce or a "
        "stick-slip transition is redone shorter, down to dt / 2^N, then the step grows back (0: never; 4 locates "
        "a first touch to dt / 16, but a rule firing at every step can pump energy into Newmark)", default=0,
        minimum=0, maximum=10),
    Key("output_every", "integer", "fields and animation frames every N steps (probes, energies every step)",
        default=10, exclusive_minimum=0),
    Key("checkpoint_every", "integer", "checkpoint every N steps for --restart (0: never)", default=100,
        minimum=0),
    Key("initial", "string", "rest, or static: start from the equilibrium under initial_loads (and the "
        "other loads at their t = 0 values), then release the initial_loads", default="rest",
        choices=("rest", "static")),
    Key("initial_loads", "vector", "indices into [[load]] of the loads held for initial = static "
        "(released at t = 0)", default=[], integer=True, minimum=0),
    Key("initial_velocity", "either", "initial velocity field", default=[0.0, 0.0, 0.0], attr="velocity",
        keys=(Key("velocity", "vector", "a uniform velocity [vx, vy, vz]", unit="m/s", length=3),
              Key("rotation", "table", "a rigid rotation { angular = [wx, wy, wz], about = [x, y, z] }",
                  keys=(Key("angular", "vector", "angular velocity", unit="rad/s", required=True, length=3),
                        Key("about", "vector", "a point on the axis", unit="m", default=[0.0, 0.0, 0.0],
                            length=3))))),
)


DynamicSpec = spec_class("DynamicSpec", "[dynamic]: how long, with which step and scheme, from which initial state.",
                         DYNAMIC_KEYS, __name__)


def _dynamic_rules(s: DynamicSpec, t: Table) -> None:
    if s.scheme == "central-difference" and s.mass != "lumped":
        raise InputError(f"{t.key('mass')} = {s.mass!r}: central-difference needs mass = \"lumped\"")
    if s.dt > s.duration:
        raise InputError(f"{t.key('dt')} = {s.dt}: longer than duration = {s.duration}")
    if s.adaptive and s.scheme == "backward-euler":
        raise InputError(f"{t.key('adaptive')} = true: the step's error estimate is second-order schemes' "
                         "(newmark, generalized-alpha); backward-euler is first order")
    if s.initial_loads and s.initial != "static":
        raise InputError(f"{t.key('initial_loads')}: only with initial = \"static\"")


RAYLEIGH = Key("rayleigh", "table", "Rayleigh damping C = alpha M + beta K (K: the tangent at rest; beta K "
               "also damps rotations, so under large rotations use viscous)", keys=(
    Key("alpha", "number", "mass-proportional coefficient", default=0.0, unit="1/s", minimum=0),
    Key("beta", "number", "stiffness-proportional coefficient", default=0.0, unit="s", minimum=0)))
VISCOUS = Key("viscous", "table", "Kelvin-Voigt viscous stress from the rate of Green strain", keys=(
    Key("shear", "number", "shear viscosity (deviatoric strain rate)", default=0.0, unit="Pa s", minimum=0),
    Key("bulk", "number", "bulk viscosity (volumetric strain rate)", default=0.0, unit="Pa s", minimum=0)))
DAMPING_KEYS = (RAYLEIGH, VISCOUS)


DampingSpec = spec_class(
    "DampingSpec", "[damping]: Rayleigh coefficients and Kelvin-Voigt viscosities (all zero: undamped).",
    DAMPING_KEYS, __name__)


def _check(scene) -> None:
    n = len(scene.load)
    for i in scene.dynamic.initial_loads:
        if i >= n:
            raise InputError(f"dynamic.initial_loads: {i} is not a [[load]] index (the scene has {n} loads)")
    for i, fix in enumerate(scene.fix):
        if any(v != 0.0 for v in fix.value):
            raise InputError(f"fix[{i}].value: dynamic analysis holds supports fixed (value must be zero)")
    if scene.contact is not None and scene.dynamic.scheme == "central-difference":
        raise InputError("contact: not with dynamic.scheme = 'central-difference' (the barrier needs the implicit "
                         "step's step filter); use 'newmark', 'generalized-alpha' or 'backward-euler'")
    check_coupled(scene)
    check_impact(scene)


ANALYSIS = Analysis(
    name="dynamic",
    doc="transient motion (Newmark, generalized-alpha or central difference) with damping and energy balance",
    runner="fem_forms.analyses.dynamic:run",
    sections=(
        Section("dynamic", "time span, step, scheme, mass matrix and initial state", DynamicSpec,
                keys=DYNAMIC_KEYS, rules=_dynamic_rules),
        Section("damping", "Rayleigh and viscous (Kelvin-Voigt) damping", DampingSpec, keys=DAMPING_KEYS),
        THERMAL,                         # [thermal]: transient heat, staggered with the motion step by step
        CONTACT,                         # [contact]: obstacles and self-contact in the implicit step
        FRACTURE,                        # [fracture]: the damage minimized with the motion in each implicit step
        IMPACT_SOUND,                    # [sound.impact]: the contact forces ring the part's modes
    ),
    outputs=("results.json", "probes.csv", "energy.csv", "motion.xdmf", "motion.gif", "history.png",
             "checkpoint/", "impact.wav", "impact_spectrogram.png"),
    check=_check,
)
