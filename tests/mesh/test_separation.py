"""Separating axes of triangle pairs and the moves that restore a clean pose's order along them."""

import numpy as np

from posefix.mesh.intersections import triangle_pairs_intersect
from posefix.mesh.separation import separate, separating_axes

# face 0: a small triangle at height z = 0.5 over face 1, a large one in the plane z = 0
F = np.array([[0, 1, 2], [3, 4, 5]])
PAIR = np.array([[1, 0]])  # first the plane, then the small triangle


def _pose(z=(0.5, 0.5, 0.5)):
    small = np.array([[0.0, 0.0, z[0]], [0.2, 0.0, z[1]], [0.0, 0.2, z[2]]])
    plane = np.array([[-1.0, -1.0, 0.0], [2.0, -1.0, 0.0], [-1.0, 2.0, 0.0]])
    return np.vstack([small, plane])


def test_widest_axis_is_the_plane_normal_oriented_from_first_to_second_face():
    axes, gaps = separating_axes(_pose(), F, PAIR)
    assert np.allclose(axes, [[0, 0, 1]]) and np.allclose(gaps, [0.5])
    axes, gaps = separating_axes(_pose(), F, PAIR[:, ::-1])
    assert np.allclose(axes, [[0, 0, -1]]) and np.allclose(gaps, [0.5])


def test_axis_is_rotated_into_the_pose_it_is_used_in():
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])  # about x
    Z = _pose()
    axes, gaps = separating_axes(Z, F, PAIR, Z @ R.T + [3.0, -1.0, 2.0])
    assert np.allclose(axes[0], R @ [0, 0, 1]) and np.allclose(gaps, [0.5])


def test_intersecting_pair_has_no_axis():
    axes, gaps = separating_axes(_pose((0.5, -0.5, 0.5)), F, PAIR)
    assert gaps[0] <= 0 and not axes.any()


def test_crossing_vertex_moves_along_the_axis_to_the_margin_and_nothing_else_moves():
    axes, _ = separating_axes(_pose(), F, PAIR)
    Y = _pose((0.5, -0.3, 0.5))  # one vertex of the small triangle pushed through the plane
    assert triangle_pairs_intersect(Y[F[[0]]], Y[F[[1]]])[0]
    mobility = np.array([1.0, 1, 1, 0, 0, 0])  # the plane is fixed
    X, feasible = separate(Y, F, PAIR, axes, mobility, margin=0.01)
    assert feasible
    assert np.allclose(X[1], [0.2, 0.0, 0.01]) and np.array_equal(np.delete(X, 1, axis=0), np.delete(Y, 1, axis=0))
    assert not triangle_pairs_intersect(X[F[[0]]], X[F[[1]]])[0]


def test_moves_are_shared_in_proportion_to_mobility():
    axes, _ = separating_axes(_pose(), F, PAIR)
    Y = _pose((0.5, -0.3, 0.5))
    mobility = np.array([0.0, 1.0, 0.0, 1.0, 1.0, 1.0])  # the crossing vertex and the plane's three
    X, feasible = separate(Y, F, PAIR, axes, mobility, margin=0.0)
    assert feasible and not triangle_pairs_intersect(X[F[[0]]], X[F[[1]]])[0]
    rise, sink = X[1, 2] - Y[1, 2], Y[3:, 2] - X[3:, 2]
    assert rise > 0 and (sink > 0).all() and np.isclose(X[1, 2], X[3:, 2].max())  # met half-way, per constraint
    assert np.allclose(X[:, :2], Y[:, :2])  # only along the axis


def test_fixed_pair_is_reported_infeasible_and_left_alone():
    axes, _ = separating_axes(_pose(), F, PAIR)
    Y = _pose((0.5, -0.3, 0.5))
    X, feasible = separate(Y, F, PAIR, axes, np.zeros(6), margin=0.01)
    assert not feasible and np.array_equal(X, Y)
