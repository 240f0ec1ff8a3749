"""Thin drivers, one per analysis, on the shared path in fem_forms.model.

Each analysis module provides ``run(scene, out, echo) -> summary dict``: solve, write outputs
(results.json last, atomically), print a short summary on rank 0 when echo is set, and raise
SolveError when it did not reach an answer. Which runner serves which analysis is declared once,
in the registry (fem_forms/scene/registry.py); ``run_analysis`` dispatches through it.
"""
from __future__ import annotations

from pathlib import Path

from fem_forms.scene import Scene, registry


def run_analysis(scene: Scene, out: Path, echo: bool = False, **options) -> dict:
    """Run the scene's analysis, writing into `out`; its summary dict (`options`: e.g. a dynamic
    run's restart folder)."""
    return registry.get(scene.analysis).run_function()(scene, Path(out), echo=echo, **options)
