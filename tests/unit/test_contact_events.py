"""The contact events a time step can hold (physics/contact/events.py), on hand-made distances and slips: an
impact is a point in contact that approached by more than the barrier's layer within the step; points creeping into
the layer (settling, rolling) are none; a stick-slip transition is most of the common contact points switching."""
import numpy as np

from fem_forms.physics.contact.events import StepEvents, impact, transition
from fem_forms.physics.contact.friction import LaggedFriction, tangent_basis

DHAT = 1e-4


def test_a_point_that_jumps_the_layer_is_an_impact_one_that_creeps_in_is_not():
    assert impact(np.array([5e-4, 1.0]), np.array([5e-5, 1.0]), DHAT)          # from 5 dhat to dhat / 2
    assert impact(np.array([1.5e-4, 1.0]), np.array([2e-5, 1.0]), DHAT)        # 1.3 dhat closer within the step
    assert not impact(np.array([1.2e-4, 1.0]), np.array([5e-5, 1.0]), DHAT)    # 0.7 dhat: crept in
    assert not impact(np.array([5e-4, 1.0]), np.array([1.5e-4, 1.0]), DHAT)    # approached, still outside
    assert not impact(np.array([5e-5]), np.array([2e-5]), DHAT)                # in contact, creeping deeper


def test_a_transition_is_most_of_the_common_points_switching():
    nodes = np.arange(4)
    assert transition(nodes, np.zeros(4, bool), nodes, np.array([True, True, False, False]))
    assert not transition(nodes, np.zeros(4, bool), nodes, np.array([True, False, False, False]))
    # only the points in contact at both ends count; fewer than three: no transition is told
    assert not transition(np.arange(2), np.zeros(2, bool), np.arange(2), np.ones(2, bool))
    assert transition(np.arange(6), np.zeros(6, bool), np.arange(3, 9), np.array([1, 1, 0, 1, 1, 1], bool))


def friction(nodes, start, eps=1e-6):
    normal = np.tile([0.0, 0.0, 1.0], (len(nodes), 1))
    return LaggedFriction(np.asarray(nodes), np.ones(len(nodes)), tangent_basis(normal), start, 0.5, eps,
                          np.zeros(3))


def test_step_events_tell_a_block_that_starts_to_slide():
    """Four corners rest on a floor: a step in which they stick (slip below eps) then one in which all slide."""
    p0 = np.array([[0, 0, 5e-5], [1, 0, 5e-5], [0, 1, 5e-5], [1, 1, 5e-5]], float)
    ev = StepEvents()
    f1 = friction(range(4), p0)
    ev.start([p0[:, 2]], [], [None], p0)
    p1 = p0 + [1e-8, 0, 0]                                   # crept: sticking
    assert ev.kind([p1[:, 2]], [], [f1], p1, DHAT) == ""
    ev.start([p1[:, 2]], [], [f1], p1)                       # the last step's friction: nobody slid
    f2 = friction(range(4), p1)
    p2 = p1 + [1e-3, 0, 0]                                   # all four slide
    assert ev.kind([p2[:, 2]], [], [f2], p2, DHAT) == "stick-slip"
    assert ev.kind([p2[:, 2]], [0], [f2], p2, DHAT) == "stick-slip"
    ev.start([p1[:, 2]], [0], [None], p1)
    assert ev.kind([p1[:, 2]], [3], [None], p1, DHAT) == "impact"  # an obstacle file's first pairs
