"""S4's iterative editing on bars: rest, translation, a 90-degree bend, rigid regions, random starts."""

import numpy as np
import pytest

from posefix.mesh.rotations import rotation_exp
from posefix.volumetric.editor import PointHandles, VolumetricEditor, averaged_rotations, edit
from posefix.volumetric.shapes import tet_cylinder, tet_grid

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


@pytest.mark.parametrize("rotation", ["polar", "average"])
def test_handles_at_rest_keep_the_rest_and_a_translation_translates(bar, rotation):
    X, T, fixed, moved = bar
    editor = VolumetricEditor(X, T, np.r_[fixed, moved], rotation=rotation)
    handles = np.r_[fixed, moved]
    assert np.abs(editor.solve(X[handles], iterations=3).X - X).max() <= 1e-12
    shift = np.array([0.3, -2.0, 1.1])
    assert np.abs(editor.solve(X[handles] + shift, iterations=3).X - (X + shift)).max() <= 1e-11


@pytest.mark.parametrize("rotation", ["polar", "average"])
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
    with pytest.raises(ValueError, match="not handles"):
        VolumetricEditor(X, T, fixed, regions=[np.arange(10)])


def end_regions(X, T, length, cap=0.25):
    """Region handles: the tets within ``cap`` of either end, and their vertices."""
    centre = X[T].mean(axis=1)[:, 0]
    start, end = np.flatnonzero(centre < cap), np.flatnonzero(centre > length - cap)
    return start, end, np.unique(T[start]), np.unique(T[end])


def test_a_360_degree_twist_with_rotation_interpolation_grows_linearly_along_the_bar():
    """S4 Fig. 2.2a: one end turned in 10 frames of 36 degrees, warm-started; the cross-sections' twist angle is
    linear between the two region handles within 10 degrees, and no tet inverts."""
    X, T = tet_grid((40, 2, 2), (10.0, 1.0, 1.0))
    start, end, fixed, moved = end_regions(X, T, 10.0)
    editor = VolumetricEditor(X, T, np.r_[fixed, moved], regions=[start, end])
    sections = np.unique(X[:, 0])
    angles, rotations = [], None
    for k in range(1, 11):
        turn = rotation_exp(np.array([[2 * np.pi * k / 10, 0.0, 0.0]]))[0]
        targets = np.r_[X[fixed], (X[moved] - [0.0, 0.5, 0.5]) @ turn.T + [0.0, 0.5, 0.5]]
        result = editor.solve(targets, 5, warm_start=rotations, region_rotations=np.stack([np.eye(3), turn]))
        rotations = result.rotations
        angles.append([section_angle(X, result.X, X[:, 0] == x) for x in sections])
    twist = np.degrees(np.unwrap(np.array(angles), axis=0)[-1])
    expected = 360.0 * np.clip((sections - 0.25) / 9.5, 0.0, 1.0)
    assert np.abs(twist - expected).max() < 10.0
    assert np.all(np.linalg.det(editor.transformations(result.X)) > 0)


def section_angle(X, Y, section):
    """Rotation angle (radians) about x of a cross-section from ``X`` to ``Y``."""
    p, q = X[section, 1:] - X[section, 1:].mean(axis=0), Y[section, 1:] - Y[section, 1:].mean(axis=0)
    return np.arctan2((p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]).sum(), (p * q).sum())


def test_a_cylinder_bent_135_degrees_keeps_its_cross_sections():
    """S4 Fig. 2.2b: the mean radius of every cross-section changes by at most 5 %; without the iterations and
    the rotation interpolation the linear step inverts tets."""
    X, T = tet_cylinder(0.5, 6.0, 24, 2)
    start, end, fixed, moved = end_regions(X, T, 6.0)
    angle = np.radians(135.0)
    turn = rotation_exp(np.array([[0.0, 0.0, angle]]))[0]
    arc_end = 6.0 / angle * np.array([np.sin(angle), 1.0 - np.cos(angle), 0.0])
    targets = np.r_[X[fixed], arc_end + (X[moved] - [6.0, 0.0, 0.0]) @ turn.T]
    editor = VolumetricEditor(X, T, np.r_[fixed, moved], regions=[start, end])
    result = editor.solve(targets, 10, region_rotations=np.stack([np.eye(3), turn]))
    outer = np.abs(np.hypot(X[:, 1], X[:, 2]) - 0.5) < 1e-9
    for x in np.unique(X[:, 0]):
        section = X[:, 0] == x
        radius = np.linalg.norm(result.X[section & outer] - result.X[section].mean(axis=0), axis=1).mean()
        assert abs(radius / 0.5 - 1.0) <= 0.05
    assert np.all(np.linalg.det(editor.transformations(result.X)) > 0)
    linear = editor.solve(targets, 0)
    assert np.any(np.linalg.det(editor.transformations(linear.X)) <= 0)


def test_point_handles_inside_the_mesh_reach_their_targets_exactly(bar):
    """S4 §2.3.1: handles anywhere inside the mesh (markers) as linear combinations of tet vertices."""
    from posefix.volumetric.embedding import barycentric_embedding, embedded_points
    X, T, fixed, _ = bar
    points = np.array([[9.8, 0.5, 0.5], [9.8, 0.1, 0.5], [9.8, 0.5, 0.9], [8.3, 0.37, 0.61]])
    editor = VolumetricEditor(X, T, fixed, points=PointHandles(points))
    assert np.abs(editor.solve(X[fixed], 2, point_targets=points).X - X).max() <= 1e-10  # rest
    turn = rotation_exp(np.array([[0.0, 0.0, np.pi / 2]]))[0]
    targets = np.array([6.4, 6.4, 0.0]) + (points - [10.0, 0.5, 0.5]) @ turn.T
    result = editor.solve(X[fixed], 30, point_targets=targets)
    tets, weights = barycentric_embedding(X, T, points)
    assert np.abs(embedded_points(result.X, T, tets, weights) - targets).max() <= 1e-9
    assert result.shear[-1] < result.shear[0] and np.all(np.linalg.det(editor.transformations(result.X)) > 0)
    with pytest.raises(ValueError, match="point_targets"):
        editor.solve(X[fixed], 1)


def test_a_stiffer_middle_deforms_less(bar):
    """S4 §2.3.2: scaling G_j and g_j of a region makes it stiffer than its surroundings."""
    X, T, fixed, moved = bar
    middle = np.abs(X[T].mean(axis=1)[:, 0] - 5.0) < 1.5
    targets = np.r_[X[fixed], bent(X, moved)]

    def middle_shear(stiffness):
        editor = VolumetricEditor(X, T, np.r_[fixed, moved], stiffness=stiffness)
        result = editor.solve(targets, iterations=20)
        A = editor.transformations(result.X)[middle]
        return np.linalg.norm(A - result.rotations[middle], axis=(1, 2)).mean()

    assert middle_shear(np.where(middle, 10.0, 1.0)) < 0.5 * middle_shear(None)
