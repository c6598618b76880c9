"""S4's iterative editing on bars: rest, translation, a 90-degree bend, rigid regions, random starts."""

import numpy as np
import pytest

from posefix.mesh.rotations import rotation_exp
from posefix.volumetric.editor import VolumetricEditor, averaged_rotations, edit
from posefix.volumetric.shapes import tet_grid

EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])


@pytest.fixture(scope="module")
def bar():
    """A 10 x 1 x 1 bar of 20 x 2 x 2 cubes; handles: the vertices of both ends."""
    X, T = tet_grid((20, 2, 2), (10.0, 1.0, 1.0))
    fixed, moved = np.flatnonzero(X[:, 0] == 0), np.flatnonzero(X[:, 0] == 10)
    return X, T, fixed, moved


def bent(X, moved):
    """The end face turned 90 degrees about z and put where a quarter circle of the bar's length ends."""
    r = 10.0 / (np.pi / 2)
    turn = rotation_exp(np.array([[0.0, 0.0, np.pi / 2]]))[0]
    return np.array([r, 0.5 + r, 0.5]) + (X[moved] - [10.0, 0.5, 0.5]) @ turn.T


def edge_lengths(X, T):
    return np.linalg.norm(X[T[:, EDGES[:, 0]]] - X[T[:, EDGES[:, 1]]], axis=2)


@pytest.mark.parametrize("rotation", ["svd", "average"])
def test_handles_at_rest_keep_the_rest_and_a_translation_translates(bar, rotation):
    X, T, fixed, moved = bar
    editor = VolumetricEditor(X, T, np.r_[fixed, moved], rotation=rotation)
    handles = np.r_[fixed, moved]
    assert np.abs(editor.solve(X[handles], iterations=3).X - X).max() <= 1e-12
    shift = np.array([0.3, -2.0, 1.1])
    assert np.abs(editor.solve(X[handles] + shift, iterations=3).X - (X + shift)).max() <= 1e-11


@pytest.mark.parametrize("rotation", ["svd", "average"])
def test_a_bar_bent_90_degrees_keeps_its_tets_near_rigid_where_the_linear_step_shears(bar, rotation):
    X, T, fixed, moved = bar
    editor = VolumetricEditor(X, T, np.r_[fixed, moved], rotation=rotation)
    targets = np.r_[X[fixed], bent(X, moved)]
    linear, iterated = editor.solve(targets, iterations=0), editor.solve(targets, iterations=50)
    assert linear.shear[0] > 0.5 and iterated.shear[-1] < 0.06  # mean |T_j - R_j| (Frobenius)
    middle = np.abs(X[:, 0] - 5.0) < 1e-9
    arc = np.array([10.0 / (np.pi / 2) * np.sin(np.pi / 4), 0.5 + 10.0 / (np.pi / 2) * (1 - np.cos(np.pi / 4))])
    assert np.linalg.norm(iterated.X[middle].mean(axis=0)[:2] - arc) < 0.15  # near the quarter circle
    assert np.linalg.norm(linear.X[middle].mean(axis=0)[:2] - arc) > 1.0
    assert np.all(np.linalg.det(editor.transformations(iterated.X)) > 0)  # no tet inverted


def test_a_rigid_region_keeps_its_edge_lengths(bar):
    X, T, fixed, moved = bar
    region = np.flatnonzero(np.abs(X[T].mean(axis=1)[:, 0] - 5.0) < 1.0)
    result = edit(X, T, np.r_[fixed, moved], np.r_[X[fixed], bent(X, moved)], iterations=20, rigid=[region])
    before, after = edge_lengths(X, T[region]), edge_lengths(result.X, T[region])
    assert np.abs(after / before - 1.0).max() <= 1e-6
    assert np.abs(result.rotations[region] - result.rotations[region[0]]).max() == 0.0


def test_a_random_start_returns_to_the_rest_shape(bar):
    """S4 §3.3: randomized differential coordinates with the handles at rest converge back to the rest."""
    X, T, fixed, moved = bar
    rng = np.random.default_rng(0)
    editor = VolumetricEditor(X, T, np.r_[fixed, moved])
    start = rotation_exp(rng.normal(scale=0.5, size=(len(T), 3)))
    errors = [np.abs(editor.solve(X[np.r_[fixed, moved]], k, warm_start=start).X - X).max() for k in (0, 200)]
    assert errors[0] > 0.2 and errors[1] < 0.01


def test_averaged_rotations_are_rotations_close_to_the_polar_factor():
    rng = np.random.default_rng(1)
    R = rotation_exp(rng.normal(size=(50, 3)))
    A = R @ (np.eye(3) + 0.1 * rng.normal(size=(50, 3, 3)))
    H = averaged_rotations(A)
    assert np.abs(np.linalg.det(H) - 1.0).max() < 1e-9
    assert np.abs(H @ H.transpose(0, 2, 1) - np.eye(3)).max() < 0.05  # three steps and row normalisation
    assert np.abs(H - R).max() < 0.3


def test_an_editor_needs_a_handle_and_refuses_overlapping_regions(bar):
    X, T, fixed, moved = bar
    with pytest.raises(ValueError, match="undetermined"):
        VolumetricEditor(X, T, [])
    with pytest.raises(ValueError, match="overlaps"):
        VolumetricEditor(X, T, fixed, rigid=[np.arange(len(T))])
    with pytest.raises(ValueError, match="rotation extraction"):
        VolumetricEditor(X, T, fixed, rotation="qr")
