"""Where the manual explains a scene key: one reference page per scene table, one anchor per key.

The manual's scene reference (docs/_ext/scene_reference.py) is written from `pages()` below, `fem-forms help KEY`
prints one key from them (`help_text`), and the CLI points an error message at its key (`manual_key`,
`manual_page`): all walk the same declarations, so a pointer always names a key, a page and an anchor that exist. The manual is built with `sphinx-build -W -b html docs docs/_build/html`.
"""
from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path

from fem_forms.errors import InputError
from fem_forms.scene import registry
from fem_forms.scene.key_text import facts
from fem_forms.scene.reader import Key, Section
from fem_forms.scene.spec import CORE_SECTIONS, TITLE

BUILT = Path("docs") / "_build" / "html"           # the built manual, relative to the repository
SCENE_PAGE = "scene"                                # the page of the top-level keys (title, analysis)
_PATH = re.compile(r"^[A-Za-z_][\w-]*(?:\[\d+\])?(?:\.[A-Za-z_][\w-]*(?:\[\d+\])?)*")


@dataclass
class Entry:
    """One documented key: its dotted path below the scene, its declarations and when each applies."""
    path: str
    cases: list = field(default_factory=list)      # [(Key, condition such as "type = 'gravity'" or "")]


@dataclass
class Page:
    """A reference page: a scene table (or the top level), its sections' declarations, its keys."""
    name: str
    doc: str
    sections: list                                   # [(Section, analyses that read it: () for every one)]
    entries: dict = field(default_factory=dict)      # path -> Entry, in declaration order

    def add(self, path: str, k: Key, when: str = "") -> None:
        e = self.entries.setdefault(path, Entry(path))
        for other, conds in e.cases:
            if other is k:
                if when and when not in conds:
                    conds.append(when)
                return
        e.cases.append((k, [when] if when else []))
        for sub in _subkeys(k):
            self.add(f"{path}.{sub.name}", sub, when)


def _subkeys(k: Key) -> tuple:
    """The keys inside a sub-table, an array of sub-tables or the table alternative of an `either` key."""
    if k.kind in ("table", "tables"):
        return k.keys
    if k.kind == "either":
        return tuple(s for alt in k.keys if alt.kind == "table" for s in alt.keys)
    return ()


def _add_section(page: Page, s: Section) -> None:
    if s.variants is not None:
        page.add(f"{s.name}.{s.variants.key.name}", s.variants.key)
    for k in s.keys:
        page.add(f"{s.name}.{k.name}", k)
    if s.variants is not None:
        for case, keys in s.variants.cases.items():
            for k in keys:
                page.add(f"{s.name}.{k.name}", k, f'{s.variants.key.name} = "{case}"')


def pages() -> list[Page]:
    """Every reference page: the top-level keys, the core tables, then the tables analyses own."""
    top = Page(SCENE_PAGE, "the scene file's top-level keys", [])
    top.add(TITLE.name, TITLE)
    top.add(registry.ANALYSIS_KEY.name, registry.ANALYSIS_KEY)
    out = [top]
    for s in CORE_SECTIONS:
        page = Page(s.name, s.doc, [(s, ())])
        _add_section(page, s)
        out.append(page)
    for name, (owners, first) in registry.owned_sections().items():
        page = Page(name, first.doc, [])
        for a in owners:
            s = registry.section_of(a, name)
            page.sections.append((s, (a.name,)))
            _add_section(page, s)
        out.append(page)
    return out


def anchor(path: str) -> str:
    """The HTML anchor of a key on its page (Sphinx's id for the `key` object the reference declares)."""
    return f"key-{path}"


def key_paths() -> dict[str, str]:
    """Every documented key path -> the name of its page."""
    return {path: p.name for p in pages() for path in p.entries}


def manual_key(message: str) -> str | None:
    """The documented key (the longest) an error message starts with, e.g. "material[1].E = -1: ..." ->
    "material.E", or its table ("mesh" for "mesh.cellz: unknown key"); None when it names no scene key."""
    m = _PATH.match(message)
    if not m or re.match(r" [A-Za-z]", message[m.end():]) or "(manual: " in message:
        return None                                 # "scene file 'x': ...", or a message already pointing
    parts = re.sub(r"\[\d+\]", "", m.group()).split(".")
    known = key_paths()
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in known:
            return ".".join(parts[:n])
    return parts[0] if parts[0] in {p.name for p in pages()} else None


def manual_page(message: str) -> str | None:
    """The reference page (and the anchor of the key) for an error message that starts with a scene key, e.g.
    "material[1].E = -1: ..." -> "reference/material.html#key-material.E"; None when it names no scene key."""
    key = manual_key(message)
    if key is None:
        return None
    known = key_paths()
    return f"reference/{known[key]}.html#{anchor(key)}" if key in known else f"reference/{key}.html"


def help_text(key: str) -> str:
    """`fem-forms help KEY`: the key's reference as the manual gives it (a table: its keys), in plain text."""
    key = re.sub(r"\[\d+\]", "", key.strip())
    for page in pages():
        if key in page.entries:
            entry = page.entries[key]
            lines = [f"{key}  (manual page: reference/{page.name})"]
            for k, when in entry.cases:
                lines += ["", (f"{' or '.join(when)}: " if len(entry.cases) > 1 and when else "") + k.doc]
                lines += facts(k, [] if len(entry.cases) > 1 else when)
            return "\n".join(lines)
        if key == page.name or (key in ("", "scene") and page.name == SCENE_PAGE):
            rows = [f"{path:<32} {e.cases[0][0].doc}" for path, e in page.entries.items()]
            return "\n".join([f"[{page.name}]: {page.doc}", "", *rows])
    close = difflib.get_close_matches(key, list(key_paths()) + [p.name for p in pages()], n=3)
    raise InputError(f"help {key!r}: no such scene key" + (f" (did you mean {', '.join(close)}?)" if close else
                                                            " (fem-forms help mesh lists a table's keys)"))


def built(page: str) -> str:
    """A page of the built manual as a path: relative to the working folder when it lies below it."""
    root = Path(__file__).resolve().parents[2]
    target = root / BUILT / page
    try:
        return str(target.relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(target)
