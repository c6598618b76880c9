"""Shrinking balls: a sphere's centre, a capsule's axis, flat sheets, determinism."""

import numpy as np

from conftest import grid_sheet, icosphere
from posefix.mesh.primitives import capsule
from posefix.medial.shrinking_ball import shrinking_ball_centers


def test_balls_of_a_sphere_shrink_to_its_centre():
    V, _ = icosphere(3, radius=2.0, centre=(1.0, 0.0, 0.0))
    N = (V - [1.0, 0.0, 0.0]) / 2.0
    S, R, converged = shrinking_ball_centers(V, N, r_init=100.0)
    assert converged.all()
    assert np.allclose(S, [1.0, 0.0, 0.0], atol=1e-9) and np.allclose(R, 2.0)
    rng = np.random.default_rng(0)
    D = rng.normal(size=(3000, 3))
    D /= np.linalg.norm(D, axis=1, keepdims=True)
    S, R, converged = shrinking_ball_centers(D, D, r_init=10.0)
    assert converged.all() and np.linalg.norm(S, axis=1).max() < 1e-9


def test_balls_of_a_capsule_reach_its_axis():
    V, _ = capsule(radius=0.5, length=6.0)
    axis = np.column_stack([np.clip(V[:, 0], -3.0, 3.0), np.zeros((len(V), 2))])
    N = (V - axis) / np.linalg.norm(V - axis, axis=1, keepdims=True)
    S, R, converged = shrinking_ball_centers(V, N, r_init=20.0)
    assert converged.all()
    assert np.allclose(S, axis, atol=1e-9) and np.allclose(R, 0.5)


def test_a_flat_sheet_gives_capped_unconverged_balls():
    V, _ = grid_sheet(10, 0.0)
    N = np.tile([0.0, 0.0, 1.0], (len(V), 1))
    S, R, converged = shrinking_ball_centers(V, N, r_init=5.0)
    assert not converged.any() and np.allclose(R, 5.0)
    assert np.array_equal(S, V - 5.0 * N)


def test_zero_normals_and_determinism():
    V, F = icosphere(2)
    N = V.copy()
    N[0] = 0.0
    first = shrinking_ball_centers(V, N, r_init=10.0)
    assert not first[2][0] and first[2][1:].all()
    for a, b in zip(first, shrinking_ball_centers(V, N, r_init=10.0)):
        assert np.array_equal(a, b)
