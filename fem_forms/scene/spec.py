"""The core scene sections every analysis shares: mesh, material, discretization, fix, load, solver,
output, and boundary selectors. Each key is declared once (type, range, default, unit, doc); the
spec dataclasses take their defaults from those declarations. Cross-key rules follow as code.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fem_forms.errors import InputError
from fem_forms.materials import MODELS, Material, make_material
from fem_forms.scene.reader import AXES, Key, Section, Table, Variants, check_vector

# --- selectors ------------------------------------------------------------------------------
SEL_AXIS = Key("axis", "string", "normal axis of a plane of boundary facets (with at)", required=True,
               choices=tuple(AXES))
SEL_AT = Key("at", "number", "coordinate of that plane along its axis", unit="m", required=True)
SEL_BOX = Key("box", "points", "boundary facets inside [[x0, y0, z0], [x1, y1, z1]]", unit="m",
              required=True, length=3, min_items=2, max_items=2)
SEL_GROUP = Key("group", "string", "a gmsh physical group of the mesh file, by name", required=True)
SELECTOR_KEYS = {"plane": (SEL_AXIS, SEL_AT), "box": (SEL_BOX,), "group": (SEL_GROUP,)}


@dataclass
class Selector:
    """Where on the boundary: a plane (axis, at), a box [[lo], [hi]] or a gmsh physical group."""
    kind: str                      # "plane" | "box" | "group"
    axis: int = 0
    at: float = 0.0
    lo: tuple = ()
    hi: tuple = ()
    group: str = ""
    key: str = "where"             # the scene key, for messages

    @staticmethod
    def parse(data: Any, key: str, kinds: tuple | None = None) -> "Selector":
        """A selector from {axis, at}, {box} or {group}; `kinds` limits which are allowed."""
        t = Table(data, key)
        present = [k for k in ("axis", "box", "group") if t.has(k)]
        if len(present) != 1:
            raise InputError(f"{key}: give exactly one of axis/at, box or group")
        kind = {"axis": "plane", "box": "box", "group": "group"}[present[0]]
        if kinds is not None and kind not in kinds:
            raise InputError(f"{key}: must be a box = [[x0, y0, z0], [x1, y1, z1]]" if kinds == ("box",)
                             else f"{key}: must be one of {', '.join(kinds)}")
        if kind == "plane":
            sel = Selector("plane", axis=AXES[t.read(SEL_AXIS)], at=t.read(SEL_AT), key=key)
        elif kind == "box":
            box = t.raw("box")
            if not (isinstance(box, list) and len(box) == 2):
                raise InputError(f"{key}.box = {box!r}: must be [[x0, y0, z0], [x1, y1, z1]]")
            lo, hi = (check_vector(b, f"{key}.box[{i}]") for i, b in enumerate(box))
            if any(a > b for a, b in zip(lo, hi)):
                raise InputError(f"{key}.box: lower corner {lo} exceeds upper corner {hi}")
            sel = Selector("box", lo=tuple(lo), hi=tuple(hi), key=key)
        else:
            sel = Selector("group", group=t.read(SEL_GROUP), key=key)
        t.done()
        return sel


def where(doc: str, required: bool = True) -> Key:
    return Key("where", "selector", doc, required=required, parse=Selector.parse)


# --- mesh -----------------------------------------------------------------------------------
GENERATOR = Key("generator", "string", "how the mesh is made: a built-in shape or a mesh file",
                default="box", choices=("box", "cylinder", "sphere", "revolve", "file"))
CELL = Key("cell", "string", "cell type (cylinder, sphere and revolve make tetrahedra only; prism: box only, "
           "degree 1, no surface loads)", default="tetrahedron", choices=("tetrahedron", "hexahedron", "prism"))
SIZE = Key("size", "vector", "box edge lengths [lx, ly, lz]", default=[1.0, 0.1, 0.1], unit="m",
           length=3, exclusive_minimum=0)
ORIGIN = Key("origin", "vector", "lowest corner of the box, centre of a sphere, base of a cylinder",
             default=[0.0, 0.0, 0.0], unit="m", length=3)
CELLS = Key("cells", "vector", "cells along x, y, z of the box", default=[20, 2, 2], length=3,
            integer=True, exclusive_minimum=0)
RADIUS = Key("radius", "number", "radius of the cylinder or sphere", unit="m", required=True,
             exclusive_minimum=0)
HEIGHT = Key("height", "number", "height of the cylinder (along z)", unit="m", required=True,
             exclusive_minimum=0)
H = Key("h", "number", "target cell size of the gmsh mesh", unit="m", exclusive_minimum=0,
        default_note="radius / 4 (0.025 m for revolve)")
PROFILE = Key("profile", "points", "closed outline [[r, z], ...] revolved about the z axis", unit="m",
              required=True, length=2, min_items=3,
              note="must list at least 3 points [r, z] of a closed outline")
FILE = Key("file", "file", "mesh file (gmsh .msh or any meshio format), relative to the scene file",
           required=True)
MESH_VARIANTS = Variants(GENERATOR, {
    "box": (SIZE, ORIGIN, CELLS),
    "cylinder": (ORIGIN, RADIUS, HEIGHT, H),
    "sphere": (ORIGIN, RADIUS, H),
    "revolve": (ORIGIN, PROFILE, H),
    "file": (FILE,),
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
    profile: list | None = None
    file: Path | None = None


def _mesh_rules(m: MeshSpec, t: Table) -> None:
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
    """What dolfinx 0.5.2 cannot do on prisms, refused when the scene is read (see fem_forms/prisms.py)."""
    if mesh.cell != "prism":
        return
    if analysis == "inverse":
        raise InputError("analysis = 'inverse': not on prism meshes (its rest-shape mesh files hold "
                         "tetrahedra or hexahedra)")
    if disc.degree != 1:
        raise InputError(f"discretization.degree = {disc.degree}: prisms take degree 1 only (FFCx 0.5.0: "
                         "\"Elements with different numbers of DOFs on subentities of the same dimension are "
                         "not yet supported\"); set degree = 1")
    surface = [f"load[{i}]" for i, ld in enumerate(loads) if ld.type in ("traction", "pressure")]
    if surface:
        raise InputError(f"{surface[0]}: surface loads cannot be applied on a prism mesh (FFCx 0.5.0 cannot "
                         "integrate over prism facets); use tetrahedra or hexahedra")


# --- material -------------------------------------------------------------------------------
MATERIAL_KEYS = (
    Key("model", "string", "hyperelastic energy density", default="neo-hookean", choices=tuple(MODELS),
        note=f"unknown model (choose from {', '.join(MODELS)})"),
    Key("E", "number", "Young's modulus (with nu)", unit="Pa", exclusive_minimum=0,
        note="Young's modulus must be positive"),
    Key("nu", "number", "Poisson's ratio (with E)", exclusive_minimum=-1.0, exclusive_maximum=0.5,
        note="Poisson's ratio must lie in (-1, 0.5) for a compressible model"),
    Key("mu", "number", "shear modulus (with lambda)", unit="Pa", exclusive_minimum=0),
    Key("lambda", "number", "Lame's first parameter (with mu)", unit="Pa", attr="lmbda"),
    Key("C10", "number", "Mooney-Rivlin C10 (default 3 mu / 8)", unit="Pa", minimum=0),
    Key("C01", "number", "Mooney-Rivlin C01 (default mu / 8)", unit="Pa", minimum=0),
    Key("rho", "number", "mass density (gravity and modal analysis need it)", default=0.0, unit="kg/m^3",
        minimum=0),
)
_MAT = {k.name: k for k in MATERIAL_KEYS}


@dataclass
class MaterialSpec:
    model: str = _MAT["model"].field()
    E: float | None = None
    nu: float | None = None
    mu: float | None = None
    lmbda: float | None = None
    C10: float | None = None
    C01: float | None = None
    rho: float = _MAT["rho"].field()
    _built: tuple | None = field(default=None, repr=False, compare=False)   # (values, Material)

    @property
    def material(self) -> Material:
        """The validated model, built once when the scene is read (again only if a value was changed
        since, so a changed E can never be silently ignored)."""
        values = (self.model, self.E, self.nu, self.mu, self.lmbda, self.C10, self.C01)
        if self._built is None or self._built[0] != values:
            self._built = (values, make_material(self.model, E=self.E, nu=self.nu, mu=self.mu,
                                                 lmbda=self.lmbda, C10=self.C10, C01=self.C01))
        return self._built[1]


def _material_rules(s: MaterialSpec, t: Table) -> None:
    if (s.E is not None or s.nu is not None) and (s.mu is not None or s.lmbda is not None):
        raise InputError(f"{t.path}: give either E and nu or mu and lambda, not both")
    s.material                                           # builds and validates the model once, now


# --- discretization -------------------------------------------------------------------------
DISCRETIZATION_KEYS = (
    Key("degree", "integer", "Lagrange degree of the displacement", default=2, choices=(1, 2),
        note="unsupported element (Lagrange degree 1 or 2)"),
    Key("quadrature_degree", "integer", "quadrature degree of the forms", exclusive_minimum=0,
        default_note="2 x degree"),
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


# --- supports and loads ---------------------------------------------------------------------
FIX_KEYS = (
    where("boundary facets held"),
    Key("components", "axes", "displacement components held", default=["x", "y", "z"]),
    Key("value", "vector", "prescribed displacement of the held components", default=[0.0, 0.0, 0.0],
        unit="m", length=3),
)
_FIX = {k.name: k for k in FIX_KEYS}


@dataclass
class Fix:
    where: Selector
    components: list = _FIX["components"].field()
    value: list = _FIX["value"].field()


LOAD_WHERE = where("boundary facets loaded")
# Each load type and its keys: a new load type is one entry here (and its term in physics/).
LOAD_TYPES = {
    "gravity": (Key("g", "vector", "gravitational acceleration", default=[0.0, 0.0, -9.81], unit="m/s^2",
                    length=3),),
    "traction": (LOAD_WHERE, Key("value", "vector", "dead traction per unit reference area", unit="Pa",
                                 required=True, length=3)),
    "pressure": (LOAD_WHERE, Key("value", "number", "follower pressure on the deformed surface", unit="Pa",
                                 required=True, attr="pressure")),
}
LOAD_VARIANTS = Variants(Key("type", "string", "kind of load", required=True, choices=tuple(LOAD_TYPES)),
                         LOAD_TYPES)


@dataclass
class Load:
    type: str                      # a key of LOAD_TYPES
    g: list | None = None
    where: Selector | None = None
    value: list | None = None      # traction vector
    pressure: float | None = None  # follower pressure


# --- solver and output ----------------------------------------------------------------------
SOLVER_KEYS = (
    Key("steps", "integer", "initial number of load steps", default=1, exclusive_minimum=0),
    Key("max_cutbacks", "integer", "how often a failed load step may be halved", default=12, minimum=0),
    Key("linear", "string", "linear solver: auto, direct (MUMPS) or iterative (CG + GAMG)", default="auto",
        choices=("auto", "direct", "iterative")),
    Key("petsc", "options", "PETSc options (name without dash = value), applied last", default={}),
)
_SOLVER = {k.name: k for k in SOLVER_KEYS}


@dataclass
class SolverSpec:
    steps: int = _SOLVER["steps"].field()
    max_cutbacks: int = _SOLVER["max_cutbacks"].field()
    linear: str = _SOLVER["linear"].field()
    petsc: dict = _SOLVER["petsc"].field()


OUTPUT_KEYS = (
    Key("probes", "map", "named points where results are reported", default={},
        item=Key("point", "vector", "[x, y, z]", unit="m", length=3)),
    Key("picture", "boolean", "write a PNG picture", default=True),
    Key("fields", "boolean", "write fields for ParaView (XDMF)", default=True),
)
_OUTPUT = {k.name: k for k in OUTPUT_KEYS}


@dataclass
class OutputSpec:
    probes: dict = _OUTPUT["probes"].field()
    picture: bool = _OUTPUT["picture"].field()
    fields: bool = _OUTPUT["fields"].field()


# --- the core sections, in reading order ----------------------------------------------------
TITLE = Key("title", "string", "a name for the scene, shown in pictures and summaries", default="untitled")
CORE_SECTIONS = (
    Section("mesh", "the body's shape and its mesh", MeshSpec, keys=(CELL,), variants=MESH_VARIANTS,
            rules=_mesh_rules, required=True),
    Section("material", "the hyperelastic material: E and nu, or mu and lambda", MaterialSpec,
            keys=MATERIAL_KEYS, rules=_material_rules, required=True),
    Section("discretization", "finite elements and quadrature", Discretization, keys=DISCRETIZATION_KEYS,
            rules=_discretization_rules),
    Section("fix", "a support: held displacement components on a boundary", Fix, keys=FIX_KEYS, array=True),
    Section("load", "a load: gravity, dead traction or follower pressure", Load, variants=LOAD_VARIANTS,
            array=True),
    Section("solver", "Newton, load stepping and the linear solver", SolverSpec, keys=SOLVER_KEYS),
    Section("output", "what is written besides results.json", OutputSpec, keys=OUTPUT_KEYS),
)
