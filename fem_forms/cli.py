"""Command line: `fem-forms run SCENE.toml [--out DIR] [-q] [--no-limits] [--petsc "-log_view"] [-snes_monitor ...]`,
`fem-forms study SCENE.toml`,
`fem-forms fit TEST.csv ... --model M [--terms N] [--mode uniaxial|biaxial|shear] [--out DIR]`,
`fem-forms schema [--out FILE]`, `fem-forms faces CAD_FILE [--units mm] [--out DIR]` (the faces numbered),
`fem-forms help KEY` (a scene key's reference; error messages about a key end with this command),
`fem-forms view OUT` (a run's report.html in the browser).

Exit status: 0 solved, 2 bad input (one line on stderr naming the key), 3 no convergence (a static limit
point included), 1 a form whose compile never finished (a killed run's lock in the form cache), 130
interrupted (Ctrl-C), 143 terminated (SIGTERM); an interrupt prints one line, "fem-forms: interrupted", no
traceback, and a static run leaves its last accepted load step and a results.json with "interrupted": true
(output/interrupts.py, also under mpirun).
Progress (load step, Newton iteration, residual, elapsed time) goes to stderr on rank 0 unless --quiet.
A scene is data (docs/sharing.md): its PETSc options are the ones users tune, its caps (scene/limits.py) hold
unless --no-limits, and nothing is written outside the output folder (output/folder.py); the command line is the
user's own, so PETSc options given there (trailing, or --petsc) may be any, -log_view included.
Results: results.json is written last and atomically, and a run removes an old results.json from its
output folder before it solves, so after an interrupted or failed rerun no results.json from an earlier
run is left looking like this run's answer (a scene that fails to read changes nothing)."""
from __future__ import annotations

import argparse
from pathlib import Path
import shlex
import signal
import sys

from mpi4py import MPI

from fem_forms.analyses import run_analysis
from fem_forms.errors import InputError, SolveError
from fem_forms.logs import quiet_jit, stale_compile_lock
from fem_forms.materials.fitting import FIT_MODELS, RESIDUALS, fit as fit_model, read_test
from fem_forms.materials.homogeneous import MODES
from fem_forms.output.fit_report import fit_text, write_fit
from fem_forms.meshes.cad import cad_faces
from fem_forms.output.faces_report import faces_text, write_faces
from fem_forms.output.folder import check_output_folder
from fem_forms.output.interrupts import Terminated
from fem_forms.output.progress_line import show_progress
from fem_forms.output.results import forget_results
from fem_forms.scene import LIMITS, NO_LIMITS, Scene, parse_assignment
from fem_forms.scene.manual import built, help_text, manual_key, manual_page
from fem_forms.scene.petsc_options import check_options
from fem_forms.scene.schema import schema_json
from fem_forms.scene.spec import CAD_SUFFIXES, UNIT_SCALES
from fem_forms.solvers.petsc_log import petsc_log
from fem_forms.study import run_study, solve_to_tolerance


