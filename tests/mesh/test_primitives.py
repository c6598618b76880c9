"""Parametric meshes: the capsule is closed, outward and of the announced size."""

import numpy as np

from posefix.mesh.intersections import self_intersecting_pairs
from posefix.mesh.primitives import capsule
from posefix.mesh.topology import edges


def test_capsule_is_a_closed_outward_surface_of_the_given_size():
    around, cap_rings, length_rings = 12, 3, 10
    V, F = capsule(around=around, cap_rings=cap_rings, length_rings=length_rings, radius=0.5, length=6.0)
    assert len(V) == 2 + around * (2 * cap_rings + length_rings - 1)
    assert len(V) - len(edges(F)) + len(F) == 2  # a sphere
    assert np.allclose(V.min(axis=0), [-3.5, -0.5, -0.5]) and np.allclose(V.max(axis=0), [3.5, 0.5, 0.5])
    v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    volume = np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum() / 6.0
    assert 0.9 * (np.pi * 0.25 * 6.0 + 4 / 3 * np.pi * 0.125) < volume < np.pi * 0.25 * 6.0 + 4 / 3 * np.pi * 0.125
    assert len(self_intersecting_pairs(V, F)) == 0
