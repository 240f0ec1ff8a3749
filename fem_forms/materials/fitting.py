"""Fitting a rubber model to lab tests: least squares (scipy) of the closed-form homogeneous stresses
(homogeneous.py) against measured nominal stresses in uniaxial, equibiaxial and pure shear tests, with the
parameters' standard errors, the error at each point and Drucker's stable range of the result."""
from __future__ import annotations

from dataclasses import dataclass, field
import csv
import itertools
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from fem_forms.errors import InputError
from fem_forms.materials.homogeneous import MODES, locked, mode_stretches, nominal_stress, stable_range

FIT_MODELS = ("ogden", "yeoh", "gent", "arruda-boyce")
MAX_TERMS = {"ogden": 3, "yeoh": 3}
RESIDUALS = ("relative", "absolute")
MAX_ALPHA = 20.0        # |alpha_i| of a fitted Ogden term: beyond it l^alpha spans more digits than a solve keeps


@dataclass
class LabTest:
    """One homogeneous test: its mode, stretches and nominal stresses (Pa), and the file it came from."""
    mode: str
    stretch: np.ndarray
    stress: np.ndarray
    source: str = ""


def read_test(path: Path | str, mode: str, key: str = "fit") -> LabTest:
    """A CSV with a header naming `stretch` and `nominal_stress` (Pa) columns; one clear line when it is not."""
    if mode not in MODES:
        raise InputError(f"{key}: unknown test mode {mode!r} (one of {', '.join(MODES)})")
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:      # a byte-order mark (Excel) is dropped
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{key}: cannot read {path}: {e.strerror if isinstance(e, OSError) else 'not text'}")
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    header = [c.strip().lower() for c in rows[0]] if rows else []
    if "stretch" not in header or "nominal_stress" not in header:
        raise InputError(f"{key}: {path}: the first line must name the columns stretch and nominal_stress "
                         f"(found {', '.join(header) or 'nothing'})")
    i, j = header.index("stretch"), header.index("nominal_stress")
    values = []
    for n, r in enumerate(rows[1:], start=2):
        try:
            values.append((float(r[i]), float(r[j])))
        except (ValueError, IndexError):
            raise InputError(f"{key}: {path} line {n}: stretch and nominal_stress must be numbers") from None
    data = np.array(values, dtype=float).reshape(-1, 2)
    if len(data) < 2 or not np.all(np.isfinite(data)):
        raise InputError(f"{key}: {path}: needs at least two finite points (found {len(data)})")
    if not np.any(data[:, 1]):
        raise InputError(f"{key}: {path}: every nominal_stress is zero (nothing to fit)")
    if np.any(data[:, 0] <= 0):
        raise InputError(f"{key}: {path}: a stretch must be positive (l = deformed length / rest length)")
    return LabTest(mode, data[:, 0], data[:, 1], str(path))


@dataclass
class Fit:
    """A fitted parameter set and how well it fits."""
    model: str
    parameters: dict                      # name -> number or list (the scene's keys)
    errors: dict                          # name -> standard error (same shape)
    tests: list                           # LabTest
    relative_errors: list                 # per test: (model - data) / |data| at each point
    stable: dict = field(default_factory=dict)     # mode -> [smallest, largest] stable stretch
    unstable_in_data: list = field(default_factory=list)   # messages: data points outside the stable range
    at_bound: list = field(default_factory=list)    # parameters the optimum left on a bound of the search

    def summary(self) -> dict:
        """What fit.json and results.json say."""
        return {"material": {"model": self.model, **self.parameters}, "standard_errors": self.errors,
                "tests": [{"mode": t.mode, "file": t.source, "stretch": t.stretch.tolist(),
                           "nominal_stress": t.stress.tolist(), "relative_error": e.tolist()}
                          for t, e in zip(self.tests, self.relative_errors)],
                "stable_range": self.stable, "unstable_in_data": self.unstable_in_data, "at_bound": self.at_bound}

    def toml(self) -> str:
        """The parameters as lines to paste into a [[material]] table (10 significant digits: Ogden's mu and
        alpha are tightly coupled)."""
        def fmt(v):
            return "[" + ", ".join(f"{x:.10g}" for x in v) + "]" if isinstance(v, list) else f"{v:.10g}"
        return "\n".join([f'model = "{self.model}"'] + [f"{k} = {fmt(v)}" for k, v in self.parameters.items()])


