"""The cases of the verification manual: each a scene in verification/cases/, the numbers read from its
results.json (or probes.csv), their targets with sources and tolerances."""
from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path
from typing import Callable

from time_histories import (cantilever_tip_static, damped_fit, first_mode_share, harmonic_fit,
                            rayleigh_decay_per_cycle, rayleigh_zeta)
import targets
from targets import uniaxial_neo_hookean, hydrostatic_neo_hookean, cantilever_gravity_sag, cantilever_frequency, bar_conduction, thick_sphere_outer_displacement
from targets import ogden_sphere_maximum, ogden_sphere_pressure, bimetal_curvature, prony_relaxation


class NotAvailable(Exception):
    """The number is not in results.json (a key the package does not write yet)."""


# --- cases ------------------------------------------------------------------------------------
@dataclass
class Row:
    """One compared number: `extract(results, reference)` -> value; error relative to the target
    (`relative`) or absolute; pass if |error| <= tolerance."""
    quantity: str
    target: Callable[[dict], float] | float
    extract: Callable[[dict, dict], float]
    tolerance: float
    unit: str = ""
    relative: bool = True
    scale: float = 1.0            # display unit factor (e.g. 1e-6 for MPa)


@dataclass
class Case:
    name: str
    benchmark: str
    source: str
    scene: str                                       # file in verification/cases/
    rows: list
    fast: bool = True
    exit_status: int = 0                             # expected exit status of `fem-forms run`
    mesh: tuple | None = None                        # (geometry module, build kwargs): write the .msh first
    reference: str | None = None                     # script in verification/reference/ printing JSON
    notes: str = ""
    side_check: str | None = None                    # script whose output is reported, not compared


MU_SPHERE = 3.0 / (2 * 1.499)          # E = 3, nu = 0.499 in the inflated sphere cases
OGDEN = ("closed form for the incompressible neo-Hookean thick sphere (Ogden, Non-linear Elastic Deformations, "
         "1984, section 5.2.6)")


def cavity_stretch(res: dict) -> float:
    """The inner hoop stretch l_a = (V / V0)^(1/3) from results.json cavities.inside."""
    cav = (res.get("cavities") or {}).get("inside")
    if cav is None:
        raise NotAvailable("results.json has no cavities.inside")
    return (cav["volume"] / (cav["volume"] - cav["volume_change"])) ** (1 / 3)


def pair_stretches(res: dict) -> list:
    """The two balloons' inner hoop stretches, 1 + |u_x| at their inner poles (probes a, b)."""
    return [1 + abs(probe(k, "displacement", 0)(res, {})) for k in "ab"]


def pair_total(res: dict) -> float:
    """l_a^3 + l_b^3: what the two balloons hold together, in units of one's rest volume."""
    return sum(s**3 for s in pair_stretches(res))


def probe(name: str, key: str, *index):
    """results.json probes[name][key][index...]; NotAvailable if the key is missing."""
    def get(res: dict, ref: dict):
        p = (res.get("probes") or {}).get(name)
        if p is None or key not in p:
            raise NotAvailable(f"results.json has no probes.{name}.{key}")
        v = p[key]
        for i in index:
            v = v[i]
        return float(v)
    return get


def frequency(i: int):
    def get(res, ref):
        f = res.get("frequencies_hz")
        if not f or len(f) <= i:
            raise NotAvailable(f"results.json has no frequencies_hz[{i}]")
        return float(f[i])
    return get


# --- time histories: probes.csv of a dynamic run ---------------------------------------------------
def history(res: dict, column: str):
    """(time, column) arrays from the run's probes.csv (the file results.json names in `files`)."""
    import numpy as np
    name = (res.get("files") or {}).get("probes")
    path = Path(res.get("run_dir", ".")) / (name or "probes.csv")
    if not name or not path.is_file():
        raise NotAvailable("the run wrote no probes.csv")
    data = np.genfromtxt(path, delimiter=",", names=True)
    if column not in data.dtype.names:
        raise NotAvailable(f"probes.csv has no column {column}")
    return data["time"], data[column]


def swing(column: str, what: str, sign: float = 1.0, after: float = 0.0):
    """A number from the fitted swing of probes.csv's `column` (times >= after): center, amplitude or
    frequency (harmonic fit); decay (per cycle) or damped_frequency (damped fit); peak (largest value)."""
    def get(res, ref):
        t, x = history(res, column)
        keep = t >= after
        t, x = t[keep], sign * x[keep]
        if what == "peak":
            return float(x.max())
        if what in ("decay", "damped_frequency"):
            s, w = damped_fit(t, x)
            return math.exp(-2 * math.pi * s / w) if what == "decay" else w / (2 * math.pi)
        c, a, w = harmonic_fit(t, x)
        return {"center": c, "amplitude": a, "frequency": w / (2 * math.pi)}[what]
    return get


