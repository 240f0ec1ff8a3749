"""Plastic flow at a material point, written in closed form in UFL (no Newton loop at the point).

Two models, each a function of the total strain and the COMMITTED history (plastic strain eps_p,
equivalent plastic strain alpha) returning the stress and the new history:
- von Mises (J2) with linear isotropic hardening. Small strain (material "linear"): radial return.
  Trial elastic strain eps - eps_p, trial deviatoric stress s = 2 mu dev(eps - eps_p), q = sqrt(3/2 s:s),
  yield function f = q - (sigma_y + H alpha). If f > 0: dgamma = f / (3 mu + H), n = 3/2 s / q, eps_p += dgamma n,
  alpha += dgamma. ufl.derivative of the resulting stress is the algorithmic consistent tangent.
  Finite strain (material "neo-hookean"): Simo's multiplicative J2 (return_map_finite), history C_p^-1.
- O'Brien, Bargteil & Hodgins (2002), as the lecture gives it: eps_e = E - eps_p with E the total strain
  (Green strain for stvk, small strain for linear), eps' = dev eps_e; if |eps'| > gamma1 (Frobenius):
  d eps_p = (|eps'| - gamma1)/|eps'| eps', then eps_p := (eps_p + d eps_p) min(1, gamma2/|eps_p + d eps_p|).
  The paper updates eps_p explicitly after each accepted step: the stress of a step uses the committed
  eps_p, and the update is applied at commit (so the flow lags one step, as in the paper).
Parameters are fem.Constants once bound (bind_constants): a new yield stress compiles nothing.
"""
from __future__ import annotations

from dataclasses import dataclass

import ufl

from fem_forms.errors import InputError

# a tiny fraction of the yield stress inside sqrt: the norm of a zero deviator has a finite derivative
_GUARD = 1e-24
MODELS = ("von-mises", "obrien")


def dev(A):
    """Deviatoric part of a 3x3 tensor."""
    return A - ufl.tr(A) / 3 * ufl.Identity(3)


@dataclass(frozen=True)
class VonMises:
    """J2 plasticity with linear isotropic hardening (perfectly plastic when hardening = 0)."""
    yield_stress: float
    hardening: float = 0.0
    name: str = "von-mises"

    def __post_init__(self):
        if not isinstance(self.yield_stress, (int, float)):
            return                                               # bound to Constants: checked already
        if not self.yield_stress > 0:
            raise InputError(f"material.plasticity.yield_stress = {self.yield_stress}: must be positive")
        if not self.hardening >= 0:
            raise InputError(f"material.plasticity.hardening = {self.hardening}: must not be negative")

    def return_map(self, mu, eps, eps_p_old, alpha_old):
        """(elastic strain, new plastic strain, new equivalent plastic strain) after the radial return."""
        s = 2 * mu * dev(eps - eps_p_old)
        q = ufl.sqrt(1.5 * ufl.inner(s, s) + _GUARD * self.yield_stress**2)
        f = q - (self.yield_stress + self.hardening * alpha_old)
        dgamma = ufl.conditional(ufl.gt(f, 0), f, 0) / (3 * mu + self.hardening)
        eps_p = eps_p_old + dgamma * 1.5 * s / q
        return eps - eps_p, eps_p, alpha_old + dgamma


    def return_map_finite(self, mu, kappa, F, Cp_inv_old, alpha_old):
        """Simo's finite-strain J2 (Simo & Hughes, Computational Inelasticity, 1998, Box 9.1), closed form on
        the isochoric elastic left Cauchy-Green tensor, no eigen-decomposition. Elastic law (Simo's split):
        psi = kappa/2 (ln J)^2 + mu/2 (tr bbar_e - 3). Returns (Kirchhoff stress, new C_p^-1, new alpha)."""
        I = ufl.Identity(3)
        J = ufl.det(F)
        be_trial = F * Cp_inv_old * F.T
        bbar = J ** (-2.0 / 3.0) * be_trial
        Ie = ufl.tr(bbar) / 3
        s_trial = mu * dev(bbar)
        norm = ufl.sqrt(ufl.inner(s_trial, s_trial) + _GUARD * self.yield_stress**2)
        f = norm - (2.0 / 3.0) ** 0.5 * (self.yield_stress + self.hardening * alpha_old)
        mu_bar = mu * Ie
        dgamma = ufl.conditional(ufl.gt(f, 0), f, 0) / (2 * mu_bar * (1 + self.hardening / (3 * mu_bar)))
        s = s_trial - 2 * mu_bar * dgamma * s_trial / norm
        tau = kappa * ufl.ln(J) * I + s
        be_new = J ** (2.0 / 3.0) * (s / mu + Ie * I)
        Finv = ufl.inv(F)
        return tau, Finv * be_new * Finv.T, alpha_old + (2.0 / 3.0) ** 0.5 * dgamma


@dataclass(frozen=True)
class OBrien:
    """O'Brien-Bargteil-Hodgins plasticity: elastic limit gamma1, plastic limit gamma2 (strains)."""
    elastic_limit: float
    plastic_limit: float
    name: str = "obrien"

    def __post_init__(self):
        if not isinstance(self.elastic_limit, (int, float)):
            return
        if not 0 < self.elastic_limit < self.plastic_limit:
            raise InputError(f"material.plasticity: need 0 < elastic_limit < plastic_limit "
                             f"(got {self.elastic_limit}, {self.plastic_limit})")

    def elastic_strain(self, E, eps_p_old):
        """The strain the elastic forces come from: total minus the committed plastic strain."""
        return E - eps_p_old

    def update(self, E, eps_p_old):
        """The new plastic strain from the accepted total strain E (applied at commit)."""
        d = dev(E - eps_p_old)
        g1, g2 = self.elastic_limit, self.plastic_limit
        norm = ufl.sqrt(ufl.inner(d, d) + _GUARD * g1**2)
        trial = eps_p_old + ufl.conditional(ufl.gt(norm, g1), (norm - g1) / norm, 0) * d
        tnorm = ufl.sqrt(ufl.inner(trial, trial) + _GUARD * g1**2)
        return trial * ufl.conditional(ufl.gt(tnorm, g2), g2 / tnorm, 1)


def make_plasticity(model: str | None, yield_stress=None, hardening=0.0, elastic_limit=None,
                    plastic_limit=None):
    """The named plastic model from the [material.plasticity] values (None: no plasticity)."""
    if model is None:
        return None
    if model == "von-mises":
        if yield_stress is None:
            raise InputError("material.plasticity.yield_stress: missing (required for model = 'von-mises')")
        return VonMises(float(yield_stress), float(hardening))
    if model == "obrien":
        if elastic_limit is None or plastic_limit is None:
            raise InputError("material.plasticity: model = 'obrien' needs elastic_limit and plastic_limit")
        return OBrien(float(elastic_limit), float(plastic_limit))
    raise InputError(f"material.plasticity.model = {model!r}: unknown (choose from {', '.join(MODELS)})")