class _Parametrization:
    """A model's fitted unknowns x and the parameter dict they stand for, with box bounds on x (which keep the
    initial shear modulus positive) and the starting points to try."""

    def __init__(self, model: str, terms: int, tests: list):
        self.model, self.terms = model, terms
        data = np.concatenate([t.stress / np.where(t.stretch != 1, t.stretch - 1, 1) for t in tests])
        self.mu0 = float(np.clip(np.median(np.abs(data)) / 3, 1e-3, None))      # E ~ 3 mu0 from the slopes
        i1 = max(float(np.max(sum(s ** 2 for s in mode_stretches(t.mode, t.stretch)) - 3)) for t in tests)
        self.i1_max = i1

    def params(self, x) -> dict:
        m, n = self.model, self.terms
        if m == "ogden":      # x = (m_i >= 0, alpha_i): mu_i alpha_i = 2 m_i keeps every term's modulus positive
            alpha = np.asarray(x[n:])
            return {"mu": 2 * np.asarray(x[:n]) / alpha, "alpha": alpha}
        if m == "yeoh":
            return dict(zip(("C10", "C20", "C30")[:n], x))
        if m == "gent":
            return {"mu": x[0], "Jm": x[1]}
        return {"mu": x[0], "lambda_m": x[1]}

    def at_bound(self, active) -> list[tuple[str, int]]:
        """(parameter name, index) of the unknowns least_squares left on a bound (its active_mask)."""
        n, out = self.terms, []
        for j in np.flatnonzero(active):
            if self.model == "ogden":
                out.append(("mu" if j < n else "alpha", int(j % n)))
            else:
                out.append((list(self.params(np.zeros(len(active))))[j], 0))
        return out

    def starts(self):
        """(x0, lower, upper) to try; Ogden's exponents start on each sign pattern (the best fit is kept)."""
        m, n, mu0 = self.model, self.terms, self.mu0
        if m == "ogden":
            for signs in itertools.product((1.0, -1.0), repeat=n):
                if signs[0] < 0 and n > 1:        # one sign pattern of each pair (the terms are interchangeable)
                    continue
                alpha0 = [s * a for s, a in zip(signs, (2.0, 4.0, 1.0)[:n])]
                lo = [0.0] * n + [0.05 if s > 0 else -MAX_ALPHA for s in signs]
                hi = [np.inf] * n + [MAX_ALPHA if s > 0 else -0.05 for s in signs]
                yield [mu0 / n] * n + alpha0, lo, hi
        elif m == "yeoh":
            yield [mu0 / 2] + [0.0] * (n - 1), [1e-12 * mu0] + [-np.inf] * (n - 1), [np.inf] * n
        elif m == "gent":
            jm = max(10.0 * self.i1_max, 1.0)
            yield [mu0, jm], [1e-12 * mu0, self.i1_max * (1 + 1e-9)], [np.inf, np.inf]
        else:
            yield [mu0, 5.0], [1e-12 * mu0, 1.0], [np.inf, np.inf]


def _residual(model: str, tests: list, p: dict, relative: bool) -> np.ndarray:
    out = []
    for t in tests:
        r = nominal_stress(model, p, t.mode, t.stretch) - t.stress
        if relative:
            scale = np.maximum(np.abs(t.stress), 1e-3 * np.max(np.abs(t.stress)))
            r = r / scale
        out.append(r)
    return np.concatenate(out)


