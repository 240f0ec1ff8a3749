"""JSON Schema (draft-07) of every scene key, generated from the key declarations and the registry.

Editors that read JSON Schema for TOML (Taplo, Even Better TOML) use it to complete and check
scenes. It is generated, never written by hand, so it cannot drift from what the reader accepts.
"""
from __future__ import annotations

import json

from fem_forms.scene import registry
from fem_forms.scene.manual import BUILT
from fem_forms.scene.reader import Key, Section, Variants
from fem_forms.scene.selectors import SELECTOR_KEYS
from fem_forms.scene.spec import CORE_SECTIONS, TITLE

DRAFT = "http://json-schema.org/draft-07/schema#"
_BOUNDS = (("minimum", "minimum"), ("exclusive_minimum", "exclusiveMinimum"),
           ("maximum", "maximum"), ("exclusive_maximum", "exclusiveMaximum"))


def describe(k: Key) -> str:
    """The key's one-line doc with its unit and a computed default in words."""
    text = k.doc + (f" [{k.unit}]" if k.unit else "")
    return text + (f" (default: {k.default_note})" if k.default_note else "")


def _bounds(k: Key) -> dict:
    return {js: getattr(k, py) for py, js in _BOUNDS if getattr(k, py) is not None}


def _vector(k: Key) -> dict:
    s = {"type": "array", "items": {"type": "integer" if k.integer else "number", **_bounds(k)}}
    if k.length is not None:
        s.update(minItems=k.length, maxItems=k.length)
    return s


def _selector(kinds: tuple | None) -> dict:
    shapes = []
    for kind, keys in SELECTOR_KEYS.items():
        if kinds is None or kind in kinds:
            shapes.append(_object(keys))
    return shapes[0] if len(shapes) == 1 else {"oneOf": shapes}


def key_schema(k: Key) -> dict:
    """The JSON Schema of one declared key."""
    if k.kind in ("number", "integer"):
        s = {"type": k.kind, **_bounds(k)}
    elif k.kind in ("string", "file"):
        s = {"type": "string"}
    elif k.kind == "boolean":
        s = {"type": "boolean"}
    elif k.kind == "vector":
        s = _vector(k)
    elif k.kind == "points":
        s = {"type": "array", "items": _vector(k), "minItems": k.min_items or 1}
        if k.max_items is not None:
            s["maxItems"] = k.max_items
    elif k.kind == "axes":
        s = {"type": "array", "items": {"enum": ["x", "y", "z"]}, "minItems": 1, "uniqueItems": True}
    elif k.kind == "table":
        s = _object(k.keys)
    elif k.kind == "tables":
        s = {"type": "array", "items": _object(k.keys)}
    elif k.kind == "map":
        s = {"type": "object", "additionalProperties": key_schema(k.item)}
    elif k.kind == "options":
        s = {"type": "object", "propertyNames": {"pattern": "^[A-Za-z0-9_]+$"},
             "additionalProperties": {"type": ["string", "number", "boolean"]}}
    elif k.kind == "selector":
        s = _selector(k.choices)
    elif k.kind == "selection":
        s = {"anyOf": [{"type": "boolean"},
                       {"type": "array", "items": {"enum": list(k.choices)}, "uniqueItems": True}]}
    elif k.kind == "names":
        s = {"type": "array", "items": {"type": "string"}, "uniqueItems": True}
        if k.length is not None:
            s["minItems"] = s["maxItems"] = k.length
    elif k.kind == "either":
        s = {"oneOf": [key_schema(a) for a in k.keys]}
    else:
        raise ValueError(f"{k.name}: no schema for kind {k.kind!r}")
    if k.choices is not None and k.kind not in ("selector", "selection"):
        s["enum"] = list(k.choices)
    s["description"] = describe(k)
    if k.default is not None:
        s["default"] = k.default
    return s