def _petsc_options(extra: list[str], where: str = "command line") -> dict:
    """PETSc-style trailing options (`-snes_rtol 1e-8 -snes_monitor`) as a dict."""
    opts, i = {}, 0
    while i < len(extra):
        tok = extra[i]
        if not (tok.startswith("-") and len(tok) > 1 and tok[1:].replace("_", "").isalnum()):
            raise InputError(f"{where}: {tok!r} is not an option (PETSc options look like -snes_rtol 1e-8)")
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
    manual = built("index.html")
    run = sub.add_parser("run", help="solve a scene file and write results to --out (default out/<scene stem>/)",
                         epilog="Trailing -key value pairs are passed to PETSc (e.g. -snes_monitor). Every scene "
                                f"key (type, default, range, unit, meaning) is in the manual's scene reference, "
                                f"{built('reference/index.html')}; the manual: {manual} (build it with "
                                "`.venv/bin/python -m sphinx -W -b html docs docs/_build/html`).")
    run.add_argument("scene", help="scene file (TOML)")
    run.add_argument("--out", help="output folder (created; default out/<scene file stem>/ in the current folder)")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene key, e.g. --set mesh.cells=[8,1,1] or --set load.0.value=[0,0,-5] "
                          "(TOML value; an integer part indexes an array)")
    run.add_argument("--no-adapt", action="store_true",
                     help="solve the discretization as given, ignoring [discretization] tolerance")
    run.add_argument("--restart", metavar="DIR", help="continue the stopped dynamic run in DIR from its checkpoint")
    run.add_argument("--petsc", action="append", default=[], metavar="OPTIONS",
                     help="PETSc options of your own, e.g. --petsc \"-log_view -snes_monitor\" (a scene may not set "
                          "options that write files, monitor or import code; the command line may)")
    run.add_argument("--no-limits", action="store_true",
                     help="lift the caps a scene file is held to (cells, load and time steps, modes, probes, sound "
                          "samples, obstacle triangles, the file's size)")
    run.add_argument("-v", "--verbose", action="store_true", help="show FFCx/UFL compilation logs")
    run.add_argument("-q", "--quiet", action="store_true", help="show no progress on stderr")
    study = sub.add_parser("study", help="solve a scene on a ladder of meshes and degrees; error vs cost")
    study.add_argument("scene", help="scene file (TOML); its mesh is the coarsest of the ladder")
    study.add_argument("--out", help="output folder (created; default out/<scene file stem>_study/ in the current "
                       "folder, beside a run's out/<stem>/)")
    study.add_argument("--degrees", type=int, nargs="+", default=[1, 2], help="element degrees (1, 2)")
    study.add_argument("--refine", type=int, default=3, help="number of mesh levels (each refined by 2)")
    study.add_argument("--ranks", type=int, default=1, help="MPI ranks per run")
    study.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a scene key")
    study.add_argument("--no-limits", action="store_true", help="lift the caps a scene file is held to")
    study.add_argument("-v", "--verbose", action="store_true", help="show FFCx/UFL compilation logs")
    study.add_argument("-q", "--quiet", action="store_true", help="show no progress (the per-run lines)")
    fit = sub.add_parser("fit", help="fit a rubber model to lab tests (CSV: stretch,nominal_stress in Pa); prints "
                         "the parameters as TOML, writes fit.json and fit.png to --out (default out/<stem>_fit/)")
    fit.add_argument("tests", nargs="+", help="CSV files with a header naming stretch and nominal_stress (Pa)")
    fit.add_argument("--model", required=True, choices=FIT_MODELS, help="the model to fit")
    fit.add_argument("--terms", type=int, help="terms of ogden (1-3, default 2) or yeoh (1-3, default 3)")
    fit.add_argument("--mode", action="append", choices=MODES, help="each file's test (default uniaxial): once "
                     "for all files, or once per file in order")
    fit.add_argument("--residual", choices=RESIDUALS, default="relative", help="fit relative or absolute errors")
    fit.add_argument("--out", help="output folder (created)")
    fit.set_defaults(verbose=False, quiet=True)
    faces = sub.add_parser("faces", help="number a CAD file's faces for where = { face = N }: prints them, writes "
                           "faces.png and faces.json to --out (default out/<stem>_faces/)")
    faces.add_argument("file", help="a CAD file (.step, .stp, .iges, .igs, .brep)")
    faces.add_argument("--units", choices=tuple(UNIT_SCALES), help="read it in this unit (a STEP or IGES file "
                       "declares its own: the part comes at its true size anyway; a BREP needs it)")
    faces.add_argument("--out", help="output folder (created)")
    faces.set_defaults(verbose=False, quiet=True)
    view = sub.add_parser("view", help="open a run's report.html (the part in 3D, its numbers) in the browser")
    view.add_argument("out", help="the run's output folder (or its report.html)")
    view.set_defaults(verbose=False, quiet=True)
    helper = sub.add_parser("help", help="print a scene key's reference (type, default, range, unit, meaning): "
                            "fem-forms help mesh.h; a table's keys: fem-forms help mesh")
    helper.add_argument("key", nargs="?", default="scene", help="a scene key (mesh.h, load.where) or a table (mesh)")
    helper.set_defaults(verbose=False, quiet=True)
    schema = sub.add_parser("schema", help="print the JSON Schema of scene files (for editors: Taplo, "
                            "Even Better TOML); the same keys, explained: the manual's scene reference",
                            epilog=f"The manual's scene reference explains every key: {built('reference/index.html')}")
    schema.add_argument("--out", help="write it to this file instead")
    schema.set_defaults(verbose=False, quiet=True)
    return p


