"""Reading scene tables: key declarations, the typed reader that checks values against them, --set.

Every scene key is declared once as a `Key` (type, range, default, unit, one-line doc); the
reader validates through these declarations and `schema.py` turns the same declarations into
JSON Schema. Errors are one line naming the key (InputError); unknown keys are refused.
No string from a scene is ever evaluated as code.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from fem_forms.errors import InputError
from fem_forms.keys import AXES, Key, brief, check_range, range_message
from fem_forms.scene.petsc_options import check_options

@dataclass(frozen=True)
class Variants:
    """Keys that depend on the value of one discriminator key (load type, mesh generator, method)."""
    key: Key
    cases: dict                       # discriminator value -> tuple of Keys allowed for it

    def __post_init__(self):
        if tuple(self.cases) != self.key.choices:
            raise TypeError(f"{self.key.name}: its choices and its cases differ")   # a declaration error

    def owners(self, name: str) -> list:
        return [v for v, keys in self.cases.items() if any(k.name == name for k in keys)]

    def all_keys(self) -> list:
        seen, out = set(), []
        for keys in self.cases.values():
            for k in keys:
                if id(k) not in seen:
                    seen.add(id(k))
                    out.append(k)
        return out


_PLAIN_NAME = re.compile(r"^[A-Za-z0-9_-]{1,40}$")


def key_name(name: Any) -> str:
    """A table key as it appears in messages: plain names as they are, anything else quoted and shortened."""
    return name if isinstance(name, str) and _PLAIN_NAME.match(name) else brief(name, 40)


_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")     # C0 (but tab and newline), DEL and C1
_NAME = re.compile(r"^\w[\w .()+-]{0,79}$")          # \w: letters (any script), digits, _


def plain_text(v: str, key: str) -> None:
    """Refuse a string with control characters (a terminal's escape sequences would run when it is printed)."""
    if _CONTROL.search(v):
        raise InputError(f"{key} = {brief(v)}: control characters are not allowed in a scene's text")


def check_name(v: str, key: str) -> None:
    """A name the package writes into its outputs (a probe's, a support's, an obstacle's: results.json, CSV
    headers): letters, digits, spaces and _ . ( ) + -, starting with a letter, digit or _ (no path, no comma,
    no spreadsheet formula), no '..', at most 80 characters."""
    if not isinstance(v, str) or not _NAME.match(v) or ".." in v:
        raise InputError(f"{key} = {brief(v)}: a name is up to 80 letters, digits, spaces and _ . ( ) + -, "
                         "starting with a letter, digit or _ (no '/', '..' or ',')")


def check_number(v: Any, key: str, *, positive=False, nonneg=False, integer=False):
    """A finite number (a whole one with `integer`), as float (or int)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise InputError(f"{key} = {brief(v)}: must be a number")
    if integer and not isinstance(v, int):
        raise InputError(f"{key} = {brief(v)}: must be a whole number")
    if isinstance(v, int) and abs(v) > 2**63 - 1:
        raise InputError(f"{key} = {brief(v)}: too large")
    if not math.isfinite(v):
        raise InputError(f"{key} = {brief(v)}: must be finite")
    if positive and v <= 0:
        raise InputError(f"{key} = {brief(v)}: must be positive")
    if nonneg and v < 0:
        raise InputError(f"{key} = {brief(v)}: must not be negative")
    return v if integer else float(v)


def check_vector(v: Any, key: str, length: int | None = 3, *, positive=False, integer=False) -> list:
    """A list of `length` finite numbers."""
    if not isinstance(v, list) or (length is not None and len(v) != length):
        raise InputError(f"{key} = {brief(v)}: must be a list of {length} numbers")
    return [check_number(x, f"{key}[{i}]", positive=positive, integer=integer) for i, x in enumerate(v)]


def _scalar(k: Key, v: Any, key: str) -> Any:
    given = v
    if k.kind in ("number", "integer"):
        v = check_number(v, key, integer=k.kind == "integer")
    elif k.kind == "string" or k.kind == "file":
        if not isinstance(v, str):
            raise InputError(f"{key} = {brief(v)}: must be a string")
        plain_text(v, key)
        if k.name == "name":
            check_name(v, key)
    elif k.kind == "boolean":
        if not isinstance(v, bool):
            raise InputError(f"{key} = {brief(v)}: must be true or false")
    if k.choices is not None and v not in k.choices:
        raise InputError(f"{key} = {brief(v)}: " + (k.note or f"must be one of {', '.join(map(repr, k.choices))}"))
    if k.kind in ("number", "integer") and not k.checked_by:
        check_range(k, given, key)
    return v


def _elements(k: Key, v: list, key: str) -> list:
    """The numbers of a vector, each checked against k's range."""
    v = check_vector(v, key, k.length, integer=k.integer)
    for i, x in enumerate(v):
        why = range_message(k, x)
        if why:
            raise InputError(f"{key}[{i}] = {brief(x)}: {why}")
    return v


class Table:
    """A TOML table being read: values checked against Key declarations, and a check for leftovers."""

    def __init__(self, data: Any, path: str, base_dir: Path = Path(".")):
        if not isinstance(data, dict):
            raise InputError(f"{path}: must be a table, got {type(data).__name__}")
        self.data, self.path, self.base_dir, self.used = data, path, Path(base_dir), set()

    def key(self, name: Any) -> str:
        name = key_name(name)
        return f"{self.path}.{name}" if self.path else name

    def has(self, name: str) -> bool:
        return name in self.data

    def raw(self, name: str, default: Any = None) -> Any:
        self.used.add(name)
        return self.data.get(name, default)

    def table(self, name: str) -> "Table":
        return Table(self.raw(name, {}), self.key(name), self.base_dir)

    def read(self, k: Key, needed_by: str = "") -> Any:
        """The value of key k, validated and converted, or its default when absent."""
        self.used.add(k.name)
        if k.name not in self.data:
            if k.required:
                raise InputError(f"{self.key(k.name)}: missing (required{needed_by})")
            return k.value_default()
        return read_value(k, self.data[k.name], self.key(k.name), self.base_dir)

    def read_keys(self, keys, needed_by: str = "") -> dict:
        """{attribute: value} for each declared key (sub-table keys flattened into it)."""
        out = {}
        for k in keys:
            if k.kind == "table":
                if k.required and not self.has(k.name):
                    raise InputError(f"{self.key(k.name)}: missing (required table)")
                sub = self.table(k.name)
                out.update(sub.read_keys(k.keys))
                sub.done()
            else:
                out[k.target] = self.read(k, needed_by)
        return out

    def read_variant(self, common, variants: Variants) -> dict:
        """Common keys plus the keys of the case the discriminator names; a key of another case is refused."""
        case = self.read(variants.key)
        allowed = {k.name for k in variants.cases[case]}
        for k in variants.all_keys():
            if self.has(k.name) and k.name not in allowed:
                owners = " or ".join(repr(o) for o in variants.owners(k.name))
                raise InputError(f"{self.key(k.name)}: only for {variants.key.name} = {owners} "
                                 f"({variants.key.name} is {case!r})")
        values = {variants.key.target: case}
        values.update(self.read_keys(common))
        values.update(self.read_keys(variants.cases[case], f" for {variants.key.name} = {case!r}"))
        return values

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.used, key=str)
        if unknown:
            raise InputError(f"{self.key(unknown[0])}: unknown key")


