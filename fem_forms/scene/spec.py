"""The core scene sections every analysis shares: mesh, material, discretization, fix, load, solver and
output (their boundary selectors: scene/selectors.py). Each key is declared once (type, range, default,
unit, doc); the spec dataclasses take their defaults from those declarations. Cross-key rules follow as code.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fem_forms.keys import spec_class
from fem_forms.errors import InputError
from fem_forms.elements import MAX_DEGREE as MAX_QUADRATURE_DEGREE, check_degree
from fem_forms.scene.materials import MATERIAL
from fem_forms.scene.reader import Key, Section, Table, Variants
from fem_forms.scene.selectors import AREA_SELECTORS, Selector, where
from fem_forms.scene.term_sections import TERM_SECTIONS

# --- mesh -----------------------------------------------------------------------------------
SURFACE_SUFFIXES = (".stl", ".obj", ".ply", ".off")    # closed surfaces the loader fills with tetrahedra
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs", ".brep")   # CAD solids gmsh meshes (meshes/cad.py)
GENERATOR = Key("generator", "string", "how the mesh is made: a built-in shape or a mesh file",
                default="box", choices=("box", "cylinder", "sphere", "revolve", "file"))
CELL = Key("cell", "string", "cell type (cylinder, sphere and revolve make tetrahedra only; prism: box only, "
           "degree 1, no surface loads)", default="tetrahedron", choices=("tetrahedron", "hexahedron", "prism"))
SIZE = Key("size", "vector", "box edge lengths [lx, ly, lz]", default=[1.0, 0.1, 0.1], unit="m",
           length=3, exclusive_minimum=0, maximum=1e6, note="must be positive and at most 1e6 m")
ORIGIN = Key("origin", "vector", "lowest corner of the box, centre of a sphere, base of a cylinder",
             default=[0.0, 0.0, 0.0], unit="m", length=3)
CELLS = Key("cells", "vector", "cells along x, y, z of the box", default=[20, 2, 2], length=3,
            integer=True, exclusive_minimum=0, maximum=10**7, note="must be positive and at most 10^7")
RADIUS = Key("radius", "number", "radius of the cylinder or sphere", unit="m", required=True,
             exclusive_minimum=0)
HEIGHT = Key("height", "number", "height of the cylinder (along z)", unit="m", required=True,
             exclusive_minimum=0)
H = Key("h", "number", "target cell size of the gmsh mesh", unit="m", exclusive_minimum=0,
        default_note="radius / 4 (0.025 m for revolve; a surface file's mean edge length)")
PROFILE = Key("profile", "points", "closed outline [[r, z], ...] revolved about the z axis", unit="m",
              required=True, length=2, min_items=3,
              note="must list at least 3 points [r, z] of a closed outline")
FILE = Key("file", "file", "mesh file, relative to the scene file: a volume mesh (gmsh .msh or any meshio "
           "format), a closed surface (.stl, .obj, .ply, .off) or a CAD solid (.step, .stp, .iges, .igs, .brep) "
           "that gmsh fills with tetrahedra of size h", required=True)
H_MIN = Key("h_min", "number", "CAD files: the smallest cell gmsh may make", unit="m", exclusive_minimum=0,
            default_note="h / 4")
H_MAX = Key("h_max", "number", "CAD files: the largest cell gmsh may make", unit="m", exclusive_minimum=0,
            default_note="h")
NEAR = Key("near", "points", "CAD files: finer cells near points, [[x, y, z, r, h], ...]: size h within r of "
           "(x, y, z), growing to h_max over another r", unit="m", length=5, min_items=1, max_items=100,
           note="must list 1 to 100 rows [x, y, z, r, h]")
REPAIR = Key("repair", "boolean", "surface files only: fill holes and remove duplicate, degenerate and "
             "self-intersecting faces with MeshFix before gmsh meshes the surface (results.json mesh.repair "
             "says what changed); without it an open surface is refused", default=False)
SCALE = Key("scale", "number", "every coordinate of the mesh file is multiplied by this (0.001 for a file "
            "in mm); h and all other lengths of the scene stay in metres", exclusive_minimum=0,
            default_note="1 (or what units says)")
UNITS = Key("units", "string", "the length unit of the mesh file's coordinates, instead of scale "
            "(mm: scale 0.001); h and all other lengths of the scene stay in metres",
            choices=("m", "mm", "cm", "in"), default_note="m")
UNIT_SCALES = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254}
MESH_VARIANTS = Variants(GENERATOR, {
    "box": (SIZE, ORIGIN, CELLS),
    "cylinder": (ORIGIN, RADIUS, HEIGHT, H),
    "sphere": (ORIGIN, RADIUS, H),
    "revolve": (ORIGIN, PROFILE, H),
    "file": (FILE, H, H_MIN, H_MAX, NEAR, REPAIR, SCALE, UNITS),
})
GENERATORS = GENERATOR.choices
CELL_TYPES = CELL.choices


@dataclass
class MeshSpec:
    generator: str = GENERATOR.field()
    size: list = SIZE.field()
    origin: list = ORIGIN.field()
    cells: list = CELLS.field()
    cell: str = CELL.field()
    radius: float | None = None
    height: float | None = None
    h: float | None = None
    h_min: float | None = None
    h_max: float | None = None
    near: list | None = None         # [[x, y, z, r, h], ...]
    profile: list | None = None
    file: Path | None = None
    repair: bool = False
    scale: float | None = None
    units: str | None = None
    max_cells: int | None = None     # the scene's cap on cells (scene/limits.py), checked when the mesh is built

    @property
    def length_scale(self) -> float:
        """What every coordinate of the mesh file is multiplied by to be in metres (scale or units)."""
        if self.scale is not None:
            return float(self.scale)
        return UNIT_SCALES[self.units] if self.units is not None else 1.0


MAX_CELL_ASPECT = 1e5      # box cells longer than this many times their width defeat point location


def _mesh_rules(m: MeshSpec, t: Table) -> None:
    if m.generator == "box":
        edges = [s / n for s, n in zip(m.size, m.cells)]
        if max(edges) > MAX_CELL_ASPECT * min(edges):
            raise InputError(f"{t.path}: box cells of {' x '.join(f'{e:.3g}' for e in edges)} m are too "
                             f"elongated (aspect above {MAX_CELL_ASPECT:.0e}); change size or cells")
    suffix = m.file.suffix.lower() if m.generator == "file" else ""
    if m.generator == "file" and m.h is not None and suffix not in SURFACE_SUFFIXES + CAD_SUFFIXES:
        raise InputError(f"{t.key('h')}: only for surface and CAD files "
                         f"({', '.join(SURFACE_SUFFIXES + CAD_SUFFIXES)}); {m.file.name!r} is meshed already")
    for name, value in (("h_min", m.h_min), ("h_max", m.h_max), ("near", m.near)):
        if value is not None and suffix not in CAD_SUFFIXES:
            raise InputError(f"{t.key(name)}: only for CAD files ({', '.join(CAD_SUFFIXES)})")
    for other, value in (("h_max", m.h_max), ("h", m.h)):
        if m.h_min is not None and value is not None and m.h_min > value:
            raise InputError(f"{t.key('h_min')} = {m.h_min}: exceeds {other} = {value}")
    if any(r <= 0 or h <= 0 for _, _, _, r, h in m.near or []):
        raise InputError(f"{t.key('near')}: each row's r and h must be positive")
    if m.h_min is not None and any(h < m.h_min for *_, h in m.near or []):
        raise InputError(f"{t.key('near')}: a row asks for cells below h_min = {m.h_min}")
    if suffix in (".step", ".stp", ".iges", ".igs") and m.scale is not None:
        raise InputError(f"{t.key('scale')}: a STEP or IGES file declares its length unit (it is read at its "
                         "true size); scale is for files that do not")
    if suffix in CAD_SUFFIXES and m.cell != "tetrahedron":
        raise InputError(f"{t.key('cell')} = {m.cell!r}: a CAD file is filled with tetrahedra only")
    if m.generator == "file" and m.repair and suffix not in SURFACE_SUFFIXES:
        raise InputError(f"{t.key('repair')}: only for surface files ({', '.join(SURFACE_SUFFIXES)}); "
                         f"{m.file.name!r} is a volume mesh")
    if m.scale is not None and m.units is not None:
        raise InputError(f"{t.key('units')}: give scale or units, not both (units = 'mm' is scale = 0.001)")
    if m.generator == "file" and m.file.suffix.lower() in SURFACE_SUFFIXES and m.cell != "tetrahedron":
        raise InputError(f"{t.key('cell')} = {m.cell!r}: a surface file is filled with tetrahedra only")
    if m.cell == "prism" and m.generator != "box":
        raise InputError(f"{t.key('cell')} = 'prism': only the box generator makes prisms")
    if m.generator in ("cylinder", "sphere", "revolve"):
        if m.cell != "tetrahedron":
            raise InputError(f"{t.key('cell')} = {m.cell!r}: the {m.generator} generator makes tetrahedra only")
        if m.generator == "revolve" and any(r < 0 for r, _ in m.profile):
            raise InputError(f"{t.key('profile')}: radii r must not be negative")
        if m.h is None:
            m.h = (m.radius or 0.1) / 4


def prism_rules(mesh: MeshSpec, disc: "Discretization", loads: list, analysis: str) -> None:
    """What dolfinx 0.5.2 cannot do on prisms, refused when the scene is read (see fem_forms/meshes/prisms.py)."""
    if mesh.cell != "prism":
        return
    if analysis == "inverse":
        raise InputError("analysis = 'inverse': not on prism meshes (its rest-shape mesh files hold "
                         "tetrahedra or hexahedra)")
    if disc.degree != 1:
        raise InputError(f"discretization.degree = {disc.degree}: prisms take degree 1 only (FFCx 0.5.0: "
                         "\"Elements with different numbers of DOFs on subentities of the same dimension are "
                         "not yet supported\"); set degree = 1")
    surface = [f"load[{i}]" for i, ld in enumerate(loads) if ld.type in ("traction", "pressure", "inflation")]
    if surface:
        raise InputError(f"{surface[0]}: surface loads cannot be applied on a prism mesh (FFCx 0.5.0 cannot "
                         "integrate over prism facets); use tetrahedra or hexahedra")


# --- discretization -------------------------------------------------------------------------
DISCRETIZATION_KEYS = (
    Key("degree", "integer", "Lagrange degree of the displacement", default=2, choices=(1, 2),
        note="unsupported element (Lagrange degree 1 or 2)"),
    Key("quadrature_degree", "integer", "quadrature degree of the forms (1..8; at least the element's safe "
        "degree: P1 tetrahedra 1, P2 tetrahedra 2, Q1 hexahedra 2, Q2 hexahedra 4, P1 prisms 2)",
        exclusive_minimum=0, maximum=MAX_QUADRATURE_DEGREE, default_note="2 x degree",
        note=f"an integer from 1 to {MAX_QUADRATURE_DEGREE}"),
    Key("formulation", "string", "displacement, or mixed: Taylor-Hood P2 displacement / P1 pressure",
        default="displacement", choices=("displacement", "mixed")),
    Key("tolerance", "number", "relative accuracy asked for: pick the cheapest degree and mesh meeting it",
        exclusive_minimum=0, exclusive_maximum=1, note="a relative error, above 0 and below 1"),
)
_DISC = {k.name: k for k in DISCRETIZATION_KEYS}


@dataclass
class Discretization:
    degree: int = _DISC["degree"].field()
    quadrature_degree: int | None = None
    formulation: str = _DISC["formulation"].field()
    tolerance: float | None = None         # accuracy on request: pick the cheapest degree/mesh meeting it

    @property
    def quadrature(self) -> int:
        """Quadrature degree actually used: twice the element degree unless the scene says."""
        return self.quadrature_degree if self.quadrature_degree is not None else 2 * self.degree


def _discretization_rules(d: Discretization, t: Table) -> None:
    if d.formulation == "mixed" and d.degree != 2:
        raise InputError(f"discretization.degree = {d.degree}: the mixed formulation "
                         "is Taylor-Hood, degree 2 displacement with degree 1 pressure")


def quadrature_rules(mesh: MeshSpec, disc: Discretization) -> None:
    """An explicit quadrature_degree below the element's safe degree (singular tangent and mass: hourglass
    modes) or above 8 is refused when the scene is read (a mesh file's cell is checked again when loaded)."""
    why = check_degree(mesh.cell, disc.degree, disc.quadrature_degree, disc.formulation)
    if why:
        raise InputError(why)


# --- supports and loads ---------------------------------------------------------------------
FIX_KEYS = (
    Key("name", "string", "the support's name in results.json reactions", default_note="fix0, fix1, ... in scene order"),
    where("where the displacement is held: boundary facets, a group of any dimension, a point or a line"),
    Key("components", "axes", "displacement components held", default=["x", "y", "z"]),
    Key("value", "vector", "prescribed displacement of the held components", default=[0.0, 0.0, 0.0],
        unit="m", length=3),
    Key("history", "points", "static: [time, factor] pairs scaling value over the pseudo-time of the load steps, "
        "piecewise linear, held after the last (e.g. stretch, then hold: relaxation); default: with the load "
        "factor", length=2, min_items=1, note="must list [time, factor] pairs"),
)
_FIX = {k.name: k for k in FIX_KEYS}


@dataclass
class Fix:
    where: Selector
    components: list = _FIX["components"].field()
    value: list = _FIX["value"].field()
    name: str | None = None
    history: list | None = None        # [[t, factor], ...] (static), else value scales with the load factor


def fix_names(fixes: list[Fix]) -> list[str]:
    """Each support's name: its `name`, else fix<i> (i its place in the scene); a repeated name is an error."""
    names, seen = [], {}
    for i, fix in enumerate(fixes):
        name = fix.name if fix.name is not None else f"fix{i}"
        if name in seen:
            raise InputError(f"fix[{i}].name: {name!r} already names fix[{seen[name]}]")
        seen[name] = i
        names.append(name)
    return names


LOAD_WHERE = where("boundary facets loaded", kinds=AREA_SELECTORS)
# Each load type and its keys: a new load type is one entry here (and its term in physics/).
LOAD_TYPES = {
    "gravity": (Key("g", "vector", "gravitational acceleration", default=[0.0, 0.0, -9.81], unit="m/s^2",
                    length=3),
                where("a gmsh volume group the weight acts on (default: the whole body)", required=False,
                      kinds=("group",))),
    "traction": (LOAD_WHERE, Key("value", "vector", "dead traction per unit reference area", unit="Pa",
                                 required=True, length=3)),
    "pressure": (LOAD_WHERE, Key("pressure", "number", "follower pressure on the deformed surface", unit="Pa"),
                 Key("value", "number", "the same as pressure (its first spelling, still read)", unit="Pa")),
    # a closed cavity's pressure as an energy, -p (V - V0): pressure or volume control (physics/cavities.py)
    "inflation": (where("the cavity's walls: a closed surface, or one closed by symmetry planes through the origin",
                        kinds=AREA_SELECTORS),
                  Key("name", "string", "the cavity's name in results.json cavities and probes.csv",
                      default_note="cavity0, cavity1, ... in scene order"),
                  Key("pressure", "number", "cavity pressure (pressure control)", unit="Pa"),
                  Key("volume", "number", "volume added to the cavity (volume control: its pressure is solved "
                      "with the displacement)", unit="m^3")),
    # an elastic (Winkler) foundation: a support under the selected facets (physics/foundation.py)
    "foundation": (where("the facets resting on the foundation", kinds=AREA_SELECTORS),
                   Key("stiffness", "number", "the foundation's push per area per unit of normal displacement "
                       "(Winkler modulus)", unit="Pa/m", required=True, exclusive_minimum=0)),
}
# one key every load type shares: the load's factor over time (dynamic analysis), piecewise linear
LOAD_HISTORY = Key("history", "points", "[time, factor] pairs, piecewise linear in time, held after the last "
                   "(dynamic; static: pseudo-time of the load steps, e.g. load then unload; default: constant 1)", length=2, min_items=1,
                   note="must list [time, factor] pairs")
LOAD_VARIANTS = Variants(Key("type", "string", "kind of load", required=True, choices=tuple(LOAD_TYPES)),
                         LOAD_TYPES)


@dataclass
class Load:
    type: str                      # a key of LOAD_TYPES
    g: list | None = None
    where: Selector | None = None
    value: list | None = None      # traction vector
    pressure: float | None = None  # follower pressure; an inflated cavity's pressure
    volume: float | None = None    # volume added to an inflated cavity (volume control)
    name: str | None = None        # an inflated cavity's name
    stiffness: float | None = None # a foundation's Winkler modulus (Pa/m)
    history: list | None = None    # [[t, factor], ...] piecewise linear; None: constant 1


def _fix_rules(fix: Fix, t: Table) -> None:
    if fix.history is not None and any(b[0] <= a[0] for a, b in zip(fix.history, fix.history[1:])):
        raise InputError(f"{t.key('history')}: times must increase")


def _load_rules(ld: Load, t: Table) -> None:
    if ld.type == "pressure":                      # `pressure`, as Load's attribute; `value` read as before
        if (ld.pressure is None) == (ld.value is None):
            raise InputError(f"{t.key('pressure')}: a pressure load gives its pressure (Pa) as pressure = ... "
                             "(or value = ..., its first spelling), once")
        ld.pressure, ld.value = (ld.pressure if ld.value is None else float(ld.value)), None
    if ld.type == "inflation" and (ld.pressure is None) == (ld.volume is None):
        raise InputError(f"{t.key('pressure')}: an inflation load gives either pressure (pressure control) or "
                         "volume (volume control), not both, not neither")
    if ld.history is not None and any(b[0] <= a[0] for a, b in zip(ld.history, ld.history[1:])):
        raise InputError(f"{t.key('history')}: times must increase")


# --- solver and output ----------------------------------------------------------------------
SOLVER_KEYS = (
    Key("steps", "integer", "initial number of load steps", default=1, exclusive_minimum=0),
    Key("max_cutbacks", "integer", "how often a failed load step may be halved", default=12, minimum=0),
    Key("max_step", "number", "largest load-factor increment of a static run's step (load control; not the "
        "inverse designs nor arc length): steps grow 1.5x after a success up to it, so the load path is sampled "
        "at least this finely", default=1.0, exclusive_minimum=0,
        maximum=1),
    Key("linear", "string", "linear solver: auto, direct (MUMPS) or iterative (CG + GAMG)", default="auto",
        choices=("auto", "direct", "iterative")),
    Key("control", "string", "what the continuation steps: the load factor (load), the arc length along "
        "the load-displacement path (arc-length: passes limit points, the load factor may fall), or the load "
        "factor until a step fails near a limit point, then the arc length on from there (auto; where arc length "
        "cannot follow the loads, load control throughout)", default="auto",
        choices=("auto", "load", "arc-length")),
    Key("load_drop", "number", "arc length past a limit point ends once the load factor has dropped by this "
        "fraction of its peak (as a test machine stops at a load drop; 1: followed down to zero load, and up "
        "again where the path rises: a snap-through)", default=1.0, exclusive_minimum=0, maximum=1),
    Key("petsc", "options", "PETSc options of the solver (name without dash = value), applied last: snes_*, ksp_*, "
        "pc_*, mat_mumps_*, eps_*, st_*, none that names a file, viewer, monitor or code (docs/sharing.md)",
        default={}),
)


SolverSpec = spec_class("SolverSpec", "[solver]: Newton, load stepping and the linear solver.",
                        SOLVER_KEYS, __name__)


# fields [output] fields may name (fem_forms/output/quantities.py computes each)
FIELD_NAMES = ("displacement", "von_mises", "cauchy_stress", "pk1_stress", "pk2_stress", "principal_stresses",
               "green_strain", "biot_strain", "hencky_strain", "infinitesimal_strain", "deformation_gradient",
               "contact_pressure", "material", "utilization")
OUTPUT_KEYS = (
    Key("probes", "map", "named points where results are reported", default={},
        item=Key("point", "vector", "[x, y, z]", unit="m", length=3)),
    Key("picture", "boolean", "write a PNG picture", default=True),
    Key("report", "boolean", "write report.html: the part in 3D to turn around in a browser (deformed, coloured by "
        "|u|, and at the end by von Mises stress, damage, contact pressure or material; supports and loads marked), "
        "the numbers of results.json, the warnings; "
        "`fem-forms view OUT` opens it", default=True),
    Key("fields", "selection", "fields for ParaView (XDMF, P1 nodal values of recovered stresses and strains; "
        "material: the material index of each cell, in [[material]] order from 0): "
        "a list of names, true (the default list) or false (none)", default=["displacement", "von_mises"],
        choices=FIELD_NAMES),
)


OutputSpec = spec_class("OutputSpec", "[output]: probes, picture, report and the fields written for ParaView.",
                        OUTPUT_KEYS, __name__)


# --- the core sections, in reading order ----------------------------------------------------
TITLE = Key("title", "string", "a name for the scene, shown in pictures and summaries", default="untitled")
CORE_SECTIONS = (
    Section("mesh", "the body's shape and its mesh", MeshSpec, keys=(CELL,), variants=MESH_VARIANTS,
            rules=_mesh_rules, required=True),
    MATERIAL,
    Section("discretization", "finite elements and quadrature", Discretization, keys=DISCRETIZATION_KEYS,
            rules=_discretization_rules),
    Section("fix", "a support: held displacement components on a boundary", Fix, keys=FIX_KEYS, array=True,
            rules=_fix_rules),
    Section("load", "a load: gravity, dead traction or follower pressure", Load, keys=(LOAD_HISTORY,),
            variants=LOAD_VARIANTS, rules=_load_rules, array=True),
    Section("solver", "Newton, load stepping and the linear solver", SolverSpec, keys=SOLVER_KEYS),
    Section("output", "what is written besides results.json", OutputSpec, keys=OUTPUT_KEYS),
) + TERM_SECTIONS
