"""The tutorials (docs/tutorials/<demo>.md): one page per demos/*.py, written at every build from the demo's
docstring (Markdown), its scene files and source (included, so never copied), what it printed
(docs/demos/<demo>.txt) and the pictures it drew (docs/demos/<demo>/).

The printed output and pictures come from `python docs/refresh_demos.py`; the test suite compares every demo's
output with its transcript (docs/demo_transcripts.py), so a page cannot show numbers the code no longer gives.
A demo without a transcript or a picture, or a transcript without a demo, is a build warning (an error under -W).
"""
from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

from sphinx.application import Sphinx
from sphinx.util import logging

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from demo_transcripts import REPORT_SHOT  # noqa: E402

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
DEMOS = ROOT / "demos"
STORED = DOCS / "demos"
OUT = DOCS / "tutorials"
logger = logging.getLogger(__name__)


def split_docstring(source: str, name: str) -> tuple[str, str]:
    """(title, body) of a demo's docstring: a leading "# Title" line, else its first paragraph."""
    doc = (ast.get_docstring(ast.parse(source)) or name).strip()
    first, _, rest = doc.partition("\n\n")
    rest = rest.strip("\n")                      # keep an indented first line: a code block
    if first.startswith("# ") and "\n" not in first:
        return first[2:].strip(), rest
    return " ".join(first.split()).rstrip("."), rest


def scenes_of(source: str, name: str) -> list[Path]:
    """The scene files of demos/scenes/ a demo reads (named in its source, with or without ".toml")."""
    named = re.findall(r"([A-Za-z0-9_]+)\.toml", source) + re.findall(r"[\"']([A-Za-z0-9_]+)[\"']", source)
    names = dict.fromkeys(named)
    if (DEMOS / "scenes" / f"{name}.toml").is_file():
        names = {name: None, **names}
    return [DEMOS / "scenes" / f"{n}.toml" for n in names if (DEMOS / "scenes" / f"{n}.toml").is_file()]


def checks() -> dict[str, tuple[str, str, str]]:
    """demo -> (test file, test name, its docstring): the test the suite checks each demo with (the CHECKS table of
    tests/system/demo_runs.py, read without importing the tests)."""
    tests = ROOT / "tests" / "system"
    tree = ast.parse((tests / "demo_runs.py").read_text())
    table = next(ast.literal_eval(n.value) for n in tree.body
                 if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", "") == "CHECKS")
    found = {}
    for path in sorted(tests.glob("test_*.py")):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.FunctionDef) and node.name in table.values():
                found[node.name] = (path.name, node.name, " ".join((ast.get_docstring(node) or "").split()))
    return {demo: found[test] for demo, test in table.items() if test in found}


def page_text(name: str, checked: tuple[str, str, str] | None = None) -> str:
    source = (DEMOS / f"{name}.py").read_text()
    title, body = split_docstring(source, name)
    lines = [f"(tutorial-{name})=", f"# {title}", "", body, "", "## Run it", "", "```sh",
             f".venv/bin/python demos/{name}.py            # writes out/{name}/", "```", ""]
    transcript = STORED / f"{name}.txt"
    if transcript.is_file():
        lines += ["## What it prints", "", f"```{{literalinclude}} ../demos/{name}.txt", ":language: text", "```", ""]
    else:
        logger.warning(f"demos/{name}.py has no transcript docs/demos/{name}.txt: "
                       f"run `python docs/refresh_demos.py {name}`")
    if checked is not None and checked[2]:
        lines += ["## What it is checked against", "", checked[2], "",
                  f"The test suite runs the demo and checks this: `tests/system/{checked[0]}::{checked[1]}`.", ""]
    else:
        logger.warning(f"demos/{name}.py: no test with a docstring checks it (tests/system/demo_runs.py CHECKS)")
    shot = STORED / name / REPORT_SHOT
    if shot.is_file():
        lines += ["## Its report.html", "",
                  "The run's page in the browser (`fem-forms view OUT`), as the demo left it:", "",
                  f"```{{figure}} ../demos/{name}/{REPORT_SHOT}", ":alt: report.html", "```", ""]
    pictures = [p for p in sorted((STORED / name).glob("*.png")) + sorted((STORED / name).glob("*.gif"))
                if p.name != REPORT_SHOT]
    if pictures:
        lines += ["## Pictures", ""]
        for p in pictures:
            lines += [f"```{{figure}} ../demos/{name}/{p.name}", f":alt: {p.stem}", "", f"`{p.name}`", "```", ""]
    else:
        logger.warning(f"demos/{name}.py has no pictures in docs/demos/{name}/: "
                       f"run `python docs/refresh_demos.py {name}`")
    for scene in scenes_of(source, name):
        lines += [f"## The scene: `demos/scenes/{scene.name}`", "",
                  f"```{{literalinclude}} ../../demos/scenes/{scene.name}", ":language: toml", "```", ""]
    lines += [f"## The script: `demos/{name}.py`", "",
              f"```{{literalinclude}} ../../demos/{name}.py", ":language: python", "```", ""]
    return "\n".join(lines)


def generate(app: Sphinx) -> None:
    OUT.mkdir(exist_ok=True)
    names = sorted(p.stem for p in DEMOS.glob("*.py"))
    for stale in sorted(set(p.stem for p in STORED.glob("*.txt")) - set(names)):
        logger.warning(f"docs/demos/{stale}.txt belongs to no demo: remove it")
    wanted = {f"{n}.md" for n in names} | {"index.md"}           # index.md: the hand-written overview
    for old in OUT.glob("*.md"):
        if old.name not in wanted:
            old.unlink()
    checked = checks()
    for name in names:
        text = page_text(name, checked.get(name))
        path = OUT / f"{name}.md"
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)


def setup(app: Sphinx) -> dict:
    app.connect("builder-inited", generate)
    return {"parallel_read_safe": True, "version": "1"}
