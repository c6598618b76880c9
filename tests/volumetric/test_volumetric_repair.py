"""The volumetric fill (third repair): rigid motions come back, a dent pushed through the body is filled."""

import numpy as np
import pytest

from posefix.mesh.rotations import rotation_exp
from posefix.volumetric.repair import VolumetricRepair
from posefix.volumetric.shapes import tet_grid
from posefix.volumetric.transfer import boundary_faces


@pytest.fixture(scope="module")
def bar():
    """A 3 x 1 x 1 bar: its tet grid and its boundary surface (V, F) on the grid's boundary vertices."""
    X, T = tet_grid((6, 2, 2), (3.0, 1.0, 1.0))
    faces, _ = boundary_faces(T)
    used, F = np.unique(faces, return_inverse=True)
    return X[used], F.reshape(-1, 3), X, T


def moved(V):
    R = rotation_exp(np.array([[0.1, 0.5, -0.2]]))[0]
    return V @ R.T + [1.0, -2.0, 0.5]


def test_a_rigid_motion_comes_back_with_the_free_region_in_place(bar):
    V, F, X, T = bar
    target = moved(V)
    free = (V[:, 0] > 1.0) & (V[:, 0] < 2.0) & (V[:, 2] == 1.0)
    X_free, edit, _ = VolumetricRepair(V, F, X, T).fill(target, free, iterations=40)
    assert np.abs(X_free - target).max() <= 1e-6 and edit.shear[-1] <= 1e-6


def test_a_dent_pushed_through_the_bar_is_filled_without_new_intersections(bar):
    V, F, X, T = bar
    dent = (V[:, 0] > 1.0) & (V[:, 0] < 2.0) & (V[:, 2] == 1.0)
    pushed = V.copy()
    pushed[dent, 2] -= 1.5  # the top's middle pushed out through the bottom
    fill = VolumetricRepair(V, F, X, T)
    assert fill.intersecting(moved(pushed)).any()
    result = fill.repair(moved(pushed), constrained=~dent, iterations=40)
    assert result.target_faces > 0 and not result.new_faces.any() and result.rings == 0
    assert np.abs(result.X - moved(V)).max() <= 1e-6
    assert np.array_equal(result.X[~dent], moved(pushed)[~dent])  # V_C reproduced exactly
    assert np.array_equal(fill.repair(moved(pushed), ~dent, iterations=40, max_rings=0).X, result.X)
