"""Offscreen rasterizer: camera, view limits, highlighted faces seen through the surface."""

import numpy as np
from matplotlib.figure import Figure

from conftest import icosphere, pixels
from posefix.report.rasterizer import HIGHLIGHT, camera, draw_mesh, view_limits


def test_camera_is_a_rotation_looking_across_the_thinnest_side():
    V = np.random.default_rng(0).random((50, 3)) * [1.0, 3.0, 0.2]  # thinnest along z
    R = camera(V, azimuth=0.0, elevation=0.0)
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(np.abs(R[2]), [0, 0, 1])  # looks along z
    assert np.allclose(R[1], [0, 1, 0])  # y up
    R = camera(V * [1, 0.01, 1], azimuth=0.0, elevation=0.0)  # thinnest along y: z is up
    assert np.allclose(np.abs(R[2]), [0, 1, 0]) and np.allclose(R[1], [0, 0, 1])


def test_view_limits_contain_every_mesh():
    V, _ = icosphere(1)
    R = camera(V)
    limits = view_limits(V, V + [5.0, 0.0, 0.0], R=R)
    P = np.concatenate([V, V + [5.0, 0.0, 0.0]]) @ R[:2].T
    assert (P >= limits[:, 0]).all() and (P <= limits[:, 1]).all()


def test_highlighted_faces_are_visible_even_behind_the_surface():
    V, F = icosphere(2)
    R = camera(V, azimuth=0.0, elevation=0.0)
    back = (V[F].mean(axis=1) @ R[2]) < -0.5  # faces on the far side of the sphere
    plain, marked = Figure(figsize=(3, 3), dpi=60), Figure(figsize=(3, 3), dpi=60)
    draw_mesh(plain.add_subplot(), V, F, R)
    draw_mesh(marked.add_subplot(), V, F, R, highlight=[(back, HIGHLIGHT)])
    a, b = pixels(plain), pixels(marked)
    assert a.var() > 0
    red = (b[..., 0] > 0.6) & (b[..., 1] < 0.5) & (b[..., 2] < 0.5)
    assert red.sum() > 50 and not ((a[..., 0] > 0.6) & (a[..., 1] < 0.5)).any()
