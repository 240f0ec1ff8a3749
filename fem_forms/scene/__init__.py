"""Scene: what to simulate, read from TOML (or a dict) and validated with one-line messages.

Every key is checked for type and range here, before any mesh is built or file written;
unknown keys are rejected. No string from a scene is ever evaluated as code.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fem_forms.errors import InputError

ANALYSES = ("static", "modal", "inverse")   # extended as analyses register (see analyses/__init__.py)
GENERATORS = ("box", "cylinder", "sphere", "revolve", "file")
CELLS = ("tetrahedron", "hexahedron")
AXES = {"x": 0, "y": 1, "z": 2}


class _Table:
    """A TOML table being read: typed getters that name the key path, and a check for leftovers."""

    def __init__(self, data: Any, path: str):
        if not isinstance(data, dict):
            raise InputError(f"{path}: must be a table, got {type(data).__name__}")
        self.data, self.path, self.used = data, path, set()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def has(self, name: str) -> bool:
        return name in self.data

    def raw(self, name: str, default: Any = None) -> Any:
        self.used.add(name)
        return self.data.get(name, default)

    def number(self, name: str, default: Any = None, *, required: bool = False,
               positive: bool = False, nonneg: bool = False, integer: bool = False) -> Any:
        if name not in self.data:
            if required:
                raise InputError(f"{self.key(name)}: missing (required)")
            self.used.add(name)
            return default
        v = self.raw(name)
        return check_number(v, self.key(name), positive=positive, nonneg=nonneg, integer=integer)

    def string(self, name: str, default: str | None = None, *, choices=None, required=False) -> Any:
        if name not in self.data:
            if required:
                raise InputError(f"{self.key(name)}: missing (required)")
            self.used.add(name)
            return default
        v = self.raw(name)
        if not isinstance(v, str):
            raise InputError(f"{self.key(name)} = {v!r}: must be a string")
        if choices is not None and v not in choices:
            raise InputError(f"{self.key(name)} = {v!r}: must be one of {', '.join(map(repr, choices))}")
        return v

    def boolean(self, name: str, default: bool) -> bool:
        v = self.raw(name, default)
        if not isinstance(v, bool):
            raise InputError(f"{self.key(name)} = {v!r}: must be true or false")
        return v

    def vector(self, name: str, length: int | None = 3, default=None, *, required=False,
               positive=False, integer=False) -> Any:
        if name not in self.data:
            if required:
                raise InputError(f"{self.key(name)}: missing (required)")
            self.used.add(name)
            return default
        return check_vector(self.raw(name), self.key(name), length, positive=positive, integer=integer)

    def table(self, name: str, required: bool = False) -> "_Table":
        if name not in self.data and required:
            raise InputError(f"{self.key(name)}: missing (required table)")
        return _Table(self.raw(name, {}), self.key(name))

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise InputError(f"{self.key(unknown[0])}: unknown key")


def check_number(v: Any, key: str, *, positive=False, nonneg=False, integer=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise InputError(f"{key} = {v!r}: must be a number")
    if integer and not isinstance(v, int):
        raise InputError(f"{key} = {v!r}: must be a whole number")
    if not math.isfinite(v):
        raise InputError(f"{key} = {v!r}: must be finite")
    if positive and v <= 0:
        raise InputError(f"{key} = {v!r}: must be positive")
    if nonneg and v < 0:
        raise InputError(f"{key} = {v!r}: must not be negative")
    return v if integer else float(v)


def check_vector(v: Any, key: str, length: int | None = 3, *, positive=False, integer=False) -> list:
    if not isinstance(v, list) or (length is not None and len(v) != length):
        raise InputError(f"{key} = {v!r}: must be a list of {length} numbers")
    return [check_number(x, f"{key}[{i}]", positive=positive, integer=integer) for i, x in enumerate(v)]


def set_key(data: dict, dotted: str, value: Any) -> None:
    """data["a"]["b"] = value for dotted = "a.b" (tables are created as needed)."""
    node = data
    parts = dotted.split(".")
    for k in parts[:-1]:
        node = node.setdefault(k, {})
        if not isinstance(node, dict):
            raise InputError(f"--set {dotted}: {k!r} is not a table")
    node[parts[-1]] = value


def parse_assignment(text: str) -> tuple[str, Any]:
    """'mesh.cells=[8, 1, 1]' -> ("mesh.cells", [8, 1, 1]); the value is read as a TOML value."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise InputError(f"--set {text!r}: must be KEY=VALUE, e.g. --set discretization.degree=1")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()                          # a bare word: a string
    return key.strip(), value


