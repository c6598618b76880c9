"""Distortion ratios: analytic one-triangle cases, symmetric in stretch and crush, degenerate faces."""

import numpy as np

from posefix.mesh.distortion import distorted_faces, distortion_summary, face_distortion
from posefix.mesh.rotations import rotation_exp

TRIANGLE = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
ONE = np.array([[0, 1, 2]])


def test_a_rigid_motion_has_ratio_one():
    R = rotation_exp(np.array([[0.4, -1.0, 0.3]]))[0]
    edge, area = face_distortion(TRIANGLE @ R.T + 5.0, TRIANGLE, ONE)
    assert np.allclose(edge, 1.0) and np.allclose(area, 1.0)


def test_stretch_and_crush_are_equally_bad():
    stretched = TRIANGLE * [3.0, 1.0, 1.0]
    crushed = TRIANGLE * [1 / 3.0, 1.0, 1.0]
    for X in (stretched, crushed):
        edge, area = face_distortion(X, TRIANGLE, ONE)
        assert np.isclose(edge[0], 3.0) and np.isclose(area[0], 3.0)


def test_a_uniform_scale_squares_the_area_ratio():
    edge, area = face_distortion(2.0 * TRIANGLE, TRIANGLE, ONE)
    assert np.isclose(edge[0], 2.0) and np.isclose(area[0], 4.0)


def test_degenerate_faces():
    flat = TRIANGLE * [1.0, 0.0, 1.0]  # area 0, one edge 0
    edge, area = face_distortion(TRIANGLE, flat, ONE)
    assert np.isinf(edge[0]) and np.isinf(area[0])
    edge, area = face_distortion(flat, flat, ONE)
    assert edge[0] == 1.0 and area[0] == 1.0


def test_a_face_is_distorted_only_against_every_rest_shape():
    X = TRIANGLE * [5.0, 1.0, 1.0]
    assert distorted_faces(X, [TRIANGLE], ONE, 4.0).tolist() == [True]
    assert distorted_faces(X, [TRIANGLE, X], ONE, 4.0).tolist() == [False]
    s = distortion_summary(X, {"target": X, "reference": TRIANGLE}, ONE, 4.0)
    assert s["edge_target"] == 1.0 and np.isclose(s["edge_reference"], 5.0) and s["faces_over"] == 0
