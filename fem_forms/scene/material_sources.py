"""Where a [[material]]'s parameters come from when the scene does not list them: a named material of the
library (`library = "..."`) or a fit to lab tests (`fit = { uniaxial = "dogbone.csv", ... }`), run when the
scene is read so the analysis sees an ordinary model."""
from __future__ import annotations

from fem_forms.errors import InputError
from fem_forms.materials.fitting import FIT_MODELS, fit, read_test
from fem_forms.materials.homogeneous import MODES
from fem_forms.materials.library import LIBRARY, PARAMETERS, parameters, record

ATTRIBUTE = {"lambda": "lmbda"}              # scene key -> spec attribute where they differ
VOLUMETRIC = ("nu", "bulk")                  # what a user may still choose for a library or fitted rubber


def _set(s, name: str, value) -> None:
    setattr(s, ATTRIBUTE.get(name, name), value)


def _given(t, keys) -> list[str]:
    return [k for k in keys if t.has(k)]


def from_library(s, t) -> None:
    """Fill model, parameters, density and yield stress from the library entry; nu or bulk given in the scene
    replace the entry's (how nearly incompressible the part is modelled), the density too."""
    if s.library is None:
        return
    clash = _given(t, ("model", *(p for p in PARAMETERS if p not in VOLUMETRIC), "fit"))
    if clash:
        raise InputError(f"{t.key(clash[0])}: not with library = {s.library!r} (the library gives the model and its "
                         "parameters; to change them, give model and parameters instead of library)")
    entry = LIBRARY[s.library]
    s.model = entry["model"]
    own = _given(t, VOLUMETRIC)
    for name, value in parameters(s.library).items():
        if not (own and name in VOLUMETRIC):
            _set(s, name, value)
    if "E" in entry and "nu" not in entry and not own:
        raise InputError(f"{t.key('library')} = {s.library!r}: its source gives no Poisson's ratio; give nu")
    if not t.has("rho") and "rho" in entry:
        s.rho = float(entry["rho"])
    if "yield" in entry and s.strength_yield is None:
        s.strength_yield = float(entry["yield"])


def from_fit(s, t) -> None:
    """Fit the scene's model to the test files and take its parameters; a fit whose energy is unstable
    (Drucker) inside the data is refused, not used."""
    if not t.has("fit"):
        return
    key = t.key("fit")
    if s.model not in FIT_MODELS or not t.has("model"):
        raise InputError(f"{key}: give model = one of {', '.join(map(repr, FIT_MODELS))} to fit")
    clash = _given(t, tuple(p for p in PARAMETERS if p not in VOLUMETRIC))
    if clash:
        raise InputError(f"{t.key(clash[0])}: not with fit (the fit gives the parameters; keep nu or bulk)")
    files = {m: getattr(s, f"fit_{m}") for m in MODES if getattr(s, f"fit_{m}") is not None}
    if not files:
        raise InputError(f"{key}: give at least one test file: uniaxial, biaxial or shear")
    tests = [read_test(path, mode, f"{key}.{mode}") for mode, path in files.items()]
    try:
        result = fit(s.model, tests, s.fit_terms, s.fit_residual)
    except InputError as e:                          # fit's messages name fit.<key>: say which material
        raise InputError(f"{t.path}.{e}") from None
    if result.unstable_in_data:
        raise InputError(f"{key}: {result.unstable_in_data[0]}")
    for name, value in result.parameters.items():
        _set(s, name, value)
    s.fitted = result


def describe(s) -> dict:
    """results.json's account of a material's model: its name and parameters as the scene (or the library, or
    the fit) gave them, and where they came from."""
    out = {"model": s.model}
    for name in PARAMETERS:
        value = getattr(s, ATTRIBUTE.get(name, name), None)
        if value is not None:
            out[name] = value
    if s.library is not None:
        out["library"] = record(s.library)
    if s.fitted is not None:
        out["fit"] = s.fitted.summary()
    return out
