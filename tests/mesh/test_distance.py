"""The exact capped distance from points to a triangle mesh."""

import numpy as np

from conftest import icosphere
from posefix.mesh.distance import surface_distance_below
from posefix.mesh.geometry import point_triangle_distance


def test_surface_distance_is_exact_below_the_limit():
    V, F = icosphere(2)
    V = V * [1.0, 0.6, 0.3]
    P = np.random.default_rng(0).uniform(-1.2, 1.2, size=(300, 3))
    limit = np.random.default_rng(1).uniform(0.0, 0.8, size=len(P))
    A, B, C = (np.repeat(V[F[:, i]][None], len(P), 0).reshape(-1, 3) for i in range(3))
    brute = point_triangle_distance(np.repeat(P, len(F), 0), A, B, C).reshape(len(P), len(F)).min(1)
    assert np.allclose(surface_distance_below(V, F, P, limit), np.minimum(brute, limit), atol=1e-12)