# ---------------------------------------------------------------------------------------------
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
    def parse(data: Any, key: str) -> "Selector":
        t = _Table(data, key)
        kinds = [k for k in ("axis", "box", "group") if t.has(k)]
        if len(kinds) != 1:
            raise InputError(f"{key}: give exactly one of axis/at, box or group")
        if kinds[0] == "axis":
            axis = t.string("axis", choices=tuple(AXES), required=True)
            sel = Selector("plane", axis=AXES[axis], at=t.number("at", required=True), key=key)
        elif kinds[0] == "box":
            box = t.raw("box")
            if not (isinstance(box, list) and len(box) == 2):
                raise InputError(f"{key}.box = {box!r}: must be [[x0, y0, z0], [x1, y1, z1]]")
            lo, hi = (check_vector(b, f"{key}.box[{i}]") for i, b in enumerate(box))
            if any(a > b for a, b in zip(lo, hi)):
                raise InputError(f"{key}.box: lower corner {lo} exceeds upper corner {hi}")
            sel = Selector("box", lo=tuple(lo), hi=tuple(hi), key=key)
        else:
            sel = Selector("group", group=t.string("group", required=True), key=key)
        t.done()
        return sel


@dataclass
class MeshSpec:
    generator: str = "box"
    size: list = field(default_factory=lambda: [1.0, 0.1, 0.1])
    origin: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    cells: list = field(default_factory=lambda: [20, 2, 2])
    cell: str = "tetrahedron"
    radius: float | None = None
    height: float | None = None
    h: float | None = None
    profile: list | None = None
    file: Path | None = None


@dataclass
class MaterialSpec:
    model: str = "neo-hookean"
    E: float | None = None
    nu: float | None = None
    mu: float | None = None
    lmbda: float | None = None
    C10: float | None = None
    C01: float | None = None
    rho: float = 0.0


@dataclass
class Discretization:
    degree: int = 2
    quadrature_degree: int | None = None
    formulation: str = "displacement"      # or "mixed": Taylor-Hood P2 displacement / P1 pressure
    tolerance: float | None = None         # accuracy on request: pick the cheapest degree/mesh meeting it

    @property
    def quadrature(self) -> int:
        """Quadrature degree actually used: twice the element degree unless the scene says."""
        return self.quadrature_degree if self.quadrature_degree is not None else 2 * self.degree


@dataclass
class Fix:
    where: Selector
    components: list = field(default_factory=lambda: [0, 1, 2])
    value: list = field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclass
class Load:
    type: str                      # "gravity" | "traction" | "pressure"
    g: list | None = None
    where: Selector | None = None
    value: list | None = None      # traction vector
    pressure: float | None = None  # follower pressure


@dataclass
class SolverSpec:
    steps: int = 1
    max_cutbacks: int = 12
    linear: str = "auto"           # "auto" | "direct" | "iterative"
    petsc: dict = field(default_factory=dict)


@dataclass
class OutputSpec:
    probes: dict = field(default_factory=dict)
    picture: bool = True
    fields: bool = True


@dataclass
class ModalSpec:
    """[modal]: how many elastic modes, about which state, with which mass matrix."""
    count: int = 6
    prestress: bool = False        # True: tangent at the static equilibrium under the scene's loads
    mass: str = "consistent"       # "consistent" | "lumped"


@dataclass
class SoundSpec:
    """[sound]: a modal impulse response at a struck point, written as a WAV."""
    point: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    direction: list = field(default_factory=lambda: [0.0, 0.0, 1.0])   # unit length after parsing
    duration: float = 2.0
    alpha: float = 1.0             # Rayleigh damping zeta = alpha / (2 omega) + beta omega / 2
    beta: float = 1e-7
    sample_rate: int = 44100


@dataclass
class InverseSpec:
    """[inverse]: how to find the rest shape that deforms into the target under the scene's loads."""
    method: str = "direct"                 # "direct" | "adjoint" | "fixed-point"
    target: Path | None = None             # another mesh file as target (default: the scene's mesh)
    check_tolerance: float | None = None   # forward check must land within this (m); default 1e-3 x size
    iterations: int = 200                  # adjoint / fixed-point iteration limit
    tolerance: float = 1e-9                # adjoint: gradient norm; fixed point: update size (relative)
    match_points: list | None = None       # adjoint: match only these points (snapped to vertices)
    match_region: Selector | None = None   # adjoint: match only inside this box
    smoothness: float = 0.0                # adjoint: weight of int |grad d|^2 (d = rest - target)
    stay_close: float = 0.0                # adjoint: weight of int |d|^2 (shape preservation)
    max_move: float | None = None          # adjoint: bound on each component of d
    optimizer: str = "gauss-newton"        # adjoint: "gauss-newton" | "lbfgs" (PETSc TAO BLMVM)