def fit(model: str, tests: list, terms: int | None = None, residual: str = "relative") -> Fit:
    """The least-squares parameters of `model` for the tests (LabTest), with standard errors from the
    Jacobian at the optimum (s^2 (J^T J)^-1, s^2 the residual variance) and Drucker's stable ranges."""
    if model not in FIT_MODELS:
        raise InputError(f"fit: model {model!r} cannot be fitted (one of {', '.join(FIT_MODELS)})")
    if residual not in RESIDUALS:
        raise InputError(f"fit.residual = {residual!r}: one of {', '.join(RESIDUALS)}")
    if terms is not None and model not in MAX_TERMS:
        raise InputError(f"fit.terms: only for ogden and yeoh (model is {model!r})")
    n = terms if terms is not None else {"ogden": 2, "yeoh": 3}.get(model, 2)
    if model in MAX_TERMS and not 1 <= n <= MAX_TERMS[model]:
        raise InputError(f"fit.terms = {n}: {model} takes 1 to {MAX_TERMS[model]} terms")
    par = _Parametrization(model, n, tests)
    relative = residual == "relative"
    best = None
    for x0, lo, hi in par.starts():
        x0 = np.clip(x0, lo, hi)
        try:
            sol = least_squares(lambda x: _residual(model, tests, par.params(x), relative), x0, bounds=(lo, hi),
                                x_scale="jac", max_nfev=4000)
        except ValueError:               # a start outside the model's domain (Gent beyond locking)
            continue
        if np.all(np.isfinite(sol.fun)) and (best is None or sol.cost < best.cost):
            best = sol
    if best is None:
        raise InputError(f"fit: no {model} parameters fit these tests (the least squares found no finite start)")
    p = par.params(best.x)
    params = {k: (np.asarray(v).tolist() if np.ndim(v) else float(v)) for k, v in p.items()}
    at_bound = par.at_bound(best.active_mask)
    errors = _standard_errors(model, tests, params, relative)
    for name, i in at_bound:                            # on a bound: no standard error (not a free optimum)
        if isinstance(errors[name], list):
            errors[name][i] = float("nan")
        else:
            errors[name] = float("nan")
    out = Fit(model, params, errors, tests, [_residual(model, [t], p, True) for t in tests],
              at_bound=[f"{n}[{i}]" if isinstance(params[n], list) else n for n, i in at_bound])
    check_stability(out)
    return out


def _standard_errors(model: str, tests: list, params: dict, relative: bool) -> dict:
    """The standard error of each parameter (delta method: the Jacobian by central differences)."""
    names = list(params)
    flat = np.concatenate([np.atleast_1d(params[k]) for k in names]).astype(float)
    sizes = [np.size(params[k]) for k in names]

    def unflat(x):
        parts = np.split(x, np.cumsum(sizes)[:-1])
        return {k: (v if np.ndim(params[k]) else v[0]) for k, v in zip(names, parts)}
    r0 = _residual(model, tests, unflat(flat), relative)
    scale = np.where(np.abs(flat) > 0, np.abs(flat), 1.0)   # columns of J x diag(scale): comparable
    Js = np.empty((r0.size, flat.size))
    for i in range(flat.size):
        h = 1e-6 * scale[i]
        xp, xm = flat.copy(), flat.copy()
        xp[i] += h
        xm[i] -= h
        Js[:, i] = scale[i] * (_residual(model, tests, unflat(xp), relative)
                               - _residual(model, tests, unflat(xm), relative)) / (2 * h)
    dof = max(r0.size - flat.size, 1)
    _, S, Vt = np.linalg.svd(Js, full_matrices=False)
    kept = S > 1e-7 * S[0]                             # directions the data determine
    cov = (Vt[kept].T / S[kept] ** 2) @ Vt[kept] * float(r0 @ r0) / dof
    se = scale * np.sqrt(np.clip(np.diag(cov), 0, None))
    free = (Vt[~kept] ** 2).sum(axis=0) > 1e-2        # a parameter with a share in an undetermined direction
    se[free] = np.inf
    parts = np.split(se, np.cumsum(sizes)[:-1])
    return {k: (v.tolist() if np.ndim(params[k]) else float(v[0])) for k, v in zip(names, parts)}


def check_stability(f: Fit) -> None:
    """Drucker's stable stretch range in each mode, and which test points lie outside it (reported: a fit
    unstable inside its data is not to be used silently)."""
    p = {k: np.asarray(v) for k, v in f.parameters.items()}
    lo = min([0.1] + [0.9 * float(t.stretch.min()) for t in f.tests])
    hi = max([10.0] + [1.1 * float(t.stretch.max()) for t in f.tests])
    f.stable = {mode: list(stable_range(f.model, p, mode, lo, hi)) for mode in MODES}
    f.unstable_in_data = []
    for t in f.tests:
        lo, hi = f.stable[t.mode]
        outside = (t.stretch < lo * (1 - 1e-9)) | (t.stretch > hi * (1 + 1e-9)) | locked(f.model, p, t.mode, t.stretch)
        if outside.any():
            f.unstable_in_data.append(f"{t.mode} test {t.source or ''}: the fitted {f.model} energy is unstable "
                                      f"(Drucker) at stretch {float(t.stretch[outside][0]):.4g}, inside the data; "
                                      f"stable from {lo:.4g} to {hi:.4g}")
