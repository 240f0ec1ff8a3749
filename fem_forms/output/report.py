"""report.html: one self-contained page per run, opened in any browser without a network - the part in 3D to turn
around (rest and deformed, a slider over its load steps, coloured by |u| or von Mises stress with a colour bar
and units, its supports and loads marked), the numbers of results.json as a table, the warnings.

The viewer is three.js (the npm registry's package, which setup.sh fetches into the venv: share/fem_forms/three),
embedded into the page as it is written; no third-party code is in the repository. Chosen over pyvista/trame's
vtk.js export by size: three.js's module build is 2.1 MB, embedded once per page (base64: 2.8 MB); the part is
its outer surface only, float32 (benchmarks/report_size.md measures pages of large runs). Without three.js the
page is left out with a warning (results.json says so); `fem-forms view OUT` opens it."""
from __future__ import annotations

import base64
import functools
from dataclasses import asdict, dataclass, field
import json
import math
from pathlib import Path
import sys

import numpy as np

from fem_forms.output.marks import mark_colour, marked_facets

THREE = Path(sys.prefix) / "share" / "fem_forms" / "three"        # setup.sh unpacks three.js here
THREE_FILES = ("three.module.js", "three.core.js", "OrbitControls.js")
TEMPLATE = Path(__file__).with_name("report_page.html")
FRAME_BYTES = 12e6             # report.html's frames (displacements, magnitudes) share this; a page stays < 20 MB


@dataclass
class ReportPart:
    """What the page draws: the outer surface's rest points (n, 3) and triangles (m, 3), the displacement of each
    frame, scalar fields at the points per frame ({name: (unit, [values per frame])}) and marked triangles."""
    rest: np.ndarray
    triangles: np.ndarray
    frames: list = field(default_factory=list)      # [(label, displacement (n, 3))]
    fields: dict = field(default_factory=dict)      # name -> (unit, [values (n,) per frame])
    marks: list = field(default_factory=list)       # [(label, triangle indices)]
    obstacles: list = field(default_factory=list)   # [{name, shape, its keys, offsets}]: the rigid obstacles


def viewer_installed() -> bool:
    return all((THREE / f).is_file() for f in THREE_FILES)


def _module_url(text: str) -> str:
    return "data:text/javascript;base64," + base64.b64encode(text.encode()).decode()


@functools.lru_cache(maxsize=1)
def _viewer_urls() -> dict:
    """The three.js modules as data URLs for the page's import map; three.module.js imports its core by a relative
    path, which a data URL cannot resolve: it is pointed at the map's name for it."""
    module, core, orbit = ((THREE / f).read_text() for f in THREE_FILES)
    return {"__THREE__": _module_url(module.replace("'./three.core.js'", "'three/core'")),
            "__THREE_CORE__": _module_url(core), "__ORBIT__": _module_url(orbit)}


def _b64(a: np.ndarray, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=dtype).tobytes()).decode()


def _number(v) -> str:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    if isinstance(v, int):
        return f"{v:,}"
    return "nan" if math.isnan(v) else f"{v:.6g}"


def result_rows(summary: dict, prefix: str = "", depth: int = 0) -> list[tuple[str, str]]:
    """results.json as (key, value) rows: numbers, words and short lists; nested tables (probes, reactions)
    with dotted keys; long lists and the file list left to results.json."""
    rows = []
    for key, value in summary.items():
        name = f"{prefix}{key}"
        if key in ("warnings", "files") or value is None:
            continue
        if isinstance(value, dict) and depth < 3:
            rows += result_rows(value, name + ".", depth + 1)
        elif isinstance(value, (list, tuple)) and len(value) <= 6 and all(
                isinstance(v, (int, float, str)) for v in value):
            rows.append((name, "[" + ", ".join(_number(v) for v in value) + "]"))
        elif isinstance(value, (int, float, str, bool)):
            rows.append((name, _number(value)))
    return rows