@dataclass
class Scene:
    title: str = "untitled"
    analysis: str = "static"
    mesh: MeshSpec = field(default_factory=MeshSpec)
    material: MaterialSpec = field(default_factory=MaterialSpec)
    discretization: Discretization = field(default_factory=Discretization)
    fix: list = field(default_factory=list)
    load: list = field(default_factory=list)
    solver: SolverSpec = field(default_factory=SolverSpec)
    output: OutputSpec = field(default_factory=OutputSpec)
    modal: ModalSpec = field(default_factory=ModalSpec)
    sound: SoundSpec | None = None     # None: no sound
    inverse: InverseSpec = field(default_factory=InverseSpec)
    source: Path | None = None

    @classmethod
    def from_file(cls, path: str | Path, overrides: dict | None = None) -> "Scene":
        """Read and validate a TOML scene; `overrides` {"mesh.cells": [8, 1, 1], ...} replace keys first."""
        path = Path(path)
        if not path.is_file():
            raise InputError(f"scene file {str(path)!r}: not found")
        try:
            data = tomllib.loads(path.read_text())
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
            raise InputError(f"scene file {str(path)!r}: not valid TOML ({e})") from None
        for key, value in (overrides or {}).items():
            set_key(data, key, value)
        return cls.from_dict(data, base_dir=path.parent, source=path)

    @classmethod
    def from_dict(cls, data: dict, base_dir: str | Path = ".", source: Path | None = None) -> "Scene":
        return _parse_scene(data, Path(base_dir), source)


def _parse_mesh(t: _Table, base_dir: Path) -> MeshSpec:
    m = MeshSpec(generator=t.string("generator", "box", choices=GENERATORS))
    m.cell = t.string("cell", "tetrahedron", choices=CELLS)
    if m.generator == "box":
        m.size = t.vector("size", 3, m.size, positive=True)
        m.origin = t.vector("origin", 3, m.origin)
        m.cells = t.vector("cells", 3, m.cells, positive=True, integer=True)
    elif m.generator in ("cylinder", "sphere", "revolve"):
        if m.cell != "tetrahedron":
            raise InputError(f"{t.key('cell')} = {m.cell!r}: the {m.generator} generator makes tetrahedra only")
        m.origin = t.vector("origin", 3, m.origin)
        if m.generator in ("cylinder", "sphere"):
            m.radius = t.number("radius", required=True, positive=True)
        if m.generator == "cylinder":
            m.height = t.number("height", required=True, positive=True)
        if m.generator == "revolve":
            prof = t.raw("profile")
            if not isinstance(prof, list) or len(prof) < 3:
                raise InputError(f"{t.key('profile')}: must list at least 3 points [r, z] of a closed outline")
            m.profile = [check_vector(p, f"{t.key('profile')}[{i}]", 2) for i, p in enumerate(prof)]
            if any(r < 0 for r, _ in m.profile):
                raise InputError(f"{t.key('profile')}: radii r must not be negative")
        default_h = (m.radius or 0.1) / 4
        m.h = t.number("h", default_h, positive=True)
    else:
        f = t.string("file", required=True)
        p = Path(f)
        m.file = p if p.is_absolute() else (base_dir / p)
        if not m.file.is_file():
            raise InputError(f"{t.key('file')} = {f!r}: file not found")
    t.done()
    return m


def _parse_material(t: _Table) -> MaterialSpec:
    from fem_forms.materials import make_material
    s = MaterialSpec(model=t.string("model", "neo-hookean"))
    s.E = t.number("E")
    s.nu = t.number("nu")
    s.mu = t.number("mu")
    s.lmbda = t.number("lambda")
    s.C10 = t.number("C10", nonneg=True)
    s.C01 = t.number("C01", nonneg=True)
    s.rho = t.number("rho", 0.0, nonneg=True)
    t.done()
    if (s.E is not None or s.nu is not None) and (s.mu is not None or s.lmbda is not None):
        raise InputError(f"{t.path}: give either E and nu or mu and lambda, not both")
    make_material(s.model, E=s.E, nu=s.nu, mu=s.mu, lmbda=s.lmbda, C10=s.C10, C01=s.C01)  # validates
    return s


