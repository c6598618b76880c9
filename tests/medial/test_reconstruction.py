"""Reconstruction from a deformed skeletal mesh (S1 Eq. 3-5): identities on an ellipsoid."""

import numpy as np
import pytest

from conftest import icosphere
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.rotations import rotation_exp
from posefix.medial.reconstruction import (SkeletalReconstruction, collapsed_faces, corner_cotangents,
                                             frame_maps, triangle_frames)
from posefix.medial.skeletal_mesh import skeletal_mesh


@pytest.fixture(scope="module")
def ellipsoid():
    V, F = icosphere(3)
    V = V * [2.0, 1.0, 0.5]
    return V, F, skeletal_mesh(V, F).S


def test_corner_cotangents_of_a_right_isosceles_triangle():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert np.allclose(corner_cotangents(V, np.array([[0, 1, 2]])), [[0.0, 1.0, 1.0]])


def test_frames_of_a_triangle_and_a_degenerate_one_take_the_fallback():
    S = np.array([[0.0, 0, 0], [2, 0, 0], [0, 3, 0], [4, 0, 0]])
    F = np.array([[0, 1, 2], [0, 1, 3]])
    B, sine = triangle_frames(S, F)
    assert np.allclose(B[0], [[0, 1, 0], [0, 0, 1], [1, 0, 0]]) and np.allclose(sine, [1.0, 0.0])
    Q = rotation_exp(np.array([[0.0, 0.0, 0.7]]))[0]
    fallback = np.repeat(np.eye(3)[None] * 7.0, 2, axis=0)
    A, degenerate = frame_maps(S, S @ Q.T, F, fallback)
    assert degenerate.tolist() == [False, True] and np.allclose(A[0], Q) and np.allclose(A[1], 7.0 * np.eye(3))


def test_a_skeleton_collapsed_to_a_point_is_collapsed_everywhere_and_the_mesh_itself_nowhere(ellipsoid):
    V, F, S = ellipsoid
    assert collapsed_faces(V, 0.01 * V, F).all() and not collapsed_faces(V, V, F).any()
    assert collapsed_faces(V, S, F).mean() < 0.1  # an ellipsoid's skeletal sheet keeps its triangles' areas


def test_the_rest_skeleton_returns_the_mesh(ellipsoid):
    V, F, S = ellipsoid
    X = SkeletalReconstruction(V, F, S).reconstruct(S, np.repeat(np.eye(3)[None], len(F), axis=0))
    assert np.abs(X - V).max() <= 1e-9 * bbox_diagonal(V)


def test_a_rigid_motion_of_the_skeleton_moves_the_mesh_rigidly(ellipsoid):
    V, F, S = ellipsoid
    Q = rotation_exp(np.array([[0.4, -1.1, 0.3]]))[0]
    t = np.array([0.5, -2.0, 1.0])
    X = SkeletalReconstruction(V, F, S).reconstruct(S @ Q.T + t, np.repeat(Q[None], len(F), axis=0))
    assert np.abs(X - (V @ Q.T + t)).max() <= 1e-9 * bbox_diagonal(V)