T_UNI, E_BLOCK = 4.0e5, 1.0e6
DYN_ALPHA, DYN_BETA = 0.32, 0.005          # verification/cases/dynamic_rayleigh_decay.toml
FV32_HZ = [44.623, 130.03, 162.70, 246.05, 379.90, 391.44]
TUTORIAL_NEWTON = [8, 9, 10, 9, 8, 7, 6, 6, 6]

NAFEMS_LE = ("NAFEMS, The Standard NAFEMS Benchmarks, rev. 3, NAFEMS Ltd, 1990, test LE1")
NAFEMS_FV = ("NAFEMS, Selected Benchmarks for Natural Frequency Analysis (publication SBNFA), "
             "NAFEMS Ltd, 1987, test FV32")
BONET_WOOD = ("closed form; energy of Bonet & Wood, Nonlinear Continuum Mechanics for Finite Element "
              "Analysis, 2nd ed., Cambridge UP, 2008, ch. 6")
HILL = ("closed form: R. Hill, The Mathematical Theory of Plasticity, Oxford UP, 1950, ch. V "
        "(thick spherical shell, Tresca = von Mises under spherical symmetry)")
TUTORIAL = ("J. S. Dokken, The FEniCSx tutorial, ch. 2 Hyperelasticity, "
            "https://jsdokken.com/dolfinx-tutorial/chapter2/hyperelasticity.html (v0.5.0)")

HEMI_R = 0.05
HEMI_MASS = 1000.0 * 2 / 3 * math.pi * HEMI_R**3
BOX_L, BOX_B, BOX_H, BOX_T = 0.4, 0.2, 0.1, 0.037
HEMISPHERE = ("closed form: mass properties of homogeneous solids (J. L. Meriam, L. G. Kraige, Engineering "
              "Mechanics: Dynamics, Wiley, appendix D, table D/4)")
FLOTATION = ("closed form: Archimedes and the metacentre, BM = I_waterplane / V (K. J. Rawson, E. C. Tupper, "
             "Basic Ship Theory, 5th ed., Butterworth-Heinemann, 2001, vol. 1)")

SOLIDS = ("closed form: mass properties of homogeneous solids (J. L. Meriam, L. G. Kraige, Engineering "
          "Mechanics: Dynamics, Wiley, appendix D, table D/4); a cavity by difference of two solids and the "
          "parallel-axis theorem")
BLOCK = targets.block(0.3, 0.2, 0.5, 7800.0)                     # verification/cases/balance_box.toml
CYLINDER = targets.cylinder(0.05, 0.12, 1000.0)                  # balance_cylinder.toml
CONE = targets.cone(0.05, 0.12, 1000.0)                          # balance_cone.toml
HOLLOW_R, HOLLOW_r = 0.05, 0.03                                  # balance_hollow_hemisphere.toml
HOLLOW = targets.hollow_hemisphere(HOLLOW_R, HOLLOW_r, 1000.0)
FLOAT_CYL = targets.floating_cylinder(0.06, 0.05, 0.025)         # balance_floating_cylinder.toml

# Tolerances about twice the errors measured with these meshes (straight-sided tetrahedra inscribed in the
# curved surfaces lose volume: cylinder -0.12..-0.25 %, cone -0.3..-0.9 %, hollow hemisphere -0.2..-0.5 %,
# floating cylinder -0.09..-0.13 %); the flat-faced block is exact.
TOL_CYLINDER, TOL_CONE, TOL_HOLLOW, TOL_FLOAT = 0.005, 0.015, 0.01, 0.003


def mass_rows(t: dict, tolerance: float, base_z: float = 0.0) -> list:
    """Mass, CoM height above the base (at z = base_z), inertia about the CoM along z and across (x)."""
    return [Row("mass", t["mass"], lambda r, ref: float(r["mass"]), tolerance, "kg"),
            Row("CoM height above the base", t["z"], lambda r, ref: float(r["center_of_mass"][2]) - base_z,
                tolerance, "m"),
            Row("inertia about the axis (z)", t["axial"], lambda r, ref: float(r["inertia"][2][2]), tolerance,
                "kg m^2"),
            Row("transverse inertia about the CoM (x)", t["transverse"], lambda r, ref: float(r["inertia"][0][0]),
                tolerance, "kg m^2")]


def hertz(quantity: str):
    """Hertz's force (N) or contact radius (m) on the whole sphere from the quarter's results.json contact."""
    def get(res, ref):
        c = (res.get("contact") or {}).get("plane")
        if c is None:
            raise NotAvailable("results.json has no contact.plane")
        return 4 * float(c["force"][2]) if quantity == "force" else math.sqrt(4 * float(c["area"]) / math.pi)
    return get


def sliding_acceleration(res, ref) -> float:
    """Twice the t^2 coefficient of a parabola through the probe's slide (times >= 0.02 s) in probes.csv."""
    import numpy as np
    t, x = history(res, "c_ux")
    keep = t >= 0.02
    return 2.0 * float(np.polyfit(t[keep], x[keep], 2)[0])


