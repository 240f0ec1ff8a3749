"""Command line: `fem-forms run SCENE.toml --out DIR [-snes_monitor ...]`.

Exit status: 0 solved, 2 bad input (one line on stderr naming the key), 3 no convergence."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import InputError, SolveError
from .logs import quiet_jit


def _petsc_options(extra: list[str]) -> dict:
    """PETSc-style trailing options (`-snes_rtol 1e-8 -snes_monitor`) as a dict."""
    opts, i = {}, 0
    while i < len(extra):
        tok = extra[i]
        if not (tok.startswith("-") and len(tok) > 1 and tok[1:].replace("_", "").isalnum()):
            raise InputError(f"command line: {tok!r} is not an option (PETSc options look like -snes_rtol 1e-8)")
        key = tok.lstrip("-")
        if i + 1 < len(extra) and not (extra[i + 1].startswith("-") and extra[i + 1][1:2].isalpha()):
            opts[key] = extra[i + 1]
            i += 2
        else:
            opts[key] = ""
            i += 1
    return opts


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="fem-forms", description="Hyperelastic solids from scene files.")
    sub = p.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="solve a scene file and write results to --out",
                         epilog="Trailing -key value pairs are passed to PETSc (e.g. -snes_monitor).")
    run.add_argument("scene", help="scene file (TOML)")
    run.add_argument("--out", required=True, help="output folder (created)")
    run.add_argument("-v", "--verbose", action="store_true", help="show FFCx/UFL compilation logs")
    return p


def _run(args, petsc: dict) -> int:
    from .scene import Scene
    from .analyses import run_analysis

    scene = Scene.from_file(args.scene)
    scene.solver.petsc.update(petsc)
    run_analysis(scene, Path(args.out), echo=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = _parser()
    args, extra = parser.parse_known_args(argv)
    quiet_jit(args.verbose)
    rank = 0
    try:
        from mpi4py import MPI
        rank = MPI.COMM_WORLD.rank
        petsc = _petsc_options(extra)
        return _run(args, petsc)
    except (InputError, SolveError) as e:
        if rank == 0:
            print(f"fem-forms: error: {e}", file=sys.stderr)
        return e.exit_status


def entry() -> None:
    sys.exit(main())