def _parse_components(v: Any, key: str) -> list:
    if not isinstance(v, list) or not v or any(c not in AXES for c in v) or len(set(v)) != len(v):
        raise InputError(f"{key} = {v!r}: must be a list of distinct names from 'x', 'y', 'z'")
    return [AXES[c] for c in v]


def _parse_modal(t: _Table) -> ModalSpec:
    m = ModalSpec(count=t.number("count", 6, integer=True, positive=True),
                  prestress=t.boolean("prestress", False),
                  mass=t.string("mass", "consistent", choices=("consistent", "lumped")))
    if m.count > 500:
        raise InputError(f"{t.key('count')} = {m.count}: at most 500 modes")
    t.done()
    return m


def _parse_sound(t: _Table) -> SoundSpec:
    s = SoundSpec()
    strike = t.table("strike", required=True)
    s.point = strike.vector("point", 3, required=True)
    s.direction = strike.vector("direction", 3, required=True)
    norm = math.sqrt(sum(c * c for c in s.direction))
    if norm == 0:
        raise InputError(f"{strike.key('direction')} = {s.direction}: must not be the zero vector")
    s.direction = [c / norm for c in s.direction]
    strike.done()
    s.duration = t.number("duration", 2.0, positive=True)
    s.sample_rate = t.number("sample_rate", 44100, integer=True, positive=True)
    if not 1000 <= s.sample_rate <= 384000:
        raise InputError(f"{t.key('sample_rate')} = {s.sample_rate}: must lie in 1000..384000 Hz")
    if s.duration * s.sample_rate > 2**26:
        raise InputError(f"{t.key('duration')} = {s.duration}: too long (at most {2**26} samples)")
    damping = t.table("damping")
    s.alpha = damping.number("alpha", s.alpha, nonneg=True)
    s.beta = damping.number("beta", s.beta, nonneg=True)
    damping.done()
    t.done()
    return s


def _parse_scene(data: dict, base_dir: Path, source: Path | None) -> Scene:
    t = _Table(data, "")
    sc = Scene(source=source)
    sc.title = t.string("title", "untitled")
    sc.analysis = t.string("analysis", "static", choices=ANALYSES)
    sc.mesh = _parse_mesh(t.table("mesh", required=True), base_dir)
    sc.material = _parse_material(t.table("material", required=True))

    d = t.table("discretization")
    sc.discretization = Discretization(
        degree=d.number("degree", 2, integer=True),
        quadrature_degree=d.number("quadrature_degree", None, integer=True, positive=True),
        formulation=d.string("formulation", "displacement", choices=("displacement", "mixed")),
        tolerance=d.number("tolerance", None, positive=True))
    if sc.discretization.tolerance is not None and sc.discretization.tolerance >= 1:
        raise InputError(f"discretization.tolerance = {sc.discretization.tolerance}: a relative error, below 1")
    if sc.discretization.formulation == "mixed":
        if sc.discretization.degree != 2:
            raise InputError(f"discretization.degree = {sc.discretization.degree}: the mixed formulation "
                             "is Taylor-Hood, degree 2 displacement with degree 1 pressure")
        if sc.analysis != "static":
            raise InputError(f"discretization.formulation = 'mixed': available for analysis = 'static' only")
    if sc.discretization.degree not in (1, 2):
        raise InputError(f"discretization.degree = {sc.discretization.degree}: unsupported element "
                         "(Lagrange degree 1 or 2)")
    d.done()

    fixes = t.raw("fix", [])
    if not isinstance(fixes, list):
        raise InputError("fix: must be an array of tables [[fix]]")
    for i, f in enumerate(fixes):
        ft = _Table(f, f"fix[{i}]")
        where = Selector.parse(ft.raw("where"), ft.key("where")) if ft.has("where") else None
        if where is None:
            raise InputError(f"{ft.key('where')}: missing (required)")
        comps = _parse_components(ft.raw("components", ["x", "y", "z"]), ft.key("components"))
        value = ft.vector("value", 3, [0.0, 0.0, 0.0])
        ft.done()
        sc.fix.append(Fix(where, comps, value))

    loads = t.raw("load", [])
    if not isinstance(loads, list):
        raise InputError("load: must be an array of tables [[load]]")
    for i, ld in enumerate(loads):
        lt = _Table(ld, f"load[{i}]")
        kind = lt.string("type", required=True, choices=("gravity", "traction", "pressure"))
        if kind == "gravity":
            load = Load("gravity", g=lt.vector("g", 3, [0.0, 0.0, -9.81]))
        else:
            if not lt.has("where"):
                raise InputError(f"{lt.key('where')}: missing (a {kind} load needs a boundary)")
            where = Selector.parse(lt.raw("where"), lt.key("where"))
            if kind == "traction":
                load = Load("traction", where=where, value=lt.vector("value", 3, required=True))
            else:
                load = Load("pressure", where=where, pressure=lt.number("value", required=True))
        lt.done()
        sc.load.append(load)
    if any(ld.type == "gravity" for ld in sc.load) and sc.material.rho <= 0:
        raise InputError("material.rho: gravity needs a positive density")

    s = t.table("solver")
    sc.solver = SolverSpec(
        steps=s.number("steps", 1, integer=True, positive=True),
        max_cutbacks=s.number("max_cutbacks", 12, integer=True, nonneg=True),
        linear=s.string("linear", "auto", choices=("auto", "direct", "iterative")))
    petsc = s.raw("petsc", {})
    if not isinstance(petsc, dict):
        raise InputError("solver.petsc: must be a table of PETSc options")
    for k, v in petsc.items():
        if isinstance(v, (dict, list)) or not k.replace("_", "").isalnum():
            raise InputError(f"solver.petsc.{k}: must be a PETSc option name with a scalar value")
    sc.solver.petsc = dict(petsc)
    s.done()

    o = t.table("output")
    probes = o.raw("probes", {})
    if not isinstance(probes, dict):
        raise InputError("output.probes: must be a table name = [x, y, z]")
    sc.output = OutputSpec(
        probes={n: check_vector(p, f"output.probes.{n}") for n, p in probes.items()},
        picture=o.boolean("picture", True), fields=o.boolean("fields", True))
    o.done()

    for name in ("modal", "sound"):
        if t.has(name) and sc.analysis != "modal":
            raise InputError(f"{name}: only for analysis = 'modal' "
                             f"(this scene's analysis is {sc.analysis!r})")
    sc.modal = _parse_modal(t.table("modal"))
    sc.sound = _parse_sound(t.table("sound")) if t.has("sound") else None
    if sc.analysis == "modal" and sc.material.rho <= 0:
        raise InputError("material.rho: modal analysis needs a positive density")
    if t.has("inverse") and sc.analysis != "inverse":
        raise InputError(f"inverse: only for analysis = 'inverse' (this scene's analysis is {sc.analysis!r})")
    sc.inverse = _parse_inverse(t.table("inverse"), base_dir)
    t.done()
    return sc


