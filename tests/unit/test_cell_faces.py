"""The closed surface of a set of cells (fem_forms/meshes/cell_faces.py): the faces only one cell has, outward, so
that the divergence theorem gives back the cells' volume (a face kept twice, missed or turned inward would not)."""
import numpy as np

from fem_forms.meshes.cell_faces import surface_triangles


def enclosed_volume(points: np.ndarray, tris: np.ndarray) -> float:
    a, b, c = (points[tris[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def test_two_hexahedra_side_by_side_enclose_their_volume_with_ten_outer_quads():
    x, y, z = np.meshgrid([0.0, 1.0, 2.0], [0.0, 1.0], [0.0, 1.0], indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    index = np.arange(12).reshape(3, 2, 2)

    def hexa(i):                                      # VTK order: the bottom quad counter-clockwise, then the top
        return [index[i, 0, 0], index[i + 1, 0, 0], index[i + 1, 1, 0], index[i, 1, 0],
                index[i, 0, 1], index[i + 1, 0, 1], index[i + 1, 1, 1], index[i, 1, 1]]
    tris = surface_triangles(np.array([hexa(0), hexa(1)]))
    assert len(tris) == 20                            # the shared face is left out
    assert np.isclose(enclosed_volume(points, tris), 2.0)


def test_a_cube_of_six_tetrahedra_encloses_its_volume_and_the_inner_faces_are_left_out():
    points = np.array([[i, j, k] for i in (0.0, 1.0) for j in (0.0, 1.0) for k in (0.0, 1.0)])   # index 4i + 2j + k
    tets = np.array([[0, 4, 6, 7], [0, 6, 2, 7], [0, 2, 3, 7], [0, 3, 1, 7], [0, 1, 5, 7], [0, 5, 4, 7]])
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    assert np.all(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) > 0)     # positively oriented
    tris = surface_triangles(tets)
    assert len(tris) == 12
    assert np.isclose(enclosed_volume(points, tris), 1.0)
    assert np.isclose(enclosed_volume(points, surface_triangles(tets[:1])), 1.0 / 6.0)
