"""Inverse design analysis: its [inverse] section, whose keys depend on the method."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fem_forms.errors import InputError
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.analyses.balance import INVERSE_BALANCE, check_carving
from fem_forms.scene.analyses.contact_section import CONTACT
from fem_forms.scene.reader import Key, Section, Table, Variants
from fem_forms.scene.selectors import Selector

METHOD = Key("method", "string", "how the rest shape is found", default="direct",
             choices=("direct", "adjoint", "fixed-point"))
COMMON_KEYS = (
    Key("target", "file", "another mesh file as the target shape (default: the scene's mesh)"),
    Key("check", "string", "how the design is checked on its written rest mesh: equilibrium (the forward "
        "residual at the target, a few Newton steps at most, and the tangent's inertia there) or path (a "
        "forward solve ramping the loads from the rest shape)", default="equilibrium",
        choices=("equilibrium", "path")),
    Key("check_tolerance", "number", "the forward check must land within this of the target", unit="m",
        exclusive_minimum=0, default_note="1e-3 x the body's size"),
    Key("iterations", "integer", "adjoint / fixed-point iteration limit", default=200, exclusive_minimum=0),
    Key("tolerance", "number", "adjoint: gradient norm; fixed point: update size (relative)", default=1e-9,
        exclusive_minimum=0),
)
ADJOINT_KEYS = (
    Key("match_points", "points", "match the target only at these points (snapped to vertices)", unit="m",
        length=3, min_items=1, note="must be a non-empty list of [x, y, z] points"),
    Key("match_region", "selector", "match the target only inside this box", choices=("box",),
        parse=Selector.parse),
    Key("smoothness", "number", "weight of the integral of |grad d|^2 (d = rest - target)", default=0.0,
        minimum=0),
    Key("stay_close", "number", "weight of the integral of |d|^2 (shape preservation)", default=0.0, minimum=0),
    Key("max_move", "number", "bound on each component of d", unit="m", exclusive_minimum=0),
    Key("optimizer", "string", "Gauss-Newton, or L-BFGS (PETSc TAO BLMVM)", default="gauss-newton",
        choices=("gauss-newton", "lbfgs")),
)
VARIANTS = Variants(METHOD, {"direct": (), "adjoint": ADJOINT_KEYS, "fixed-point": ()})
_K = {k.name: k for k in (METHOD,) + COMMON_KEYS + ADJOINT_KEYS}


@dataclass
class InverseSpec:
    """[inverse]: how to find the rest shape that deforms into the target under the scene's loads."""
    method: str = _K["method"].field()                     # "direct" | "adjoint" | "fixed-point"
    target: Path | None = None             # another mesh file as target (default: the scene's mesh)
    check: str = _K["check"].field()       # "equilibrium" | "path": how the forward check solves
    check_tolerance: float | None = None   # forward check must land within this (m); default 1e-3 x size
    iterations: int = _K["iterations"].field()             # adjoint / fixed-point iteration limit
    tolerance: float = _K["tolerance"].field()             # adjoint: gradient norm; fixed point: update size
    match_points: list | None = None       # adjoint: match only these points (snapped to vertices)
    match_region: Selector | None = None   # adjoint: match only inside this box
    smoothness: float = _K["smoothness"].field()           # adjoint: weight of int |grad d|^2
    stay_close: float = _K["stay_close"].field()           # adjoint: weight of int |d|^2
    max_move: float | None = None          # adjoint: bound on each component of d
    optimizer: str = _K["optimizer"].field()               # adjoint: "gauss-newton" | "lbfgs"


def _rules(s: InverseSpec, t: Table) -> None:
    if s.match_points is not None and s.match_region is not None:
        raise InputError(f"{t.path}: give match_points or match_region, not both")


def _check(scene) -> None:
    """Rules across sections: the mixed u-p formulation with the direct method only, volume-controlled cavities not
    with the fixed point, a carving or contact."""
    volume = next((i for i, ld in enumerate(scene.load) if ld.type == "inflation" and ld.volume is not None), None)
    if volume is not None and (scene.inverse.method == "fixed-point" or scene.balance is not None
                               or scene.contact is not None):
        raise InputError(f"load[{volume}].volume: volume control in an inverse scene is designed by the direct or "
                         "the adjoint method, without [balance] or [contact] (or give the cavity's pressure)")
    if scene.discretization.formulation == "mixed":
        if scene.inverse.method != "direct":
            raise InputError(f"inverse.method = {scene.inverse.method!r}: the mixed formulation is designed by "
                             "the direct method only (method = \"direct\", or formulation = \"displacement\")")
        if scene.balance is not None:
            raise InputError("balance: carving in an inverse scene is not implemented with formulation = "
                             "\"mixed\"; use \"displacement\"")
    check_carving(scene)
    _check_contact(scene)


def _check_contact(scene) -> None:
    """[contact] in an inverse scene: a part standing on a table. The adjoint method only (the direct method's
    deformed positions are the target, fixed: the barrier would push with whatever force the target's gaps give;
    carving, [balance], takes the direct method: refused by its own rule), analytic obstacles that hold still."""
    contact = getattr(scene, "contact", None)
    if contact is None:
        return
    if scene.inverse.method != "adjoint":
        raise InputError(f"inverse.method = {scene.inverse.method!r}: a part standing on obstacles ([contact]) is "
                         "designed by the adjoint method (method = \"adjoint\"): the direct method solves on the "
                         "target, where the contact forces are not determined")
    if contact.self or any(ob.shape == "file" for ob in contact.obstacle):
        raise InputError("contact: an inverse design stands on plane, sphere, box or cylinder obstacles (self-contact "
                         "and obstacle files are not designed for yet)")
    if not scene.fix and not any(ob.friction > 0 for ob in contact.obstacle):
        raise InputError("contact.obstacle: a part standing on frictionless obstacles with no [[fix]] slides and turns "
                         "freely along them (no equilibrium to design for); give the table friction")
    moving = next((i for i, ob in enumerate(contact.obstacle) if ob.motion), None)
    if moving is not None:
        raise InputError(f"contact.obstacle[{moving}].motion: the obstacles hold still in an inverse design")


ANALYSIS = Analysis(
    name="inverse",
    doc="the rest shape that deforms into the given shape under the loads, checked by a forward solve",
    runner="fem_forms.analyses.inverse:run",
    sections=(Section("inverse", "how to find the rest shape that deforms into the target", InverseSpec,
                      keys=COMMON_KEYS, variants=VARIANTS, rules=_rules),
              INVERSE_BALANCE,           # [balance]: carve the interior too (designed on the target)
              CONTACT),                  # [contact]: standing on a table (adjoint method)
    outputs=("results.json", "rest_shape.msh", "rest_shape.stl", "fields.xdmf", "inverse.png",
             "void.stl (with [balance])"),
    formulations=("displacement", "mixed"),
    check=_check,
)
