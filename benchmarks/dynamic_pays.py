"""The "when each scheme pays" section of benchmarks/dynamic_steps.py: steps and cost of a short impact and
a slow swing, explicit against implicit, for a stiff and a soft part (pure arithmetic on measured costs)."""
from __future__ import annotations

import math

from dynamic_bare import LENGTH, WIDTH

MATERIALS = {"aluminium": (70e9, 0.33, 2700.0), "silicone": (0.68e6, 0.45, 1100.0)}
EVENTS = {"impact 1 ms": 1e-3, "swing 1 s": 1.0}


def first_period(e: float, rho: float) -> float:
    """Euler-Bernoulli: f1 = 1.8751^2 / (2 pi L^2) sqrt(E I / (rho A)) of the square cantilever."""
    return 1.0 / (1.8751 ** 2 / (2 * math.pi * LENGTH ** 2) * math.sqrt(e * WIDTH ** 2 / 12 / rho))


def pays_table(dofs: int, stable: dict, implicit: dict, explicit: dict) -> str:
    """Steps and cost of each event: both schemes at the accuracy step min(event / 100, T1 / 20), the
    explicit one also at most its stable step (the estimate, 0.9 x 2 / omega_max)."""
    lines = ["| part (E, nu, rho) | explicit dt_stable | T1 | event | explicit steps | implicit steps | "
             "explicit cost | implicit cost | cheaper |", "|---|---:|---:|---|---:|---:|---:|---:|---|"]
    for name, (e, nu, rho) in MATERIALS.items():
        dts, t1 = stable[name], first_period(e, rho)
        for ev, T in EVENTS.items():
            accurate = min(T / 100, t1 / 20)
            n_exp = int(-(-T // min(dts, accurate)))
            n_imp = int(-(-T // accurate))
            c_exp = n_exp * explicit["later_full"]
            c_imp = implicit["first"] + (n_imp - 1) * implicit["later_full"]
            lines.append(f"| {name} ({e:.3g} Pa, {nu}, {rho:g}) | {dts:.3g} s | {t1:.3g} s | {ev} | {n_exp:,} | "
                         f"{n_imp:,} | {_dur(c_exp)} | {_dur(c_imp)} | "
                         f"{'explicit' if c_exp < c_imp else 'implicit'} ({max(c_exp, c_imp) / min(c_exp, c_imp):.0f}x) |")
    return f"At {dofs:,} dofs:\n\n" + "\n".join(lines) + "\n"


def _dur(x: float) -> str:
    if x < 120:
        return f"{x:.2g} s" if x < 10 else f"{x:.0f} s"
    return f"{x / 60:.0f} min" if x < 7200 else f"{x / 3600:.0f} h"
