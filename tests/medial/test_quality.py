"""Bad medial centres: outside, crossing, non-finite."""

import numpy as np

from conftest import icosphere
from posefix.medial.quality import bad_centres


def test_the_true_centre_of_a_sphere_is_good_outside_and_too_large_balls_are_bad():
    V, F = icosphere(3)
    S = np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [np.nan, 0, 0]])
    R = np.array([1.0, 0.5, 3.0, 0.95, 1.0])
    q = bad_centres(V, F, S, R, tol=0.05)
    assert q.nonfinite.tolist() == [False, False, False, False, True]
    assert q.outside.tolist() == [False, True, False, False, False]
    assert q.crossing.tolist() == [False, False, True, True, False]
    assert q.bad.tolist() == [False, True, True, True, True]
    assert q.counts() == {"nonfinite": 1, "outside": 1, "crossing": 2, "bad": 4}
    assert q.clearance[0] > 0.98 and abs(q.clearance[2] - q.clearance[0] / 3) < 1e-12


def test_tolerance_decides_moderate_crossings():
    V, F = icosphere(3)
    S, R = np.zeros((1, 3)), np.array([1.5])  # clearance about 1 / 1.5
    assert bad_centres(V, F, S, R, tol=0.2).crossing[0]
    assert not bad_centres(V, F, S, R, tol=0.5).crossing[0]
