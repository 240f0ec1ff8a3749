"""How a declared scene key reads: its type, default, choices, range, unit and the forms it may take, as lines of
text. The manual's scene reference (docs/_ext/scene_reference.py, Markdown) and `fem-forms help KEY` (the terminal,
plain) are both written from these lines, so the two always say the same."""
from __future__ import annotations

import json
from typing import Callable

from fem_forms.keys import Key
from fem_forms.scene.selectors import SELECTOR_KEYS


def plain(text: str) -> str:
    return text


def toml(v) -> str:
    """A value as a scene file writes it."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml(x)}" for k, x in v.items()) + " }" if v else "{}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml(x) for x in v) + "]"
    return json.dumps(v)


def kind_text(k: Key) -> str:
    number = "whole number" if k.kind == "integer" or k.integer else "number"
    n = f"{k.length} " if k.length else ""
    return {
        "number": "number", "integer": "whole number", "string": "string", "boolean": "true or false",
        "vector": f"list of {n}{number}s", "points": f"list of points (each {n}{number}s)",
        "axes": "list of distinct axis names from \"x\", \"y\", \"z\"", "file": "file path (relative to the scene file)",
        "table": "table", "tables": "array of tables", "map": "table of name = value",
        "options": "table of PETSc options (name = value)", "selector": "a table saying where, one of the shapes below",
        "selection": "true (the default list), false (none) or a list of names", "either": "one of the forms below",
        "names": "a list of names",
    }[k.kind]


def range_text(k: Key) -> str:
    if k.note:
        return k.note
    lo = f">= {k.minimum:g}" if k.minimum is not None else f"> {k.exclusive_minimum:g}" \
        if k.exclusive_minimum is not None else ""
    hi = f"<= {k.maximum:g}" if k.maximum is not None else f"< {k.exclusive_maximum:g}" \
        if k.exclusive_maximum is not None else ""
    return " and ".join(x for x in (lo, hi) if x)


def facts(k: Key, when: list, esc: Callable[[str], str] = plain, code: Callable[[str], str] = plain) -> list[str]:
    """The bullet lines of one declaration; `esc` escapes prose, `code` marks code (Markdown: backticks)."""
    out = [f"- type: {esc(kind_text(k))}"]
    if k.required:
        out.append("- required" + (f" (for {esc(', '.join(when))})" if when else ""))
    if k.default is not None and k.default != [] or k.default_note:
        default = code(toml(k.default)) if k.default is not None else ""
        note = esc(k.default_note) if k.default_note else ""
        out.append(f"- default: {default}{' ' if default and note else ''}{note}")
    if k.choices is not None and k.kind not in ("selector",):
        out.append("- one of: " + ", ".join(code(toml(c)) for c in k.choices))
    rng = range_text(k)
    if rng and k.kind in ("number", "integer", "vector", "points"):
        out.append(f"- range: {esc(rng)}" + (" (each number)" if k.kind in ("vector", "points") and not k.note else "")
                   + (" (checked by the material model)" if k.checked_by else ""))
    if k.unit:
        out.append(f"- unit: {esc(k.unit)}")
    if when:
        out.append("- only for: " + ", ".join(code(w) for w in when))
    if k.kind == "selector":
        for kd in [kd for kd in SELECTOR_KEYS if k.choices is None or kd in k.choices]:
            keys = SELECTOR_KEYS[kd]
            out.append(f"- {code('{ ' + ', '.join(f'{s.name} = ...' for s in keys) + ' }')}: "
                       + "; ".join(esc(s.doc) for s in keys))
    if k.kind == "map" and k.item is not None:
        out.append(f"- each value: {esc(kind_text(k.item))}, {esc(k.item.doc)}"
                   + (f" [{esc(k.item.unit)}]" if k.item.unit else ""))
    if k.kind == "either":
        for alt in k.keys:
            out.append(f"- or {esc(kind_text(alt))}: {esc(alt.doc)}")
    return out
