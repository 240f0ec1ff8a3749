"""docs/benchmarks/tables.md: every table in benchmarks/*.md, included (never copied) at every build, so a
benchmark script's new table is in the manual as soon as it is written."""
from __future__ import annotations

from pathlib import Path

from sphinx.application import Sphinx

DOCS = Path(__file__).resolve().parents[1]
TABLES = DOCS.parent / "benchmarks"


def page_text() -> str:
    lines = ["# All benchmark tables", "",
             "Each table as its script wrote it (`benchmarks/<name>.py` writes `benchmarks/<name>.md`); the pages",
             "before this one say what the main ones mean.", ""]
    for f in sorted(TABLES.glob("*.md")):
        text = f.read_text().splitlines()
        start = 1 if text and text[0].startswith("# ") else 0
        title = text[0][2:].strip() if start else f.stem.replace("_", " ")
        lines += [f"## {title}", "", f"From `benchmarks/{f.name}`.", "",
                  f"```{{include}} ../../benchmarks/{f.name}", f":start-line: {start}", "```", ""]
    return "\n".join(lines)


def generate(app: Sphinx) -> None:
    path = DOCS / "benchmarks" / "tables.md"
    text = page_text()
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)


def setup(app: Sphinx) -> dict:
    app.connect("builder-inited", generate)
    return {"parallel_read_safe": True, "version": "1"}
