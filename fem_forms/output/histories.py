"""Per-step histories a term's output keeps beside the load path (a crack's force-displacement curve). A term
names the kinds it keeps (`Term.step_histories`); the static solve calls them after every accepted load step, merges
their `summary()` into results.json, and the static analysis lets them `write(out, title, picture)` their files."""
from __future__ import annotations

from fem_forms.output.fracture import FractureHistory

KINDS = {"crack": FractureHistory}


def step_histories(model, span: float) -> list:
    """The histories this model's terms keep (span: the pseudo-time at load factor 1)."""
    return [KINDS[kind](model, span, term) for term in model.terms for kind in term.step_histories]