def write_report(path: Path, title: str, subtitle: str, part: ReportPart, summary: dict, up=(0.0, 0.0, 1.0),
                 scale: str = "1") -> None:
    """The page for `part` and `summary` (results.json's dict) at `path` (written whole, then renamed), its
    shapes first shown at `scale` ("1": true scale, "10", "100", "auto"), with the run's plots already in its
    folder (the PNGs its results.json lists: load path, histories and energies, spectrum, modes) embedded."""
    from fem_forms.output.pictures import VIRIDIS
    data = {
        "subtitle": subtitle, "up": [float(c) for c in up], "scale": scale,
        "surface": {"rest": _b64(part.rest, "<f4"), "triangles": _b64(part.triangles, "<u4")},
        "frames": [{"label": label, "u": _b64(u, "<f4")} for label, u in part.frames],
        "fields": {name: {"unit": unit, "frames": [_b64(v, "<f4") for v in values]}
                   for name, (unit, values) in part.fields.items()},
        "marks": [{"label": label, "colour": mark_colour(i), "triangles": _b64(t, "<u4")}
                  for i, (label, t) in enumerate(part.marks)],
        "table": result_rows(summary), "warnings": list(summary.get("warnings", [])),
        "plots": _plots(path.parent, summary.get("files", {})),
        "obstacles": part.obstacles,
        "viridis": VIRIDIS.round(4).tolist()}
    text = TEMPLATE.read_text().replace("__TITLE__", _html(title))
    for name, url in _viewer_urls().items():
        text = text.replace(name, url)
    text = text.replace("__DATA__", json.dumps(data).replace("</", "<\\/"))
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


def _plots(folder: Path, files: dict) -> list[dict]:
    """The run's PNG plots (not its deformed-part picture: the page shows the part) as data URLs, with names."""
    out = []
    for key, name in files.items():
        p = folder / str(name)
        if str(name).endswith(".png") and name != "deformed.png" and p.is_file():
            out.append({"name": name, "src": "data:image/png;base64," + base64.b64encode(p.read_bytes()).decode()})
    return out


