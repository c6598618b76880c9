"""Inner Voronoi poles: on a sphere near its centre, on a capsule near its axis, duplicates, determinism."""

import numpy as np

from conftest import icosphere
from posefix.mesh.geometry import vertex_normals
from posefix.mesh.primitives import capsule
from posefix.medial.poles import inner_poles


def _distance_to_segment(P, half):
    nearest = np.column_stack([np.clip(P[:, 0], -half, half), np.zeros(len(P)), np.zeros(len(P))])
    return np.linalg.norm(P - nearest, axis=1)


def _fibonacci_sphere(n):
    i = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
    return np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])


def test_poles_of_a_densely_sampled_sphere_are_near_its_centre():
    D = _fibonacci_sphere(4000)
    # radial noise of 1e-6 (off the degenerate exact sphere); poles need noise << spacing^2 / radius
    radius = 2.0 * (1 + 1e-6 * np.random.default_rng(0).uniform(-1, 1, size=(len(D), 1)))
    S, found = inner_poles(3.0 + radius * D, D)
    assert found.all()
    assert np.linalg.norm(S - 3.0, axis=1).max() < 0.02 * 2.0
    V, F = icosphere(4, radius=2.0)
    S, found = inner_poles(V, vertex_normals(V, F))
    assert found.all() and np.linalg.norm(S, axis=1).max() < 0.02 * 2.0


def test_poles_of_a_capsule_are_near_its_axis_segment():
    V, F = capsule(radius=0.5, length=6.0)
    V = V + 1e-6 * np.random.default_rng(1).uniform(-1, 1, size=V.shape)
    S, found = inner_poles(V, vertex_normals(V, F))
    assert found.all()
    assert _distance_to_segment(S, 3.0).max() < 0.02 * 0.5


def test_duplicates_share_their_cell_and_zero_normals_get_no_pole():
    V, F = icosphere(3)
    N = vertex_normals(V, F)
    V2, N2 = np.vstack([V, V[:2]]), np.vstack([N, N[:2]])
    N2[5] = 0.0
    S, found = inner_poles(V2, N2)
    assert not found[5] and np.isnan(S[5]).all()
    assert found[len(V):].all() and np.allclose(S[len(V):], S[:2])
    assert np.array_equal(S, inner_poles(V2, N2)[0], equal_nan=True)
