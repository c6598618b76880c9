"""Vertex classification: ring growth, reference re-add, manual exclusion; near contacts."""

import numpy as np

from posefix.mesh.intersections import new_pairs
from posefix.mesh.topology import grow_rings, vertex_adjacency
from posefix.spacetime.classification import (EXCLUDED_INTERSECTION, EXCLUDED_MANUAL, EXCLUDED_RING, READDED_REFERENCE,
                                              constraint_mask)


def _strip(n):
    """A flat strip of 2 x n vertices and 2 (n - 1) faces along x."""
    V = np.concatenate([np.stack([np.arange(n), np.zeros(n), np.zeros(n)], 1),
                        np.stack([np.arange(n), np.ones(n), np.zeros(n)], 1)]).astype(float)
    F = np.array([f for c in range(n - 1) for f in ([c, c + 1, n + c + 1], [c, n + c + 1, n + c])])
    return V, F


def test_rings_on_a_strip():
    V, F = _strip(10)
    seed = np.zeros(20, dtype=bool)
    seed[4] = True
    A = vertex_adjacency(F, 20)
    # vertex 4 (bottom row) touches 3, 5 (bottom) and 14, 15 (top) through faces [4,5,15] and [3,14,13]->[3,4,14]
    assert set(np.flatnonzero(grow_rings(seed, A, 1))) == {3, 4, 5, 14, 15}
    assert grow_rings(seed, A, 0).sum() == 1
    assert grow_rings(seed, A, 2).sum() > grow_rings(seed, A, 1).sum()


def test_new_intersection_excludes_face_vertices_and_one_ring():
    V, F = _strip(10)
    n = len(V)
    none = np.zeros((0, 2), dtype=np.int64)
    frames = [none, none, np.array([[2, 12]])]  # faces 2 and 12 intersect in the last frame
    mask, reasons = constraint_mask(F, n, frames, ring=1)
    hit = set(F[[2, 12]].ravel())
    assert set(np.flatnonzero(reasons & EXCLUDED_INTERSECTION)) == hit
    seeds = np.zeros(n, dtype=bool)
    seeds[list(hit)] = True
    ring = grow_rings(seeds, vertex_adjacency(F, n), 1) & ~seeds
    assert np.array_equal(reasons & EXCLUDED_RING > 0, ring)
    assert np.array_equal(~mask, seeds | ring)
    mask0, _ = constraint_mask(F, n, frames, ring=0)
    assert np.array_equal(~mask0, seeds)


def test_reference_intersections_are_readded_but_their_rings_are_not():
    V, F = _strip(12)
    n = len(V)
    A = vertex_adjacency(F, n)
    ref = np.array([[0, 4]])  # faces [0, 1, 13] and [2, 3, 15] already intersect in the reference
    frames = [ref, ref, np.array([[0, 4], [10, 14]])]  # later also faces [5, 6, 18] and [7, 8, 20]
    mask, reasons = constraint_mask(F, n, frames, ring=1)
    ref_vertices = np.zeros(n, dtype=bool)
    ref_vertices[F[[0, 4]].ravel()] = True
    assert mask[ref_vertices].all()  # reproduced, not repaired (S0 4.3)
    assert (reasons[ref_vertices] == EXCLUDED_INTERSECTION | READDED_REFERENCE).all()
    ring = grow_rings(ref_vertices, A, 1) & ~ref_vertices
    assert ring.any() and not mask[ring].any()
    assert not mask[F[[10, 14]].ravel()].any()
    assert np.array_equal(new_pairs(frames[2], ref), [[10, 14]])
    # a hand-picked exclusion wins over the re-add
    mask, reasons = constraint_mask(F, n, frames, ring=1, exclude=[1])
    assert not mask[1] and reasons[1] == EXCLUDED_INTERSECTION | EXCLUDED_MANUAL


def test_manual_exclusion_without_rings():
    V, F = _strip(6)
    none = np.zeros((0, 2), dtype=np.int64)
    mask, reasons = constraint_mask(F, len(V), [none, none], ring=3, exclude=[4, 7])
    assert set(np.flatnonzero(~mask)) == {4, 7}
    assert (reasons[[4, 7]] == EXCLUDED_MANUAL).all()
