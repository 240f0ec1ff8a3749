"""The obstacles as pictures draw them (output/obstacle_shapes.py): every point on the obstacle's own surface (its
distance function, physics/contact/obstacles.py, is zero there), the sphere and the box closed (each edge shared
by two triangles), the plane's square and the cylinder's length centred on the part."""
from types import SimpleNamespace

import numpy as np
import pytest

from fem_forms.output.obstacle_shapes import obstacle_surfaces
from fem_forms.physics.contact.obstacles import make_obstacle

PART = np.array([[0.0, 0.0, 0.0], [0.1, 0.2, 0.3]])       # the part's bounding box corners


def shapes(**spec):
    ob = make_obstacle(SimpleNamespace(name="o", friction=0.0, motion=None, **spec))
    ob.move_to(0.0)
    model = SimpleNamespace(terms=[SimpleNamespace(role="contact", obstacles=[ob], files=[])])
    (name, points, triangles), = obstacle_surfaces(model, PART)
    return ob, points, triangles


def closed(points, triangles) -> bool:
    """Every edge in two triangles, once coincident points are merged and degenerate triangles dropped (a UV
    sphere's poles)."""
    _, index = np.unique(points.round(12), axis=0, return_inverse=True)
    t = index.ravel()[triangles]
    t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 2] != t[:, 0])]
    edges = np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


@pytest.mark.parametrize("spec", [dict(shape="sphere", center=[0.0, 0.0, -1.0], radius=0.5),
                                  dict(shape="box", min=[-1.0, -1.0, -1.0], max=[1.0, 1.0, -0.5])])
def test_closed_obstacles_lie_on_their_surface(spec):
    ob, points, triangles = shapes(**spec)
    assert np.allclose(ob.distance(points), 0.0, atol=1e-12) and closed(points, triangles)


def test_a_plane_and_a_cylinder_are_centred_on_the_part():
    centre = PART.mean(axis=0)
    ob, points, _ = shapes(shape="plane", point=[0.0, 0.0, -0.01], normal=[0.0, 0.0, 1.0])
    assert np.allclose(ob.distance(points), 0.0) and np.allclose(points.mean(axis=0)[:2], centre[:2])
    ob, points, _ = shapes(shape="cylinder", point=[0.0, 0.5, 0.0], axis=[1.0, 0.0, 0.0], radius=0.1)
    assert np.allclose(ob.distance(points), 0.0, atol=1e-12)
    assert points[:, 0].mean() == pytest.approx(centre[0])
