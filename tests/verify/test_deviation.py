"""Deviation from the target: per vertex relative to d, summarized over V_C and the rest."""

import numpy as np

from posefix.verify.deviation import deviation


def test_deviation_summary():
    X = np.zeros((4, 3))
    V = np.array([[0.0, 0, 0], [3.0, 0, 0], [0, 4.0, 0], [0, 0, 1.0]])
    dev, s = deviation(X, V, np.array([True, True, False, False]), d=2.0)
    assert np.allclose(dev, [0, 1.5, 2.0, 0.5])
    assert s["constrained_max"] == 1.5 and s["constrained_mean"] == 0.75 and s["free_max"] == 2.0
    assert s["free_mean"] == 1.25 and s["constrained_p95"] == np.percentile([0, 1.5], 95)


def test_empty_sets_summarize_to_zero():
    dev, s = deviation(np.ones((3, 3)), np.zeros((3, 3)), np.ones(3, dtype=bool), d=1.0)
    assert np.allclose(dev, np.sqrt(3)) and s["free_max"] == s["free_mean"] == s["free_p95"] == 0.0
