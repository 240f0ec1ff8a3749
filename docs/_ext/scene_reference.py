"""The scene reference (docs/reference/): one page per scene table, written at every build from the key
declarations (fem_forms.scene.manual walks them, the CLI's error pointers walk the same), so a key the code
declares is always documented and a key it no longer declares is gone.

Each key is a `key` object (`{key}`material.E`` links to it from any page; under -W a link to a key that does
not exist fails the build), with its type, default, range, unit and meaning.
"""
from __future__ import annotations

import re
from pathlib import Path

from sphinx.application import Sphinx
from sphinx.util import logging

from fem_forms.keys import Key
from fem_forms.scene.key_text import facts as key_facts
from fem_forms.scene.manual import Page, pages

OUT = Path(__file__).resolve().parents[1] / "reference"
logger = logging.getLogger(__name__)
GUIDES = {"scene": "scenes", "mesh": "scenes", "material": "analyses/materials", "discretization": "analyses/elements",
          "fix": "scenes", "load": "analyses/static", "solver": "analyses/static", "output": "analyses/stresses",
          "thermal": "analyses/thermal", "contact": "analyses/contact", "fracture": "analyses/fracture",
          "modal": "analyses/modal", "sound": "analyses/modal", "inverse": "analyses/inverse",
          "balance": "analyses/balance", "dynamic": "analyses/dynamic", "damping": "analyses/dynamic"}
_SPECIAL = re.compile(r"([\\*_\[\]<>|{}$])")         # backticks stay: docs quote `keys` as code


def esc(text: str) -> str:
    """Text with Markdown's special characters escaped (docs say x * y, [[x0, y0, z0], ...], a_i)."""
    return _SPECIAL.sub(r"\\\1", text)


def code(text: str) -> str:
    return f"`{text}`"


def facts(k: Key, when: list) -> list[str]:
    """The bullet lines of one declaration, in Markdown (fem_forms/scene/key_text.py writes them)."""
    return key_facts(k, when, esc=esc, code=code)


def page_text(page: Page) -> str:
    if page.name == "scene":
        title, intro = "Top-level keys", ["The keys outside any table, at the top of a scene file."]
    else:
        s0 = page.sections[0][0]
        brackets = f"[[{page.name}]]" if s0.array else f"[{page.name}]"
        title = f"`{brackets}`"
        intro = [esc(page.doc[0].upper() + page.doc[1:]) + "."]
        if s0.array:
            intro.append(f"An array of tables: write `{brackets}` once per item, any number of them.")
        if s0.either:
            intro.append(f"One table `[{page.name}]`, or several `[[{page.name}]]`.")
        owners = [a for _, analyses in page.sections for a in analyses]
        intro.append("Read by " + (", ".join(f"`analysis = \"{a}\"`" for a in owners) if owners
                                   else "every analysis") + ("; required." if s0.required else "."))
    if page.name in GUIDES:
        intro.append(f"What these keys do together: [the guide](../{GUIDES[page.name]}.md).")
    lines = [f"(reference-{page.name})=", f"# {title}", "", *intro, "",
             "Written from the key declarations in `fem_forms/` when the manual is built "
             "(`fem-forms schema` prints the same declarations as JSON Schema).", ""]
    for entry in page.entries.values():
        lines += ["```{key} " + entry.path]
        for i, (k, when) in enumerate(entry.cases):
            if len(entry.cases) > 1:
                lines += [f"**{' or '.join(when) if when else 'otherwise'}:** {esc(k.doc)}", ""]
            else:
                lines += [esc(k.doc), ""]
            lines += facts(k, [] if len(entry.cases) > 1 else when) + [""]
        lines += ["```", ""]
    return "\n".join(lines)


def index_text(all_pages: list[Page]) -> str:
    rows = ["| table | what it holds | keys |", "|---|---|---|"]
    for p in all_pages:
        label = "top level" if p.name == "scene" else f"`[{p.name}]`"
        rows.append(f"| [{label}]({p.name}.md) | {esc(p.doc)} | {len(p.entries)} |")
    return "\n".join([
        "# Scene reference", "",
        "Every key a scene file may hold, one page per table: its type, default, range, unit and meaning. These",
        "pages are written from the same declarations the scene reader checks a scene against, at every build",
        "of this manual, so they cannot drift from the code. The guides explain what the keys do together;",
        "`fem-forms schema` prints the same declarations as a JSON Schema for editors.", "",
        "An error message about a key ends with the command that prints that key's reference in the terminal",
        "and, once the manual is built, the page and anchor of that key, e.g.",
        "`(help: fem-forms help material.E; manual: docs/_build/html/reference/material.html#key-material.E)`.", "",
        *rows, "",
        "```{toctree}", ":hidden:", "", *[p.name for p in all_pages], "```", ""])


def write_if_changed(path: Path, text: str) -> None:
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)


def generate(app: Sphinx) -> None:
    OUT.mkdir(exist_ok=True)
    all_pages = pages()
    wanted = {f"{p.name}.md" for p in all_pages} | {"index.md"}
    for old in OUT.glob("*.md"):
        if old.name not in wanted:
            old.unlink()
    for p in all_pages:
        write_if_changed(OUT / f"{p.name}.md", page_text(p))
    write_if_changed(OUT / "index.md", index_text(all_pages))


def unknown_key(app: Sphinx, env, node, contnode) -> None:
    """A `{key}` link to a key the scene no longer declares: a warning (an error under -W)."""
    if node.get("refdomain") == "std" and node.get("reftype") == "key":
        logger.warning(f"no scene key {node['reftarget']!r} (the reference documents every declared key)",
                       location=node)


def setup(app: Sphinx) -> dict:
    app.add_object_type("key", "key", objname="scene key", indextemplate="pair: %s; scene key")
    app.connect("builder-inited", generate)
    app.connect("missing-reference", unknown_key)
    return {"parallel_read_safe": True, "version": "1"}
