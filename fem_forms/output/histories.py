"""Per-step histories a term's output keeps beside the load path (a crack's force-displacement curve). Each kind
builds from a model or declines (None); the static solve calls them after every accepted load step, merges their
`summary()` into results.json, and the static analysis lets them `write(out, title, picture)` their files."""
from __future__ import annotations

from fem_forms.output.fracture import FractureHistory

KINDS = (FractureHistory.of,)


def step_histories(model, span: float) -> list:
    """The histories this model's terms keep (span: the pseudo-time at load factor 1)."""
    return [h for make in KINDS if (h := make(model, span)) is not None]
