"""Sphinx configuration of the fem_forms manual: `sphinx-build -W -b html docs docs/_build/html`.

Pages are Markdown (MyST). The scene reference (reference/) and the demo tutorials (tutorials/) are written
at every build by the extensions in docs/_ext/ from the scene's key declarations and the demos themselves."""
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))          # this tree's fem_forms, for autodoc and the reference

project = "fem_forms"
author = "the fem_forms authors"
copyright = "2026, the fem_forms authors"
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "scene_reference", "demo_pages", "benchmark_tables"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]
html_theme = "furo"
smartquotes = False                     # keep TOML's straight quotes copyable: type = "gravity"
html_title = "fem_forms manual"
autodoc_typehints = "description"
autodoc_member_order = "bysource"


def _plain_bars(app, what, name, obj, options, lines):
    """Docstrings are plain text: |F - R| is a norm, not an RST substitution."""
    lines[:] = [line.replace("|", r"\|") for line in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars)