def read_value(k: Key, v: Any, key: str, base_dir: Path) -> Any:
    """Check one present value against its declaration and convert it for the spec."""
    if k.kind in ("number", "integer", "string", "boolean"):
        return _scalar(k, v, key)
    if k.kind == "vector":
        return _elements(k, v, key)
    if k.kind == "points":
        if not isinstance(v, list) or not (k.min_items or 1) <= len(v) <= (k.max_items or len(v)):
            raise InputError(f"{key}: " + (k.note or f"must list at least {k.min_items or 1} points"))
        return [_elements(k, p, f"{key}[{i}]") for i, p in enumerate(v)]
    if k.kind == "axes":
        if (not isinstance(v, list) or not v or any(not isinstance(c, str) or c not in AXES for c in v)
                or len(set(v)) != len(v)):
            raise InputError(f"{key} = {brief(v)}: must be a list of distinct names from 'x', 'y', 'z'")
        return [AXES[c] for c in v]
    if k.kind == "file":
        _scalar(k, v, key)
        p = Path(v) if Path(v).is_absolute() else base_dir / v
        try:
            found = p.is_file()
        except (OSError, ValueError):                # a name too long, or one the system cannot hold
            found = False
        if not found:
            raise InputError(f"{key} = {brief(v)}: file not found")
        return p
    if k.kind == "map":
        if not isinstance(v, dict):
            raise InputError(f"{key}: must be a table name = {k.item.doc}")
        for n in v:
            check_name(n, f"{key}.{key_name(n)}")
        return {n: read_value(k.item, x, f"{key}.{key_name(n)}", base_dir) for n, x in v.items()}
    if k.kind == "options":
        if not isinstance(v, dict):
            raise InputError(f"{key}: must be a table of PETSc options")
        return check_options(v, key)
    if k.kind == "selector":
        return k.parse(v, key, k.choices)
    if k.kind == "tables":
        if not isinstance(v, list):
            raise InputError(f"{key}: must be an array of tables [[{key}]]")
        out = []
        for i, d in enumerate(v):
            t = Table(d, f"{key}[{i}]", base_dir)
            out.append(t.read_keys(k.keys))
            t.done()
        return out
    if k.kind == "selection":
        return read_selection(k, v, key)
    if k.kind == "names":
        if not isinstance(v, list) or (k.length is not None and len(v) != k.length):
            raise InputError(f"{key} = {brief(v)}: must be a list of {k.length or 'some'} names")
        for i, x in enumerate(v):
            check_name(x, f"{key}[{i}]")
        if len(set(v)) != len(v):
            raise InputError(f"{key}: names must not repeat")
        return list(v)
    if k.kind == "either":
        same = [a for a in k.keys if _shape(v) == _shape_of_kind(a.kind)]
        # among single values, the alternative of the value's own type first ("all" or 1)
        for alt in sorted(same, key=lambda a: _scalar_type(v) != _SCALAR_TYPE.get(a.kind))[:1]:
            if alt.kind != "table":
                return read_value(alt, v, key, base_dir)
            t = Table(v, key, base_dir)
            out = t.read_keys(alt.keys)
            t.done()
            return out
        raise InputError(f"{key} = {v!r}: must be " + " or ".join(a.doc for a in k.keys))
    raise TypeError(f"{key}: no reader for kind {k.kind!r}")   # a declaration error, not user input


