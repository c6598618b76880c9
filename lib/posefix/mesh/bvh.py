"""Bounding-volume hierarchy of axis-aligned boxes and vectorized overlap queries.

The tree is a linear BVH: items are sorted along a Morton (Z-order) curve of their box centres,
cut into leaves of ``leaf_size`` items, and the leaves form a complete binary tree (padded to a
power of two with empty boxes). Queries walk the tree breadth-first over *pairs* of nodes, a few
vectorized operations per level, so their cost is proportional to the number of overlapping node
pairs; at the leaves every item of one leaf is tested against every item of the other at once.

Boxes are stored coordinate-major, ``(3, ...)``, so that the gathers and comparisons of a level run
over long contiguous rows (``np.take`` along the last axis), and long levels are processed in chunks
whose temporaries stay in cache; both matter more than the operation count in numpy.
"""

from dataclasses import dataclass

import numpy as np

from posefix.mesh.tolerances import TINY

_CHUNK = 16384


@dataclass(frozen=True)
class BoxTree:
    """A complete binary tree of boxes.

    Attributes
    ----------
    lo, hi : list of (3, 2**level) float
        Node boxes per level, root first, coordinate-major; empty nodes have ``lo = +inf, hi = -inf``.
    items : (leaf_size, leaves) int64
        Item index stored in each leaf slot, -1 for padding.
    item_lo, item_hi : (3, leaf_size, leaves) float
        The item box in each leaf slot (empty for padding).
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


def build_box_tree(lo, hi, leaf_size=4):
    """Build a :class:`BoxTree` over ``k`` boxes.

    Parameters
    ----------
    lo, hi : (k, 3) float
        Box corners, ``lo <= hi``.
    leaf_size : int
        Items per leaf.
    """
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    k = len(lo)
    order = np.argsort(_morton_codes(0.5 * (lo + hi)), kind="stable")
    leaves = 1 << max(0, int(np.ceil(np.log2(max(1, -(-k // leaf_size))))))
    slots = np.full(leaves * leaf_size, k, dtype=np.int64)  # k: the empty box appended below
    slots[:k] = order
    slots = slots.reshape(leaves, leaf_size).T
    item_lo = np.take(np.concatenate([lo.T, np.full((3, 1), np.inf)], 1), slots, axis=1)
    item_hi = np.take(np.concatenate([hi.T, np.full((3, 1), -np.inf)], 1), slots, axis=1)
    levels_lo, levels_hi = [item_lo.min(axis=1)], [item_hi.max(axis=1)]
    while levels_lo[0].shape[1] > 1:
        levels_lo.insert(0, np.minimum(levels_lo[0][:, 0::2], levels_lo[0][:, 1::2]))
        levels_hi.insert(0, np.maximum(levels_hi[0][:, 0::2], levels_hi[0][:, 1::2]))
    return BoxTree(levels_lo, levels_hi, np.where(slots < k, slots, -1), item_lo, item_hi)


def self_overlapping_pairs(tree):
    """All pairs of distinct items of one tree whose boxes overlap (closed boxes).

    Returns
    -------
    (p, 2) int64
        Item pairs ``(i, j)`` with ``i < j``, each pair once, in the tree's (deterministic) order;
        sort them if the order matters.
    """
    a = b = np.zeros(0, dtype=np.int64)
    for level in range(1, tree.depth + 1):
        siblings = 2 * np.arange(1 << (level - 1))
        a = np.concatenate([2 * a, 2 * a, 2 * a + 1, 2 * a + 1, siblings])
        b = np.concatenate([2 * b, 2 * b + 1, 2 * b, 2 * b + 1, siblings + 1])
        keep = _nodes_overlap(tree.lo[level], tree.hi[level], a, tree.lo[level], tree.hi[level], b)
        a, b = a[keep], b[keep]
    i, j = np.concatenate([_leaf_pairs(tree, a, tree, b), _within_leaves(tree)], 1)
    return np.stack([np.minimum(i, j), np.maximum(i, j)], 1)


def cross_overlapping_pairs(tree_a, tree_b):
    """All pairs (item of ``tree_a``, item of ``tree_b``) whose boxes overlap (closed boxes).

    Returns
    -------
    (p, 2) int64
        Column 0 indexes ``tree_a``'s items, column 1 ``tree_b``'s; each pair once, in the trees'
        (deterministic) order; sort them if the order matters.
    """
    a = b = np.zeros(1, dtype=np.int64)
    la = lb = 0
    while la < tree_a.depth or lb < tree_b.depth:
        if la < tree_a.depth:
            a, b, la = np.concatenate([2 * a, 2 * a + 1]), np.concatenate([b, b]), la + 1
        if lb < tree_b.depth:
            a, b, lb = np.concatenate([a, a]), np.concatenate([2 * b, 2 * b + 1]), lb + 1
        keep = _nodes_overlap(tree_a.lo[la], tree_a.hi[la], a, tree_b.lo[lb], tree_b.hi[lb], b)
        a, b = a[keep], b[keep]
    return _leaf_pairs(tree_a, a, tree_b, b).T


def _nodes_overlap(lo_a, hi_a, a, lo_b, hi_b, b):
    """Closed overlap of the boxes ``a`` of (3, n) ``lo_a, hi_a`` with the boxes ``b`` of ``lo_b, hi_b``, (p,) bool.

    Done in chunks whose temporaries stay in cache, as :func:`_leaf_pairs`.
    """
    chunks = [_nodes_chunk_overlap(lo_a, hi_a, a[s:s + _CHUNK], lo_b, hi_b, b[s:s + _CHUNK])
              for s in range(0, len(a), _CHUNK)]
    return np.concatenate(chunks) if chunks else np.zeros(0, dtype=bool)


def _nodes_chunk_overlap(lo_a, hi_a, a, lo_b, hi_b, b):
    """:func:`_nodes_overlap` in one pass."""
    la, ha = np.take(lo_a, a, axis=1), np.take(hi_a, a, axis=1)
    lb, hb = np.take(lo_b, b, axis=1), np.take(hi_b, b, axis=1)
    ok = (la[0] <= hb[0]) & (lb[0] <= ha[0])
    for axis in (1, 2):
        ok &= (la[axis] <= hb[axis]) & (lb[axis] <= ha[axis])
    return ok


def _leaf_pairs(tree_a, a, tree_b, b):
    """Overlapping item pairs of the leaf pairs ``(a[p], b[p])``, every slot against every slot, (2, q) int64.

    Done in chunks of leaf pairs whose temporaries stay in cache (up to twice as fast as one pass).
    """
    chunks = [_leaf_chunk_pairs(tree_a, a[s:s + _CHUNK], tree_b, b[s:s + _CHUNK])
              for s in range(0, len(a), _CHUNK)]
    return np.concatenate(chunks, 1) if chunks else np.zeros((2, 0), dtype=np.int64)


def _leaf_chunk_pairs(tree_a, a, tree_b, b):
    """:func:`_leaf_pairs` in one pass."""
    la, ha = np.take(tree_a.item_lo, a, axis=2), np.take(tree_a.item_hi, a, axis=2)
    lb, hb = np.take(tree_b.item_lo, b, axis=2), np.take(tree_b.item_hi, b, axis=2)
    ok = (la[0][:, None] <= hb[0][None]) & (lb[0][None] <= ha[0][:, None])  # (slots a, slots b, p)
    for axis in (1, 2):
        ok &= (la[axis][:, None] <= hb[axis][None]) & (lb[axis][None] <= ha[axis][:, None])
    ij, p = np.divmod(np.flatnonzero(ok), len(a))
    i, j = np.divmod(ij, ok.shape[1])
    return np.stack([np.take(tree_a.items, i * tree_a.items.shape[1] + np.take(a, p)),
                     np.take(tree_b.items, j * tree_b.items.shape[1] + np.take(b, p))])


def _within_leaves(tree):
    """Overlapping item pairs that share a leaf, (2, q) int64."""
    iu, ju = np.triu_indices(tree.items.shape[0], 1)
    lo, hi = tree.item_lo, tree.item_hi
    ok = (lo[0, iu] <= hi[0, ju]) & (lo[0, ju] <= hi[0, iu])  # (slot pairs, leaves)
    for axis in (1, 2):
        ok &= (lo[axis, iu] <= hi[axis, ju]) & (lo[axis, ju] <= hi[axis, iu])
    t, leaf = np.divmod(np.flatnonzero(ok), ok.shape[1])
    return np.stack([tree.items[iu[t], leaf], tree.items[ju[t], leaf]])


def _morton_codes(points):
    """48-bit Morton codes of points quantized on their bounding box (16 bits per axis), (k,) uint64."""
    code = np.zeros(len(points), dtype=np.uint64)
    for axis in range(3):  # column by column: reductions along a length-3 axis are slow in numpy
        x = points[:, axis]
        lo = x.min() if len(x) else 0.0
        extent = x.max() - lo if len(x) else 0.0
        q = ((x - lo) * (65535.0 / extent if extent > TINY else 0.0)).astype(np.uint16)
        low, high = np.take(_SPREAD_BYTE, q & 255), np.take(_SPREAD_BYTE, q >> 8)
        code |= ((high << np.uint64(24)) | low) << np.uint64(2 - axis)
    return code


def _spread_bits(x):
    """Insert two zero bits between each of the low 8 bits of ``x`` (uint64)."""
    out = np.zeros_like(x)
    for bit in range(8):
        out |= ((x >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit)
    return out


_SPREAD_BYTE = _spread_bits(np.arange(256, dtype=np.uint64))
