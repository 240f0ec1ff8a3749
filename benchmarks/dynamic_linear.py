"""The --linear section of benchmarks/dynamic_steps.py: the implicit step's cost per time step with MUMPS
(the tangent and its LU kept across steps, GMRES on the kept tangent) against CG + GAMG (a fresh tangent
at every Newton iteration, the multigrid hierarchy kept across iterations and steps by the driver's cost
rule), both through fem_forms ([solver] linear = "direct" / "iterative"), at the sizes where the static
driver's "auto" switches."""
from __future__ import annotations

import statistics

LINEAR_SIZES = [(140, 14, 14), (200, 20, 20)]     # P1: 95,175 / 265,923 dofs
KINDS = ("direct", "iterative")


def _med(rows: list, key: str) -> float:
    return statistics.median(r[key] for r in rows)


def linear_table(results: dict) -> str:
    """One row per (size, scheme): CPU costs direct / iterative, the run lengths (steps) for which the
    iterative path is cheaper overall, iteration and build counts, and the agreement of the two answers."""
    head = ("| dofs | scheme | first step s CPU | later steps ms CPU | later: iterative / direct | "
            "whole run of the steps s CPU | iterative cheaper for | Newton (Krylov) its | "
            "LU factorisations / multigrid builds | max |u| relative difference |\n"
            "|---:|---|---|---|---:|---|---|---|---|---:|\n")
    rows = []
    for (cells, scheme), rs in results.items():
        d, i = ([r for r in rs if r["impl"] == k] for k in KINDS)
        fd, fi = _med(d, "first_cpu"), _med(i, "first_cpu")
        ld, li = _med(d, "later_cpu"), _med(i, "later_cpu")
        n = d[0]["steps"]
        if li < ld:
            cheaper = "runs of any length" if fi <= fd else f"runs of {1 + (fi - fd) / (ld - li):.0f} steps or more"
        else:
            cheaper = "no run" if fi >= fd else f"runs up to {1 + (fd - fi) / (li - ld):.0f} steps"
        diff = abs(i[0]["max_u"] - d[0]["max_u"]) / abs(d[0]["max_u"])
        rows.append(f"| {d[0]['dofs']:,} | {scheme} | {fd:.2f} / {fi:.2f} | {1e3 * ld:,.0f} / {1e3 * li:,.0f} | "
                    f"{li / ld:.2f} | {fd + (n - 1) * ld:.1f} / {fi + (n - 1) * li:.1f} ({n} steps) | {cheaper} | "
                    f"{d[0]['newton']} ({d[0]['krylov']}) / {i[0]['newton']} ({i[0]['krylov']}) | "
                    f"{d[0]['lu']} / {i[0]['builds']} | {diff:.1e} |")
    return head + "\n".join(rows) + "\n"