def _parse_inverse(t: _Table, base_dir: Path) -> InverseSpec:
    s = InverseSpec(method=t.string("method", "direct", choices=("direct", "adjoint", "fixed-point")))
    if t.has("target"):
        f = t.string("target")
        s.target = Path(f) if Path(f).is_absolute() else base_dir / f
        if not s.target.is_file():
            raise InputError(f"inverse.target = {f!r}: file not found")
    s.check_tolerance = t.number("check_tolerance", None, positive=True)
    s.iterations = t.number("iterations", 200, integer=True, positive=True)
    s.tolerance = t.number("tolerance", 1e-9, positive=True)
    adjoint_only = ("match_points", "match_region", "smoothness", "stay_close", "max_move", "optimizer")
    if s.method != "adjoint":
        for k in adjoint_only:
            if t.has(k):
                raise InputError(f"{t.key(k)}: only for method = 'adjoint' (method is {s.method!r})")
    if t.has("match_points"):
        pts = t.raw("match_points")
        if not isinstance(pts, list) or not pts:
            raise InputError(f"{t.key('match_points')}: must be a non-empty list of [x, y, z] points")
        s.match_points = [check_vector(p, f"{t.key('match_points')}[{i}]") for i, p in enumerate(pts)]
    if t.has("match_region"):
        s.match_region = Selector.parse(t.raw("match_region"), t.key("match_region"))
        if s.match_region.kind != "box":
            raise InputError(f"{t.key('match_region')}: must be a box = [[x0, y0, z0], [x1, y1, z1]]")
    if s.match_points is not None and s.match_region is not None:
        raise InputError(f"{t.path}: give match_points or match_region, not both")
    s.smoothness = t.number("smoothness", 0.0, nonneg=True)
    s.stay_close = t.number("stay_close", 0.0, nonneg=True)
    s.max_move = t.number("max_move", None, positive=True)
    s.optimizer = t.string("optimizer", "gauss-newton", choices=("gauss-newton", "lbfgs"))
    t.done()
    return s
