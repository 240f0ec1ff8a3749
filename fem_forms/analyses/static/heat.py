"""A coupled steady temperature in a static scene ([thermal]): solved first (heat alone, staggered), then the
mechanics with its thermal strain ramped by the load factor."""
from __future__ import annotations

from fem_forms.errors import InputError, SolveError
from fem_forms.model import Model
from fem_forms.physics.thermal import HeatForms
from fem_forms.physics.thermoelastic import young_modulus
from fem_forms.solvers.thermal_step import HeatSolver, max_value, min_value
from fem_forms.state import State


def solve_temperature(model: Model) -> None:
    """The steady temperature of a coupled static scene (staggered: heat first, then the mechanics with
    its thermal strain ramped by the load factor); SolveError if the heat solve fails."""
    scene = model.scene
    T = model.temperature
    forms = HeatForms(scene.thermal, scene.materials, model.loaded, T, model.state.old["temperature"],
                      False, scene.discretization.quadrature, regions=model.context.materials)
    out = HeatSolver(forms, State({"temperature": T}), linear_kind=scene.solver.linear).solve()
    if not out.accepted:
        raise SolveError(f"{scene.title}: the steady heat problem did not converge ({out.why})")
    check_modulus(model)
    model.state.commit()


def check_modulus(model: Model) -> None:
    """E(T) = E + dE/dT (T - T_ref) must stay positive over the temperatures reached (one-line InputError)."""
    th = model.scene.thermal
    if th.modulus_slope == 0.0:
        return
    E = young_modulus(model.material)
    for T in (min_value(model.temperature), max_value(model.temperature)):
        if E + th.modulus_slope * (T - th.reference_temperature) <= 0:
            raise InputError(f"thermal.modulus_slope = {th.modulus_slope}: E(T) = "
                             f"{E + th.modulus_slope * (T - th.reference_temperature):.4g} Pa at T = {T:.6g} "
                             "is not positive")
