"""Per-mesh geometry: analytic one-triangle and one-tetrahedron cases."""

import numpy as np

from conftest import icosphere
from posefix.mesh.geometry import (bbox_diagonal, edge_lengths, face_areas, face_cross, point_triangle_distance,
                                   vertex_areas, vertex_normals)

TRI_V = np.array([[0.0, 0, 0], [2.0, 0, 0], [0, 1.0, 0]])
TRI_F = np.array([[0, 1, 2]])


def test_one_triangle():
    assert bbox_diagonal(TRI_V) == np.sqrt(5.0)
    assert np.array_equal(face_cross(TRI_V, TRI_F), [[0.0, 0.0, 2.0]])
    assert face_areas(TRI_V, TRI_F).tolist() == [1.0]
    assert np.allclose(vertex_areas(TRI_V, TRI_F), [1 / 3] * 3)
    assert np.array_equal(vertex_normals(TRI_V, TRI_F), [[0, 0, 1.0]] * 3)
    assert edge_lengths(TRI_V, np.array([[0, 1], [1, 2]])).tolist() == [2.0, np.sqrt(5.0)]


def test_vertex_areas_sum_to_the_surface_and_normals_point_out():
    V, F = icosphere(2)
    assert np.isclose(vertex_areas(V, F).sum(), face_areas(V, F).sum())
    N = vertex_normals(V, F)
    assert np.allclose(np.linalg.norm(N, axis=1), 1.0) and (np.einsum("ij,ij->i", N, V) > 0.99).all()
    assert np.array_equal(vertex_normals(np.vstack([V, [[5.0, 5, 5]]]), F)[-1], [0, 0, 0])  # on no face


def test_point_triangle_distance_in_every_region():
    P = np.array([[0.5, 0.25, 3.0],   # above the inside: the height
                  [-1.0, -1.0, 0.0],  # nearest the corner (0, 0)
                  [1.0, -2.0, 0.0],   # nearest the edge along x
                  [3.0, 0.0, 4.0]])   # beyond the corner (2, 0), lifted
    k = len(P)
    d = point_triangle_distance(P, np.repeat(TRI_V[:1], k, 0), np.repeat(TRI_V[1:2], k, 0), np.repeat(TRI_V[2:], k, 0))
    assert np.allclose(d, [3.0, np.sqrt(2.0), 2.0, np.sqrt(17.0)])


def test_point_to_a_degenerate_triangle_is_the_distance_to_its_segment():
    A, B, C = np.array([[0.0, 0, 0]]), np.array([[2.0, 0, 0]]), np.array([[1.0, 0, 0]])
    assert np.allclose(point_triangle_distance(np.array([[1.0, 3.0, 4.0]]), A, B, C), 5.0)
