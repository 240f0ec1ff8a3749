"""Scene files: TOML read with one-line errors, and the command line's --set KEY=VALUE overrides."""
from __future__ import annotations

from pathlib import Path
import tomllib
from typing import Any

from fem_forms.errors import InputError


def read_toml(path: str | Path, overrides: dict | None = None) -> dict:
    """The scene file as a dict, with `overrides` {"mesh.cells": [8, 1, 1], ...} applied."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"scene file {str(path)!r}: not found")
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"scene file {str(path)!r}: not valid TOML ({e})") from None
    for key, value in (overrides or {}).items():
        set_key(data, key, value)
    return data


def set_key(data: dict, dotted: str, value: Any) -> None:
    """data["a"]["b"] = value for dotted = "a.b" (tables are created as needed)."""
    node = data
    parts = dotted.split(".")
    for k in parts[:-1]:
        node = node.setdefault(k, {})
        if not isinstance(node, dict):
            raise InputError(f"--set {dotted}: {k!r} is not a table")
    node[parts[-1]] = value


def parse_assignment(text: str) -> tuple[str, Any]:
    """'mesh.cells=[8, 1, 1]' -> ("mesh.cells", [8, 1, 1]); the value is read as a TOML value."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise InputError(f"--set {text!r}: must be KEY=VALUE, e.g. --set discretization.degree=1")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()                          # a bare word: a string
    return key.strip(), value
