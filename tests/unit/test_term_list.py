"""The model's terms are one declared list, found by role: a term of a new kind placed after the solid is
never taken for a load, and every term says which scene keys made it."""
import numpy as np
import pytest
import ufl

import fem_forms as ff
from fem_forms.model import build_model
from fem_forms.output.reactions import applied_load
from fem_forms.physics.term_list import TermList
from fem_forms.physics.terms import Term
from helpers import beam_scene


class Spring(Term):
    """A term of a role no analysis knows: k/2 int |u|^2 dX."""
    name, role, keys = "spring", "spring", ("spring",)

    def energy(self, ctx):
        return 0.5 * 1e3 * ctx.volume(ufl.inner(ctx.u, ctx.u))


def scene():
    return ff.Scene.from_dict(beam_scene(load=[
        {"type": "gravity", "g": [0.0, 0.0, -9.81]},
        {"type": "traction", "where": {"axis": "x", "at": 1.0}, "value": [0.0, 0.0, -10.0],
         "history": [[0.0, 0.0], [1.0, 1.0]]}]))


def test_roles_and_keys_of_a_scene_model():
    model = build_model(scene())
    assert model.solid.role == "solid" and model.solid.keys == ("material",)
    assert [t.name for t in model.loads] == ["gravity", "traction"]
    assert [t.keys for t in model.loads] == [("load", 0), ("load", 1)]
    assert all(t.fields == ("displacement",) for t in model.terms)
    assert model.physics == ["elastic (neo-hookean)", "gravity", "traction"]


def test_a_term_after_the_solid_is_not_a_load():
    model = build_model(scene())
    without = applied_load(model)
    model.terms = TermList([model.solid, Spring(), *model.loads])
    assert [t.name for t in model.loads] == ["gravity", "traction"]
    assert model.terms.with_role("spring")[0].name == "spring"
    # the applied load sums the loads alone: the spring (a term of another role) is not in it
    np.testing.assert_allclose(applied_load(model), without, rtol=1e-14, atol=1e-14)


def test_update_moves_each_load_along_its_own_history():
    model = build_model(scene())
    model.terms.update(0.25)
    gravity, traction = model.loads
    assert float(gravity.factor.value) == 1.0           # no history: held at 1
    assert float(traction.factor.value) == pytest.approx(0.25)


def test_exactly_one_solid():
    model = build_model(scene())
    with pytest.raises(ValueError, match="exactly one solid"):
        TermList(list(model.loads))


def test_a_registered_section_adds_its_terms_to_every_model(monkeypatch):
    """One module and one registration: the spring's builder runs for every model, results.json's physics
    names it, and its force is in the equilibrium: support reactions + applied loads = the spring's pull,
    k int u dX, assembled independently of the solver's forms."""
    from dolfinx import fem
    from mpi4py import MPI
    from fem_forms.analyses.static.solve import solve_static
    from fem_forms.physics import terms as terms_module
    monkeypatch.setitem(terms_module.SCENE_TERMS, "spring", lambda sc, mesh: [Spring()])
    held = solve_static(scene())
    assert held.report.converged
    assert held.model.physics == ["elastic (neo-hookean)", "gravity", "traction", "spring"]
    u = held.model.u
    pull = [held.model.mesh.comm.allreduce(fem.assemble_scalar(fem.form(1e3 * u[i] * ufl.dx)), op=MPI.SUM)
            for i in range(3)]
    support = np.sum(list(held.reactions["reactions"].values()), axis=0)
    np.testing.assert_allclose(support + held.reactions["applied_load"], pull, rtol=1e-6, atol=1e-8)
    assert abs(pull[2]) > 1e-2 * abs(held.reactions["applied_load"][2])   # the spring carries a share


def test_paths_that_assemble_ufl_alone_refuse_array_terms():
    """An energy computed as arrays must never be silently left out: the analyses that do not take array
    terms yet say so by name (InputError: exit 2), the static solve hands them to the driver."""
    from fem_forms.errors import InputError
    from fem_forms.physics.array_term import ArrayTerm

    class Floor(ArrayTerm):
        name, role = "floor", "contact"

    model = build_model(scene())
    model.terms = TermList([*model.terms, Floor()])
    with pytest.raises(InputError, match="floor: not available in modal analysis"):
        model.only_ufl_terms("modal analysis")
    assert [t.name for t in model.problem().array_terms] == ["floor"]