HERTZ_R, HERTZ_E, HERTZ_NU, HERTZ_D = 0.01, 1.0e6, 0.3, 1.0e-5
JOHNSON = "Hertz's solution (K. L. Johnson, Contact Mechanics, Cambridge University Press, 1985, section 4.2)"


CASES = [
    Case("uniaxial_tension", "Uniaxial tension, neo-Hookean (stretch 1.54)", BONET_WOOD,
         "uniaxial_tension.toml",
         [Row("u_x at (2, 1, 0.5)", lambda r: (uniaxial_neo_hookean(T_UNI)[0] - 1) * 2.0,
              probe("corner", "displacement", 0), 1e-6, "m"),
          Row("u_y at (2, 1, 0.5)", lambda r: (uniaxial_neo_hookean(T_UNI)[1] - 1) * 1.0,
              probe("corner", "displacement", 1), 1e-6, "m")],
         notes="Homogeneous deformation: any mesh reproduces it to solver tolerance (Q2 hexahedra, 2x2x2)."),
    Case("hydrostatic_pressure", "Hydrostatic follower pressure p = 0.5 E, neo-Hookean", BONET_WOOD,
         "hydrostatic_pressure.toml",
         [Row("u_x at (1, 1, 1)", lambda r: hydrostatic_neo_hookean(0.5 * E_BLOCK) - 1,
              probe("corner", "displacement", 0), 1e-6, "m")],
         notes="Pressure acts on the deformed faces; a dead load of the same value would give a stretch "
               "1e-2 away, so the case tells follower from dead load."),
    Case("stvk_limit_load", "StVK uniaxial compression limit load E / (3 sqrt 3)",
         "closed form: P = E (l^3 - l) / 2 for StVK at nu = 0 is extremal at l = 1/sqrt 3 "
         "(the StVK model: Holzapfel, Nonlinear Solid Mechanics, Wiley, 2000, ch. 6)",
         "stvk_limit_load.toml",
         [Row("largest load carried |P|", E_BLOCK / (3 * math.sqrt(3)),
              lambda r, ref: float(r["load_reached"]) * 2 * E_BLOCK, 0.03, "Pa")],
         exit_status=3,
         notes="Asks for 2 E: the run must fail (exit 3, `converged` false) and report the load reached by "
               "its cut-backs (8 halvings: the limit is bracketed from below within a few %)."),
    Case("stvk_limit_arc_length", "StVK compression limit passed by arc length",
         "closed form as stvk_limit_load", "stvk_limit_arc_length.toml",
         [Row("largest load on the path |P|", E_BLOCK / (3 * math.sqrt(3)),
              lambda r, ref: float(r["peak_load_factor"]) * 2 * E_BLOCK, 0.005, "Pa")],
         exit_status=3,
         notes="control = \"arc-length\": the load factor is solved with the displacement and falls after the "
               "limit; the path ends at load factor 0 (exit 3) with peak_load_factor."),
    Case("inflated_sphere", "Thick neo-Hookean sphere b/a = 2 inflated to 0.6 mu (pressure control)", OGDEN,
         "inflated_sphere.toml",
         [Row("pressure at the stretch the cavity volume gives", lambda r: ogden_sphere_pressure(cavity_stretch(r), MU_SPHERE),
              lambda r, ref: float(r["cavities"]["inside"]["pressure"]), 0.01, "Pa")],
         fast=False, mesh=("thick_sphere", {"h": 0.3}),
         notes="The cavity's pressure as an energy -p (V - V0) with V = -1/3 int x . n da over the inner wall (the "
               "symmetry planes close it). nu = 0.499 (mixed P2/P1) stands in for incompressibility."),
    Case("inflated_sphere_limit", "Thick neo-Hookean sphere asked for 1.0 mu: the pressure maximum 0.8164 mu",
         OGDEN, "inflated_sphere_limit.toml",
         [Row("largest pressure carried", ogden_sphere_maximum(MU_SPHERE),
              lambda r, ref: float(r["load_reached"]) * 1.0007, 0.02, "Pa")],
         fast=False, exit_status=3, mesh=("thick_sphere", {"h": 0.3}),
         notes="Pressure control cannot pass the maximum: the run stops with \"limit point\" (exit 3); the flat "
               "facets of the coarse mesh make it 0.7 % stiffer."),
    Case("inflated_sphere_volume", "Thick neo-Hookean sphere past its maximum by volume control (l_a = 2.3)",
         OGDEN, "inflated_sphere_volume.toml",
         [Row("pressure on the falling branch", lambda r: ogden_sphere_pressure(cavity_stretch(r), MU_SPHERE),
              lambda r, ref: float(r["cavities"]["inside"]["pressure"]), 0.02, "Pa")],
         fast=False, mesh=("thick_sphere", {"h": 0.3}),
         notes="volume = 5.7 m^3 added: the pressure is a Lagrange multiplier solved with the displacement."),
    Case("two_balloons", "Two joined thick spheres past their maximum: one takes the air (volume control)",
         OGDEN + ", each sphere at the one pressure with l_a^3 + l_b^3 fixed", "two_balloons.toml",
         [Row("stretch of the balloon that took the air", lambda r: targets.ogden_balloon_pair(pair_total(r))[0],
              lambda r, ref: max(pair_stretches(r)), 0.01),
          Row("stretch of the other", lambda r: targets.ogden_balloon_pair(pair_total(r))[1],
              lambda r, ref: min(pair_stretches(r)), 0.01),
          Row("the one pressure", lambda r: ogden_sphere_pressure(targets.ogden_balloon_pair(pair_total(r))[0],
                                                                  3.0 / (2 * 1.45)),
              lambda r, ref: float(r["cavities"]["inside"]["pressure"]), 0.01, "Pa")],
         fast=False, mesh=("thick_sphere", {"h": 0.3, "pair": True}),
         notes="Inflated alike, the pair is a saddle (the tangent lost two eigenvalues, the volume holds one): the "
               "solver rejects it (results.json unstable_rejected), leaves it along its unstable mode and ends "
               "where one balloon took the air. The stretches are 1 + the inner poles' radial displacement; "
               "their cubes' sum, what the two hold together, gives Ogden's split. nu = 0.45 (displacement "
               "formulation) for incompressibility."),
    Case("thick_sphere_yield", "Thick sphere b/a = 2, perfectly plastic, P = 250 MPa (front c = 1.33 a)", HILL,
         "thick_sphere_yield.toml",
         [Row("outer displacement u(b)", thick_sphere_outer_displacement(250e6),
              probe("outer", "displacement", 0), 0.035, "m")],
         fast=False, mesh=("thick_sphere", {"h": 0.3}),
         notes="P2 tetrahedra of size 0.3 on flat-faceted spheres: the elastic u(b) at 100 MPa is off by the "
               "same -2.7 % (geometry), so the error is the facets', not the return mapping's."),
    Case("thick_sphere_collapse", "Thick sphere b/a = 2, collapse load 2 sigma_y ln(b/a)", HILL,
         "thick_sphere_collapse.toml",
         [Row("largest pressure carried", 2 * 240e6 * math.log(2.0),
              lambda r, ref: float(r["collapse"]["load_factor"]) * 350e6, 0.02, "MPa", scale=1e-6)],
         fast=False, exit_status=3, mesh=("thick_sphere", {"h": 0.3}),
         notes="Asks for 350 MPa: the run must exit 3 and report collapse.load_factor (4 halvings of the "
               "failing step bracket it from below)."),
    Case("cantilever_gravity", "Cantilever under gravity, P2 (L/h = 20)",
         "Euler-Bernoulli w L^4/(8EI) + Timoshenko shear term w L^2/(2 kappa G A) (Timoshenko & Gere, "
         "Mechanics of Materials)", "cantilever_gravity.toml",
         [Row("tip sag -u_z at (1, 0.025, 0.025)", lambda r: cantilever_gravity_sag(),
              lambda r, ref: -probe("tip", "displacement", 2)(r, ref), 0.01, "m")],
         notes="P2 tetrahedra 20x2x2; the clamp's local 3-D effects and the mesh are inside 1 %."),
    Case("bimetal_strip", "Steel-brass bimetal strip heated uniformly by 100 K (two materials)",
         "S. Timoshenko, Analysis of bi-metal thermostats, J. Opt. Soc. Am. 11 (1925) 233-255",
         "bimetal_strip.toml",
         [Row("tip deflection -u_z = kappa L^2 / 2",
              bimetal_curvature(0.001, 0.001, 2e11, 1e11, 1.2e-5, 1.9e-5, 100.0) * 0.1**2 / 2,
              lambda r, ref: -probe("tip", "displacement", 2)(r, ref), 0.01, "m")],
         notes="[[material]] steel below (box), brass above (the rest); linear, nu = 0; Q2 hexahedra 25x1x4, one "
               "layer of cells per 0.5 mm; the temperature is the steady solution with one end held at 100 K."),
    Case("phase_field_bar_at1", "AT1 phase-field bar in tension: elastic until the critical stress",
         "E. Tanne, T. Li, B. Bourdin, J.-J. Marigo, C. Maurini, Crack nucleation in variational phase-field "
         "models of brittle fracture, J. Mech. Phys. Solids 110 (2018) 80-99: sigma_c = sqrt(3 Gc E / (8 l))",
         "phase_field_bar_at1.toml",
         [Row("peak stress F / A", math.sqrt(3 * 1.0 * 1.0 / (8 * 0.1)),
              lambda r, ref: float(r["peak_force"]["pull"]) / 0.01, 0.01)],
         notes="E = Gc = 1, l = 0.1, P1 tetrahedra 40x1x1 (h = l/4), 100 displacement steps of 0.02: the peak is "
               "the last undamaged step's stress, within one step (1 %) below sigma_c; the whole curve against "
               "the homogeneous closed form is tests/system/test_fracture.py's."),
    Case("phase_field_bar_at2", "AT2 phase-field bar in tension: the peak of the homogeneous solution",
         "K. Pham, H. Amor, J.-J. Marigo, C. Maurini, Gradient damage models and their use to approximate brittle "
         "fracture, Int. J. Damage Mech. 20 (2011) 618-652: sigma_max = (3/16) sqrt(3 Gc E / l) at d = 1/4",
         "phase_field_bar_at2.toml",
         [Row("peak stress F / A", 3 / 16 * math.sqrt(3 * 1.0 * 1.0 / 0.1),
              lambda r, ref: float(r["peak_force"]["pull"]) / 0.01, 0.005)],
         notes="E = Gc = 1, l = 0.1, 60 displacement steps of 0.05 across the smooth maximum."),
    Case("centre_crack", "Centre-cracked plate (2a / W = 0.2) pulled until its crack runs (AT1 phase field)",
         "LEFM: K = sigma sqrt(pi a sec(pi a / W)) (Feddersen; Tada, Paris & Irwin, The Stress Analysis of Cracks "
         "Handbook, 3rd ed., 2000, p. 5.2) reaching sqrt(E Gc_eff), Gc_eff = Gc (1 + 3 h / (8 l)) (B. Bourdin, "
         "G. Francfort, J.-J. Marigo, The variational approach to fracture, J. Elasticity 91 (2008) 5-148)",
         "centre_crack.toml",
         [Row("peak stress F / (W/2 t)", targets.centre_crack_stress(0.1, 1.0, 1.0, 1e-3, 0.0033, 0.01),
              lambda r, ref: float(r["peak_force"]["pull"]) / (0.5 * 0.01), 0.06)],
         fast=False, mesh=("centre_crack", {"ell": 0.01, "h_fine": 0.0033}),
         notes="A quarter plate (symmetry on x = 0 and on the crack's plane y = 0), one layer of P1 tetrahedra, "
               "h = l/3 along the crack's path; 40 displacement steps of 2.9 % of the critical one: the peak is "
               "the last step before the crack runs across (within one step below the true one) and a/l = 10 "
               "leaves the phase field a few percent from LEFM (Tanne et al. 2018)."),
    Case("prony_relaxation", "Stress relaxation of a two-term Prony bar held at constant stretch for 3 s",
         "linear viscoelasticity, the Prony series of the relaxation modulus (W. N. Findley, J. S. Lai, K. Onaran, "
         "Creep and Relaxation of Nonlinear Viscoelastic Materials, North-Holland, 1976, ch. 5)",
         "prony_relaxation.toml",
         [Row("held force at t = 3 s", 1e6 * 1e-4 * 0.01 * prony_relaxation(3.0, 0.001, [[0.3, 0.01], [0.2, 1.0]]),
              lambda r, ref: float(r["reactions"]["pull"][0]), 1e-6, "N")],
         notes="g = 0.3, 0.2; tau = 0.01 s, 1 s; ramp 1 ms; Simo's recursive update is exact for a strain linear "
               "in time over each step, so the force is right to round-off whatever the (adaptive) load steps."),
    Case("modal_cantilever", "Cantilever bending frequencies, modes 1-2 in y and z",
         "Euler-Bernoulli, 1 + cos(bL) cosh(bL) = 0 (Blevins, Formulas for Natural Frequency and Mode "
         "Shape, Van Nostrand Reinhold, 1979, table 8-1)", "modal_cantilever.toml",
         [Row(f"f{i + 1}", (lambda m: lambda r: cantilever_frequency(m))(i // 2 + 1), frequency(i), 0.01, "Hz")
          for i in range(4)],
         notes="40:1 beam, P2 tetrahedra 30x2x2: shear and rotary inertia lower mode 2 by about 0.25 % "
               "against Euler-Bernoulli."),
    Case("dynamic_sudden_load", "Cantilever under a suddenly applied tip load, undamped",
         "single degree of freedom: peak = 2 x static (Clough & Penzien, Dynamics of Structures, 2nd ed., "
         "McGraw-Hill, 1993, ch. 4); static F L^3/(3EI) + F L/(kappa G A); Euler-Bernoulli frequency and "
         "modal superposition (Blevins, table 8-1)", "dynamic_sudden_load.toml",
         [Row("largest tip deflection vs 2 x static", lambda r: 2 * cantilever_tip_static(),
              swing("tip_uz", "peak", -1.0), 0.03, "m"),
          Row("mean of the swing (fit) vs static", lambda r: cantilever_tip_static(),
              swing("tip_uz", "center", -1.0), 0.005, "m"),
          Row("amplitude of the swing (fit) vs first-mode share 12/(beta_1 L)^4 x static",
              lambda r: first_mode_share() * cantilever_tip_static(), swing("tip_uz", "amplitude", -1.0), 0.005, "m"),
          Row("frequency of the swing (fit) vs f1", lambda r: cantilever_frequency(1),
              swing("tip_uz", "frequency", -1.0), 0.005, "Hz")],
         notes="The modal_cantilever beam (1 x 0.025 x 0.025 m, nu = 0, linear elasticity) as Q2 hexahedra "
               "20x1x1 (1,107 dofs), tip traction 1 kPa applied at t = 0 and held, Newmark average "
               "acceleration with 50 steps per period for 1.7 periods. Numbers come from the run's "
               "probes.csv: the largest tip deflection, and a least-squares fit c + a cos(wt) + b sin(wt) "
               "of the tip history (its mean c, amplitude |(a, b)| and frequency w / 2 pi). Twice the "
               "static deflection is the single-mode idealisation: the first mode carries 97.07 % of the "
               "static tip deflection (12 / (beta_1 L)^4), the higher modes the rest, out of phase with it "
               "at the peak, so the continuum's peak lies between 1.94 and 2 x static (tolerance 3 %); "
               "the fitted mean, amplitude and frequency each test one closed form to 0.5 %."),
    Case("dynamic_rayleigh_decay", "Cantilever released from a tip load, Rayleigh damping zeta = 0.04",
         "zeta = alpha / (2 omega) + beta omega / 2, decay per cycle exp(-2 pi zeta / sqrt(1 - zeta^2)), "
         "damped frequency f1 sqrt(1 - zeta^2) (Clough & Penzien, Dynamics of Structures, ch. 2 and 12); "
         "omega the Euler-Bernoulli first bending frequency", "dynamic_rayleigh_decay.toml",
         [Row("decay per cycle (fit) vs exp(-2 pi zeta / sqrt(1 - zeta^2))",
              lambda r: rayleigh_decay_per_cycle(DYN_ALPHA, DYN_BETA, 2 * math.pi * cantilever_frequency(1)),
              swing("tip_uz", "decay", -1.0, after=0.4), 0.005),
          Row("damped frequency (fit) vs f1 sqrt(1 - zeta^2)", lambda r: cantilever_frequency(1) * math.sqrt(
              1 - rayleigh_zeta(DYN_ALPHA, DYN_BETA, 2 * math.pi * cantilever_frequency(1))**2),
              swing("tip_uz", "damped_frequency", -1.0, after=0.4), 0.005, "Hz")],
         notes="The beam of dynamic_sudden_load held bent by the tip traction (initial = \"static\"), "
               "released at t = 0, alpha = 0.32 1/s and beta = 0.005 s (zeta 0.02 each at the first "
               "mode), 3.2 periods. The tip history after half a period (the stiffness-proportional part "
               "has then damped the higher modes out) is fitted by c + exp(-s t) (a cos(w t) + b sin(w t)); "
               "decay per cycle exp(-2 pi s / w). The ratio of successive peaks gives the same to 0.2 %. "
               "A tolerance of 0.5 % on the ratio is 2 % on zeta."),
    Case("nafems_fv32", "NAFEMS FV32 cantilevered tapered membrane, in-plane modes", NAFEMS_FV,
         "fv32.toml",
         [Row(f"f{i + 1}", f, frequency(i), 0.005, "Hz") for i, f in enumerate(FV32_HZ)],
         mesh=("fv32", {"nx": 16, "ny": 8, "nz": 1}),
         notes="Half the thickness is meshed (z >= 0, 16x8x1 Q2 hexahedra, linear elasticity) with w = 0 on "
               "the mid-plane z = 0: only modes symmetric about the mid-plane remain, i.e. the membrane "
               "(plane stress) modes and thickness modes far above 400 Hz; the plate's bending modes "
               "(antisymmetric) are excluded without holding the Poisson thinning (w = 0 through the "
               "whole thickness would be plane strain). Tolerance 0.5 % per frequency; this mesh is "
               "within 0.13 %; 32x16 (19,305 dofs) changes them by < 0.08 % and lands within 0.06 %."),
    Case("nafems_le1", "NAFEMS LE1 elliptic membrane, sigma_yy at D (2, 0)", NAFEMS_LE, "le1.toml",
         [Row("sigma_yy at D", 92.7e6, probe("D", "stress", 1, 1), 0.015, "MPa", scale=1e-6)],
         fast=True,           # about 8 s
         mesh=("le1", {"n_arc": 48, "n_radial": 16, "n_z": 1}),
         side_check="le1_stress_check.py",
         notes="Half the 0.1 m thickness is meshed (z >= 0, 48 x 16 x 1 Q2 hexahedra graded towards D, "
               "linear elasticity, outward pressure 10 MPa as a follower load) with w = 0 on the mid-plane "
               "z = 0 (symmetry; it also removes the rigid motion along z), u_x = 0 on x = 0, u_y = 0 on "
               "y = 0; the top face is free (plane stress). The stress is read from results.json "
               "`probes.D.stress[1][1]` (recovered Cauchy stress); until the package writes that key the "
               "case reports \"not available\" and fails. Tolerance 1.5 %: the independent side check "
               "(bare dolfinx, L2-projected stress) on this mesh family gives 95.82 / 94.13 / 93.47 / "
               "93.12 MPa at 12x4 / 24x8 / 48x16 / 96x32 cells (error +0.83 % at 48x16), converging to "
               "about 92.8 MPa; the chords of the straight-sided cells along the curved edges dominate "
               "the error."),
    Case("transient_conduction", "Transient conduction in a bar suddenly heated at one end",
         "Fourier series of the heat equation (Carslaw & Jaeger, Conduction of Heat in Solids, 2nd ed., "
         "Oxford, 1959, sec. 3.3)", "transient_conduction.toml",
         [Row("T at x = L/2, t = 0.2 s", lambda r: bar_conduction(0.5, 0.2), probe("mid", "temperature"), 0.005, "K"),
          Row("T at x = L, t = 0.2 s", lambda r: bar_conduction(1.0, 0.2), probe("end", "temperature"), 0.005, "K")],
         notes="P2 tetrahedra 40x1x1, backward Euler with dt = 1e-3 (200 steps); the first-order time error "
               "dominates. Tolerance 0.5 %."),
    Case("tutorial_beam", "FEniCSx tutorial hyperelastic beam (Q2 hex 20x5x5, 9 load steps)", TUTORIAL,
         "tutorial_beam.toml",
         [Row("reference: Newton iterations per step (published 8,9,10,9,8,7,6,6,6)", 0.0,
              lambda r, ref: float(max(abs(a - b) for a, b in zip(ref["newton_per_step"], TUTORIAL_NEWTON))
                                   + 99 * (len(ref["newton_per_step"]) != len(TUTORIAL_NEWTON))),
              0.0, "iterations", relative=False),
          Row("tip u_z at (20, 0.5, 0.5)", lambda ref: ref["tip_displacement"][2],
              probe("tip", "displacement", 2), 1e-6, "m"),
          Row("tip u_x at (20, 0.5, 0.5)", lambda ref: ref["tip_displacement"][0],
              probe("tip", "displacement", 0), 1e-6, "m")],
         fast=False, reference="tutorial_beam.py",
         notes="The tutorial publishes its Newton iterations per load step, not a tip displacement. The "
               "reference script verification/reference/tutorial_beam.py solves the tutorial's problem with "
               "bare dolfinx 0.5.2 and the tutorial's own Newton method; the first row checks that it "
               "reproduces the published iteration counts exactly (max difference 0), and its tip "
               "displacement is then the target for fem_forms (same discrete problem: agreement to the "
               "solvers' tolerances). fem_forms takes its own path (energy line search, growing load "
               "steps, secant predictor), so its Newton count is reported, not compared."),
    Case("balance_hemisphere", "Solid hemisphere: mass, CoM 3R/8, inertia 2/5 and 83/320 m R^2",
         HEMISPHERE, "balance_hemisphere.toml",
         [Row("mass", lambda r: HEMI_MASS, lambda r, ref: float(r["mass"]), 0.015, "kg"),
          Row("CoM height above the flat face", 3 * HEMI_R / 8,
              lambda r, ref: float(r["center_of_mass"][2]), 0.015, "m"),
          Row("inertia about the axis", 2 / 5 * HEMI_MASS * HEMI_R**2,
              lambda r, ref: float(r["inertia"][2][2]), 0.015, "kg m^2"),
          Row("transverse inertia about the CoM", 83 / 320 * HEMI_MASS * HEMI_R**2,
              lambda r, ref: float(r["inertia"][0][0]), 0.015, "kg m^2")],
         mesh=("hemisphere", {"radius": HEMI_R, "h": HEMI_R / 10}),
         notes="goal = \"check\" (mass properties only). gmsh tetrahedra of size R/10: the mesh is a polyhedron "
               "inscribed in the dome (its nodes on the sphere), so volume and moments come out slightly small; "
               "the integrals themselves are exact for straight-sided cells (boxes: 1e-12 in tests/unit). "
               "Tolerance 1.5 %."),
    Case("balance_floating_box", "Floating box: metacentric height GM = KB + BM - KG", FLOTATION,
         "balance_floating_box.toml",
         [Row("displaced volume L B T", BOX_L * BOX_B * BOX_T,
              lambda r, ref: float(r["displaced_volume"]), 1e-9, "m^3"),
          Row("KB (centre of buoyancy height)", BOX_T / 2,
              lambda r, ref: float(r["center_of_buoyancy"][2]), 1e-9, "m"),
          Row("mass = displaced water (it floats at T)", 1000.0 * BOX_L * BOX_B * BOX_T,
              lambda r, ref: float(r["mass"]), 1e-9, "kg"),
          Row("GM", BOX_T / 2 + BOX_B**2 / (12 * BOX_T) - BOX_H / 2,
              lambda r, ref: float(r["metacentric_height"]), 1e-9, "m")],
         notes="goal = \"check\" with a waterline: the cells are clipped at the water plane (exact for flat "
               "faces), BM = I / V with I the waterplane's smaller principal second moment, L B^3 / 12."),
    Case("balance_box", "Block 0.3 x 0.2 x 0.5 m: mass, CoM, inertia m (b^2 + c^2) / 12", SOLIDS,
         "balance_box.toml", mass_rows(BLOCK, 1e-9, base_z=-0.2),
         notes="goal = \"check\" (mass properties only). Flat faces: the tetrahedra (3 x 2 x 4 blocks) fill the "
               "block exactly, so the only error is round-off."),
    Case("balance_cylinder", "Solid cylinder R = 0.05, H = 0.12 m: mass, CoM H/2, inertia m R^2 / 2, "
         "m (3 R^2 + H^2) / 12", SOLIDS, "balance_cylinder.toml", mass_rows(CYLINDER, TOL_CYLINDER),
         notes="goal = \"check\". gmsh tetrahedra of size R/10 (`generator = \"cylinder\"`): the side is a "
               "polyhedron inscribed in the cylinder, so mass and inertia come out slightly small."),
    Case("balance_cone", "Solid cone R = 0.05, H = 0.12 m: mass, CoM H/4, inertia 3/10 m R^2, "
         "3/80 m (4 R^2 + H^2)", SOLIDS, "balance_cone.toml", mass_rows(CONE, TOL_CONE),
         notes="goal = \"check\". The triangle (0, 0), (R, 0), (0, H) revolved (`generator = \"revolve\"`), "
               "gmsh tetrahedra of size R/10 inscribed in the conical surface."),
    Case("balance_hollow_hemisphere", "Hemisphere R = 0.05 m with a concentric hemispherical cavity r = 0.03 m",
         SOLIDS, "balance_hollow_hemisphere.toml", mass_rows(HOLLOW, TOL_HOLLOW),
         mesh=("hemisphere", {"radius": HOLLOW_R, "h": HOLLOW_R / 10, "inner": HOLLOW_r}),
         notes="goal = \"check\". Both spherical surfaces are polyhedra inscribed by gmsh tetrahedra of size "
               "R/10: the outer one loses mass, the cavity's gains some back."),
    Case("balance_floating_cylinder", "Floating vertical cylinder: GM = T/2 + R^2 / (4 T) - H/2", FLOTATION,
         "balance_floating_cylinder.toml",
         [Row("displaced volume pi R^2 T", FLOAT_CYL["volume"], lambda r, ref: float(r["displaced_volume"]),
              TOL_FLOAT, "m^3"),
          Row("KB (centre of buoyancy height)", FLOAT_CYL["KB"],
              lambda r, ref: float(r["center_of_buoyancy"][2]), TOL_FLOAT, "m"),
          Row("mass = displaced water (it floats at T)", 1000.0 * FLOAT_CYL["volume"],
              lambda r, ref: float(r["mass"]), TOL_FLOAT, "kg"),
          Row("GM", FLOAT_CYL["GM"], lambda r, ref: float(r["metacentric_height"]), TOL_FLOAT, "m")],
         notes="goal = \"check\" with a waterline (0.025 m, half the height: density 500). The cells are "
               "clipped at the water plane; the waterplane is the inscribed polygon of the tetrahedra, so V "
               "and I = pi R^4 / 4 come out slightly small."),
    Case("hertz_contact", "Hertz: elastic sphere pressed on a rigid plane (IPC barrier contact)", JOHNSON,
         "hertz_contact.toml",
         [Row("contact force F = 4/3 E* sqrt(R) d^1.5",
              4 / 3 * HERTZ_E / (1 - HERTZ_NU**2) * math.sqrt(HERTZ_R) * HERTZ_D**1.5, hertz("force"), 0.03, "N"),
          Row("contact radius a = sqrt(R d)", math.sqrt(HERTZ_R * HERTZ_D), hertz("radius"), 0.04, "m")],
         fast=False, mesh=("hertz_hemisphere", {}),
         notes="R = 10 mm, d = 10 um (d / R = 1e-3: the finite hemisphere stays close to Hertz's half-space), P2 "
               "tetrahedra graded to 0.1 mm at the contact (6,639 dofs), dhat = d / 50. The radius is that of the "
               "rest area whose nodes are all within dhat of the plane. How dhat trades accuracy: "
               "benchmarks/contact_distance.md."),
    Case("sliding_block", "Block sliding down a 30 degree slope, Coulomb friction mu = 0.3 (IPC)",
         "rigid block with Coulomb friction: a = g (sin theta - mu cos theta) (any dynamics text, e.g. Meriam & "
         "Kraige, Engineering Mechanics: Dynamics, 3/3)", "sliding_block.toml",
         [Row("acceleration down the slope", 9.81 * (0.5 - 0.3 * math.cos(math.pi / 6)), sliding_acceleration,
              0.03, "m/s^2")],
         fast=False,
         notes="Smoothed Coulomb friction lagged per step (IPC); generalized-alpha (rho_inf 0.5) damps the barrier's "
               "stiff rocking; the acceleration is fitted to the slide after 0.02 s (probes.csv)."),
]
