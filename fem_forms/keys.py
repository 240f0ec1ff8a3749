"""A declared input key (type, range, default, unit, one-line doc) and its range check: shared by the scene
reader and the parts of the package that own their keys (a material validates its own parameters)."""
from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from typing import Any, Callable

from fem_forms.errors import InputError

AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class Key:
    """One scene key: its TOML type (`kind`), range, default, unit and a one-line doc.

    kinds: number, integer, string, boolean, vector (numbers; `integer` for whole ones), points
    (a list of vectors), axes (distinct names from x, y, z -> indices), file (a path that must
    exist), table (a sub-table of `keys`, read into the same spec), map (name -> `item`), options
    (PETSc option -> scalar), selector (a boundary selector read by `parse`; `choices` limits its kinds),
    selection (distinct names from `choices`; true means the default list, false none), names (distinct names
    of things the scene declares, `length` of them), tables (an array
    of sub-tables of `keys`, each read into a dict),
    either (one of the alternatives in `keys`, told apart by shape: a list or a table).
    `note` replaces the generic range message; `attr` names the spec attribute when it differs.
    """
    name: str
    kind: str
    doc: str
    default: Any = None
    unit: str = ""
    required: bool = False
    minimum: float | None = None
    exclusive_minimum: float | None = None
    maximum: float | None = None
    exclusive_maximum: float | None = None
    choices: tuple | None = None
    length: int | None = None
    min_items: int | None = None
    max_items: int | None = None
    integer: bool = False
    keys: tuple = ()
    item: "Key | None" = None
    attr: str | None = None
    note: str = ""
    default_note: str = ""            # a default computed from other keys, said in words
    parse: Callable | None = None     # selector kind: parse(value, key, allowed kinds) -> Selector
    checked_by: str = ""              # "material": the reader checks the type, the material its range (once)

    @property
    def target(self) -> str:
        """The spec attribute this key fills."""
        return self.attr or self.name

    def value_default(self) -> Any:
        """The default as the spec holds it (axes names become indices; lists are fresh copies)."""
        if self.kind == "axes" and self.default is not None:
            return [AXES[c] for c in self.default]
        return copy.deepcopy(self.default)

    def field(self) -> Any:
        """A dataclass field whose default is this key's default (so defaults are declared once)."""
        if isinstance(self.default, (list, dict)):
            return dataclasses.field(default_factory=self.value_default)
        return dataclasses.field(default=self.value_default())


def brief(v: Any, limit: int = 60) -> str:
    """repr(v) on one line and at most `limit` characters (a message must never repeat a huge value)."""
    text = repr(v)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def range_message(k: Key, v: Any) -> str | None:
    """Why v is outside k's declared range, or None."""
    lo, xlo, hi, xhi = k.minimum, k.exclusive_minimum, k.maximum, k.exclusive_maximum
    bad = ((lo is not None and v < lo) or (xlo is not None and v <= xlo)
           or (hi is not None and v > hi) or (xhi is not None and v >= xhi))
    if not bad:
        return None
    if k.note:
        return k.note
    if xlo == 0 and hi is None and xhi is None:
        return "must be positive"
    if lo == 0 and hi is None and xhi is None:
        return "must not be negative"
    left = f"[{lo}" if lo is not None else f"({xlo}" if xlo is not None else "(-inf"
    right = f"{hi}]" if hi is not None else f"{xhi})" if xhi is not None else "inf)"
    return f"must lie in {left}, {right}"


def check_range(k: Key, v: Any, key: str) -> None:
    """InputError naming `key` if the number v lies outside k's declared range."""
    why = range_message(k, v)
    if why:
        raise InputError(f"{key} = {brief(v)}: {why}")


def flat_keys(keys) -> list[Key]:
    """The keys a spec holds: sub-table keys flattened in (the reader fills them into the same spec), each
    attribute once (the first declaration's)."""
    out, seen = [], set()
    for k in keys:
        for leaf in (flat_keys(k.keys) if k.kind == "table" else [k]):
            if leaf.target not in seen:
                seen.add(leaf.target)
                out.append(leaf)
    return out


def spec_class(name: str, doc: str, keys, module: str) -> type:
    """The dataclass a scene table is read into, one field per key with the key's default: the keys are its
    one declaration (a field's type and meaning are in the key's kind, unit and doc)."""
    fields = [(k.target, Any, k.field()) for k in flat_keys(keys)]
    cls = dataclasses.make_dataclass(name, fields, namespace={"__doc__": doc})
    cls.__module__ = module
    return cls
