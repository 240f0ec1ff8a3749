"""What each analysis declares for the registry: its name, its own scene sections, its runner, its outputs.

These declarations live in the scene package, one module per analysis, rather than beside the
runners in fem_forms/analyses/: the scene reader must know every analysis's sections without
importing dolfinx, and any module under fem_forms/analyses/ first runs that package's __init__,
which dispatches through the registry; declaring them there would close an import cycle
(scene -> registry -> analyses -> registry). The runner is named "module:function" and imported
when the analysis runs, for the same two reasons (runners import dolfinx and fem_forms.scene).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Analysis:
    """One analysis: the scene sections it owns, how it runs, the files it writes."""
    name: str
    doc: str
    runner: str                         # "package.module:function", run(scene, out, echo) -> summary
    sections: tuple = ()                # reader.Section objects: tables only this analysis accepts
    outputs: tuple = ()                 # file names written into the output folder
    formulations: tuple = ("displacement",)
    check: Callable | None = None       # check(scene): rules across sections, after all are read

    def run_function(self) -> Callable:
        """The runner, imported on first use."""
        module, _, function = self.runner.partition(":")
        return getattr(importlib.import_module(module), function)
