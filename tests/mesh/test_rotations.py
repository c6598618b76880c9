"""Rotations: polar decomposition, log/exp near 0 and pi, Kabsch, branch unwrapping."""

import numpy as np

from posefix.mesh.rotations import (cofactors, kabsch, polar_decomposition, polar_rotations, rotation_angle_between,
                                    rotation_exp, rotation_log, unwrap_rotation_vectors)


def _random_rotations(rng, k):
    axis = rng.normal(size=(k, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return rotation_exp(axis * rng.uniform(0, np.pi, size=(k, 1)))


def test_polar_decomposition_reconstructs_and_is_proper():
    rng = np.random.default_rng(0)
    J = rng.normal(size=(200, 3, 3))
    R, S = polar_decomposition(J)
    assert np.allclose(R @ S, J, atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.allclose(R @ np.transpose(R, (0, 2, 1)), np.eye(3), atol=1e-12)
    assert np.allclose(S, np.transpose(S, (0, 2, 1)), atol=1e-12)


def test_polar_rotations_by_newton_equal_the_svd_factor_and_handle_reflections():
    rng = np.random.default_rng(3)
    J = rotation_exp(rng.normal(size=(200, 3))) @ (np.eye(3) + 0.4 * rng.normal(size=(200, 3, 3)))
    J[:5] *= -1.0  # det < 0: reflections
    R = polar_rotations(J)
    assert np.abs(R - polar_decomposition(J)[0]).max() < 1e-10
    assert np.abs(np.linalg.det(R) - 1.0).max() < 1e-12
    assert np.abs(cofactors(J) - np.linalg.det(J)[:, None, None] * np.linalg.inv(J).transpose(0, 2, 1)).max() < 1e-9


def test_exp_log_round_trip_including_near_zero_and_pi():
    rng = np.random.default_rng(1)
    axis = rng.normal(size=(400, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = np.concatenate([rng.uniform(0, np.pi, 100), np.full(100, 1e-9), np.pi - np.logspace(-12, -3, 100),
                            np.zeros(100)])
    R = rotation_exp(axis * angle[:, None])
    omega = rotation_log(R)
    assert np.allclose(rotation_exp(omega), R, atol=1e-12)
    assert np.allclose(np.linalg.norm(omega, axis=1), angle, atol=1e-10)


def test_log_at_exactly_pi():
    R = np.diag([1.0, -1.0, -1.0])[None]  # pi about x
    omega = rotation_log(R)[0]
    assert np.isclose(np.linalg.norm(omega), np.pi)
    assert np.allclose(np.abs(omega), [np.pi, 0, 0])


def test_kabsch_recovers_a_rigid_motion():
    rng = np.random.default_rng(2)
    X = rng.normal(size=(50, 3))
    R_true = _random_rotations(rng, 1)[0]
    Y = (X - X.mean(0)) @ R_true.T + np.array([1.0, -2.0, 3.0])
    R, cx, cy = kabsch(X, Y, np.ones(len(X)))
    assert np.allclose(R, R_true, atol=1e-12)
    assert np.allclose((X - cx) @ R.T + cy, Y, atol=1e-12)


def test_unwrap_keeps_rotations_and_makes_a_twist_continuous():
    # a strip of faces twisting continuously from 0 to 300 degrees about x: principal logs jump at 180
    angles = np.radians(np.linspace(0, 300, 61))
    omega = rotation_log(rotation_exp(np.stack([angles, np.zeros(61), np.zeros(61)], 1)))
    assert np.abs(np.diff(omega[:, 0])).max() > np.pi  # the jump
    pairs = np.stack([np.arange(60), np.arange(1, 61)], 1)
    unwrapped, turns = unwrap_rotation_vectors(omega, pairs)
    assert np.allclose(rotation_exp(unwrapped), rotation_exp(omega), atol=1e-12)
    assert np.allclose(unwrapped[:, 0], angles, atol=1e-9)
    assert np.count_nonzero(turns) == np.count_nonzero(angles > np.pi + 1e-12)
    assert np.allclose(rotation_angle_between(rotation_exp(unwrapped[:-1]), rotation_exp(unwrapped[1:])),
                       np.radians(5.0))
