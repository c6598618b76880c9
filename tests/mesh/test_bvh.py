"""Box tree queries equal brute force."""

import numpy as np

from posefix.mesh import bvh
from posefix.mesh.bvh import build_box_tree, cross_overlapping_pairs, self_overlapping_pairs


def _random_boxes(rng, k, size):
    lo = rng.uniform(0, 1, size=(k, 3))
    return lo, lo + rng.uniform(0, size, size=(k, 3))


def _brute(lo_a, hi_a, lo_b, hi_b):
    ov = np.all((lo_a[:, None] <= hi_b[None]) & (lo_b[None] <= hi_a[:, None]), axis=2)
    return ov


def _sorted(P):
    return P[np.lexsort(P.T[::-1])]


def test_self_pairs_equal_brute_force():
    rng = np.random.default_rng(2)
    for k, leaf in ((0, 4), (1, 2), (7, 2), (300, 1), (300, 2), (300, 8), (513, 4), (513, 3)):
        lo, hi = _random_boxes(rng, k, 0.15)
        P = self_overlapping_pairs(build_box_tree(lo, hi, leaf_size=leaf))
        assert P.shape[1] == 2 and np.all(P[:, 0] < P[:, 1])
        ov = np.triu(_brute(lo, hi, lo, hi), 1)
        assert np.array_equal(_sorted(P), np.argwhere(ov)), (k, leaf)


def test_cross_pairs_equal_brute_force():
    rng = np.random.default_rng(3)
    for ka, kb, leaf_a, leaf_b in ((1, 1, 4, 4), (40, 300, 2, 4), (300, 17, 4, 1), (0, 5, 4, 4), (65, 9, 3, 8)):
        lo_a, hi_a = _random_boxes(rng, ka, 0.1)
        lo_b, hi_b = _random_boxes(rng, kb, 0.05)
        P = cross_overlapping_pairs(build_box_tree(lo_a, hi_a, leaf_size=leaf_a),
                                    build_box_tree(lo_b, hi_b, leaf_size=leaf_b))
        assert np.array_equal(_sorted(P), np.argwhere(_brute(lo_a, hi_a, lo_b, hi_b)))


def test_pairs_in_small_chunks_equal_brute_force(monkeypatch):
    monkeypatch.setattr(bvh, "_CHUNK", 7)
    lo, hi = _random_boxes(np.random.default_rng(5), 300, 0.2)
    P = self_overlapping_pairs(build_box_tree(lo, hi))
    assert np.array_equal(_sorted(P), np.argwhere(np.triu(_brute(lo, hi, lo, hi), 1)))
    P = cross_overlapping_pairs(build_box_tree(lo[:100], hi[:100]), build_box_tree(lo[100:], hi[100:]))
    assert np.array_equal(_sorted(P), np.argwhere(_brute(lo[:100], hi[:100], lo[100:], hi[100:])))


def test_pairs_are_deterministic():
    lo, hi = _random_boxes(np.random.default_rng(4), 400, 0.1)
    first = self_overlapping_pairs(build_box_tree(lo, hi))
    assert np.array_equal(first, self_overlapping_pairs(build_box_tree(lo.copy(), hi.copy())))


def test_touching_boxes_overlap():
    lo = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    hi = np.array([[1.0, 1, 1], [2.0, 1, 1]])
    assert self_overlapping_pairs(build_box_tree(lo, hi)).tolist() == [[0, 1]]
    assert cross_overlapping_pairs(build_box_tree(lo[:1], hi[:1]), build_box_tree(lo[1:], hi[1:])).tolist() == [[0, 0]]


def test_degenerate_and_identical_boxes():
    lo = np.zeros((9, 3))
    P = self_overlapping_pairs(build_box_tree(lo, lo))  # nine equal points: every pair overlaps
    assert np.array_equal(_sorted(P), np.argwhere(np.triu(np.ones((9, 9), bool), 1)))
