"""Bounding-volume hierarchy of axis-aligned boxes and vectorized overlap queries.

The tree is a linear BVH: items are sorted along a Morton (Z-order) curve of their box centres,
cut into leaves of ``leaf_size`` items, and the leaves form a complete binary tree (padded to a
power of two with empty boxes). Queries walk the tree breadth-first over *pairs* of nodes, one
numpy operation per level, so their cost is proportional to the number of overlapping node pairs.
"""

from dataclasses import dataclass

import numpy as np

_MORTON_BITS = 21


@dataclass(frozen=True)
class BoxTree:
    """A complete binary tree of boxes.

    Attributes
    ----------
    lo, hi : list of (2**level, 3) float
        Node boxes per level, root first; empty nodes have ``lo = +inf, hi = -inf``.
    items : (leaves, leaf_size) int64
        Item index stored in each leaf slot, -1 for padding.
    item_lo, item_hi : (k, 3) float
        The item boxes.
    """

    lo: list
    hi: list
    items: np.ndarray
    item_lo: np.ndarray
    item_hi: np.ndarray

    @property
    def depth(self):
        """Index of the leaf level."""
        return len(self.lo) - 1


def build_box_tree(lo, hi, leaf_size=2):
    """Build a :class:`BoxTree` over ``k`` boxes.

    Parameters
    ----------
    lo, hi : (k, 3) float
        Box corners, ``lo <= hi``.
    leaf_size : int
        Items per leaf.
    """
    lo = np.ascontiguousarray(lo, dtype=np.float64)
    hi = np.ascontiguousarray(hi, dtype=np.float64)
    k = len(lo)
    order = np.argsort(_morton_codes(0.5 * (lo + hi)), kind="stable")
    leaves = 1 << max(0, int(np.ceil(np.log2(max(1, -(-k // leaf_size))))))
    items = np.full(leaves * leaf_size, -1, dtype=np.int64)
    items[:k] = order
    items = items.reshape(leaves, leaf_size)
    valid = items >= 0
    leaf_lo = np.where(valid[..., None], lo[np.maximum(items, 0)], np.inf).min(axis=1)
    leaf_hi = np.where(valid[..., None], hi[np.maximum(items, 0)], -np.inf).max(axis=1)
    levels_lo, levels_hi = [leaf_lo], [leaf_hi]
    while len(levels_lo[0]) > 1:
        levels_lo.insert(0, np.minimum(levels_lo[0][0::2], levels_lo[0][1::2]))
        levels_hi.insert(0, np.maximum(levels_hi[0][0::2], levels_hi[0][1::2]))
    return BoxTree(levels_lo, levels_hi, items, lo, hi)


def boxes_overlap(lo_a, hi_a, lo_b, hi_b):
    """Closed-interval overlap test of paired boxes (k, 3), (k,) bool."""
    ok = (lo_a[:, 0] <= hi_b[:, 0]) & (lo_b[:, 0] <= hi_a[:, 0])
    for axis in (1, 2):
        ok &= (lo_a[:, axis] <= hi_b[:, axis]) & (lo_b[:, axis] <= hi_a[:, axis])
    return ok


def self_overlapping_pairs(tree):
    """All pairs of distinct items of one tree whose boxes overlap.

    Returns
    -------
    (p, 2) int64
        Item pairs ``(i, j)`` with ``i < j``, sorted lexicographically; each pair once.
    """
    a = b = np.zeros(1, dtype=np.int64)
    for level in range(1, tree.depth + 1):
        same = a == b
        s2, a2, b2 = 2 * a[same], 2 * a[~same], 2 * b[~same]
        a = np.concatenate([(s2[:, None] + _SAME_A).ravel(), (a2[:, None] + _CROSS_A).ravel()])
        b = np.concatenate([(s2[:, None] + _SAME_B).ravel(), (b2[:, None] + _CROSS_B).ravel()])
        keep = boxes_overlap(tree.lo[level][a], tree.hi[level][a], tree.lo[level][b], tree.hi[level][b])
        a, b = a[keep], b[keep]
    same = a == b
    s = tree.items.shape[1]
    iu, ju = np.triu_indices(s, 1)
    items_a, items_b = tree.items[a[~same]], tree.items[b[~same]]
    pairs = np.concatenate([
        np.stack([tree.items[a[same]][:, iu].ravel(), tree.items[a[same]][:, ju].ravel()], 1),
        np.stack([np.repeat(items_a, s, axis=1).ravel(), np.tile(items_b, (1, s)).ravel()], 1)])
    return _finish(pairs, tree, tree, symmetric=True)


# children of a node pair (a, a) are (2a, 2a), (2a, 2a+1), (2a+1, 2a+1); of (a, b): all four
_SAME_A, _SAME_B = np.array([0, 0, 1]), np.array([0, 1, 1])
_CROSS_A, _CROSS_B = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])


def cross_overlapping_pairs(tree_a, tree_b):
    """All pairs (item of ``tree_a``, item of ``tree_b``) whose boxes overlap.

    Returns
    -------
    (p, 2) int64
        Column 0 indexes ``tree_a``'s items, column 1 ``tree_b``'s; sorted lexicographically.
    """
    nodes = np.zeros((1, 2), dtype=np.int64)
    la = lb = 0
    while la < tree_a.depth or lb < tree_b.depth:
        a, b = nodes[:, 0], nodes[:, 1]
        if la < tree_a.depth:
            a, b, la = np.concatenate([2 * a, 2 * a + 1]), np.concatenate([b, b]), la + 1
        if lb < tree_b.depth:
            a, b, lb = np.concatenate([a, a]), np.concatenate([2 * b, 2 * b + 1]), lb + 1
        keep = boxes_overlap(tree_a.lo[la][a], tree_a.hi[la][a], tree_b.lo[lb][b], tree_b.hi[lb][b])
        nodes = np.stack([a[keep], b[keep]], 1)
    sa, sb = tree_a.items.shape[1], tree_b.items.shape[1]
    pairs = np.stack([np.repeat(tree_a.items[nodes[:, 0]], sb, axis=1).ravel(),
                      np.tile(tree_b.items[nodes[:, 1]], (1, sa)).ravel()], 1)
    return _finish(pairs, tree_a, tree_b, symmetric=False)


def _finish(pairs, tree_a, tree_b, symmetric):
    """Drop padding and non-overlapping item boxes; order (and for self queries, orient) pairs."""
    pairs = pairs[(pairs[:, 0] >= 0) & (pairs[:, 1] >= 0)]
    keep = boxes_overlap(tree_a.item_lo[pairs[:, 0]], tree_a.item_hi[pairs[:, 0]],
                         tree_b.item_lo[pairs[:, 1]], tree_b.item_hi[pairs[:, 1]])
    pairs = pairs[keep]
    if symmetric:
        pairs.sort(axis=1)
    width = np.int64(len(tree_b.item_lo))
    key = np.sort(pairs[:, 0] * width + pairs[:, 1])
    return np.stack([key // width, key % width], 1)


def _morton_codes(points):
    """63-bit Morton codes of points quantized on their bounding box, (k,) uint64."""
    lo = points.min(axis=0)
    extent = np.maximum(points.max(axis=0) - lo, np.finfo(float).tiny)
    q = ((points - lo) / extent * ((1 << _MORTON_BITS) - 1)).astype(np.uint64)
    return (_spread_bits(q[:, 0]) << np.uint64(2)) | (_spread_bits(q[:, 1]) << np.uint64(1)) | _spread_bits(q[:, 2])


def _spread_bits(x):
    """Insert two zero bits between each of the low 21 bits of ``x`` (uint64)."""
    x = x & np.uint64(0x1FFFFF)
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                        (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
        x = (x | (x << np.uint64(shift))) & np.uint64(mask)
    return x