def _object(keys, variants: Variants | None = None, doc: str = "") -> dict:
    """An object of declared keys, no others; with variants, each case allows only its own keys."""
    props = {k.name: key_schema(k) for k in keys}
    required = [k.name for k in keys if k.required]
    s = {"type": "object"}
    if doc:
        s["description"] = doc
    if variants is not None:
        disc = variants.key
        props[disc.name] = key_schema(disc)
        if disc.required:
            required.append(disc.name)
        union: dict[str, list] = {}
        for k in variants.all_keys():
            ks = key_schema(k)
            if ks not in union.setdefault(k.name, []):
                union[k.name].append(ks)
        for name, schemas in union.items():
            props[name] = schemas[0] if len(schemas) == 1 else {"anyOf": schemas}
        common = [k.name for k in keys] + [disc.name]
        cases = []
        for case, case_keys in variants.cases.items():
            cond = {"properties": {disc.name: {"const": case}}}
            if case != disc.default:
                cond["required"] = [disc.name]
            then = {"propertyNames": {"enum": common + [k.name for k in case_keys]}}
            narrowed = {k.name: key_schema(k) for k in case_keys if len(union[k.name]) > 1}
            if narrowed:                      # a name with different types per case (load value)
                then["properties"] = narrowed
            if any(k.required for k in case_keys):
                then["required"] = [k.name for k in case_keys if k.required]
            cases.append({"if": cond, "then": then})
        s["allOf"] = cases
    s["properties"] = props
    if required:
        s["required"] = required
    s["additionalProperties"] = False
    return s


def manual(name: str) -> str:
    """Where the manual explains a table's keys (fem_forms.scene.manual names the same pages)."""
    return f"manual: {BUILT.as_posix()}/reference/{name}.html"


def section_schema(section: Section) -> dict:
    """A section's table (or array of tables) as JSON Schema."""
    doc = f"{section.doc} ({manual(section.name)})"
    table = _object(section.keys, section.variants, doc)
    if section.array:
        return {"type": "array", "description": doc, "items": table}
    if section.either:
        return {"description": doc, "oneOf": [table, {"type": "array", "items": table, "minItems": 1}]}
    return table


def _distinct(owners, first: Section) -> list:
    """The declarations of `first`'s table by other analyses that are not `first` nor a narrowing of it (a
    narrowing has the same keys or fewer)."""
    out = []
    for a in owners:
        d = registry.section_of(a, first.name)
        if d is first or any(d is o for o in out):
            continue
        if not {k.name for k in d.all_keys()} <= {k.name for k in first.all_keys()}:
            out.append(d)
    return out


def scene_schema() -> dict:
    """The whole scene: core sections, analysis-owned sections allowed only for their analysis."""
    owned = registry.owned_sections()
    props = {TITLE.name: key_schema(TITLE), registry.ANALYSIS_KEY.name: key_schema(registry.ANALYSIS_KEY)}
    props.update({s.name: section_schema(s) for s in CORE_SECTIONS})
    rules = []
    for analysis in registry.ANALYSES.values():
        narrowed = {}
        for s in analysis.sections:
            if s is not owned[s.name][1]:     # this analysis reads a table another declares more widely
                narrowed[s.name] = section_schema(s)
                narrowed[s.name]["description"] = f"{s.doc} (analysis = {analysis.name!r}; {manual(s.name)})"
                continue
            props[s.name] = section_schema(s)
            names = " or ".join(repr(a.name) for a in owned[s.name][0])
            props[s.name]["description"] = f"{s.doc} (analysis = {names} only; {manual(s.name)})"
            others_decl = _distinct(owned[s.name][0], s)
            if others_decl:                   # declared apart by another analysis ([sound]): either shape here,
                props[s.name] = {"description": props[s.name]["description"],   # the analysis's rule narrows
                                 "anyOf": [section_schema(d) for d in [s, *others_decl]]}
        others = [name for name, (owners, _) in owned.items() if analysis not in owners]
        if others or narrowed:
            cond = {"properties": {"analysis": {"const": analysis.name}}}
            if analysis.name != registry.ANALYSIS_KEY.default:
                cond["required"] = ["analysis"]
            then = {"propertyNames": {"not": {"enum": others}}} if others else {}
            if narrowed:
                then["properties"] = narrowed
            rules.append({"if": cond, "then": then})
    analyses = "; ".join(f"{a.name} writes {', '.join(a.outputs)}" for a in registry.ANALYSES.values())
    return {
        "$schema": DRAFT,
        "title": "fem_forms scene",
        "description": f"A scene for `fem-forms run` (TOML). Outputs: {analyses}. Every key explained: "
                       f"the manual's scene reference, {BUILT.as_posix()}/reference/index.html.",
        "type": "object",
        "properties": props,
        "required": [s.name for s in CORE_SECTIONS if s.required],
        "additionalProperties": False,
        "allOf": rules,
    }


def schema_json() -> str:
    """The scene schema as indented JSON text."""
    return json.dumps(scene_schema(), indent=2) + "\n"
