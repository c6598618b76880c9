"""Geodesic farthest-point samples: the tips of a body first, both of two feet that stand close."""

import numpy as np

from posefix.mesh.sampling import geodesic_farthest_points


def legs():
    """Two thin strips ("legs") 0.2 apart in x, joined at the top (y = 2) by a bridge strip: a U of triangles."""
    def strip(points):
        points = np.asarray(points, dtype=float)
        V = np.concatenate([points, points + [0.0, 0.0, 0.05]])
        k = len(points)
        F = [[i, i + 1, k + i] for i in range(k - 1)] + [[i + 1, k + i + 1, k + i] for i in range(k - 1)]
        return V, np.array(F)
    path = [[0.0, y, 0.0] for y in np.linspace(0.0, 2.0, 21)] + [[x, 2.0, 0.0] for x in (0.05, 0.1, 0.15)] + \
        [[0.2, y, 0.0] for y in np.linspace(2.0, 0.0, 21)]
    return strip(path)


def test_both_feet_come_first_though_they_are_close():
    V, F = legs()
    ids = geodesic_farthest_points(V, F, 3)
    feet = V[ids[:2], :2]
    assert sorted(feet[:, 0].round(6).tolist()) == [0.0, 0.2] and np.allclose(feet[:, 1], 0.0)
    assert abs(V[ids[2], 1] - 2.0) < 0.11  # then the middle of the U, at the top
    assert len(set(geodesic_farthest_points(V, F, 20).tolist())) == 20
