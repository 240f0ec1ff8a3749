"""What `fem-forms fit` writes and prints: fit.json (the material and how well it fits), fit.png (the test
points, the fitted curves in all three modes, Drucker's stable range marked) and a summary with the TOML
lines to paste into a scene."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fem_forms.errors import InputError
from fem_forms.materials.fitting import Fit
from fem_forms.materials.homogeneous import MODES, nominal_stress
from fem_forms.output.results import write_json_atomic

COLOURS = {"uniaxial": "tab:blue", "biaxial": "tab:orange", "shear": "tab:green"}


def write_fit(f: Fit, out: Path) -> None:
    """fit.json and fit.png in `out` (created); a folder that cannot be written is one line (InputError)."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        fit_picture(f, out / "fit.png")
    except OSError as e:
        raise InputError(f"--out {str(out)!r}: cannot write ({e.strerror or e})") from None
    write_json_atomic(out / "fit.json", f.summary())


def fit_picture(f: Fit, path: Path) -> None:
    """Nominal stress against stretch: each test's points, the fitted model in the three modes (dashed where
    Drucker's condition fails), the stable range's ends as vertical ticks."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    p = {k: np.asarray(v) for k, v in f.parameters.items()}
    top = max(float(t.stretch.max()) for t in f.tests)
    bottom = min(float(t.stretch.min()) for t in f.tests)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for mode in MODES:
        lo, hi = f.stable[mode]
        lam = np.linspace(min(bottom, 1.0), max(top, 1.0) * 1.05, 400)
        with np.errstate(all="ignore"):
            P = nominal_stress(f.model, p, mode, lam)
        inside = (lam >= lo) & (lam <= hi)
        ax.plot(lam[inside], P[inside] / 1e6, color=COLOURS[mode], label=f"{f.model} {mode}")
        ax.plot(np.where(inside, np.nan, lam), P / 1e6, color=COLOURS[mode], ls="--", lw=0.8)
        for end in (lo, hi):
            if lam[0] < end < lam[-1]:                   # not a scan's end (stable all the way)
                ax.axvline(end, color=COLOURS[mode], ls=":", lw=0.8)
    for t in f.tests:
        ax.plot(t.stretch, t.stress / 1e6, "o", ms=4, mfc="none", color=COLOURS[t.mode],
                label=f"{t.mode} test ({Path(t.source).name})" if t.source else f"{t.mode} test")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlabel("stretch")
    ax.set_ylabel("nominal stress (MPa)")
    ax.set_title(f"{f.model} fit: dashed = unstable (Drucker), dotted = stable range's ends", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fit_text(f: Fit) -> str:
    """The printed summary: the TOML lines, standard errors, errors per point, stable ranges, warnings."""
    lines = ["# paste into a [[material]] table (add bulk = ... or nu = ...):", f.toml(), "",
             "standard errors (nan: on a bound; inf: not determined by these tests):"]
    for k, v in f.errors.items():
        lines.append(f"  {k}: " + (", ".join(f"{x:.3g}" for x in v) if isinstance(v, list) else f"{v:.3g}"))
    for t, e in zip(f.tests, f.relative_errors):
        lines.append(f"{t.mode} test {t.source}: relative error per point (model - data) / |data|, "
                     f"rms {np.sqrt(np.mean(e ** 2)):.3g}:")
        lines.append("  " + ", ".join(f"{s:.4g}: {x:+.3f}" for s, x in zip(t.stretch, e)))
    lines.append("Drucker-stable stretch range: " + "; ".join(f"{m} {lo:.4g} to {hi:.4g}"
                                                             for m, (lo, hi) in f.stable.items()))
    lines += [f"warning: {w}" for w in f.unstable_in_data]
    if f.at_bound:
        lines.append(f"warning: {', '.join(f.at_bound)} ended on a bound of the search (Ogden: a term's mu alpha >= 0, "
                     "|alpha| <= 20; Yeoh: C10 > 0; Gent: Jm beyond the data): no standard error; fewer terms may fit "
                     "as well")
    return "\n".join(lines)
