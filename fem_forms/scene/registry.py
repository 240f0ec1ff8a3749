"""The one registry of analyses: the scene reader, `run_analysis` and the JSON Schema all ask it.

A new analysis is a module in fem_forms/scene/analyses/ declaring ANALYSIS (its sections, runner,
outputs), one entry in ANALYSES below, and its runner module in fem_forms/analyses/. Each of its
sections is read into scene.<section name> (declare a Scene field there for the type hint).
"""
from __future__ import annotations

from fem_forms.errors import InputError
from fem_forms.scene.analyses import Analysis, balance, design, dynamic, inverse, modal, static, thermal
from fem_forms.scene.reader import Key, Section

ANALYSES: dict[str, Analysis] = {a.name: a for a in (static.ANALYSIS, modal.ANALYSIS, inverse.ANALYSIS,
                                                     balance.ANALYSIS, dynamic.ANALYSIS,
                                                     thermal.ANALYSIS, design.ANALYSIS)}

ANALYSIS_KEY = Key("analysis", "string", "what to compute: " + "; ".join(
    f"{a.name}: {a.doc}" for a in ANALYSES.values()), default="static", choices=tuple(ANALYSES))


def get(name: str) -> Analysis:
    """The registered analysis called `name`."""
    if name not in ANALYSES:
        raise InputError(f"analysis = {name!r}: must be one of {', '.join(map(repr, ANALYSES))}")
    return ANALYSES[name]


def names() -> tuple[str, ...]:
    return tuple(ANALYSES)


def owned_sections() -> dict[str, tuple[tuple[Analysis, ...], Section]]:
    """Every analysis-owned section by table name, with its owners (a table several analyses read, such
    as [thermal], has several) and its main declaration: the one of the analysis named like the table
    ([balance] of analysis = "balance"; an inverse scene reads it too), else the first."""
    out: dict = {}
    for a in ANALYSES.values():
        for s in a.sections:
            owners, first = out.get(s.name, ((), s))
            out[s.name] = (owners + (a,), s if a.name == s.name else first)
    return out


def section_of(analysis: Analysis, name: str) -> Section | None:
    """The analysis's own declaration of table `name`, or None if it does not read that table."""
    return next((s for s in analysis.sections if s.name == name), None)
