"""S4's high-resolution transfer: rest and affine maps reproduced, rows a partition of unity, continuity."""

import numpy as np

from posefix.volumetric.shapes import tet_grid
from posefix.volumetric.transfer import boundary_faces, transfer_matrix, wendland


def fine_points(seed=0, count=400):
    """Points in and around the 4 x 1 x 1 box, some outside its faces."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.1, 4.1, count), rng.uniform(-0.05, 1.05, count), rng.uniform(0, 1, count)])


def test_the_rest_and_affine_maps_come_back_and_rows_sum_to_one():
    X, T = tet_grid((8, 2, 2), (4.0, 1.0, 1.0))
    V = fine_points()
    B = transfer_matrix(X, T, V, radius=0.6)
    assert np.abs(B @ X - V).max() <= 1e-12 and np.abs(np.asarray(B.sum(axis=1)).ravel() - 1.0).max() <= 1e-12
    A, t = np.array([[1.2, 0.3, 0.0], [-0.2, 0.9, 0.1], [0.0, 0.4, 1.1]]), np.array([0.5, -2.0, 3.0])
    assert np.abs(B @ (X @ A.T + t) - (V @ A.T + t)).max() <= 1e-12


def test_a_point_moved_across_a_tet_face_changes_its_row_continuously():
    X, T = tet_grid((8, 2, 2), (4.0, 1.0, 1.0))
    across = np.array([[1.5, 0.31, 0.47]])  # x = 1.5 is a plane of tet faces of the grid
    rows = [transfer_matrix(X, T, across + [eps, 0.0, 0.0], radius=0.6).toarray() for eps in (-1e-7, 1e-7, -1e-4)]
    assert np.abs(rows[1] - rows[0]).max() < 1e-5 and np.abs(rows[2] - rows[0]).max() < 1e-2
    Y = X + 0.1 * np.sin(X[:, [1, 2, 0]] * 3.0)  # a smooth non-affine deformation: the image moves continuously
    images = [transfer_matrix(X, T, across + [eps, 0.0, 0.0], radius=0.6) @ Y for eps in (-1e-7, 1e-7)]
    assert np.linalg.norm(images[1] - images[0]) < 1e-5


def test_wendland_weights_fall_smoothly_to_zero_and_the_box_has_its_boundary():
    assert wendland(0.0, 1.0) == 1.0 and wendland(1.0, 1.0) == 0.0 and wendland(2.0, 1.0) == 0.0
    d = np.linspace(0.0, 1.0, 101)
    assert np.all(np.diff(wendland(d, 1.0)) <= 0) and abs(wendland(0.999, 1.0)) < 1e-9
    X, T = tet_grid((2, 1, 1), (2.0, 1.0, 1.0))
    faces, owner = boundary_faces(T)
    assert len(faces) == 2 * (2 * 1 + 2 * 1 + 1 * 1) * 2 and np.all(owner < len(T))  # 10 unit squares, 2 triangles each