def default_out(command: str, scene: str) -> Path:
    """out/<stem>/ for run, out/<stem>_study/ for study, out/<stem>_fit/ for fit (of the first test file),
    out/<stem>_faces/ for faces: a study's, a fit's or a face listing's folders never mix with a run's files."""
    stem = Path(scene).stem
    return Path("out") / (f"{stem}_{command}" if command in ("study", "fit", "faces") else stem)


def _fit(args) -> int:
    """`fem-forms fit`: the fit printed, fit.json and fit.png written."""
    modes = args.mode or ["uniaxial"]
    if len(modes) not in (1, len(args.tests)):
        raise InputError(f"--mode: give it once (all files) or once per file ({len(args.tests)} files, "
                         f"{len(modes)} modes)")
    modes = modes * len(args.tests) if len(modes) == 1 else modes
    tests = [read_test(path, mode, path) for path, mode in zip(args.tests, modes)]
    f = fit_model(args.model, tests, args.terms, args.residual)
    out = Path(args.out) if args.out else default_out("fit", args.tests[0])
    check_output_folder(out, default=not args.out)
    if MPI.COMM_WORLD.rank == 0:
        write_fit(f, out)
        print(fit_text(f) + f"\n-> {out / 'fit.json'}, {out / 'fit.png'}")
    return 0


def _faces(args) -> int:
    """`fem-forms faces`: a CAD file's faces listed, faces.png and faces.json written."""
    path = Path(args.file)
    if not path.is_file():
        raise InputError(f"faces {str(path)!r}: file not found")
    if path.suffix.lower() not in CAD_SUFFIXES:
        raise InputError(f"faces {str(path)!r}: not a CAD file ({', '.join(CAD_SUFFIXES)})")
    out = Path(args.out) if args.out else default_out("faces", args.file)
    check_output_folder(out, default=not args.out)
    faces, triangles = cad_faces(path, args.units)
    if MPI.COMM_WORLD.rank == 0:
        write_faces(faces, triangles, path.name, out)
        print(faces_text(faces) + f"\n-> {out / 'faces.png'}, {out / 'faces.json'}")
    return 0


def _view(out: Path) -> int:
    """`fem-forms view OUT`: the run's report.html opened in the user's browser (its path printed either way)."""
    page = out if out.suffix == ".html" else out / "report.html"
    if not page.is_file():
        raise InputError(f"view {str(out)!r}: no report.html there (a run writes it unless [output] report = false)")
    import webbrowser
    opened = webbrowser.open(page.resolve().as_uri())
    print(f"{page}" + ("" if opened else " (no browser found: open it in one)"))
    return 0


def pointer(message: str) -> str:
    """Where an error about a scene key is explained: `fem-forms help KEY` (always there), and the built manual's
    page once it is built."""
    key = manual_key(message)
    if key is None:
        return ""
    page = built(manual_page(message))
    return f" (help: fem-forms help {key}" + (f"; manual: {page}" if Path(page.split("#")[0]).is_file() else "") + ")"


