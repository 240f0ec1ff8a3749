"""The verification manual: run every benchmark in verification/cases/ through `fem-forms run`, compare
each extracted number with its published or closed-form target, write verification/README.md, and exit
non-zero if any error exceeds its stated tolerance (or a number cannot be read: "not available").

    .venv/bin/python verification/run.py            # all cases, writes verification/README.md
    .venv/bin/python verification/run.py --fast     # the fast ones (CI: tests/system/test_verification.py)
    .venv/bin/python verification/run.py --only fv32 le1 --no-readme

Each case is a scene file in verification/cases/ (meshes of the NAFEMS cases are written first by the
gmsh scripts in verification/geometry/ into the output folder), run once as a subprocess of this tree's
package; its results.json is read, never the package's internals. Targets are closed forms computed
below, published numbers, or (tutorial beam) a bare-dolfinx reproduction that first has to reproduce
the tutorial's published Newton counts. Run outputs go to verification/out/ (not committed).
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
import datetime
import json
import math
import os
from pathlib import Path
import platform
import subprocess
import sys
import time
from typing import Callable

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PYTHON = sys.executable
sys.path.insert(0, str(HERE / "geometry"))
sys.path.insert(0, str(HERE))

from time_histories import (cantilever_beta_l, cantilever_tip_static, damped_fit, first_mode_share, harmonic_fit,  # noqa: E402
                            rayleigh_decay_per_cycle, rayleigh_zeta)


class NotAvailable(Exception):
    """The number is not in results.json (a key the package does not write yet)."""


# --- closed-form targets --------------------------------------------------------------------
def lame(E: float, nu: float) -> tuple[float, float]:
    return E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))


def uniaxial_neo_hookean(T: float, E: float = 1e6, nu: float = 0.3) -> tuple[float, float]:
    """Stretches (l1, l2) of the compressible neo-Hookean bar under dead traction T, lateral P = 0:
    mu (l1 - 1/l1) + lambda ln J / l1 = T and mu (l2 - 1/l2) + lambda ln J / l2 = 0, J = l1 l2^2."""
    from scipy.optimize import fsolve
    mu, lm = lame(E, nu)

    def eqs(v):
        l1, l2 = v
        lnJ = math.log(l1 * l2 * l2)
        return [mu * (l1 - 1 / l1) + lm * lnJ / l1 - T, mu * (l2 - 1 / l2) + lm * lnJ / l2]
    l1, l2 = fsolve(eqs, [1.1, 0.95], xtol=1e-14)
    return float(l1), float(l2)


def hydrostatic_neo_hookean(p: float, E: float = 1e6, nu: float = 0.3) -> float:
    """Stretch l of F = l I under follower pressure p: (mu (l^2 - 1) + 3 lambda ln l) / l^3 = -p."""
    from scipy.optimize import brentq
    mu, lm = lame(E, nu)
    return float(brentq(lambda s: (mu * (s * s - 1) + 3 * lm * math.log(s)) / s**3 + p, 0.3, 1.0, xtol=1e-15))


def cantilever_gravity_sag(L=1.0, h=0.05, E=1e9, rho=1000.0, g=9.81) -> float:
    """Euler-Bernoulli w L^4 / (8 E I) + Timoshenko shear w L^2 / (2 kappa G A), kappa 5/6, nu = 0."""
    A, I = h * h, h**4 / 12
    w = rho * g * A
    return w * L**4 / (8 * E * I) + w * L**2 / (2 * (5 / 6) * (E / 2) * A)


def cantilever_frequency(mode: int, L=1.0, t=0.025, E=1e8, rho=1000.0) -> float:
    """Euler-Bernoulli clamped-free bending frequency of mode 1, 2, ... (square section t x t)."""
    return cantilever_beta_l(mode)**2 / (2 * math.pi * L**2) * math.sqrt(E * t**2 / 12 / rho)


def bar_conduction(x: float, t: float, L: float = 1.0, kappa: float = 1.0, terms: int = 400) -> float:
    """T / T1 in a bar 0 < x < L initially at 0, x = 0 held at T1 from t = 0, x = L insulated (Fourier series)."""
    total = 0.0
    for n in range(terms):
        b = (2 * n + 1) * math.pi / (2 * L)
        total += 4 / ((2 * n + 1) * math.pi) * math.sin(b * x) * math.exp(-b * b * kappa * t)
    return 1.0 - total


def thick_sphere_outer_displacement(P: float, E=210e9, nu=0.3, sy=240e6, a=1.0, b=2.0) -> float:
    """u(b) of the perfectly plastic thick sphere: Lame below first yield, (1 - nu) sy c^3 / (E b^2) with the
    plastic front c from P = 2 sy ln(c/a) + (2 sy / 3)(1 - c^3/b^3) while yielding (Hill 1950, ch. V)."""
    from scipy.optimize import brentq
    if P <= 2 * sy / 3 * (1 - a**3 / b**3):
        return 1.5 * (1 - nu) * P * a**3 * b / (E * (b**3 - a**3))
    c = brentq(lambda c: 2 * sy * math.log(c / a) + 2 * sy / 3 * (1 - c**3 / b**3) - P, a, b, xtol=1e-14)
    return (1 - nu) * sy * c**3 / (E * b**2)


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
]


# --- running ------------------------------------------------------------------------------------
def _env() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                OPENBLAS_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def _script_json(script: Path, args: list[str] | None = None, timeout: float = 1800) -> dict:
    p = subprocess.run([PYTHON, str(script)] + (args or []), cwd=ROOT, env=_env(), capture_output=True,
                       text=True, timeout=timeout)
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"{script.name}: exit {p.returncode}: {p.stderr.strip()[-400:]}")
    return json.loads(lines[-1])


def run_case(case: Case, out: Path) -> list[dict]:
    """Run one case; one result dict per row (status pass / FAIL / not available / error)."""
    out.mkdir(parents=True, exist_ok=True)
    base = {"case": case.name, "benchmark": case.benchmark, "source": case.source}
    cmd = [PYTHON, "-m", "fem_forms", "run", str(HERE / "cases" / case.scene), "--out", str(out / "run"), "-q"]
    t0 = time.perf_counter()
    res, ref, err, extra = {}, {}, None, {}
    try:
        if case.mesh is not None:
            module, kwargs = case.mesh
            geo = __import__(module)
            msh = geo.build(out / f"{module}.msh", **kwargs)
            cmd += ["--set", f"mesh.file={json.dumps(str(msh))}"]
        p = subprocess.run(cmd, cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=1800)
        wall = time.perf_counter() - t0
        rj = out / "run" / "results.json"
        if p.returncode != case.exit_status:
            err = f"exit status {p.returncode}, expected {case.exit_status}: {p.stderr.strip()[-300:]}"
        elif not rj.exists():
            err = "no results.json"
        else:
            res = json.loads(rj.read_text())
            res["run_dir"] = str(out / "run")         # where the run's probes.csv lies (dynamic cases)
        if case.reference:
            ref = _script_json(HERE / "reference" / case.reference)
            extra["reference_time_s"] = ref.get("time_s")
        if case.side_check and case.mesh:
            extra["side_check"] = _script_json(HERE / "reference" / case.side_check,
                                               ["--n-arc", str(case.mesh[1]["n_arc"]),
                                                "--n-radial", str(case.mesh[1]["n_radial"])])
    except Exception as e:                              # a crash is a failed case, reported
        wall = time.perf_counter() - t0
        err = f"{type(e).__name__}: {e}"
    rows = []
    for row in case.rows:
        r = dict(base, quantity=row.quantity, unit=row.unit, tolerance=row.tolerance, relative=row.relative,
                 scale=row.scale, dofs=res.get("dofs"), solve_time_s=res.get("wall_time_s"), wall_time_s=wall,
                 newton_iterations=res.get("newton_iterations"), **extra)
        try:
            target = row.target if not callable(row.target) else row.target(ref if case.reference else res)
            r["target"] = float(target)
        except Exception as e:
            r.update(status="error", note=f"target: {type(e).__name__}: {e}")
            rows.append(r)
            continue
        if err is not None:
            r.update(status="error", note=err)
        else:
            try:
                value = row.extract(res, ref)
                error = (value - target) / abs(target) if row.relative else value - target
                r.update(result=value, error=error,
                         status="pass" if abs(error) <= row.tolerance else "FAIL")
            except NotAvailable as e:
                r.update(status="not available", note=str(e))
            except Exception as e:
                r.update(status="error", note=f"{type(e).__name__}: {e}")
        rows.append(r)
    return rows


def run_cases(cases: list[Case], out: Path, echo: bool = True) -> list[dict]:
    rows = []
    for case in cases:
        t0 = time.perf_counter()
        got = run_case(case, out / case.name)
        rows += got
        if echo:
            bad = [r for r in got if r["status"] != "pass"]
            print(f"{case.name:22s} {'pass' if not bad else bad[0]['status']:14s} "
                  f"{time.perf_counter() - t0:6.1f} s", flush=True)
            for r in bad:
                print(f"    {r['quantity']}: {r.get('note') or _fmt_err(r)}", flush=True)
    return rows


# --- README -----------------------------------------------------------------------------------
def _fmt(v, scale=1.0) -> str:
    if v is None:
        return "-"
    v = v * scale
    return f"{v:.6g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.5e}"


def _fmt_err(r: dict) -> str:
    if "error" not in r:
        return "-"
    return f"{100 * r['error']:+.3g} %" if r["relative"] else f"{r['error']:+.3g}"


def _fmt_tol(r: dict) -> str:
    return f"{100 * r['tolerance']:.3g} %" if r["relative"] else f"{r['tolerance']:g}"


def machine_note() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        import dolfinx
        dv = dolfinx.__version__
    except Exception:
        dv = "?"
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"{platform.node()}: {os.cpu_count()} cores ({cpu}), {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}, dolfinx {dv}, OPENBLAS_NUM_THREADS=1, one run per case; "
            f"load average at the end {load} (times are noisy when other jobs share the machine)")


def write_readme(rows: list[dict], cases: list[Case], path: Path, command: str, total_s: float) -> None:
    passed = sum(r["status"] == "pass" for r in rows)
    lines = [
        "# Verification manual",
        "",
        "Written by `verification/run.py`; do not edit by hand. Each benchmark is a scene file in "
        "`verification/cases/` run by `fem-forms run` (one run per case); the number is read from its "
        "`results.json` and compared with the target. A row passes when |error| <= tolerance; "
        "\"not available\" (the package does not write that number yet) and \"error\" (the run failed) "
        "count as failures. `run.py --fast` runs the cases marked fast (CI: "
        "`tests/system/test_verification.py`).",
        "",
        f"- date: {datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}",
        f"- machine: {machine_note()}",
        f"- command: `{command}`",
        f"- {passed} of {len(rows)} rows pass; total {total_s:.0f} s",
        "",
        "| case | benchmark | source | quantity | target | result | error | tolerance | status | dofs | "
        "time (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    seen = set()
    for r in rows:
        unit = f" {r['unit']}" if r["unit"] else ""
        first = r["case"] not in seen                  # benchmark and source once per case
        seen.add(r["case"])
        cell = lambda text: str(text).replace("|", "\\|")   # noqa: E731  (a pipe would split the cell)
        t = r.get("wall_time_s")
        st = r["status"] if r["status"] in ("pass", "FAIL") else f"**{r['status']}**"
        if r["status"] == "FAIL":
            st = "**FAIL**"
        lines.append(
            f"| {r['case'] if first else ''} | {cell(r['benchmark']) if first else ''} | "
            f"{cell(r['source']) if first else ''} | {cell(r['quantity'])} | "
            f"{_fmt(r.get('target'), r['scale'])}{unit} | {_fmt(r.get('result'), r['scale'])} | {_fmt_err(r)} | "
            f"{_fmt_tol(r)} | {st} | {r.get('dofs') or '-'} | "
            f"{'-' if t is None else f'{t:.1f}'} |")
    lines += ["", "Time: wall time of the `fem-forms run` subprocess (start-up and form compilation "
              "included; the solve alone is `wall_time_s` in each results.json).", "", "## Cases", ""]
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"], []).append(r)
    for case in cases:
        if case.name not in by_case:
            continue
        rs = by_case[case.name]
        lines.append(f"### {case.name}: {case.benchmark}")
        lines.append("")
        lines.append(f"Scene `verification/cases/{case.scene}`"
                     + (f", mesh `verification/geometry/{case.mesh[0]}.py` {case.mesh[1]}" if case.mesh else "")
                     + (f", reference `verification/reference/{case.reference}`" if case.reference else "")
                     + f"; {'fast' if case.fast else 'full run only'}. Source: {case.source}.")
        lines.append("")
        lines.append(case.notes)
        r0 = rs[0]
        facts = []
        if r0.get("newton_iterations") is not None:
            facts.append(f"fem_forms took {r0['newton_iterations']} Newton iterations")
        if r0.get("solve_time_s") is not None:
            facts.append(f"solve {r0['solve_time_s']:.2f} s")
        if r0.get("reference_time_s") is not None:
            facts.append(f"reference script {r0['reference_time_s']:.1f} s")
        if facts:
            lines += ["", "This run: " + ", ".join(facts) + "."]
        sc = r0.get("side_check")
        if sc:
            lines += ["", f"Side check (bare dolfinx, `verification/reference/{case.side_check}`, not the "
                      f"package's result and not counted): sigma_yy at D = {sc['sigma_yy_D_projected_MPa']:.4g} MPa "
                      f"(L2 projection onto Q2; {sc['error_pct']:+.2f} % from 92.7), raw cell values "
                      f"{', '.join(f'{v:.4g}' for v in sc['sigma_yy_D_cells_MPa'])} MPa, {sc['dofs']} dofs."]
        notes = {r["note"] for r in rs if r.get("note")}
        if notes:
            lines += ["", "Not passed: " + "; ".join(sorted(notes)) + "."]
        lines.append("")
    path.write_text("\n".join(lines))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="only the cases marked fast")
    ap.add_argument("--only", nargs="+", metavar="CASE", help="only these cases (by name)")
    ap.add_argument("--out", default=str(HERE / "out"), help="folder for the runs (default verification/out)")
    ap.add_argument("--no-readme", action="store_true", help="do not write verification/README.md")
    ap.add_argument("--readme", default=str(HERE / "README.md"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    cases = [c for c in CASES if (not a.fast or c.fast) and (not a.only or c.name in a.only)]
    if a.only and len(cases) != len(a.only):
        known = ", ".join(c.name for c in CASES)
        print(f"run.py: unknown case in {a.only} (known: {known})", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    rows = run_cases(cases, Path(a.out))
    total = time.perf_counter() - t0
    failed = [r for r in rows if r["status"] != "pass"]
    print(f"{len(rows) - len(failed)} of {len(rows)} rows pass in {total:.0f} s")
    if not a.no_readme:
        cmd = "OPENBLAS_NUM_THREADS=1 .venv/bin/python verification/run.py" + (" --fast" if a.fast else "") \
            + (f" --only {' '.join(a.only)}" if a.only else "")
        write_readme(rows, cases, Path(a.readme), cmd, total)
        print(f"wrote {a.readme}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
