"""Box tree queries equal brute force."""

import numpy as np

from posefix.mesh.bvh import build_box_tree, cross_overlapping_pairs, self_overlapping_pairs


def _random_boxes(rng, k, size):
    lo = rng.uniform(0, 1, size=(k, 3))
    return lo, lo + rng.uniform(0, size, size=(k, 3))


def _brute(lo_a, hi_a, lo_b, hi_b):
    ov = np.all((lo_a[:, None] <= hi_b[None]) & (lo_b[None] <= hi_a[:, None]), axis=2)
    return ov


def test_self_pairs_equal_brute_force():
    rng = np.random.default_rng(2)
    for k, leaf in ((1, 2), (7, 2), (300, 2), (300, 8), (513, 4)):
        lo, hi = _random_boxes(rng, k, 0.15)
        P = self_overlapping_pairs(build_box_tree(lo, hi, leaf_size=leaf))
        ov = np.triu(_brute(lo, hi, lo, hi), 1)
        expected = np.argwhere(ov)
        assert np.array_equal(P, expected), (k, leaf)


def test_cross_pairs_equal_brute_force():
    rng = np.random.default_rng(3)
    for ka, kb in ((1, 1), (40, 300), (300, 17)):
        lo_a, hi_a = _random_boxes(rng, ka, 0.1)
        lo_b, hi_b = _random_boxes(rng, kb, 0.05)
        P = cross_overlapping_pairs(build_box_tree(lo_a, hi_a), build_box_tree(lo_b, hi_b, leaf_size=4))
        assert np.array_equal(P, np.argwhere(_brute(lo_a, hi_a, lo_b, hi_b)))


def test_touching_boxes_overlap():
    lo = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    hi = np.array([[1.0, 1, 1], [2.0, 1, 1]])
    assert self_overlapping_pairs(build_box_tree(lo, hi)).tolist() == [[0, 1]]