def _shape(v: Any) -> str:
    """What an `either` key's alternatives are told apart by: a table, a list or a single value."""
    return "table" if isinstance(v, dict) else "list" if isinstance(v, list) else "value"


_SCALAR_TYPE = {"number": "number", "integer": "number", "string": "string", "file": "string", "boolean": "boolean"}


def _scalar_type(v: Any) -> str | None:
    """A single value's type, to prefer the alternative of that type among an `either` key's single values."""
    return ("boolean" if isinstance(v, bool) else "number" if isinstance(v, (int, float))
            else "string" if isinstance(v, str) else None)


def _shape_of_kind(kind: str) -> str:
    return ("table" if kind == "table" else "list" if kind in ("vector", "points", "tables", "axes", "selection", "names")
            else "value")


def read_selection(k: Key, v: Any, key: str) -> list:
    """A list of distinct names from k.choices; true gives k's default list, false an empty one."""
    if isinstance(v, bool):
        return k.value_default() if v else []
    if not isinstance(v, list) or any(not isinstance(x, str) for x in v):
        raise InputError(f"{key}: must be true, false or a list of names")
    for x in v:
        if x not in k.choices:
            raise InputError(f"{key}: unknown name {shorten(x)!r} (known: {', '.join(k.choices)})")
    if len(set(v)) != len(v):
        raise InputError(f"{key}: names must not repeat")
    return list(v)


def shorten(text: str, limit: int = 40) -> str:
    """text cut to `limit` characters, one line (for messages that quote a user's value)."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


@dataclass(frozen=True)
class Section:
    """A scene table ([mesh], [[load]], [modal], ...): its keys, the spec it builds, its cross-key rules.

    The reader checks every key against its declaration first; `rules(spec, table)` then checks
    what involves several keys (E and nu vs mu and lambda, ...) and may fill computed defaults.
    """
    name: str
    doc: str
    spec: type                                  # the dataclass built from the keys' values
    keys: tuple = ()
    variants: Variants | None = None
    rules: Callable | None = None
    array: bool = False                         # [[name]]: an array of tables
    required: bool = False
    absent: Callable | None = None              # the value when the table is missing (default: spec())
    attr: str = ""                              # the Scene attribute it is read into (default: name)
    either: bool = False                        # a table or an array of tables (read as a list)
    refuse: tuple = ()                          # (sub-key, why) pairs: keys another analysis's table reads

    def parse(self, data: Any, base_dir: Path = Path(".")) -> Any:
        """The spec (a list of specs for an array of tables) from the table's data."""
        if self.array:
            if not isinstance(data, list):
                raise InputError(f"{self.name}: must be an array of tables [[{self.name}]]")
            return [self._one(Table(d, f"{self.name}[{i}]", base_dir)) for i, d in enumerate(data)]
        return self._one(Table(data, self.name, base_dir))

    def missing(self) -> Any:
        """The value when the scene has no such table."""
        if self.required:
            raise InputError(f"{self.name}: missing (required table)")
        if self.absent is not None:
            return self.absent()
        return [] if self.array else self.spec()

    def all_keys(self) -> list:
        """Every key declared for this table (common and per case)."""
        keys = list(self.keys)
        if self.variants is not None:
            keys = [self.variants.key] + keys + self.variants.all_keys()
        return keys

    def _one(self, t: Table) -> Any:
        for name, why in self.refuse:
            if t.has(name):
                raise InputError(f"{t.key(name)}: {why}")
        values = t.read_variant(self.keys, self.variants) if self.variants else t.read_keys(self.keys)
        t.done()
        spec = self.spec(**values)
        if self.rules is not None:
            self.rules(spec, t)
        return spec