def _run(args, petsc: dict) -> int:
    if args.command == "help":
        print(help_text(args.key))
        return 0
    if args.command == "view":
        return _view(Path(args.out))
    if args.command == "faces":
        return _faces(args)
    if args.command == "fit":
        if petsc:
            raise InputError(f"fit: no PETSc options ({next(iter(petsc))!r})")
        return _fit(args)
    if args.command == "schema":
        if not args.out:
            print(schema_json(), end="")
            return 0
        try:
            Path(args.out).write_text(schema_json())
        except OSError as e:
            raise InputError(f"--out {args.out!r}: cannot write ({e.strerror})") from None
        return 0
    overrides = dict(parse_assignment(a) for a in args.set)
    limits = NO_LIMITS if args.no_limits else LIMITS
    check_output_folder(Path(args.out or default_out(args.command, args.scene)), default=args.out is None)
    if args.out is None:
        args.out = str(default_out(args.command, args.scene))
    if args.command == "study":
        if petsc:
            raise InputError("study: PETSc options go into the scene ([solver] petsc) or --set")
        run_study(Path(args.scene), Path(args.out), args.degrees, args.refine, overrides, args.ranks,
                  echo=not args.quiet, limits=limits)
        return 0
    scene = Scene.from_file(args.scene, overrides, limits)
    for text in args.petsc:
        try:
            words = shlex.split(text)
        except ValueError as e:
            raise InputError(f"--petsc {text!r}: {e}") from None
        petsc.update(_petsc_options(words, "--petsc"))
    user = check_options(petsc, "command line: -", sep="", scene=False)
    if args.restart and scene.analysis != "dynamic":
        raise InputError(f"--restart: only for analysis = \"dynamic\" (this scene's is {scene.analysis!r})")
    forget_results(Path(args.out) / "results.json")
    if scene.discretization.tolerance is not None and not args.no_adapt:
        if user or MPI.COMM_WORLD.size > 1:
            raise InputError("discretization.tolerance: run serially, with PETSc options in the scene")
        s = solve_to_tolerance(Path(args.scene), Path(args.out), scene.discretization.tolerance, overrides,
                               limits=limits)
        print(f"{scene.title}: P{s['chosen']['degree']} at mesh level {s['chosen']['mesh_level']} meets "
              f"tolerance {s['tolerance']} (estimated error {s['error_estimate']:.2e}), {s['dofs']} dofs "
              f"-> {args.out}")
        return 0
    log = petsc_log(user)                                # -log_view: PETSc's own, not the solver's
    scene.solver.petsc.update(user)
    try:
        run_analysis(scene, Path(args.out), echo=True, **({"restart": Path(args.restart)} if args.restart else {}))
    finally:
        if log is not None:                              # also after a failed or interrupted run
            log.view()
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = _parser()
    args, extra = parser.parse_known_args(argv)
    quiet_jit(args.verbose)
    rank = MPI.COMM_WORLD.rank
    reporter = show_progress(not args.quiet)
    previous = _interrupts_raise()
    try:
        petsc = _petsc_options(extra)
        return _run(args, petsc)
    except (InputError, SolveError) as e:
        if reporter:
            reporter.close()
        if rank == 0:
            print(f"fem-forms: error: {e}" + (pointer(str(e)) if isinstance(e, InputError) else ""), file=sys.stderr)
        return e.exit_status
    except (TimeoutError, RuntimeError) as e:
        if (lock := stale_compile_lock(e)) is None:
            raise
        if reporter:
            reporter.close()
        if rank == 0:
            print(f"fem-forms: error: a form's compile never finished (a run killed while compiling it left its lock "
                  f"in the form cache): delete {lock} and run again", file=sys.stderr)
        return 1
    except KeyboardInterrupt as e:
        if reporter:
            reporter.close()
        if rank == 0 and not getattr(e, "announced", False):     # under MPI a handler may have said it
            print("fem-forms: interrupted", file=sys.stderr, flush=True)
        return getattr(e, "exit_status", 130)
    finally:
        show_progress(False)
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _raise_terminated(signum, frame) -> None:
    raise Terminated()


def _interrupts_raise() -> dict:
    """Make Ctrl-C raise KeyboardInterrupt again (importing gmsh, which dolfinx.io.gmshio does, sets SIGINT
    to SIG_DFL: the process died silently with status -2) and SIGTERM raise Terminated. Python runs these
    handlers between bytecodes, so inside one long C call (a MUMPS factorisation, gmsh meshing) the
    interrupt takes effect when the call returns. Returns the handlers replaced ({} off the main thread)."""
    previous = {}
    try:
        for signum, handler in ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, _raise_terminated)):
            previous[signum] = signal.signal(signum, handler)
    except ValueError:                   # not the main thread (main() called from a thread): leave them
        pass
    return previous


def entry() -> None:
    sys.exit(main())