def _html(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def triangulated(polys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of triangles or quadrilaterals (a quadrilateral in two), and the polygon each came from."""
    if polys.shape[1] == 3:
        return polys, np.arange(len(polys))
    return np.vstack([polys[:, [0, 1, 2]], polys[:, [0, 2, 3]]]), np.tile(np.arange(len(polys)), 2)


def obstacles(scene, times: list | None = None) -> list[dict]:
    """The scene's rigid obstacles as the page draws them: a plane, a sphere, a box, a cylinder by their keys; a
    surface file by its triangles; one that moves with its translation at each frame's time (`offsets`, `times`
    one per frame: dynamic time or the load steps' pseudo-time) and at time 0 (`offset0`, the rest shape's)."""
    if scene.contact is None:
        return []
    from fem_forms.meshes.surfaces import read_surface
    from fem_forms.physics.contact.obstacles import translation
    out = []
    for ob in scene.contact.obstacle:
        keys = asdict(ob)
        row = {"name": ob.name, "shape": ob.shape,
               **{k: keys[k] for k in ("point", "normal", "center", "radius", "min", "max", "axis")
                  if keys.get(k) is not None}}
        if ob.motion:
            row["offset0"] = translation(ob.motion, 0.0).tolist()
            row["offsets"] = [translation(ob.motion, t).tolist() for t in (times or [])]
        if ob.shape == "file":
            points, triangles = read_surface(Path(ob.file), f"contact.obstacle {ob.name}.file")
            row["points"], row["triangles"] = _b64(points, "<f4"), _b64(triangles, "<u4")
        out.append(row)
    return out


def within_budget(frames: list, points: int, budget: float = FRAME_BYTES) -> list:
    """As many frames as fit `budget` bytes (a point's displacement and magnitude: 16 bytes, 4/3 of it in base64),
    evenly spread from the first to the last: a long motion of a large part stays a page to send."""
    fit = max(1, int(budget // (16 * points * 4 / 3)))
    if len(frames) <= fit:
        return frames
    if fit == 1:
        return frames[-1:]
    return [frames[i] for i in sorted(set(np.linspace(0, len(frames) - 1, fit).round().astype(int).tolist()))]


def surface_frames(frames: list) -> list:
    """[(label, Function)] -> [(label, displacement of the gathered surface's points)] on rank 0 (a collective
    call; the same points' order as every boundary_surface gather of that mesh)."""
    from fem_forms.output.fields import boundary_surface
    out = []
    for label, u in frames:
        surf = boundary_surface(u)
        out.append((label, None if surf is None else surf[2]))
    return out


def end_fields(model, von_mises=None) -> list[tuple[str, str, object]]:
    """The fields a report colours the last frame by besides |u| (a collective call): von Mises stress when given,
    the damage of a crack, the contact pressure, the material where there are several, as (name, unit, P1
    Function)."""
    from dolfinx import fem
    from fem_forms.output.quantities import term_field
    out = [("von Mises", "Pa", von_mises)] if von_mises is not None else []
    out += [("damage", "", f) for f in model.terms.output_fields() if f.name == "damage"]
    if getattr(model.scene, "contact", None) is not None:
        out.append(("contact pressure", "Pa", term_field(model, "contact_pressure")))
    regions = model.context.materials
    if len(regions.materials) > 1:                   # each vertex takes one of its cells' material (index from 0)
        p1 = fem.Function(fem.FunctionSpace(model.mesh, ("Lagrange", 1)), name="material")
        p1.interpolate(regions.field(list(range(len(regions.materials))), "material"))
        out.append(("material (scene order from 0)", "", p1))
    return out


def write_model_report(model, u, shapes: list, von_mises, out: Path, summary: dict, subtitle: str, up=None,
                       scale: str = "1", magnitude: tuple = ("|u|", "m"), times: list | None = None) -> bool:
    """report.html of a solved model (a collective call; rank 0 writes): its outer surface gathered with u and the
    end_fields (von Mises stress when given, damage, contact pressure, material), moved by each of `shapes`
    ([(label, displacement at the surface's points)] from surface_frames or a run's own gathers; None: u's),
    coloured by the displacement's magnitude (named and in the unit of `magnitude`) or, on the last frame, by those
    fields; its supports and loads marked, shown at `scale` ("1", "10", "100", "auto"); its moving obstacles where
    they are at each shape's time (`times`, one per shape; None: where they start). False (and a warning in
    summary) when the viewer is not installed."""
    if not viewer_installed():
        summary.setdefault("warnings", []).append(
            "report.html left out: its viewer (three.js) is not installed; run setup.sh")
        return False
    from fem_forms.output.fields import boundary_surface
    marked = marked_facets(model)
    at_end = end_fields(model, von_mises)
    base = boundary_surface(u, [f for _, _, f in at_end], [facets for _, facets in marked])
    if model.mesh.comm.rank == 0:
        points, polys, disp, values, bits = base
        tris, origin = triangulated(polys)
        timed = zip(shapes, times if times is not None else [None] * len(shapes), strict=True)
        kept = within_budget([(label, disp if d is None else d, t) for (label, d), t in timed], len(points))
        moves = [(label, d) for label, d, _ in kept]
        fields = {magnitude[0]: (magnitude[1], [np.linalg.norm(d, axis=1) for _, d in moves])}
        for k, (name, unit, _) in enumerate(at_end):    # known at the end only: shown with the last frame
            fields[name if len(moves) == 1 else f"{name} (last frame)"] = (unit, [values[:, k]])
        marks = [(label, tris[(bits[origin] >> i) & 1 == 1].ravel()) for i, (label, _) in enumerate(marked)]
        write_report(out / "report.html", model.scene.title, subtitle,
                     ReportPart(points, tris, moves, fields, marks,
                                obstacles(model.scene, None if times is None else [t for _, _, t in kept])),
                     summary, (0.0, 0.0, 1.0) if up is None else up, scale)
    return True
