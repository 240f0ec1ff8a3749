"""Scene files: TOML read with one-line errors, and the command line's --set KEY=VALUE overrides."""
from __future__ import annotations

from pathlib import Path
import tomllib
from typing import Any

from fem_forms.errors import InputError
from fem_forms.scene.limits import LIMITS, Limits, nesting_depth


def read_toml(path: str | Path, overrides: dict | None = None, limits: Limits = LIMITS) -> dict:
    """The scene file as a dict, with `overrides` {"mesh.cells": [8, 1, 1], ...} applied. A file larger than
    limits.scene_bytes is refused before it is read, one nested deeper than limits.nesting once parsed."""
    path = Path(path)
    name = f"scene file {str(path)!r}"
    if not path.is_file():
        raise InputError(f"{name}: not found")
    limits.check("scene_bytes", path.stat().st_size, name, "bytes")
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"{name}: not valid TOML ({e})") from None
    except RecursionError:
        raise InputError(f"{name}: tables and arrays nested too deeply to read") from None
    limits.check("nesting", nesting_depth(data), name, "levels of tables and arrays inside each other")
    for key, value in (overrides or {}).items():
        set_key(data, key, value)
    return data


# keys a table of this `type` may spell two ways (a pressure load's pressure, first spelled value): an override of
# one replaces the other, so `--set load.0.pressure=...` works on a scene that says value = ...
SPELLINGS = {"pressure": ("pressure", "value")}


def set_key(data: dict, dotted: str, value: Any) -> None:
    """data["a"]["b"] = value for dotted = "a.b" (tables are created as needed). An integer part indexes an
    array, e.g. "load.0.value" (the first [[load]]) or "mesh.cells.0"; an index out of range, a word into
    an array or a part below a plain value is refused in one line (InputError) naming the key."""
    node: Any = data
    parts = dotted.split(".")
    for depth, k in enumerate(parts):
        last = depth == len(parts) - 1
        where = ".".join(parts[:depth]) or "the scene"
        if isinstance(node, list):
            k = _index(node, k, dotted, where)
        elif not isinstance(node, dict):
            raise InputError(f"--set {dotted}: {where!r} is a {type(node).__name__}, not a table or an array")
        elif not last and k not in node and parts[depth + 1].lstrip("-").isdigit():
            raise InputError(f"--set {dotted}: the scene has no {'.'.join(parts[:depth + 1])!r} array to index")
        if last:
            if isinstance(node, dict) and k in SPELLINGS.get(node.get("type"), ()):
                for other in SPELLINGS[node["type"]]:
                    node.pop(other, None)
            node[k] = value
        elif isinstance(node, dict):
            node = node.setdefault(k, {})
        else:
            node = node[k]


def _index(array: list, part: str, dotted: str, where: str) -> int:
    """The integer `part` as an index into `array` (the value at key `where`), or a one-line InputError."""
    valid = f"0..{len(array) - 1}" if array else "none: it is empty"
    if not part.isdigit():
        raise InputError(f"--set {dotted}: {where!r} is an array: index it with an integer ({valid}), not {part!r}")
    if int(part) >= len(array):
        raise InputError(f"--set {dotted}: index {part} is out of range: {where!r} has {len(array)} "
                         f"entr{'y' if len(array) == 1 else 'ies'} ({valid})")
    return int(part)


def parse_assignment(text: str) -> tuple[str, Any]:
    """'mesh.cells=[8, 1, 1]' -> ("mesh.cells", [8, 1, 1]); the value is read as a TOML value."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise InputError(f"--set {text!r}: must be KEY=VALUE, e.g. --set discretization.degree=1")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()                          # a bare word: a string
    except RecursionError:
        raise InputError(f"--set {key.strip()}: the value is nested too deeply to read") from None
    return key.strip(), value
