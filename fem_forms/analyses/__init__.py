"""Thin drivers, one per analysis, on the shared path in fem_forms.model.

Each analysis module provides ``run(scene, out, echo) -> summary dict``: solve, write outputs
(results.json last, atomically), print a short summary on rank 0 when echo is set, and raise
SolveError when it did not reach an answer. ``run_analysis`` dispatches on ``scene.analysis``.
"""
from __future__ import annotations

import importlib
from pathlib import Path

RUNNERS = {"static": "static", "modal": "modal", "inverse": "inverse"}      # scene.analysis -> module in this package


def run_analysis(scene, out: Path, echo: bool = False) -> dict:
    module = importlib.import_module(f"{__name__}.{RUNNERS[scene.analysis]}")
    return module.run(scene, Path(out), echo=echo)
